#!/usr/bin/env python3
"""Writes docs/results/learned_backbone.md (LEARNED=mlp) and docs/results/learned_backbone_ppo.md (LEARNED=ppo)
(scripts/learned_backbone): layout of two `actionshift compare` JSONs, Gate 1 (the expert's gate1 directory and
the learned backbone's, pairs scripts/pages/gate1.pairs) and the tournament's reference cells (the expert's
tournament directory and the learned backbone's, pairs scripts/pages/learned_backbone.pairs), the learned
backbone's Gate-1 verdict file and its committed Gate-0 verdict files (configs/gates/gate0/). No statistics here.
usage: scripts/learned_backbone_report.py --learned mlp|ppo --gate1-compare FILE --tournament-compare FILE
       --gate1-verdict FILE --commit SHA --command TEXT [--wall S] [--cores N] [--gate0-dir DIR] [--numbers FILE]"""
import argparse
import json
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from pages import fmt, load_comparison, paper, provenance, sections, table  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
ap = argparse.ArgumentParser()
ap.add_argument("--learned", required=True, choices=["mlp", "ppo"])
ap.add_argument("--gate1-compare", required=True)
ap.add_argument("--tournament-compare", required=True)
ap.add_argument("--gate1-verdict", required=True, help="`actionshift gate1` verdict file of the learned backbone's gate1 directory")
ap.add_argument("--commit", required=True)
ap.add_argument("--command", required=True)
ap.add_argument("--wall")
ap.add_argument("--cores")
ap.add_argument("--gate0-dir", default=os.path.join("configs", "gates", "gate0"))
ap.add_argument("--numbers", default=paper.NUMBERS)
a = ap.parse_args()

L = a.learned
KIND = {"mlp": "imitation MLP", "ppo": "PPO"}[L]
g = load_comparison(a.gate1_compare)
t = load_comparison(a.tournament_compare)
numbers = paper.load_numbers(a.numbers)
with open(a.gate1_verdict) as f:
    g1v = json.load(f)
lg, lt = g.cells_where(backbone=L), t.cells_where(backbone=L)
specs = provenance.job_specs(g.input_dirs() + t.input_dirs(), g.jobs(lg) + t.jobs(lt))
backbones = ["expert", L]

out = [provenance.header(
    f"The learned backbone: Gate 1 and the tournament's reference cells, expert and {KIND}",
    "scripts/learned_backbone_report.py", a.command, a.commit, g.input_dirs() + t.input_dirs(),
    provenance.spec_values(specs, "profile"), g.seeds(lg + lt), g.episodes(lg) + t.episodes(lt),
    jobs=len(g.jobs(lg)) + len(t.jobs(lt)), episodes_per_seed=g.episodes_per_seed(lg + lt), wall=a.wall,
    cores=a.cores, paper_source=t.paper_source(), bootstrap=t.bootstrap(),
    extra=[f"The counts above are the `{L}` backbone's; the expert's cells come from the same experiments' expert "
           f"directories. Experiments `configs/experiments/gate1_{L}.yaml` and `configs/experiments/tournament_{L}.yaml`.",
           f"Learned backbone `{L}`, weight files by SHA-256 prefix: "
           + ", ".join(sorted({s['backbone']['sha256'][:12] + f" ({s['task']})" for s in specs})) + ".",
           "Both probe rules are run: bare `entropy_probes` / `dualabi` are the paper's rule, `{calibrated}` the "
           "project's (docs/adapters.md); only the paper's rule gets the paper's numbers."])]
out.append("Every other table of this benchmark uses the scripted expert as the frozen backbone; the paper's claims are "
           f"about frozen *learned* policies. This page sets the {KIND} (docs/backbones.md) beside the expert on Gate 1 "
           "and on the tournament's reference cells. The "
           + ("imitation MLP's page is docs/results/learned_backbone.md.\n\n" if L == "ppo"
              else "PPO backbones have their own page, docs/results/learned_backbone_ppo.md.\n\n"))

# ---- Gate 0, from the committed verdict files
out.append(f"## Gate 0 of the `{L}` backbones (from `{a.gate0_dir}`)\n\n")
rows = []
for task in sections.TASK_ORDER:
    p = os.path.join(a.gate0_dir, f"{L}.{task}.json")
    if not os.path.exists(p):
        continue
    with open(p) as f:
        v = json.load(f)["cells"][f"{L}/{task}"]
    rows.append([task, f"`{L}.{task}.json`", v["verdict"], v["decision"], fmt.rate(v["competence"]["interval"]),
                 v["competence"]["rule"], v["reason"] or fmt.DASH])
