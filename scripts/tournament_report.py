#!/usr/bin/env python3
"""Writes the tournament results page (docs/results/tournament.md) from a results directory:
`actionshift summarize DIR --json` for the cells and the promotion verdict files written by
`actionshift gate promote` (scripts/tournament) for the paired differences. It sets each reference
cell beside the paper's Table 5 (tournament) and Table 3 (DualABI vs entropy) and marks each of the
paper's findings reproduced, contradicted or untestable by a rule stated on the page.
Standard library only.
usage: scripts/tournament_report.py RESULTS_DIR ACTIONSHIFT_BINARY WALL_SECONDS > docs/results/tournament.md"""
import glob
import json
import os
import subprocess
import sys

results, binary, wall = sys.argv[1], sys.argv[2], sys.argv[3]
ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
summary = json.loads(subprocess.run([binary, "summarize", results, "--json"], check=True, capture_output=True, text=True).stdout)
cells = summary["cells"]
by = {(c["task"], c["split"], c["method"]): c for c in cells}
promos = {}
for path in glob.glob(os.path.join(results, "promotion.*.json")):
    v = json.load(open(path))
    promos[(v["candidate"], v["baseline"])] = v
jobs = set()
for c in cells:
    jobs.update(c["jobs"])
specs = [json.load(open(os.path.join(results, j + ".summary.json")))["job"] for j in sorted(jobs)]
profiles = sorted({s.get("profile", "?") for s in specs})
seeds = sorted({s["seed"] for s in specs})
commit = subprocess.run(["git", "-C", ROOT, "rev-parse", "--short", "HEAD"], capture_output=True, text=True).stdout.strip()
total = sum(c["episodes"] for c in cells)

methods = ["oracle", "entropy_probes", "dualabi", "fixed_probes", "random_probes", "exact_belief", "grammar_belief", "no_adapt"]
tasks = ["pick_cube", "push_cube", "pull_cube", "stack_cube"]
ref_splits = ["reference_seen", "reference_unseen_composition", "reference_long_lag"]
gen_splits = ["seen", "unseen_composition", "long_lag"]

# The paper (Table 5 tournament; Table 2 Gate 1 for oracle / no_adapt), frozen PPO on ManiSkill,
# 3 seeds x 200 episodes unless marked: (success, mean probe steps)
P = {}
def put(task, split, vals):
    for m, v in vals.items():
        P[(task, split, m)] = v
put("pick_cube", "reference_seen", {"oracle": (1.000, 0), "no_adapt": (0.000, 0), "exact_belief": (0.929, 0.0), "entropy_probes": (0.987, 6.0),
    "fixed_probes": (0.928, 6.0), "random_probes": (0.925, 6.0), "dualabi": (0.983, 2.78)})
put("pick_cube", "reference_unseen_composition", {"oracle": (0.995, 0), "no_adapt": (0.000, 0), "exact_belief": (0.958, 0.0), "entropy_probes": (0.975, 6.0),
    "fixed_probes": (0.970, 6.0), "random_probes": (0.980, 6.0), "dualabi": (0.983, 3.14)})
put("pick_cube", "reference_long_lag", {"oracle": (0.027, 0), "no_adapt": (0.005, 0), "exact_belief": (0.022, 0.0), "entropy_probes": (0.025, 6.0),
    "fixed_probes": (0.037, 6.0), "dualabi": (0.020, 1.61)})
put("push_cube", "reference_seen", {"oracle": (1.000, 0), "no_adapt": (0.003, 0), "exact_belief": (0.983, 0.0), "entropy_probes": (1.000, 6.0),
    "fixed_probes": (0.982, 6.0), "random_probes": (0.942, 6.0), "dualabi": (1.000, 2.60)})
put("push_cube", "reference_unseen_composition", {"oracle": (1.000, 0), "no_adapt": (0.000, 0), "exact_belief": (0.995, 0.0), "entropy_probes": (0.987, 6.0),
    "fixed_probes": (0.980, 6.0), "random_probes": (0.995, 6.0), "dualabi": (0.993, 3.03)})
put("push_cube", "reference_long_lag", {"oracle": (0.153, 0), "no_adapt": (0.000, 0), "exact_belief": (0.117, 0.0), "entropy_probes": (0.100, 6.0),
    "fixed_probes": (0.215, 6.0), "dualabi": (0.110, 1.28)})
