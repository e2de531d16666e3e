#!/usr/bin/env python3
"""Writes docs/results/tournament.md (scripts/tournament): layout of one `actionshift compare` JSON over the
tournament's results directory (and, when given, the PPO backbone's tournament_ppo directory), pairs
scripts/pages/tournament.pairs. Both probe rules side by side (the paper's: bare names; the project's:
`{calibrated}`), every paper finding with its status, the probe-displacement explanation, per-split cell tables
and the promotion audit. No statistics here.
usage: scripts/tournament_report.py --compare FILE --commit SHA --command TEXT [--wall S] [--cores N]
       [--displacement FILE] [--numbers FILE] [--across FILE]
--across: the comparison of scripts/backbone_variance (compare --across-backbones); its verdicts on the paper's
findings over independently trained PPO backbones are summarised here (the full page: backbone_variance.md)."""
import argparse
import json
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from pages import findings, fmt, load_comparison, paper, provenance, sections, table  # noqa: E402
from pages import backbones as backbones_page  # noqa: E402

ap = argparse.ArgumentParser()
ap.add_argument("--compare", required=True)
ap.add_argument("--commit", required=True)
ap.add_argument("--command", required=True)
ap.add_argument("--wall")
ap.add_argument("--cores")
ap.add_argument("--reused", type=int, default=0, help="jobs the command found complete (run by an earlier invocation)")
ap.add_argument("--displacement", help="optional JSON {summary, rows} on the cause of the probe displacement")
ap.add_argument("--numbers", default=paper.NUMBERS)
ap.add_argument("--across", help="compare --across-backbones JSON of scripts/backbone_variance (optional)")
a = ap.parse_args()

c = load_comparison(a.compare)
numbers = paper.load_numbers(a.numbers)
specs = provenance.job_specs(c.input_dirs(), c.jobs())
backbones = sorted(c.values("backbone"), key=lambda b: (b != "expert", b))
out = [provenance.header(
    "Tournament: the pool-belief ladder on the cube tasks", "scripts/tournament_report.py", a.command, a.commit,
    c.input_dirs(), provenance.spec_values(specs, "profile"), c.seeds(), c.episodes(), jobs=len(c.jobs()),
    episodes_per_seed=c.episodes_per_seed(), wall=a.wall, cores=a.cores, paper_source=c.paper_source(),
    bootstrap=c.bootstrap(), reused=a.reused,
    extra=["Experiments `configs/experiments/tournament.yaml` (expert)"
           + (" and `configs/experiments/tournament_ppo.yaml` (PPO)" if "ppo" in backbones else "")
           + "; backbones " + ", ".join(f"`{b}`" for b in backbones) + "; pools "
           + ", ".join(f"`{p}`" for p in provenance.pools(specs)) + ".",
           "Both probe rules are run: `entropy_probes` and `dualabi` are **the paper's rule**; `entropy_probes{calibrated}` "
           "and `dualabi{calibrated}` are the project's corrected rule (docs/adapters.md, *Method names and variants*). "
           "Only the paper's rule gets the paper's numbers.",
           "The paper's \"seen\", \"unseen comp.\" and \"long lag\" are our `reference_*` splits (its contracts); the "
           "generated splits have no paper counterpart."])]

# ---- the headline difference
out.append("## Entropy − fixed probes on pick_cube / reference_seen\n\n")
out.append("The paper's headline probing result (§5.2, Table 7) against ours, both probe rules, every backbone run here:\n\n")
out.append(sections.headline_table(c, backbones))

# ---- findings
out.append("\n## The paper's findings, tested\n\n" + sections.STATUS_RULE + "\n\n")
out.append(sections.findings_table(c, numbers, backbones))
if a.across:
    with open(a.across) as f:
        across = json.load(f).get("across_backbones") or []
    out.append("\n### Across independently trained backbones\n\n")
    out.append("The paper's findings on the PPO backbones of a task (the committed file and the replicas trained by its "
               "recipe with other training seeds): the pooled difference by a hierarchical bootstrap over backbones, "
               "seeds and blocks, and whether it holds on every backbone, on average, or depends on the backbone "
               "(per-backbone effects and the project's own variants: [backbone_variance.md](backbone_variance.md)).\n\n")
    def paper_text(x):
        # the paper's paired difference where it prints one, else its two cell rates (its one PPO checkpoint)
        e, rev = numbers.find_difference(x["task"], x["split"], x["candidate"], x["baseline"], "ppo")
        if e:
            return f"{paper.entry_diff_value(e, rev)} ({paper.source(e)})"
        cells = [numbers.find_cell("success_once", x["task"], x["split"], m, "ppo") for m in (x["candidate"], x["baseline"])]
        if all(cells):
            srcs = list(dict.fromkeys(paper.source(e) for e in cells))
            return " / ".join(fmt.num(e["value"]) for e in cells) + f" ({' / '.join(srcs)})"
        return fmt.DASH

    rows = [[f"`{x['candidate']}` − `{x['baseline']}`", x["task"], x["split"], str(len(x["backbones"])),
             backbones_page.diff_text(x["pooled"]), f"**{backbones_page.VERDICT_TEXT[x['verdict']]}**", paper_text(x)]
            for x in across if f"{x['candidate']} vs {x['baseline']}" in backbones_page.PAPER_PAIRS]
    out.append(table.markdown(["paper's pair", "task", "split", "backbones", "pooled difference [95 %]", "verdict",
                               "paper (its PPO: difference, or candidate / baseline rates)"], rows)
               if rows else "No paper pair in the across-backbones comparison.\n")
