#!/usr/bin/env python3
"""Start-up cost of the actionshift command line (docs/results/benchmarks.md, "Command-line start-up").

Every CLI call pays the dynamic loader and the libraries' initialisers before it does anything: a
Slurm array of one-job calls, a script hashing contracts one by one and the external-policy job all
pay it once per call. Times, over --runs runs (median, and the spread), the wall time of

1. `actionshift --version` (start-up alone),
2. `actionshift contract hash FILE` (start-up plus a small real command),

and prints the libraries the binary loads (ldd), so a start-up regression can be traced to a new link.

Usage (from the repository root, after the build):
    python3 tests/bench/cli_startup.py --cli build/apps/actionshift/actionshift [--runs 30] [--json]
"""
import argparse
import json
import os
import statistics
import subprocess
import tempfile
import time


def wall_times(cmd, runs):
    times = []
    for _ in range(runs):
        t0 = time.perf_counter()
        subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        times.append(time.perf_counter() - t0)
    return times


def loaded_libraries(cli):
    try:
        out = subprocess.run(["ldd", cli], check=True, capture_output=True, text=True).stdout
    except (OSError, subprocess.CalledProcessError):
        return []
    return sorted(line.split()[0] for line in out.splitlines() if line.strip())


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--cli", required=True, help="the actionshift binary")
    ap.add_argument("--runs", type=int, default=30, help="calls per figure (median)")
    ap.add_argument("--json", action="store_true", help="print one JSON object")
    a = ap.parse_args()
    if a.runs < 1:
        ap.error("--runs must be positive")
    with tempfile.TemporaryDirectory() as tmp:
        contract = os.path.join(tmp, "identity.json")
        with open(contract, "w") as f:
            f.write('{"frame":"base","gripper_inverted":false,"lag":0,"permutation":[0,1,2,3,4,5],'
                    '"scale":[1.0,1.0,1.0,1.0,1.0,1.0],"sign":[1,1,1,1,1,1],"target":"delta"}\n')
        figures = {
            "version": wall_times([a.cli, "--version"], a.runs),
            "contract_hash": wall_times([a.cli, "contract", "hash", contract], a.runs),
        }
    libs = loaded_libraries(a.cli)
    result = {"runs": a.runs, "libraries": len(libs), "library_names": libs}
    for name, t in figures.items():
        result[name] = {"median_ms": statistics.median(t) * 1e3, "min_ms": min(t) * 1e3, "max_ms": max(t) * 1e3,
                        "runs_ms": [x * 1e3 for x in t]}
    if a.json:
        print(json.dumps(result, indent=2))
        return
    for name, label in (("version", "actionshift --version"), ("contract_hash", "actionshift contract hash FILE")):
        r = result[name]
        print(f"{label}: median {r['median_ms']:.1f} ms (min {r['min_ms']:.1f}, max {r['max_ms']:.1f}; {a.runs} runs)")
    print(f"{len(libs)} shared libraries loaded at start-up")


if __name__ == "__main__":
    main()
