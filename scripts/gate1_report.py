#!/usr/bin/env python3
"""Writes docs/results/gate1.md (scripts/gate1): layout of `actionshift compare` (pairs
scripts/pages/gate1.pairs) and of the Gate-1 verdict file (`actionshift gate1`), with the paper's Gate-1
numbers (configs/paper/numbers.json, its reference contracts) beside our generated splits. No statistics here.
usage: scripts/gate1_report.py --compare FILE --verdict FILE --commit SHA --command TEXT [--wall S] [--cores N]"""
import argparse
import json
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from pages import fmt, load_comparison, paper, provenance, table  # noqa: E402

ap = argparse.ArgumentParser()
ap.add_argument("--compare", required=True)
ap.add_argument("--verdict", required=True, help="the verdict file of `actionshift gate1 --results DIR`")
ap.add_argument("--commit", required=True)
ap.add_argument("--command", required=True)
ap.add_argument("--wall")
ap.add_argument("--cores")
ap.add_argument("--numbers", default=paper.NUMBERS, help="the paper-numbers file (default configs/paper/numbers.json)")
a = ap.parse_args()

c = load_comparison(a.compare)
with open(a.verdict) as f:
    g = json.load(f)
numbers = paper.load_numbers(a.numbers)
specs = provenance.job_specs(c.input_dirs(), c.jobs())
out = [provenance.header(
    "Gate 1: the privileged ceiling", "scripts/gate1_report.py", a.command, a.commit, c.input_dirs(),
    provenance.spec_values(specs, "profile"), c.seeds(), c.episodes(), jobs=len(c.jobs()),
    episodes_per_seed=c.episodes_per_seed(), wall=a.wall, cores=a.cores, paper_source=c.paper_source(),
    bootstrap=c.bootstrap(),
    extra=["Experiment `configs/experiments/gate1.yaml`: the generated splits (32 contracts each), backbone(s) "
           + ", ".join(f"`{b}`" for b in c.values("backbone")) + "; Gate-1 verdicts from the verdict file "
           f"`{os.path.basename(a.verdict)}` of `actionshift gate1 --results`."])]
out.append("""Gate 1 asks whether the benchmark's premise holds: the frozen backbone succeeds when the hidden contract is
inverted exactly (the oracle adapter, which receives the true contract from the runner) and fails when its
canonical actions are sent unchanged (no adaptation). Gated cells (`seen`, `unseen_composition`) pass when
oracle >= 0.95 and no_adapt <= 0.05 (point estimates; constants in `include/actionshift/eval/gates.hpp`);
`long_lag` is reported as measured (re-encoding cannot undo a pipeline delay, so the oracle is no ceiling there).

""")
out.append(f"**Gate 1 {'passed' if g.get('passed') else 'NOT passed'}** (claim status `{g.get('claim_status')}`).\n\n")
out.append("""The paper's columns are its Gate-1 numbers (Table 2 for Pick and Push; the reference implementation's
Gate-1 table, or §5.1, for Pull and Stack; frozen PPO, 600 episodes per cell) on **its reference contracts**:
each row's paper number is the `reference_<split>` cell (two representative contracts) set beside our generated
`<split>` (32 contracts), the same kind of contract, not the same contracts.

""")
rows = []
for cell in c.cells_where(method="oracle"):
    t, s, b = cell["task"], cell["split"], cell["backbone"]
    na = c.cell(t, s, "no_adapt", b)
    cmp = c.comparison("oracle", "no_adapt", t, s, b)
    po = numbers.find_cell("success_once", t, "reference_" + s, "oracle", b)
    pn = numbers.find_cell("success_once", t, "reference_" + s, "no_adapt", b)
    pd, rev = numbers.find_difference(t, "reference_" + s, "oracle", "no_adapt", b)
    v = g.get("cells", {}).get(f"{t}/{s}", {})
    srcs = sorted({e["source"] for e in (po, pn, pd) if e})
    rows.append([t, s, b, fmt.cell_rate(cell), fmt.cell_rate(na), fmt.cmp_diff(cmp), fmt.per_seed_diff(cmp),
                 f"`reference_{s}`", paper.entry_value(po), paper.entry_value(pn), paper.entry_diff_value(pd, rev),
                 "; ".join(srcs) or fmt.DASH, v.get("verdict", fmt.DASH), v.get("reason", fmt.DASH)])
out.append(table.markdown(
    ["task", "split", "backbone", "oracle [Wilson 95 %]", "no_adapt [Wilson 95 %]", "oracle − no_adapt [95 %]",
     "per seed", "paper cell", "paper oracle", "paper no_adapt", "paper difference", "paper source", "verdict", "reason"],
    rows))
one_side = [x for p in c.pairs for x in p["cells_with_one_side"]]
if one_side:
    out.append("\nCells with only one of the two methods (no paired difference): "
               + "; ".join(f"{x['task']}/{x['split']}/{x['backbone']} ({x['present']} only)" for x in one_side) + ".\n")
out.append("\n## Every cell\n\n")
out.append(table.markdown(
    ["task", "split", "method", "backbone", "episodes", "success [Wilson 95 %]", "per seed", "success at end",
     "safety: flagged episodes (flags)"],
    [[x["task"], x["split"], x["method"], x["backbone"], x["episodes"], fmt.cell_rate(x), fmt.per_seed(x),
      fmt.num(x["success_at_end_rate"]), fmt.safety(x)] for x in c.cells]))
notes = c.notes()
if notes:
    out.append("\nNotes from `compare` (torn tails, overlapping jobs): " + "; ".join(notes) + "\n")
sys.stdout.write("".join(out))