put("pull_cube", "reference_seen", {"oracle": (1.000, 0), "no_adapt": (0.000, 0), "exact_belief": (0.952, 0.0), "entropy_probes": (0.975, 6.0),
    "fixed_probes": (0.970, 6.0), "random_probes": (0.943, 6.0), "dualabi": (0.968, 2.91)})
put("pull_cube", "reference_unseen_composition", {"oracle": (0.998, 0), "no_adapt": (0.000, 0), "exact_belief": (0.935, 0.0), "entropy_probes": (0.982, 6.0),
    "fixed_probes": (0.927, 6.0), "random_probes": (0.997, 6.0), "dualabi": (0.977, 2.50)})
put("pull_cube", "reference_long_lag", {"oracle": (0.322, 0), "no_adapt": (0.000, 0), "exact_belief": (0.287, 0.0), "entropy_probes": (0.325, 6.0),
    "fixed_probes": (0.260, 6.0)})
put("stack_cube", "reference_seen", {"oracle": (0.965, 0), "no_adapt": (0.000, 0), "exact_belief": (0.945, 0), "entropy_probes": (0.910, 6.0),
    "fixed_probes": (0.945, 6.0), "random_probes": (0.925, 6.0), "dualabi": (0.945, 2.94)})
put("stack_cube", "reference_unseen_composition", {"oracle": (0.960, 0), "no_adapt": (0.000, 0), "exact_belief": (0.960, 0), "entropy_probes": (0.940, 6.0),
    "fixed_probes": (0.915, 6.0), "random_probes": (0.930, 6.0), "dualabi": (0.960, 3.48)})
put("stack_cube", "reference_long_lag", {"oracle": (0.000, 0), "no_adapt": (0.000, 0)})


def f3(x):
    return "—" if x is None else f"{x:.3f}"


def cell_line(task, split, m):
    c = by.get((task, split, m))
    if not c:
        return None
    w = c["success_once"]
    per = "/".join("%.3f" % s["rate"] for s in c["per_seed"])
    p = P.get((task, split, m))
    paper = f"{p[0]:.3f}" if p else "—"
    paper_probe = f"{p[1]:.2f}" if p else "—"
    flags = ", ".join("%s %d" % kv for kv in sorted(c["safety_flags"].items())) or "-"
    return (f"| {task} | {m} | {w['rate']:.3f} [{w['lower']:.3f}, {w['upper']:.3f}] | {per} | {paper} | "
            f"{c['mean_probe_steps']:.2f} | {paper_probe} | {c['mean_probe_displacement']:.4f} | {flags} |")


def diff(c, b, task, split):
    v = promos.get((c, b))
    if not v:
        return None
    cell = v["cells"].get(f"{task}/{split}")
    return None if not cell else cell


print("# Tournament: the pool-belief ladder on the cube tasks\n")
print(f"Generated by `scripts/tournament_report.py` from `{os.path.relpath(os.path.abspath(results), ROOT)}` at commit `{commit}` (do not edit by hand).\n")
print(f"- Experiment `configs/experiments/tournament.yaml`: {len(jobs)} jobs, {total:,} episodes; simulator profile "
      f"**{', '.join(profiles)}** (docs/sim.md); seeds {', '.join(map(str, seeds))}; 200 episodes per (task, split, method, seed);"
      " expert backbone, live tool-frame rotation. Reference splits (two contracts each, 100 episodes per contract and seed,"
      " as the paper) with the nine-contract pool `reference9`; generated splits (32 contracts each) with the 180-contract"
      " `full` pool.")
print(f"- Command: `scripts/tournament {os.path.relpath(os.path.abspath(results), ROOT)}`; wall time {int(float(wall))} s on {os.cpu_count()} cores (shared with other work).")
print("- DualABI's threshold tau was frozen before this run by the pilot on seeds no evaluation uses (docs/results/dualabi_pilot.md).")
print("- Paper columns: the paper's Table 5 (and Table 2 for oracle / no_adapt): frozen PPO on ManiSkill, 600 episodes per cell"
      " (Stack: one seed, 200). The paper's \"seen\", \"unseen comp.\" and \"long lag\" are our `reference_*` splits (the same six"
      " contracts); the generated splits have no paper counterpart.")
print("- The `ideal` profile's earlier tournament (previous calibration protocol) is kept in docs/results/tournament_ideal.md.\n")
print("Success is success_once with its Wilson 95 % interval over the seeds; probe = mean probe steps per episode;"
      " disp. = mean TCP translation during probes [m].\n")