out.append("\nProbe cost (the paper's §5.5: DualABI probes less than entropy probing). Compare gives mean probe steps and "
           "displacement per cell, no interval for their difference, so this is descriptive:\n\n")
rows = []
for x in sections.ordered_cells(c):
    if x["method"].split("{")[0] in ("dualabi", "entropy_probes") and x["split"].startswith("reference") \
            and x["split"] != "reference_long_lag":
        rows.append([x["task"], x["split"], x["backbone"], f"`{x['method']}`", fmt.probe_steps(x),
                     paper.cell_column(x, "mean_probe_steps"), fmt.displacement(x)])
out.append(table.markdown(["task", "split", "backbone", "method", "probe steps", "paper probe steps",
                           "displacement [m]"], rows) if rows else "No probing cells.\n")
agg = [numbers.by_id(i) for i in ("s5.5.aggregate.entropy_probes.mean_probe_displacement",
                                  "s5.5.aggregate.dualabi.mean_probe_displacement")]
agg = [e for e in agg if e]
if agg:
    out.append("\nThe paper's displacement is printed only as an aggregate over Pick/Push seen and unseen composition ("
               + agg[0]["source"] + "): " + ", ".join(f"{e['method']} {paper.entry_value(e)} m" for e in agg)
               + "; per-cell values are the reference implementation's (its DualABI-vs-entropy report).\n")

# ---- displacement
out.append("\n## Why entropy probes move the arm more than the paper's\n\n")
cell = {m: c.cell("pick_cube", "reference_seen", m, "expert")
        for m in ("entropy_probes", "entropy_probes{calibrated}", "fixed_probes", "random_probes", "dualabi", "dualabi{calibrated}")}
if cell["entropy_probes"] and cell["fixed_probes"]:
    pe = paper.cell_entry(cell["entropy_probes"], "mean_probe_displacement")
    pf = paper.cell_entry(cell["fixed_probes"], "mean_probe_displacement")
    out.append(
        f"On pick_cube / reference_seen with the expert, entropy probing moves the TCP {fmt.displacement(cell['entropy_probes'])} m "
        f"per episode under the paper's rule" + (f" and {fmt.displacement(cell['entropy_probes{calibrated}'])} m under `{{calibrated}}`"
                                                 if cell["entropy_probes{calibrated}"] else "")
        + f", in {fmt.probe_steps(cell['entropy_probes'])} probe steps; fixed probes move it {fmt.displacement(cell['fixed_probes'])} m in "
        f"{fmt.probe_steps(cell['fixed_probes'])} steps. "
        + ("The paper-numbers file has no per-cell displacement for this cell, so the paper's values cannot be set "
           "beside these from it" if not (pe or pf) else
           f"The paper's reference implementation: entropy {paper.entry_value(pe)} m, fixed {paper.entry_value(pf)} m")
        + ". Both of our rules choose probes that travel farther than fixed probes, so the difference between our "
        "entropy displacement and the paper's does not come from the `{calibrated}` changes (which alter which probe "
        "is chosen, not how far a probe moves); where it does come from is measured below.\n\n")
    out.append(table.markdown(["method", "probe steps", "displacement [m]", "paper displacement"],
                              [[f"`{m}`", fmt.probe_steps(x), fmt.displacement(x),
                                paper.cell_column(x, "mean_probe_displacement", 4)] for m, x in cell.items() if x]))
else:
    out.append("pick_cube / reference_seen with the expert was not run with both entropy and fixed probes.\n")
if a.displacement and os.path.exists(a.displacement):
    with open(a.displacement) as f:
        d = json.load(f)
    out.append(f"\n<!-- displacement slot: from {a.displacement} -->\n**The measured cause** (from `{a.displacement}`):\n\n"
               + d["summary"].rstrip() + "\n")
    r = d.get("rows") or []
    if r and isinstance(r[0], dict):
        keys = list(r[0].keys())
        out.append("\n" + table.markdown(keys, [[row.get(k) for k in keys] for row in r]))
    out.append("<!-- end of displacement slot -->\n")

# ---- cells per split
for split in sections.splits(c):
    out.append(f"\n## {split}\n\n")
    out.append(sections.cells_table(c, sections.ordered_cells(c, split=split)))

# ---- promotion audit
out.append("\n## Paired differences and promotion verdicts\n\n" + sections.PROMOTION_RULES + "\n\n")
out.append(sections.promotion_table(c))
one_side = [(p, x) for p in c.pairs for x in p["cells_with_one_side"]]
if one_side:
    out.append("\nCells where a pair has only one side (not compared): "
               + "; ".join(f"`{p['candidate']}` vs `{p['baseline']}` at {x['task']}/{x['split']}/{x['backbone']} "
                           f"(only `{x['present']}`)" for p, x in one_side) + ".\n")
if c.notes():
    out.append("\nNotes from `compare`: " + "; ".join(c.notes()) + "\n")
sys.stdout.write("".join(out))
