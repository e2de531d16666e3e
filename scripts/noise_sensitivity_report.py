#!/usr/bin/env python3
"""Writes docs/results/noise_sensitivity.md from the results of scripts/noise_sensitivity: for each
sensor-noise level, the calibration measured under that noise (its R^2), the cells of
`actionshift summarize DIR --json` (success with Wilson 95 % intervals, probe steps) and the paired
differences of the verdict files written by `actionshift gate promote` (the tournament's paired
bootstrap, not re-implemented here), with the paper's Pick/seen numbers beside ours.
Standard library only.
usage: scripts/noise_sensitivity_report.py RESULTS_DIR ACTIONSHIFT_BINARY WALL_SECONDS > docs/results/noise_sensitivity.md"""
import glob
import json
import os
import subprocess
import sys

results, binary, wall = sys.argv[1], sys.argv[2], sys.argv[3]
ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
commit = subprocess.run(["git", "-C", ROOT, "rev-parse", "--short", "HEAD"], capture_output=True, text=True).stdout.strip()

BELIEF = ["exact_belief", "fixed_probes", "random_probes", "entropy_probes", "dualabi"]
METHODS = ["oracle"] + BELIEF + ["no_adapt"]
PAIRS = [("entropy_probes", "exact_belief"), ("dualabi", "exact_belief")]
DESIGN_SEEDS = [20260718, 20260719, 20260720]  # scripts/noise_sensitivity
# The paper, Pick/seen (Table 5; Table 2 for oracle / no_adapt): frozen PPO on ManiSkill, 3 seeds x 200 episodes
PAPER = {"oracle": 1.000, "no_adapt": 0.000, "exact_belief": 0.929, "fixed_probes": 0.928, "random_probes": 0.925,
         "entropy_probes": 0.987, "dualabi": 0.983}
PAPER_PROBES = {"dualabi": 2.78, "entropy_probes": 6.0, "fixed_probes": 6.0, "random_probes": 6.0, "exact_belief": 0.0}
MANISKILL_R2 = [0.28, 0.11, 0.29, 0.34, 0.09, 0.26]  # the reference implementation's ManiSkill PickCube calibration


def summarize(d):
    if not os.path.isdir(d) or not glob.glob(os.path.join(d, "*.jsonl")):
        return {}, []
    for f in glob.glob(os.path.join(d, "*.jsonl")):
        if not os.path.exists(f[:-len(".jsonl")] + ".summary.json"):
            sys.exit(f"noise_sensitivity_report: {f} is an unfinished job: finish it (run scripts/noise_sensitivity again) or remove it")
    s = json.loads(subprocess.run([binary, "summarize", d, "--json"], check=True, capture_output=True, text=True).stdout)
    cells = {c["method"]: c for c in s["cells"] if c["task"] == "pick_cube" and c["split"] == "reference_seen"}
    specs = []
    for c in s["cells"]:
        for j in c["jobs"]:
            specs.append(json.load(open(os.path.join(d, j + ".summary.json")))["job"])
    return cells, specs


def promos(d):
    out = {}
    for c, b in PAIRS:
        p = os.path.join(d, f"promotion.{c}.vs.{b}.json")
        if os.path.exists(p):
            cell = json.load(open(p))["cells"].get("pick_cube/reference_seen")
            if cell:
                out[(c, b)] = cell
    return out


levels = []
for d in glob.glob(os.path.join(results, "sigma_*mm")):
    mm = float(os.path.basename(d)[len("sigma_"):-len("mm")])
    cal = json.load(open(os.path.join(d, "calibration.json")))
    matched, specs_m = summarize(os.path.join(d, "matched"))
    mis, specs_n = summarize(os.path.join(d, "noiseless_cal"))
    levels.append({"mm": mm, "cal": cal, "matched": matched, "mis": mis, "pm": promos(os.path.join(d, "matched")),
                   "pn": promos(os.path.join(d, "noiseless_cal")), "specs": specs_m + specs_n})
levels.sort(key=lambda x: x["mm"])
if not levels:
    sys.exit("noise_sensitivity_report: no sigma_*mm directories in " + results)