out.append(table.markdown(["task", "verdict file", "verdict", "decision", "competence [Wilson 95 %]", "rule", "reason"], rows)
           if rows else f"No Gate-0 verdict file for `{L}` in `{a.gate0_dir}`.\n")
excluded = [r[0] for r in rows if r[2] != "pass"]
out.append("\n" + (f"Excluded at Gate 0 (no cells below): {', '.join(excluded)}.\n" if excluded
                   else f"Every `{L}` backbone with a verdict file passes Gate 0.\n"))

# ---- Gate 1
out.append(f"\n## Gate 1 with both backbones\n\nVerdict for `{L}`: **Gate 1 {'passed' if g1v.get('passed') else 'not passed'}** "
           f"(claim status `{g1v.get('claim_status')}`; gated cells need oracle >= 0.95 and no_adapt <= 0.05; long_lag is "
           "descriptive). The paper's numbers are for its reference contracts (`reference_<split>`), set beside our "
           "generated `<split>`.\n\n")
rows = []
for c in sections.ordered_cells(g, backbone=L):
    if c["method"] != "oracle":
        continue
    task, split = c["task"], c["split"]
    v = g1v.get("cells", {}).get(f"{task}/{split}", {})
    rows.append([task, split, fmt.cell_rate(g.cell(task, split, "oracle", "expert")), fmt.cell_rate(c),
                 paper.entry_value(numbers.find_cell("success_once", task, "reference_" + split, "oracle", L)),
                 fmt.cell_rate(g.cell(task, split, "no_adapt", "expert")), fmt.cell_rate(g.cell(task, split, "no_adapt", L)),
                 paper.entry_value(numbers.find_cell("success_once", task, "reference_" + split, "no_adapt", L)),
                 fmt.cmp_diff(g.comparison("oracle", "no_adapt", task, split, L)), v.get("verdict", fmt.DASH),
                 v.get("reason", fmt.DASH)])
out.append(table.markdown(["task", "split", "oracle, expert", f"oracle, {L}", "paper oracle", "no_adapt, expert",
                           f"no_adapt, {L}", "paper no_adapt", f"oracle − no_adapt, {L} [95 %]", f"{L} verdict",
                           "reason"], rows))

# ---- headline and findings
out.append("\n## Entropy − fixed probes on pick_cube / reference_seen\n\n")
out.append(sections.headline_table(t, backbones))
out.append("\n## The paper's findings, tested on both backbones\n\n" + sections.STATUS_RULE + "\n\n")
out.append(sections.findings_table(t, numbers, backbones))

# ---- cells
out.append("\n## The reference cells, both backbones\n\nPer-seed rates in ascending seed order (the paper's Table 5 "
           "prints per-seed rates too; they sit in the paper-numbers file's entries).\n\n")
learned_splits = set(t.values("split", lt))
for task in sections.tasks(t, lt):
    for split in sections.splits(t, lt):
        cs = [c for c in sections.ordered_cells(t, task=task, split=split) if c["backbone"] in backbones]
        if not any(c["backbone"] == L for c in cs):
            continue
        out.append(f"\n### {task} / {split}\n\n")
        cs.sort(key=lambda c: (sections._key(sections.METHOD_ORDER, c["method"]), c["backbone"] != "expert"))
        rows = []
        for c in cs:
            pe = paper.cell_entry(c)
            rows.append([f"`{c['method']}`", c["backbone"], fmt.cell_rate(c), fmt.per_seed(c), paper.cell_column(c),
                         " / ".join(fmt.num(s["rate"]) for s in pe["per_seed"]) if pe and pe.get("per_seed") else fmt.DASH,
                         fmt.probe_steps(c), paper.cell_column(c, "mean_probe_steps"), fmt.displacement(c), fmt.safety(c)])
        out.append(table.markdown(["method", "backbone", "success [Wilson 95 %]", "per seed", "paper",
                                   "paper per seed", "probe steps", "paper probe steps", "displacement [m]",
                                   "safety: flagged (flags)"], rows))

# ---- promotion audit (the paper's Table 7 has its own promotion audit)
out.append("\n## Promotion audit: every pair × cell\n\n" + sections.PROMOTION_RULES + "\n\n")
out.append(sections.promotion_table(t, [x for x in t.comparisons if x["backbone"] in backbones and x["split"] in learned_splits]))
notes = g.notes() + t.notes()
if notes:
    out.append("\nNotes from `compare`: " + "; ".join(notes) + "\n")
sys.stdout.write("".join(out))
