"""User methods from Python (docs/methods.md): a method object run by the library's runner, the same
decisions as the same rule written as a C++ plug-in, privilege by rung, identity by content."""
import json
import os
import subprocess
import sys
import threading

import numpy as np
import pytest

import actionshift

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
sys.path.insert(0, os.path.join(HERE, "..", "..", "docs", "examples"))
import simple_policy  # noqa: E402
from separation_probes import SeparationProbes  # noqa: E402

OUTCOME = ("seed", "contract_index", "episode_index", "contract_sha256", "success_once", "success_at_end",
           "return", "steps", "probe_steps", "probe_displacement", "safety_flags", "method_variant")


def records(path):
    with open(path) as f:
        return [json.loads(line) for line in f]


def test_a_python_method_makes_the_decisions_of_the_same_cpp_plugin(tmp_path):
    exe = os.environ.get("ACTIONSHIFT_SEPARATION_EXAMPLE")
    assert exe and os.path.exists(exe), "ACTIONSHIFT_SEPARATION_EXAMPLE is not set (run through ctest)"
    cpp = subprocess.run([exe, str(tmp_path / "cpp"), "9", "expert"], capture_output=True, text=True, timeout=600)
    assert cpp.returncode == 0, cpp.stderr
    cpp_id, cpp_jsonl = cpp.stdout.split()
    py = actionshift.evaluate("expert", split="reference_seen", pool="reference9", method=SeparationProbes(),
                              episodes=9, seed=20260718, out=str(tmp_path / "py"))
    a, b = records(cpp_jsonl), records(py["jsonl_path"])
    assert len(a) == len(b) == 9
    for x, y in zip(a, b):
        assert {k: x[k] for k in OUTCOME} == {k: y[k] for k in OUTCOME}
    assert sum(r["probe_steps"] for r in b) == 9 * 6 and sum(r["success_once"] for r in b) >= 6
    # the same job inputs; the identities differ only in what the method is (C++ files vs Python code)
    cpp_job = json.loads((tmp_path / "cpp" / f"{cpp_id}.summary.json").read_text())["job"]
    py_job = py["job"]
    assert cpp_job["method"]["plugin"]["kind"] == "cpp" and py_job["method"]["plugin"]["kind"] == "python"
    for job in (cpp_job, py_job):
        job["method"].pop("plugin")
    cpp_job.pop("schema_version"), py_job.pop("schema_version")
    assert cpp_job == py_job
    assert py["job_id"] != cpp_id


class Spy:
    """Records what setup() is handed; acts as no_adapt."""
    version = "1"

    def __init__(self, rung):
        self.rung = rung
        self.name = f"spy_{rung}"
        self.params = {}

    def setup(self, inputs):
        Spy.seen.append(inputs)

    def begin_episode(self, seed):
        pass

    def encode(self, canonical, R):
        return canonical

    def observe(self, raw, response, R):
        pass


@pytest.mark.parametrize("rung", ["pool", "grammar", "none"])
def test_each_rung_receives_exactly_its_inputs(tmp_path, rung):
    Spy.seen = []
    actionshift.evaluate("expert", split="reference_seen", pool="reference9" if rung == "pool" else None,
                         method=Spy(rung), episodes=2, out=str(tmp_path))
    assert len(Spy.seen) == 2  # before each episode
    for inputs in Spy.seen:
        assert set(inputs) == {"task", "rung", "params", "pool", "calibration", "grammar"}
        assert inputs["rung"] == rung
        assert (inputs["pool"] is not None) == (rung == "pool")
        assert (inputs["calibration"] is not None) == (rung != "none")
        assert (inputs["grammar"] is not None) == (rung != "none")
        if rung == "pool":
            assert len(inputs["pool"]) == 9 and all(isinstance(c, actionshift.Contract) for c in inputs["pool"])
    with pytest.raises(ValueError, match="oracle rung is reserved"):
        actionshift.evaluate("expert", method=Spy("oracle"), episodes=1, out=str(tmp_path))
    if rung == "pool":  # the pool rung's job needs a pool
        with pytest.raises(ValueError, match="needs a pool"):
            actionshift.evaluate("expert", method=Spy("pool"), episodes=1, out=str(tmp_path / "nopool"))


def test_two_lambdas_never_share_a_job(tmp_path):
    good = simple_policy.ReachGraspLift()
    a = actionshift.evaluate(lambda o: good(o), seed=5, episodes=2, out=str(tmp_path))
    b = actionshift.evaluate(lambda o: np.zeros(7), seed=5, episodes=2, out=str(tmp_path / "b"))
    assert a["job_id"] != b["job_id"]
    assert a["job"]["backbone"]["name"] == b["job"]["backbone"]["name"]  # the same name, another content
    again = actionshift.evaluate(lambda o: np.zeros(7), seed=5, episodes=2, out=str(tmp_path / "b"))
    assert again["job_id"] == b["job_id"] and again["already_complete"]  # the same content is the same job
    # into one directory: the zero policy runs its own job (no 'already complete' from the good one)
    c = actionshift.evaluate(lambda o: np.zeros(7), seed=5, episodes=2, out=str(tmp_path))
    assert not c["already_complete"] and c["episodes_run"] == 2


