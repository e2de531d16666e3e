#!/usr/bin/env python3
"""Benchmarks of the Python module (docs/results/benchmarks.md, "Python"):

1. per control step: stepping an actionshift.Env from a Python loop vs the same loop in C++
   (actionshift._native._bench_cpp_steps: same task, same action rows, same reset seeds);
2. one job: actionshift.evaluate() of a trivial policy in process vs `actionshift run` with the same
   policy as an external JSON-lines process (a standard-library-only server, the fastest form);
3. where the job's time goes, on one thread: the same two jobs with 1 episode, which splits each
   side's time into a fixed part (start-up: the CLI and the server's interpreter for the external
   process) and a part per control step; the ratio of the per-step parts is the speed-up a long job
   tends to;
4. one policy call, the only thing the two jobs do differently per step: the trivial policy called in
   process as evaluate() calls it vs one JSON-lines round trip to the same server, back to back
   (actionshift._native._bench_policy_calls).

Medians over --runs runs. Usage (from the repository root, after the build):
    PYTHONPATH=build/python python3 tests/bench/python_bench.py --cli build/apps/actionshift/actionshift
"""
import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time

import numpy as np

import actionshift
from actionshift import _native

TRIVIAL_SERVER = r'''
import sys
for line in sys.stdin:
    if '"type":"hello"' in line:
        sys.stdout.write('{"type":"ready"}\n'); sys.stdout.flush()
    elif '"type":"step"' in line:
        sys.stdout.write('{"action":[0.0,0.0,0.0,0.0,0.0,0.0,0.0]}\n'); sys.stdout.flush()
'''


def zero_policy(obs):
    return np.zeros(7)


def bench_steps(task, steps, runs):
    rng = np.random.default_rng(1)
    actions = rng.uniform(-1.0, 1.0, size=(steps, 7))
    env = actionshift.make(task)
    cpp, py = [], []
    for _ in range(runs):
        cpp.append(_native._bench_cpp_steps(task, actions, 100) / steps)
        seed = 100
        t0 = time.perf_counter()
        env.reset(seed=seed)
        for a in actions:
            obs, reward, terminated, truncated, info = env.step(a)
            if truncated or info["safety"] != "none":
                seed += 1
                env.reset(seed=seed)
        py.append((time.perf_counter() - t0) / steps)
    return statistics.median(cpp), statistics.median(py), cpp, py


def bench_evaluate(cli, episodes, runs, threads):
    """Median seconds of one job, in process and through the external process, at each thread count
    (in process: evaluate(threads=T); external: `actionshift run --threads T`, one process per worker)."""
    inproc = {t: [] for t in threads}
    external = {t: [] for t in threads}
    with tempfile.TemporaryDirectory() as tmp:
        server = os.path.join(tmp, "zero_server.py")
        with open(server, "w") as f:
            f.write(TRIVIAL_SERVER)
        backbone = f"external:{sys.executable} {server}"
        for k in range(runs):
            for t in threads:
                out = os.path.join(tmp, f"inproc{k}_{t}")
                t0 = time.perf_counter()
                r = actionshift.evaluate(zero_policy, task="pick_cube", split="seen", method="no_adapt", seed=k,
                                         episodes=episodes, out=out, backbone=backbone, threads=t)
                inproc[t].append(time.perf_counter() - t0)
                out2 = os.path.join(tmp, f"external{k}_{t}")
                t0 = time.perf_counter()
                subprocess.run([cli, "run", "--task", "pick_cube", "--split", "seen", "--method", "no_adapt",
                                "--seed", str(k), "--episodes", str(episodes), "--backbone", backbone, "--out", out2,
                                "--progress", "off", "--threads", str(t)], check=True, capture_output=True)
                external[t].append(time.perf_counter() - t0)
                a = open(os.path.join(out, r["job_id"] + ".jsonl"), "rb").read()
                b = open(os.path.join(out2, r["job_id"] + ".jsonl"), "rb").read()
                assert a == b, "in-process and external JSONL differ"
                steps = sum(json.loads(line)["steps"] for line in a.decode().splitlines())
    return inproc, external, steps


def bench_policy_calls(task, calls, runs):
    """Median seconds per call of the trivial policy: in process, and as an external JSON-lines round trip."""
    inproc, external = [], []
    with tempfile.TemporaryDirectory() as tmp:
        server = os.path.join(tmp, "zero_server.py")
        with open(server, "w") as f:
            f.write(TRIVIAL_SERVER)
        for _ in range(runs):
            r = _native._bench_policy_calls(zero_policy, f"{sys.executable} {server}", task, calls)
            inproc.append(r["in_process_s"] / calls)
            external.append(r["external_s"] / calls)
    return statistics.median(inproc), statistics.median(external), inproc, external