builtin = json.load(open(os.path.join(ROOT, "configs", "calibration", "maniskill", "pick_cube.json")))
all_specs = [s for lv in levels for s in lv["specs"]]
seeds = sorted({s["seed"] for s in all_specs})
jobs = len({json.dumps(s, sort_keys=True) for s in all_specs})
episodes = sum(s["episodes"] for s in {json.dumps(s, sort_keys=True): s for s in all_specs}.values())
profiles = sorted({s["profile"] for s in all_specs})
per_job = "/".join(str(n) for n in sorted({s["episodes"] for s in all_specs}))
cell_sizes = sorted({c["episodes"] for lv in levels for key in ("matched", "mis") for c in lv[key].values()})
cell_n = str(cell_sizes[0]) if len(cell_sizes) == 1 else f"{cell_sizes[0]}-{cell_sizes[-1]}"


def mean(xs):
    return sum(xs) / len(xs)


def mm_s(mm):
    return f"{mm:g} mm"


def rate(c):
    return None if c is None else c["success_once"]


def cell(c):
    if c is None:
        return "—"
    w = c["success_once"]
    return f"{w['rate']:.3f} [{w['lower']:.3f}, {w['upper']:.3f}]"


def dstr(p):
    if p is None:
        return "—"
    d = p["difference"]
    return f"{d['estimate']:+.3f} [{d['lower']:+.3f}, {d['upper']:+.3f}]"


def spread(cells):
    r = [cells[m]["success_once"]["rate"] for m in BELIEF if m in cells]
    return (max(r) - min(r)) if len(r) == len(BELIEF) else None


def separated(pm):
    """A paired interval that excludes zero (either sign)."""
    return [k for k, p in pm.items() if p["difference"]["lower"] > 0 or p["difference"]["upper"] < 0]


print("# Observation-noise sensitivity: when do the belief methods separate?\n")
print(f"Generated by `scripts/noise_sensitivity_report.py` from `{results}` at commit `{commit}` (do not edit by hand).\n")
print("The tournament (docs/results/tournament.md) finds every belief method tied on pick_cube / reference_seen with the")
print("nine-contract pool, where the paper separates them, because this simulator's response to a command is cleaner than")
print("ManiSkill's (docs/sim.md §0). The default simulator stays noise-free. This page turns on the explicit, off-by-default")
print("sensor-noise knob (`--obs-noise SIGMA`, docs/sim.md §6.1) and measures how much observation noise it takes for")
print("the methods to separate, and whether they then separate in the paper's order. It is a sensitivity study, not a")
print("replacement for the published tables.\n")
print(f"- Command: `scripts/noise_sensitivity {results}`; wall time {int(float(wall))} s at `nice -n 10`, two worker"
      " threads per job, the machine's two cores shared with five other engineers' builds and experiments (the CPU time is far"
      " smaller: about 15 ms of one core per episode).")
print(f"- Cells: pick_cube / `reference_seen` (two contracts), pool `reference9`, expert backbone, live tool-frame rotation,"
      f" profile **{', '.join(profiles)}**; seeds {', '.join(map(str, seeds))}; {per_job} episodes per job (half per contract"
      f" and seed, as the tournament), so {cell_n} episodes per cell; {jobs} jobs, {episodes:,} episodes in all.")
if len(seeds) < len(DESIGN_SEEDS):
    print(f"- **Coverage: {len(seeds)} of the design's {len(DESIGN_SEEDS)} seeds.** The script runs seed by seed over the whole grid;"
          " on this run the machine (two cores shared with five other engineers' builds and experiments, this study at"
          " `nice -n 10`) gave it about one job per half minute, so the run was stopped after the first seed: every level"
          f" and both calibrations have {cell_n} episodes per cell, Wilson intervals of about ±0.02 only near 0 or 1 and up to"
          " ±0.07 in between. Running `scripts/noise_sensitivity` again resumes it (the finished jobs are no-ops) and"
          " regenerates this page.")
print("- Each noise level σ: the response calibration measured under σ (`actionshift calibrate --task pick_cube --obs-noise σ`,"
      " the reference's protocol, 8 walks x 64 steps, seed 20260720); oracle and no_adapt; the five belief methods once with"
      " that calibration (**matched**) and once with the built-in noiseless calibration (**mis-modelled**: the belief"
      " under-states the noise). At σ = 0 the jobs are the tournament's own (the same job ids; code changes since the tournament ran may change a record's details, e.g. probe displacements, but not the job).")