# ---- where the benchmark discriminates
print("## Does the benchmark discriminate?\n")
print("The largest belief-family spread (max - min success over exact, fixed, random, entropy, DualABI) per split, and the")
print("paired entropy - exact difference on PickCube, from the promotion verdict files:\n")
print("| split | pool | largest spread over the tasks | PickCube entropy - exact [95 %] |")
print("|---|---|---|---|")
for split in ref_splits + gen_splits:
    best = None
    for task in tasks:
        rates = [by[(task, split, m)]["success_once"]["rate"] for m in methods if m not in ("oracle", "no_adapt", "grammar_belief") and (task, split, m) in by]
        if rates and (best is None or max(rates) - min(rates) > best[0]):
            best = (max(rates) - min(rates), task)
    d = diff("entropy_probes", "exact_belief", "pick_cube", split)
    ds = "—" if not d else f"{d['difference']['estimate']:+.3f} [{d['difference']['lower']:+.3f}, {d['difference']['upper']:+.3f}]"
    pool = "reference9" if split.startswith("reference") else "full"
    print(f"| {split} | {pool} | {best[0]:.3f} ({best[1]}) | {ds} |" if best else f"| {split} | {pool} | — | {ds} |")
print()
belief = [m for m in methods if m not in ("oracle", "no_adapt", "grammar_belief")]
ref_rates = [by[(t, "reference_seen", m)]["success_once"]["rate"] for t in ("pick_cube", "push_cube", "pull_cube")
             for m in belief if (t, "reference_seen", m) in by]
cal = json.load(open(os.path.join(ROOT, "configs/calibration", profiles[0], "pick_cube.json")))
snr = [abs(a) / s_ for a, s_ in zip(cal["alpha"], cal["sigma"])]
print(f"Reading: on `reference_seen` with the nine-contract pool every belief method scores {min(ref_rates):.3f}-{max(ref_rates):.3f}"
      " on Pick, Push and Pull, so the methods tie there. The evidence is not what makes them tie: the committed")
print(f"calibrations follow the reference's protocol as it runs in ManiSkill (`{cal.get('protocol', '?')}`; PickCube mean R² "
      f"{sum(cal['fit_r2']) / 6:.2f}, per-step alpha/sigma {min(snr):.1f}-{max(snr):.1f}, against 0.23 and about 1 in the paper's")
print("ManiSkill calibration; docs/sim.md), so each belief update is about as weak as the paper's. The likely difference is")
print("the backbone (untested until a PPO backbone passes Gate 0 on Pick): the closed-loop scripted expert replans from the state it finds, so the few steps a belief spends on a")
print("wrong contract cost it little, where the paper's frozen PPO policies lose up to 7 points. The brittleness page")
print("([`brittleness.md`](brittleness.md)) runs the same adapters with the imitation MLP. Elsewhere the methods do separate:")
sep = []
for split in ref_splits + gen_splits:
    for task in tasks:
        rs = {m: by[(task, split, m)]["success_once"]["rate"] for m in belief if (task, split, m) in by}
        if len(rs) > 1 and max(rs.values()) - min(rs.values()) >= 0.05:
            lo = min(rs, key=rs.get)
            hi = max(rs, key=rs.get)
            sep.append(f"{task}/{split}: {lo} {rs[lo]:.3f} against {hi} {rs[hi]:.3f}")
print("" if not sep else "; ".join(sep) + ".")
print("With the 180-contract `full` pool the passive exact belief falls behind the probing methods, and on an")
print("all-absolute split a probe schedule that moves the arm far (entropy probing's mean displacement is in the table)")
print("appears to disturb a stack before the belief settles.\n")
print("How much sensor noise the reference cell needs before the belief methods separate is measured in")
print("[`noise_sensitivity.md`](noise_sensitivity.md): pick_cube / reference_seen with `reference9`, the five belief methods,")
print("oracle and no_adapt under the explicit, off-by-default sensor-noise knob (`run --obs-noise SIGMA`, docs/sim.md §6.1)")
print("at a grid of noise levels fixed before the run, each with the calibration measured under the same noise and with the")
print("built-in one, paired differences by the same bootstrap as here. The tables on this page stay noise-free.\n")

