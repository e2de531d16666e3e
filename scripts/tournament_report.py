#!/usr/bin/env python3
"""Writes the tournament results page (docs/results/tournament.md) from a results directory:
`actionshift summarize DIR --json` for the table and the promotion verdict files written by
`actionshift gate promote` (scripts/tournament). Standard library only.
usage: scripts/tournament_report.py RESULTS_DIR ACTIONSHIFT_BINARY WALL_SECONDS > docs/results/tournament.md"""
import glob
import json
import subprocess
import sys

results, binary, wall = sys.argv[1], sys.argv[2], sys.argv[3]
summary = json.loads(subprocess.run([binary, "summarize", results, "--json"], check=True, capture_output=True, text=True).stdout)
cells = summary["cells"]
methods = ["oracle", "entropy_probes", "dualabi", "fixed_probes", "random_probes", "exact_belief", "no_adapt"]
tasks = ["pick_cube", "push_cube", "pull_cube", "stack_cube"]
splits = ["reference_seen", "reference_unseen_composition", "reference_long_lag", "seen", "unseen_composition", "long_lag"]
pool = {s: ("reference9" if s.startswith("reference") else "full") for s in splits}
by = {(c["task"], c["split"], c["method"]): c for c in cells}
total = sum(c["episodes"] for c in cells)

print("# Tournament: the pool-belief ladder on the cube tasks\n")
print("Every method of the ladder (docs/adapters.md) with the expert backbone, three seeds (20260718-20),")
print("200 episodes per (task, split, method, seed) job: the reference's frozen splits (two contracts")
print("each, 100 episodes per contract per seed, as the paper) with its nine-contract pool `reference9`,")
print("and the generated splits (32 contracts each) with the 180-contract `full` pool. Live tool-frame")
print("rotation. Success is success_once with its Wilson 95 % interval over the three seeds; probe =")
print("mean probe steps per episode; disp. = mean TCP translation during probes [m].\n")
print(f"- Experiment: `configs/experiments/tournament.yaml` ({len(set(j for c in cells for j in c['jobs']))} jobs, "
      f"{total:,} episodes). Command: `scripts/tournament results/tournament` (plan, run, summarize, promotion "
      f"gates). Wall time: {int(float(wall))} s on the 2-core machine.")
print("- DualABI's threshold τ = 2.5 was frozen before this run from a seed-20260718 pilot "
      "(docs/results/dualabi_pilot.md).\n")
for split in splits:
    print(f"## {split} (pool `{pool[split]}`)\n")
    print("| task | method | success | Wilson 95 % | per seed | probe | disp. [m] | safety flags |")
    print("|---|---|---:|---|---|---:|---:|---|")
    for task in tasks:
        for m in methods:
            c = by.get((task, split, m))
            if not c:
                continue
            w = c["success_once"]
            seeds = "/".join("%.3f" % s["rate"] for s in c["per_seed"])
            flags = ", ".join("%s %d" % kv for kv in sorted(c["safety_flags"].items())) or "-"
            print(f"| {task} | {m} | {w['rate']:.3f} | [{w['lower']:.3f}, {w['upper']:.3f}] | {seeds} | "
                  f"{c['mean_probe_steps']:.2f} | {c['mean_probe_displacement']:.4f} | {flags} |")
    print()

print("## Promotion verdicts (computed by `actionshift gate promote`)\n")
print("Rules (docs/reference.md, *Gates*; `include/actionshift/eval/gates.hpp`): a one-seed result under 0.3 is pruned; a")
print("safety regression rejects; fewer than three matched seeds asks for more seeds; otherwise the")
print("candidate is promoted on >= 5 points over its matched baseline with the paired 95 % bootstrap")
print("interval above 0, or on a success-vs-probe-cost Pareto point (fewer mean probe steps with a paired")
print("success estimate >= 0); else rejected. Every verdict is listed, cleared and failed.\n")
for path in sorted(glob.glob(results + "/promotion.*.json")):
    v = json.load(open(path))
    print(f"### {v['candidate']} vs {v['baseline']}\n")
    print("| cell | candidate | baseline | difference [95 % CI] | probe steps (cand / base) | verdict |")
    print("|---|---:|---:|---|---|---|")
    counts = {}
    for key in sorted(v["cells"]):
        c = v["cells"][key]
        d = c["difference"]
        counts[c["verdict"]] = counts.get(c["verdict"], 0) + 1
        print(f"| {key} | {c['candidate_success']:.3f} | {c['baseline_success']:.3f} | {d['estimate']:+.3f} "
              f"[{d['lower']:+.3f}, {d['upper']:+.3f}] | {c['candidate_probe_steps']:.2f} / {c['baseline_probe_steps']:.2f} | "
              f"**{c['verdict']}** |")
    print("\n" + ", ".join(f"{k}: {n}" for k, n in sorted(counts.items())) + "\n")
