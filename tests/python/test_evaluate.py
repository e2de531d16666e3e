"""evaluate(): a Python callable as the backbone, in process, writes exactly the job of the CLI's
external-process backbone running the same policy."""
import json
import os
import sys
import threading

import numpy as np
import pytest

import actionshift

sys.path.insert(0, os.path.dirname(__file__))
import simple_policy  # noqa: E402

COMMAND = f"{sys.executable} {os.path.abspath(simple_policy.__file__)}"


@pytest.mark.parametrize("method,pool,episodes", [("no_adapt", None, 4), ("entropy_probes", "reference9", 3)])
def test_in_process_job_equals_the_external_process_job(tmp_path, cli, method, pool, episodes):
    inproc, external = tmp_path / "inproc", tmp_path / "external"
    r = actionshift.evaluate(simple_policy.ReachGraspLift(), task="pick_cube", split="seen", method=method,
                             pool=pool, seed=7, episodes=episodes, out=str(inproc), backbone="external:" + COMMAND)
    assert r["episodes_run"] == episodes and r["job"]["backbone"]["name"] == "external:" + COMMAND
    args = ["run", "--task", "pick_cube", "--split", "seen", "--method", method, "--seed", "7",
            "--episodes", str(episodes), "--backbone", "external:" + COMMAND, "--out", str(external),
            "--progress", "off"]
    if pool:
        args += ["--pool", pool]
    out = cli(*args, check=0).stdout
    assert out.startswith(r["job_id"] + " ")
    a = (inproc / f"{r['job_id']}.jsonl").read_bytes()
    b = (external / f"{r['job_id']}.jsonl").read_bytes()
    assert a == b and a.count(b"\n") == episodes
    # the policy does something: some episodes under no adaptation differ in return
    again = actionshift.evaluate(simple_policy.ReachGraspLift(), task="pick_cube", split="seen", method=method,
                                 pool=pool, seed=7, episodes=episodes, out=str(inproc), backbone="external:" + COMMAND)
    assert again["already_complete"] and again["job_id"] == r["job_id"]


def test_policy_identity_enters_the_job_id(tmp_path):
    p = simple_policy.ReachGraspLift()
    a = actionshift.evaluate(p, episodes=1, out=str(tmp_path))
    b = actionshift.evaluate(p, episodes=1, out=str(tmp_path), backbone="python:other")
    assert a["job"]["backbone"]["name"] == "python:simple_policy.ReachGraspLift"
    assert a["job_id"] != b["job_id"]


def test_evaluate_errors(tmp_path, cli):
    with pytest.raises(ValueError) as e:
        actionshift.evaluate(lambda obs: np.zeros(7), split="no_such_split", episodes=1, out=str(tmp_path))
    p = cli("run", "--task", "pick_cube", "--split", "no_such_split", "--method", "no_adapt", "--episodes", "1",
            "--out", str(tmp_path))
    assert p.returncode == 2 and p.stderr.strip() == "actionshift: error: " + str(e.value)
    with pytest.raises(ValueError, match="policy output: must be 7 numbers"):
        actionshift.evaluate(lambda obs: np.zeros(3), episodes=1, out=str(tmp_path))

    class Boom(Exception):
        pass

    def broken(obs):
        raise Boom("policy failed")

    with pytest.raises(Boom, match="policy failed"):
        actionshift.evaluate(broken, episodes=1, out=str(tmp_path))
    with pytest.raises(TypeError):
        actionshift.evaluate(42, episodes=1, out=str(tmp_path))
    with pytest.raises(ValueError, match="unknown backbone 'not a backbone'"):  # a string names a library backbone
        actionshift.evaluate("not a backbone", episodes=1, out=str(tmp_path))
    with pytest.raises(ValueError, match="profile"):
        actionshift.evaluate(lambda obs: np.zeros(7), episodes=1, out=str(tmp_path), profile="no_such_profile")
    # a job's field errors name evaluate(), not the command line
    with pytest.raises(ValueError, match=r"^evaluate: episodes: must be > 0 and at most 2\*\*62 \(got 0\)$"):
        actionshift.evaluate(lambda obs: np.zeros(7), episodes=0, out=str(tmp_path))
    # argument types: one-line errors, and nothing written (out=None used to write to ./None)
    for kwargs, error, pattern in (({"out": None}, TypeError, "evaluate: out: expected a directory path"),
                                   ({"split": None}, TypeError, "evaluate: split: expected str"),
                                   ({"pool": [actionshift.Contract.identity()]}, TypeError, "evaluate: pool: expected a pool name"),
                                   ({"episodes": 2.5}, TypeError, "evaluate: episodes: expected int"),
                                   ({"episodes": 2 ** 63}, ValueError, "evaluate: episodes: must be > 0"),
                                   ({"threads": 2 ** 40}, ValueError, "evaluate: threads: must be 0")):
        args = {"episodes": 1, "out": str(tmp_path / "typed"), **kwargs}
        with pytest.raises(error, match=pattern) as e:
            actionshift.evaluate(lambda obs: np.zeros(7), **args)
        assert "\n" not in str(e.value)
    assert not (tmp_path / "typed").exists()
    # a job's field errors that only the library checks name evaluate(), not the command line
    with pytest.raises(ValueError, match=r"^evaluate: rotation_mode: "):
        actionshift.evaluate(lambda obs: np.zeros(7), episodes=1, out=str(tmp_path), rotation="sideways")
    with pytest.raises(ValueError, match=r"seed: must be an integer in \[0, 2\*\*64\)"):
        actionshift.evaluate(lambda obs: np.zeros(7), seed=-1, episodes=1, out=str(tmp_path))