# ---- findings
print("## The paper's findings, tested\n")
print("Rule (fixed in this script): a finding about a paired difference is **reproduced** when our paired 95 % bootstrap")
print("interval (3 seeds x 200 episodes, `actionshift gate promote`) supports the same conclusion as the paper's (the same sign")
print("excluded from zero, or a tie when the paper reports a tie); **contradicted** otherwise, with the reason; **untestable** when")
print("the cell cannot be measured here.\n")
findings = [
    ("entropy probing beats fixed probes on Pick/seen (+5.8 [+3.7, +8.2])", "entropy_probes", "fixed_probes", "pick_cube", "reference_seen", "pos"),
    ("entropy probing beats fixed probes on Pull/unseen (+5.5 [+3.3, +7.8])", "entropy_probes", "fixed_probes", "pull_cube", "reference_unseen_composition", "pos"),
    ("entropy probing beats fixed probes on Push/seen (+1.8 [+0.8, +3.0], below the 5-point margin)", "entropy_probes", "fixed_probes", "push_cube", "reference_seen", "pos"),
    ("entropy probing beats the passive exact belief on Pick/seen (+5.8)", "entropy_probes", "exact_belief", "pick_cube", "reference_seen", "pos"),
    ("entropy probing beats the passive exact belief on Pull/unseen (+4.7 [+2.5, +7.0])", "entropy_probes", "exact_belief", "pull_cube", "reference_unseen_composition", "pos"),
    ("random probes are worse than the passive exact belief on Push/seen (-4.2 [-6.3, -2.0])", "random_probes", "exact_belief", "push_cube", "reference_seen", "neg"),
    ("DualABI ties entropy probing on success, Pick/seen (-0.3 [-1.7, +1.0])", "dualabi", "entropy_probes", "pick_cube", "reference_seen", "tie"),
    ("DualABI ties entropy probing on success, Pick/unseen (+0.8 [-0.7, +2.3])", "dualabi", "entropy_probes", "pick_cube", "reference_unseen_composition", "tie"),
    ("DualABI ties entropy probing on success, Push/seen (+0.0)", "dualabi", "entropy_probes", "push_cube", "reference_seen", "tie"),
    ("DualABI ties entropy probing on success, Push/unseen (+0.7 [-0.3, +1.8])", "dualabi", "entropy_probes", "push_cube", "reference_unseen_composition", "tie"),
    ("DualABI beats fixed probes on Pick/seen (+5.5 [+3.2, +7.8])", "dualabi", "fixed_probes", "pick_cube", "reference_seen", "pos"),
]
print("| finding (paper) | ours: candidate / baseline | ours: paired difference [95 %] | status | reason |")
print("|---|---|---|---|---|")
for text, c, b, task, split, kind in findings:
    d = diff(c, b, task, split)
    if d is None:
        print(f"| {text} | — | — | untestable | cell not run |")
        continue
    e = d["difference"]
    lo, hi = e["lower"], e["upper"]
    ok = (kind == "pos" and lo > 0) or (kind == "neg" and hi < 0) or (kind == "tie" and lo <= 0 <= hi)
    reason = ""
    if not ok:
        cs, bs = d["candidate_success"], d["baseline_success"]
        if min(cs, bs) >= 0.98:
            reason = (f"both at the ceiling ({cs:.3f} vs {bs:.3f}): with the closed-loop expert as the backbone a few steps"
                      " on a wrong contract do not cost the episode (see the reading above)")
        elif kind == "tie":
            reason = f"a paired difference of {e['estimate']:+.3f} excludes zero here"
        else:
            reason = f"our interval [{lo:+.3f}, {hi:+.3f}] does not support it ({cs:.3f} vs {bs:.3f})"
    print(f"| {text} | {d['candidate_success']:.3f} / {d['baseline_success']:.3f} | {e['estimate']:+.3f} [{lo:+.3f}, {hi:+.3f}] | "
          f"**{'reproduced' if ok else 'contradicted'}** | {reason} |")
# probe-cost finding (Table 3 aggregate)
agg = {"dualabi": [0, 0, 0, 0.0], "entropy_probes": [0, 0, 0, 0.0]}
for m in agg:
    for task in ("pick_cube", "push_cube"):
        for split in ("reference_seen", "reference_unseen_composition"):
            c = by.get((task, split, m))
            if c:
                agg[m][0] += c["success_once"]["successes"]; agg[m][1] += c["episodes"]
                agg[m][2] += c["mean_probe_steps"] * c["episodes"]; agg[m][3] += c["mean_probe_displacement"] * c["episodes"]