def split_costs(short_s, short_steps, long_s, long_steps):
    """(fixed [s], per control step [s]) of a job from two sizes of it."""
    per_step = (long_s - short_s) / (long_steps - short_steps)
    return short_s - short_steps * per_step, per_step


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--cli", required=True, help="the actionshift binary")
    ap.add_argument("--task", default="pick_cube")
    ap.add_argument("--steps", type=int, default=2000, help="control steps per step-cost run")
    ap.add_argument("--episodes", type=int, default=32, help="episodes per evaluation run")
    ap.add_argument("--calls", type=int, default=2000, help="policy calls per policy-call run")
    ap.add_argument("--runs", type=int, default=5, help="runs per figure (medians)")
    ap.add_argument("--threads", default="1,2",
                    help="comma-separated thread counts of both sides (evaluate(threads=T), run --threads T)")
    ap.add_argument("--json", action="store_true", help="print one JSON object")
    a = ap.parse_args()
    if a.episodes < 2 or min(a.steps, a.runs, a.calls) < 1:
        ap.error("--episodes must be at least 2 (the 1-episode job is the reference), --steps, --runs and --calls positive")
    cpp, py, cpp_runs, py_runs = bench_steps(a.task, a.steps, a.runs)
    threads = [int(t) for t in a.threads.split(",")]
    if 1 not in threads:
        threads.insert(0, 1)  # the 1-thread jobs are the reference of the cost split
    inproc, external, job_steps = bench_evaluate(a.cli, a.episodes, a.runs, threads)
    inproc1, external1, steps1 = bench_evaluate(a.cli, 1, a.runs, [1])
    call_in, call_ext, call_in_runs, call_ext_runs = bench_policy_calls(a.task, a.calls, a.runs)
    med = statistics.median
    result = {
        "task": a.task, "steps": a.steps, "runs": a.runs,
        "cpp_us_per_step": cpp * 1e6, "python_us_per_step": py * 1e6, "python_overhead_pct": (py / cpp - 1) * 100,
        "cpp_runs_us": [x * 1e6 for x in cpp_runs], "python_runs_us": [x * 1e6 for x in py_runs],
        "episodes": a.episodes, "job_control_steps": job_steps,
        "evaluate": [{"threads": t, "in_process_s": med(inproc[t]), "external_s": med(external[t]),
                      "speedup": med(external[t]) / med(inproc[t]),
                      "in_process_runs_s": inproc[t], "external_runs_s": external[t]} for t in threads],
        "costs_1_thread": {},
        "policy_call": {"calls": a.calls, "in_process_us": call_in * 1e6, "external_us": call_ext * 1e6,
                        "ratio": call_ext / call_in,
                        "in_process_runs_us": [x * 1e6 for x in call_in_runs],
                        "external_runs_us": [x * 1e6 for x in call_ext_runs]},
    }
    for side, short, long in (("in_process", inproc1, inproc), ("external", external1, external)):
        fixed, per_step = split_costs(med(short[1]), steps1, med(long[1]), job_steps)
        result["costs_1_thread"][side] = {"fixed_s": fixed, "per_step_us": per_step * 1e6, "one_episode_runs_s": short[1]}
    if a.json:
        print(json.dumps(result, indent=2))
        return
    print(f"per control step ({a.task}, {a.steps} steps, median of {a.runs}): C++ {cpp * 1e6:.1f} us, "
          f"Python {py * 1e6:.1f} us, overhead {result['python_overhead_pct']:+.1f} %")
    pc = result["policy_call"]
    print(f"policy call (trivial policy, {a.calls} calls, median of {a.runs}): in process {pc['in_process_us']:.1f} us, "
          f"external JSON-lines round trip {pc['external_us']:.1f} us ({pc['ratio']:.0f}x)")
    for e in result["evaluate"]:
        print(f"evaluate ({a.episodes} episodes = {job_steps} control steps of a trivial policy, {e['threads']} thread(s), "
              f"median of {a.runs}): in process {e['in_process_s']:.3f} s, external process {e['external_s']:.3f} s, "
              f"speed-up {e['speedup']:.1f}x")
    c = result["costs_1_thread"]
    print(f"1 thread, from the same jobs with 1 episode: in process {c['in_process']['fixed_s']:.3f} s + "
          f"{c['in_process']['per_step_us']:.0f} us per control step, external process {c['external']['fixed_s']:.3f} s + "
          f"{c['external']['per_step_us']:.0f} us per control step (a long job tends to "
          f"{c['external']['per_step_us'] / c['in_process']['per_step_us']:.1f}x)")
    t1 = result["evaluate"][0]
    for e in result["evaluate"][1:]:
        print(f"in process on {e['threads']} threads vs external process on {t1['threads']}: "
              f"{t1['external_s'] / e['in_process_s']:.1f}x")

if __name__ == "__main__":
    main()