def test_changing_a_methods_code_or_params_changes_its_job(tmp_path):
    def make(body):
        ns = {}
        exec(f"class M:\n    name, version, rung = 'edited', '1', 'none'\n    params = {{}}\n"
             f"    def begin_episode(self, seed): pass\n    def encode(self, c, R): {body}\n"
             f"    def observe(self, raw, response, R): pass\n", ns)
        return ns["M"]()
    one = actionshift.evaluate("expert", method=make("return c"), episodes=1, out=str(tmp_path))
    two = actionshift.evaluate("expert", method=make("return c * 1.0"), episodes=1, out=str(tmp_path / "2"))
    assert one["job_id"] != two["job_id"]
    p1 = actionshift.evaluate("expert", split="reference_seen", pool="reference9", method=SeparationProbes(budget=2),
                              episodes=1, out=str(tmp_path / "p"))
    p2 = actionshift.evaluate("expert", split="reference_seen", pool="reference9", method=SeparationProbes(budget=3),
                              episodes=1, out=str(tmp_path / "p"))
    assert p1["job_id"] != p2["job_id"]
    assert p1["job"]["method"]["params"] == {"amplitude": 0.5, "budget": 2}


def test_a_policy_without_stable_content_is_refused_with_what_to_pass(tmp_path):
    lock = threading.Lock()

    def locked(obs):
        with lock:
            return np.zeros(7)

    with pytest.raises(ValueError, match="policy_version="):
        actionshift.evaluate(locked, episodes=1, out=str(tmp_path))
    r = actionshift.evaluate(locked, episodes=1, out=str(tmp_path), policy_version="locked-zero-1")
    assert r["episodes_run"] == 1


def test_method_errors_are_one_line(tmp_path):
    class NoEncode:
        rung = "none"

        def begin_episode(self, seed):
            pass

    with pytest.raises(TypeError, match="needs encode"):
        actionshift.evaluate("expert", method=NoEncode(), episodes=1, out=str(tmp_path))

    class BadName(Spy):
        pass

    bad = BadName("none")
    bad.name = "Bad Name"
    with pytest.raises(ValueError, match="method.name"):
        actionshift.evaluate("expert", method=bad, episodes=1, out=str(tmp_path))
    builtin = Spy("none")
    builtin.name = "entropy_probes"
    with pytest.raises(ValueError, match="built-in method"):
        actionshift.evaluate("expert", method=builtin, episodes=1, out=str(tmp_path))

    class NaN(Spy):
        def encode(self, canonical, R):
            return np.full(7, np.nan)

    with pytest.raises(ValueError, match="NaN"):
        actionshift.evaluate("expert", method=NaN("none"), episodes=1, out=str(tmp_path / "nan"))


class Snoop:
    """A hostile method (pool rung, the most privileged a user method can declare): keeps everything the
    runner hands it, its process's environment and arguments, and any attribute the runner sets on it."""
    name, version, rung, params = "snoop", "1", "pool", {}

    def __init__(self):
        self.log = []

    def setup(self, inputs):
        self.log.append(("setup", repr(inputs)))

    def begin_episode(self, seed):
        self.log.append(("begin_episode", seed, json.dumps(dict(os.environ)), json.dumps(sys.argv),
                         sorted(k for k in vars(self) if k != "log")))

    def encode(self, canonical, R):
        self.log.append(("encode", repr(np.asarray(canonical)), repr(np.asarray(R))))
        return canonical

    def observe(self, raw, response, R):
        self.log.append(("observe", repr(np.asarray(raw)), repr(response)))


def test_a_hostile_python_method_learns_neither_contract_nor_seed(tmp_path):
    snoop = Snoop()
    secret_seed = 987654321987
    r = actionshift.evaluate("expert", split="reference_seen", pool="reference9", method=snoop, episodes=9,
                             seed=secret_seed, out=str(tmp_path))
    recs = records(r["jsonl_path"])
    text = json.dumps(snoop.log, default=str)
    split = json.load(open(os.path.join(HERE, "..", "..", "manifests", "reference_seen.json")))
    secrets = {str(secret_seed)} | {rec["contract_sha256"] for rec in recs}
    secrets |= {json.dumps(c, sort_keys=True, separators=(",", ":")) for c in split["test"]}
    assert len({rec["contract_sha256"] for rec in recs}) >= 2
    assert not [s for s in secrets if s in text]
    begins = [e for e in snoop.log if e[0] == "begin_episode"]
    assert len(begins) == 9
    assert all(e[4] == [] for e in begins)  # the runner sets no attribute on the method
    # its seed is the block's, the same whichever contract is hidden: the 9 contracts of one block
    by_block = {}
    for e, rec in zip(begins, sorted(recs, key=lambda x: x["episode_index"])):
        by_block.setdefault(rec["episode_index"] // len(split["test"]), set()).add(e[1])
    assert all(len(seeds) == 1 for seeds in by_block.values()), by_block