def test_threads_give_the_same_job_and_copy_the_policy_per_worker(tmp_path):
    # a stateful policy (a step counter): two episodes at once on one object would interleave its
    # counter, so equal bytes need one copy per worker
    one = actionshift.evaluate(simple_policy.ReachGraspLift(), seed=3, episodes=6, out=str(tmp_path / "one"))
    p = simple_policy.ReachGraspLift()
    two = actionshift.evaluate(p, seed=3, episodes=6, out=str(tmp_path / "two"), threads=2)
    assert two["job_id"] == one["job_id"]
    assert (tmp_path / "two" / f"{two['job_id']}.jsonl").read_bytes() == \
        (tmp_path / "one" / f"{one['job_id']}.jsonl").read_bytes()
    assert p.t == 0  # the workers called their copies, not the object passed in
    allcores = actionshift.evaluate(simple_policy.ReachGraspLift(), seed=3, episodes=6, out=str(tmp_path / "all"),
                                    threads=0)
    assert allcores["job_id"] == one["job_id"]


@pytest.mark.parametrize("threads", [1, 2])
def test_each_worker_keeps_one_python_thread_state_across_policy_calls(tmp_path, threads):
    # threading.local lives in the Python thread state: a worker that created and deleted a thread
    # state around every call (an mmap and munmap each, and 50 % more CPU on two threads) would
    # see a fresh local on every call
    local = threading.local()
    runs = []

    def policy(obs):
        local.calls = getattr(local, "calls", 0) + 1
        runs.append((threading.get_ident(), local.calls))
        return np.zeros(7)

    r = actionshift.evaluate(policy, seed=1, episodes=4, out=str(tmp_path), threads=threads)
    per_thread = {}
    for ident, calls in runs:
        per_thread[ident] = per_thread.get(ident, 0) + 1
        assert calls == per_thread[ident]  # the count of this thread's calls so far: nothing was lost
    assert sum(per_thread.values()) == len(runs) > 4 * 10
    assert r["episodes_run"] == 4


def test_threads_errors(tmp_path):
    import threading

    class Uncopyable:
        def __init__(self):
            self.lock = threading.Lock()  # deepcopy cannot copy a lock

        def __call__(self, obs):
            return np.zeros(7)

    with pytest.raises(ValueError, match=r"evaluate: threads: each of the 2 workers needs copy.deepcopy\(policy\)"):
        actionshift.evaluate(Uncopyable(), episodes=2, out=str(tmp_path), threads=2, policy_version="1")
    assert not any(tmp_path.iterdir())  # nothing written
    assert actionshift.evaluate(Uncopyable(), episodes=1, out=str(tmp_path), threads=1,
                                policy_version="1")["episodes_run"] == 1
    with pytest.raises(ValueError, match="threads: must be 0"):
        actionshift.evaluate(lambda obs: np.zeros(7), episodes=1, out=str(tmp_path), threads=-1)


@pytest.mark.parametrize("threads", [1, 2])
def test_ctrl_c_stops_evaluate_and_the_job_resumes(tmp_path, threads):
    import signal

    class InterruptsItself:
        """A zero policy that sends this process SIGINT (what Ctrl-C does) once, at the 100th call of
        one of its copies (the flag is the class's, so the workers' copies share it)."""
        sent = False

        def __init__(self):
            self.calls = 0

        def __call__(self, obs):
            self.calls += 1
            if self.calls == 100 and not InterruptsItself.sent:
                InterruptsItself.sent = True
                os.kill(os.getpid(), signal.SIGINT)
            return np.zeros(7)

    with pytest.raises(KeyboardInterrupt):
        actionshift.evaluate(InterruptsItself(), seed=4, episodes=300, out=str(tmp_path / "x"), threads=threads,
                             backbone="python:zero", policy_version="zero-1")
    jsonl = next((tmp_path / "x").glob("*.jsonl"))
    kept = jsonl.read_bytes().count(b"\n")
    assert kept < 300  # 300 episodes of 50 steps take seconds; the runner polls for Ctrl-C every 100 ms
    summary = json.loads(next((tmp_path / "x").glob("*.summary.json")).read_text())
    assert summary["message"] == f"interrupted after {kept} of 300 episodes; re-run to resume"
    # the next call resumes where it stopped: another callable, declared to be the same policy (a
    # declared version names a policy instead of its code, so the job is the interrupted one)
    r = actionshift.evaluate(lambda obs: np.zeros(7), seed=4, episodes=300, out=str(tmp_path / "x"),
                             threads=threads, backbone="python:zero", policy_version="zero-1")
    assert r["episodes_before"] == kept and r["episodes_run"] == 300 - kept