print("- Paired differences: `actionshift gate promote` (paired bootstrap over the (seed, contract, episode) pairs, 10,000"
      " resamples, 95 %), the same code as the tournament's.")
print("- Paper columns: the paper's Table 5 Pick/seen (frozen PPO on ManiSkill, 600 episodes per cell): exact 0.929, fixed"
      " 0.928, random 0.925, entropy 0.987, DualABI 0.983 at 2.78 probe steps; and the reference implementation's ManiSkill"
      " PickCube calibration (mean R² 0.228).\n")
print("**The grid, fixed before the run.** σ ∈ {0, 1, 2, 5, 10, 20} mm (and the same number in mrad on the orientation):")
print("a 1-2-5 series from 1 mm up to the first value at which the noise alone gives a per-step response a residual")
print("standard deviation inside ManiSkill's 2-5 cm (a response is the difference of two noisy observations, so its")
print("noise is √2 σ: 28 mm at σ = 20 mm). Nothing on this page was chosen by looking at success rates.\n")

print("## The response under noise (calibration R²)\n")
print("| σ | mean R² (6 channels) | R² dx dy dz rx ry rz | α/σ dx dy dz | calibration |")
print("|---|---:|---|---|---|")
print(f"| ManiSkill (reference) | {mean(MANISKILL_R2):.3f} | {' '.join('%.2f' % r for r in MANISKILL_R2)} | about 1 | the reference implementation's |")
for lv in levels:
    c = lv["cal"]
    ratio = " ".join("%.1f" % (a / s) for a, s in zip(c["alpha"][:3], c["sigma"][:3]))
    note = c["profile"]
    if lv["mm"] == 0:
        # the built-in also carries the finger channel (`calibrate --gripper-channel`), which only
        # grammar_belief reads; the pool methods on this page see the six pose channels
        pose = lambda d: {k: v for k, v in d.items() if k != "gripper"}
        if c == builtin:
            note += " (identical to the built-in)"
        elif pose(c) == pose(builtin):
            note += " (the built-in's pose channels, identical; the built-in adds the finger channel)"
        else:
            note += " (differs from the built-in!)"
    print(f"| {mm_s(lv['mm'])} | {mean(c['fit_r2']):.3f} | {' '.join('%.2f' % r for r in c['fit_r2'])} | {ratio} | {note} |")
print()


def success_table(key, title):
    print(title + "\n")
    print("| method | paper | " + " | ".join(f"σ = {mm_s(lv['mm'])}" for lv in levels) + " |")
    print("|---|---:|" + "---|" * len(levels))
    for m in METHODS:
        row = []
        for lv in levels:
            cells = lv[key] if (m in BELIEF and lv["mm"] > 0) else lv["matched"]
            row.append(cell(cells.get(m)))
        print(f"| {m} | {PAPER[m]:.3f} | " + " | ".join(row) + " |")
    row = []
    for lv in levels:
        cells = lv[key] if lv["mm"] > 0 else lv["matched"]
        c = cells.get("dualabi")
        row.append("—" if c is None else f"{c['mean_probe_steps']:.2f}")
    print(f"| DualABI probe steps | {PAPER_PROBES['dualabi']:.2f} | " + " | ".join(row) + " |")
    row = []
    for lv in levels:
        cells = lv[key] if lv["mm"] > 0 else lv["matched"]
        s = spread(cells)
        row.append("—" if s is None else f"{s:.3f}")
    row = []
    for lv in levels:
        cells = lv[key] if lv["mm"] > 0 else lv["matched"]
        o = lv["matched"].get("oracle")
        r = [cells[m]["success_once"]["rate"] for m in BELIEF if m in cells]
        row.append("—" if (o is None or not r) else f"{o['success_once']['rate'] - min(r):+.3f}")
    print(f"| oracle − worst belief method | {PAPER['oracle'] - min(PAPER[m] for m in BELIEF):+.3f} | " + " | ".join(row) + " |")
    print(f"| belief-family spread (max − min) | {max(PAPER[m] for m in BELIEF) - min(PAPER[m] for m in BELIEF):.3f} | " + " | ".join(row) + " |")
    print()


