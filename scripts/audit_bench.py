#!/usr/bin/env python3
"""Runs the audit benchmark's audits (scripts/audit_benchmark drives it): every log of a set's cases
file at every length (prefixes, `audit --max-steps`) against two declarations, the recorded truth and
identity, with one audit configuration, in parallel; one JSON per audit with a `bench` block (the case,
length, declaration, configuration) for scripts/audit_report.py. Resumable: an audit whose JSON exists
is skipped.

usage: scripts/audit_bench.py --cases FILE --logs DIR --out DIR --binary PATH
                              [--config KEY=VALUE ...] [--jobs N] [--lengths 50,200,1000,5000]

--config passes audit options by their flag names without dashes (confidence-floor=0.999,
min-explained=0.2, gain-tolerance=2.5); none: the binary's defaults (how the previous model is run).
A log audited without --task (its case says calibrated: false) is the calibration-free use."""
import argparse
import concurrent.futures
import json
import os
import subprocess
import sys

LENGTHS = [50, 200, 1000, 5000]
DECLARATIONS = ("truth", "identity")


def audits_of(cases, lengths):
    for case in cases:
        for length in lengths:
            if length > case.get("length", max(lengths)):
                continue
            for decl in DECLARATIONS:
                yield case, length, decl


def run_one(binary, logs, out_dir, config, case, length, decl):
    name = f"{case['case']}_L{length}_{decl}.json"
    out = os.path.join(out_dir, name)
    if os.path.exists(out):
        return "skipped"
    log = os.path.join(logs, os.path.basename(case["path"]))
    truth = os.path.join(logs, os.path.basename(case["truth_path"]))
    cmd = [binary, "audit", log, "--declared", truth if decl == "truth" else "identity", "--max-steps", str(length), "--json"]
    if case.get("calibrated", True):
        cmd += ["--task", case["task"]]
    for k, v in sorted(config.items()):
        cmd += [f"--{k}", str(v)]
    p = subprocess.run(cmd, capture_output=True, text=True)
    if p.returncode not in (0, 1, 3):
        raise RuntimeError(f"{' '.join(cmd)}: exit {p.returncode}: {p.stderr.strip()}")
    a = json.loads(p.stdout)
    with open(truth) as f:
        a["bench"] = {"case": case, "length": length, "declared_as": decl, "config": config, "truth": json.load(f),
                      "command": " ".join(cmd[1:])}
    tmp = out + ".tmp"
    with open(tmp, "w") as f:
        json.dump(a, f)
    os.replace(tmp, out)
    return "done"


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--cases", required=True)
    ap.add_argument("--logs", required=True)
    ap.add_argument("--out", required=True)
    ap.add_argument("--binary", required=True)
    ap.add_argument("--config", nargs="*", default=[])
    ap.add_argument("--jobs", type=int, default=os.cpu_count() or 1)
    ap.add_argument("--lengths", default=",".join(map(str, LENGTHS)))
    args = ap.parse_args()
    config = {}
    for kv in args.config:
        k, _, v = kv.partition("=")
        if not k or not v:
            sys.exit(f"audit_bench.py: --config {kv!r}: expected KEY=VALUE")
        config[k] = v
    with open(args.cases) as f:
        cases = [json.loads(line) for line in f if line.strip()]
    lengths = [int(x) for x in args.lengths.split(",")]
    os.makedirs(args.out, exist_ok=True)
    with open(os.path.join(args.out, "config.json"), "w") as f:
        json.dump({"config": config, "binary": args.binary}, f)
    work = list(audits_of(cases, lengths))
    done = 0
    with concurrent.futures.ThreadPoolExecutor(max_workers=max(args.jobs, 1)) as pool:
        futures = [pool.submit(run_one, args.binary, args.logs, args.out, config, *w) for w in work]
        for fut in concurrent.futures.as_completed(futures):
            fut.result()
            done += 1
            if done % 500 == 0 or done == len(work):
                print(f"  {args.out}: {done}/{len(work)} audits", flush=True)


if __name__ == "__main__":
    main()