def test_robot_noise_and_calibration_make_the_clis_job(tmp_path, cli, source_dir):
    # evaluate(robot=, obs_noise=, calibration=) is `run --robot --obs-noise --calibration`: the same job
    # id and the same records, and each option changes the job it names
    urdf = os.path.join(source_dir, "configs", "robots", "panda.urdf")
    cal = json.loads(open(os.path.join(source_dir, "configs", "calibration", "maniskill", "pick_cube.json")).read())
    cal["sigma"] = [s * 1.5 for s in cal["sigma"]]  # a calibration that is not the built-in one
    cal_file = tmp_path / "cal.json"
    cal_file.write_text(json.dumps(cal))
    common = dict(task="pick_cube", split="seen", method="entropy_probes", pool="reference9", seed=7, episodes=2)
    plain = actionshift.evaluate("expert", out=str(tmp_path / "plain"), **common)
    r = actionshift.evaluate("expert", out=str(tmp_path / "py"), robot=urdf, obs_noise=0.002, calibration=cal_file,
                             **common)
    job = r["job"]
    assert job["robot"]["sha256"] == actionshift.make("pick_cube", robot=urdf).robot_sha256
    assert job["obs_noise"] == 0.002 and job["calibration_sha256"] != plain["job"]["calibration_sha256"]
    assert r["job_id"] != plain["job_id"]
    out = cli("run", "--task", "pick_cube", "--split", "seen", "--method", "entropy_probes", "--pool", "reference9",
              "--seed", "7", "--episodes", "2", "--backbone", "expert", "--robot", urdf, "--obs-noise", "0.002",
              "--calibration", str(cal_file), "--out", str(tmp_path / "cli"), "--progress", "off", check=0).stdout
    assert out.startswith(r["job_id"] + " ")
    assert (tmp_path / "py" / f"{r['job_id']}.jsonl").read_bytes() == \
        (tmp_path / "cli" / f"{r['job_id']}.jsonl").read_bytes()
    # a calibration given as a dict is the same job as its file
    d = actionshift.evaluate("expert", out=str(tmp_path / "dict"), robot=urdf, obs_noise=0.002, calibration=cal, **common)
    assert d["job_id"] == r["job_id"]
    # bad values: one-line errors naming the argument
    for kwargs, match in ((dict(obs_noise=float("nan")), "obs_noise: must be a finite sigma"),
                          (dict(obs_noise=0.5), "obs_noise: must be a finite sigma"),
                          (dict(packages={"x": str(tmp_path)}), "packages: need robot="),
                          (dict(robot=str(tmp_path / "none.urdf")), "none.urdf")):
        with pytest.raises(ValueError, match=match) as e:
            actionshift.evaluate("expert", out=str(tmp_path / "bad"), **common, **kwargs)
        assert "\n" not in str(e.value)
    with pytest.raises(ValueError, match="calibration: method no_adapt uses no response calibration"):
        actionshift.evaluate("expert", out=str(tmp_path / "bad"), episodes=1, calibration=cal_file)
    with pytest.raises(TypeError, match="obs_noise: expected a number"):
        actionshift.evaluate("expert", out=str(tmp_path / "bad"), episodes=1, obs_noise="0.1")
    assert not (tmp_path / "bad").exists() or not any((tmp_path / "bad").iterdir())


def test_horizon_makes_the_clis_job(tmp_path, cli):
    # evaluate(horizon=) is `run --horizon`: the same job id and records; 0 is the task's horizon (the job
    # of no option), another horizon is another job whose episodes run exactly that many steps
    common = dict(task="push_cube", split="seen", method="oracle", seed=7, episodes=2)
    plain = actionshift.evaluate("expert", out=str(tmp_path / "plain"), **common)
    zero = actionshift.evaluate("expert", out=str(tmp_path / "zero"), horizon=0, **common)
    assert zero["job_id"] == plain["job_id"] and "horizon" not in plain["job"]
    r = actionshift.evaluate("expert", out=str(tmp_path / "py"), horizon=9, **common)
    assert r["job"]["horizon"] == 9 and r["job_id"] != plain["job_id"]
    steps = [json.loads(line)["steps"] for line in open(r["jsonl_path"])]
    assert steps == [9, 9]
    out = cli("run", "--task", "push_cube", "--split", "seen", "--method", "oracle", "--seed", "7", "--episodes", "2",
              "--backbone", "expert", "--horizon", "9", "--out", str(tmp_path / "cli"), "--progress", "off", check=0).stdout
    assert out.startswith(r["job_id"] + " ")
    assert (tmp_path / "py" / f"{r['job_id']}.jsonl").read_bytes() == (tmp_path / "cli" / f"{r['job_id']}.jsonl").read_bytes()
    for bad, exc in ((-1, ValueError), (10001, ValueError), (2.5, TypeError), (True, TypeError)):
        with pytest.raises(exc, match="horizon") as e:
            actionshift.evaluate("expert", out=str(tmp_path / "bad"), horizon=bad, **common)
        assert "\n" not in str(e.value)
