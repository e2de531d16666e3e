#!/usr/bin/env python3
"""Unit check of the brittleness page's sentence on its own Diffusion Policy jobs (scripts/brittleness_report.py,
own_runs_text): the benchmark's one-thread CPU time is compared with the jobs' wall time like with like, spread
over the job's threads when there are several (the golden fixture runs one thread, so only this test reaches that
branch), never as if one thread's CPU time were the wall time of two.
usage: tests/pages/brittleness_cost_text_test.py"""
import os
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
sys.path.insert(0, os.path.join(ROOT, "scripts"))
from brittleness_report import own_runs_text  # noqa: E402


def main():
    bad = []
    # 7,040 s of wall time on 2 threads for 232,207 steps; the benchmark 49.36 ms per step on one thread:
    # 11,462 s = 3.18 h of CPU, 95.5 min of wall on 2 threads
    two = own_runs_text("pick_cube", "2", 7040.0, 232207.0, 49.36, 54.0, 201559.0)
    for phrase in ("took 117.3 min of wall time for 232,207 control steps (30.32 ms per step)",
                   "the policy alone is 3.18 h of CPU time, 95.5 min of wall time if the job's 2 threads never wait",
                   "against the 117.3 min measured",
                   "the other backbones' jobs took 54 s for 201,559 steps (0.268 ms per step"):
        if phrase not in two:
            bad.append(f"2 threads: {phrase!r} not in {two!r}")
    one = own_runs_text("pick_cube", "1", 80.0, 4075.0, 13.14, 0.0, 0.0)
    if "never wait" in one or "other backbones" in one or "54 s of CPU time, against the 80 s measured." not in one:
        bad.append(f"1 thread, no other jobs: {one!r}")
    unknown = own_runs_text("pick_cube", "?", 80.0, 4075.0, 13.14, 0.0, 0.0)
    if "never wait" in unknown or "(? thread(s) per job" not in unknown:
        bad.append(f"unknown thread count: {unknown!r}")
    for b in bad:
        print("brittleness_cost_text_test:", b)
    print("brittleness_cost_text_test:", "FAILED" if bad else "ok (3 cases)")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