print(f"## Success rate (success_once, Wilson 95 %, {cell_n} episodes per cell)\n")
success_table("matched", "### Matched: each belief uses the calibration measured under the same noise")
success_table("mis", "### Mis-modelled: each belief uses the built-in noiseless calibration (oracle and no_adapt as above)")

print("## Paired differences (bootstrap 95 %, `actionshift gate promote`)\n")
print("| σ | mean R² | entropy − exact (matched) | DualABI − exact (matched) | entropy − exact (mis-modelled) | DualABI − exact (mis-modelled) |")
print("|---|---:|---|---|---|---|")
print("| paper | 0.228 (ManiSkill) | +0.058 | +0.054 | | |")
for lv in levels:
    pm = lv["pm"]
    pn = lv["pn"] if lv["mm"] > 0 else lv["pm"]
    print(f"| {mm_s(lv['mm'])} | {mean(lv['cal']['fit_r2']):.3f} | {dstr(pm.get(PAIRS[0]))} | {dstr(pm.get(PAIRS[1]))} | "
          f"{dstr(pn.get(PAIRS[0]))} | {dstr(pn.get(PAIRS[1]))} |")
print()

# ---- the answer, by a rule fixed in this script
print("## Where the methods separate\n")
print("Rule (fixed in this script before the run): the methods **separate** at the smallest σ at which a paired interval")
print("(entropy − exact or DualABI − exact) excludes zero. The order **matches the paper's** when, at that σ, every")
print("separated difference is positive (probing above the passive exact belief, as the paper's +0.058 and +0.054).\n")
for key, pkey, name in (("matched", "pm", "matched calibration"), ("mis", "pn", "mis-modelled (noiseless) calibration")):
    first = None
    measured = []
    for lv in levels:
        p = lv[pkey] if lv["mm"] > 0 else lv["pm"]
        if p:
            measured.append(lv)
        if separated(p):
            first = (lv, p)
            break
    if first is None:
        missing = [mm_s(lv["mm"]) for lv in levels if not (lv[pkey] if lv["mm"] > 0 else lv["pm"])]
        if not measured:
            print(f"- **{name}**: not measured (no paired differences in the results).")
            continue
        top = measured[-1]
        print(f"- **{name}**: no separation among the levels measured: up to σ = {mm_s(top['mm'])} (calibration mean R²"
              f" {mean(top['cal']['fit_r2']):.3f}) every paired interval contains zero"
              + (f"; not measured: σ = {', '.join(missing)}." if missing else "."))
        continue
    lv, p = first
    ks = separated(p)
    signs = [p[k]["difference"]["estimate"] > 0 for k in ks]
    cells = lv[key] if lv["mm"] > 0 else lv["matched"]
    order = sorted((m for m in BELIEF if m in cells), key=lambda m: -cells[m]["success_once"]["rate"])
    paper_order = sorted(BELIEF, key=lambda m: -PAPER[m])
    orc = lv["matched"].get("oracle")
    print(f"- **{name}**: the methods separate at σ = {mm_s(lv['mm'])} (calibration mean R² {mean(lv['cal']['fit_r2']):.3f};"
          f" ManiSkill 0.228; oracle {cell(orc)}): " + "; ".join(f"{c} − {b} {dstr(p[(c, b)])}" for (c, b) in ks) + ". "
          + ("The sign matches the paper's (probing above the passive belief)." if all(signs)
             else "The sign does **not** match the paper's: the passive exact belief is ahead.")
          + " Order of the five at that σ: " + " > ".join("%s %.3f" % (m, cells[m]["success_once"]["rate"]) for m in order)
          + " (paper: " + " > ".join("%s %.3f" % (m, PAPER[m]) for m in paper_order) + ").")
print()
print("Reading the tables: the oracle column shows what the noise costs the backbone itself (the expert acts on the same")
print("noisy TCP pose); a difference between belief methods is only meaningful where the oracle is still competent. The")
print("noise here is white and per step; ManiSkill's unexplained response variance is, by the ablation in docs/sim.md §0,")
print("more likely persistent arm motion across control steps, which a white sensor noise does not reproduce. The")
print("study therefore tells how much evidence noise the methods' ranking needs, not that ManiSkill's gap is sensor noise.")