if agg["dualabi"][1] and agg["entropy_probes"][1]:
    dp = agg["dualabi"][2] / agg["dualabi"][1]; ep = agg["entropy_probes"][2] / agg["entropy_probes"][1]
    dd = agg["dualabi"][3] / agg["dualabi"][1]; ed = agg["entropy_probes"][3] / agg["entropy_probes"][1]
    ok = dp < ep
    print(f"| DualABI uses fewer probe steps than entropy probing (Table 3 aggregate over Pick/Push seen/unseen: 2.89 vs 6.00, -52 %;"
          f" displacement 0.0154 vs 0.0267 m, -42 %) | {dp:.2f} vs {ep:.2f} steps ({(dp / ep - 1) * 100:+.0f} %); {dd:.4f} vs {ed:.4f} m"
          f" ({(dd / ed - 1) * 100:+.0f} %) | — | **{'reproduced' if ok else 'contradicted'}** | {'' if ok else 'DualABI probed as much as entropy'} |")
ll = [by.get((t, "reference_long_lag", m)) for t in tasks for m in methods if m not in ("oracle", "no_adapt")]
ll = [c for c in ll if c]
if ll:
    top = max(c["success_once"]["rate"] for c in ll)
    orc = max((by[(t, "reference_long_lag", "oracle")]["success_once"]["rate"] for t in tasks if (t, "reference_long_lag", "oracle") in by), default=None)
    print(f"| no pool-belief method solves long lag (paper: 0.02-0.33, at the oracle's own low level) | best belief method {top:.3f};"
          f" best oracle {f3(orc)} | — | **{'reproduced' if top <= 0.5 else 'contradicted'}** | |")
print()

for split in ref_splits + gen_splits:
    pool = "reference9" if split.startswith("reference") else "full"
    print(f"## {split} (pool `{pool}`)\n")
    print("| task | method | success [Wilson 95 %] | per seed | paper | probe | paper probe | disp. [m] | safety flags |")
    print("|---|---|---|---|---:|---:|---:|---:|---|")
    for task in tasks:
        for m in methods:
            line = cell_line(task, split, m)
            if line:
                print(line)
    print()
    # spread of the belief family, per task
    for task in tasks:
        rates = [(m, by[(task, split, m)]["success_once"]["rate"]) for m in methods if m not in ("oracle", "no_adapt", "grammar_belief") and (task, split, m) in by]
        if rates:
            lo = min(rates, key=lambda x: x[1]); hi = max(rates, key=lambda x: x[1])
            if hi[1] - lo[1] < 1e-12:
                print(f"- {task}: belief-family spread 0.000 (every method {hi[1]:.3f}).")
            else:
                print(f"- {task}: belief-family spread {hi[1] - lo[1]:.3f} ({lo[0]} {lo[1]:.3f} to {hi[0]} {hi[1]:.3f}).")
    print()

print("## Paired differences and promotion verdicts (computed by `actionshift gate promote`)\n")
print("Rules (`include/actionshift/eval/gates.hpp`): a one-seed result under 0.3 is pruned; a safety regression rejects;")
print("fewer than three matched seeds asks for more seeds; otherwise the candidate is promoted on >= 5 points over its")
print("matched baseline with the paired 95 % bootstrap interval above 0, or on a success-vs-probe-cost Pareto point (fewer")
print("mean probe steps, a paired success estimate >= 0, and candidate success >= 0.3, so a tie at 0.000 promotes nothing);")
print("else rejected. Every verdict is listed.\n")
for (c, b) in sorted(promos):
    v = promos[(c, b)]
    print(f"### {c} vs {b}\n")
    print("| cell | candidate | baseline | difference [95 % CI] | probe steps (cand / base) | episodes | verdict |")
    print("|---|---:|---:|---|---|---:|---|")
    counts = {}
    for key in sorted(v["cells"]):
        x = v["cells"][key]
        d = x["difference"]
        counts[x["verdict"]] = counts.get(x["verdict"], 0) + 1
        print(f"| {key} | {x['candidate_success']:.3f} | {x['baseline_success']:.3f} | {d['estimate']:+.3f} "
              f"[{d['lower']:+.3f}, {d['upper']:+.3f}] | {x['candidate_probe_steps']:.2f} / {x['baseline_probe_steps']:.2f} | "
              f"{x.get('episodes', '—')} | **{x['verdict']}** |")
    print("\n" + ", ".join(f"{k}: {n}" for k, n in sorted(counts.items())) + "\n")
