#!/usr/bin/env python3
"""Writes docs/results/brittleness.md: per task and backbone, clean success (Gate 0's unwrapped runs, one
verdict file per seed), hidden with no adaptation, and restored by each adapter label, beside the paper's
numbers. Layout only: every rate, interval, difference and verdict is from `actionshift compare` (the
cells and the pairs of scripts/brittleness.pairs) or from a Gate 0 verdict file; the paper's numbers from
compare's paper fields or, for the Diffusion Policy scalars, configs/paper/numbers.json by id.
usage: scripts/brittleness_report.py COMPARE_JSON RESULTS_DIR [--commit C --command CMD --wall S --cores N --cpu TIMES]"""
import glob
import json
import os
import re
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from pages import findings, fmt, load_comparison, paper, provenance, table  # noqa: E402
from pages.rest_util import cpu_text, commit_of, parser, probe_rule, rel, scalar  # noqa: E402

BACKBONES = [("expert", "scripted"), ("mlp", "imitation (DAgger MLP)"), ("ppo", "RL (PPO)")]
ORDER = ["no_adapt", "oracle", "entropy_probes", "entropy_probes{calibrated}", "dualabi", "dualabi{calibrated}",
         "grammar_belief"]
DP_IDS = ["s5.8.pick_cube.diffusion_policy.clean_success", "s5.8.push_cube.diffusion_policy.clean_success",
          "s5.8.diffusion_policy.no_adapt", "abstract.no_adapt.success_once_floor_min", "abstract.no_adapt.success_once_floor_max",
          "s5.8.diffusion_policy.restored_success_min", "s5.8.diffusion_policy.restored_success_max",
          "s5.8.diffusion_policy.dualabi.probe_steps_seen"]


def main():
    ap = parser(__doc__)
    ap.add_argument("compare")
    ap.add_argument("results")
    a = ap.parse_args()
    C = load_comparison(a.compare)
    numbers = paper.load_numbers()
    res = rel(a.results)
    specs = provenance.job_specs([a.results], C.jobs())
    clean = {}  # (backbone, task) -> [(seed, cell of the verdict file)]
    for f in sorted(glob.glob(os.path.join(a.results, "clean", "*.json"))):
        with open(f) as fh:
            v = json.load(fh)
        for c in v["cells"].values():
            clean.setdefault((c["backbone"], c["task"]), []).append((c["seed"], c))
    out = [provenance.header(
        "Brittleness: scripted, imitation and RL backbones under the same hidden contracts",
        "scripts/brittleness_report.py", a.command or f"scripts/brittleness {res}", commit_of(a), [res],
        provenance.spec_values(specs, "profile"), C.seeds(), C.episodes(), jobs=len(C.jobs()),
        episodes_per_seed=C.episodes_per_seed(), wall=a.wall, cores=a.cores, paper_source=C.paper_source(),
        bootstrap=C.bootstrap(),
        extra=[f"CPU: {cpu_text(a.cpu)[2:] or 'not measured'}.",
               "Clean: Gate 0's unwrapped run (`actionshift gate0 --seed S`, one verdict file per seed in "
               f"`{res}/clean/`), shown per seed with the Wilson interval the verdict file holds (compare does not read "
               "verdict files, so no pooled clean rate is shown)."])]
    w = out.append
    w("The paper's claim (§5.8): brittleness is interface-semantic, not paradigm-specific. A frozen imitation policy\n"
      "(Diffusion Policy) collapses under the same hidden contracts that zero the frozen PPO policy, and the same\n"
      "policy-agnostic adapters restore it to its own oracle ceiling. Here each backbone runs clean, behind the hidden\n"
      "contracts of `reference_seen` with no adaptation, and through the same adapters: the oracle, entropy probing and\n"
      "DualABI over the `reference9` pool, each with the paper's probe rule (the bare name) and the project's\n"
      "`{calibrated}` rule (docs/adapters.md), and the pool-free grammar belief. What each label ran is read from the\n"
      "label (column `what ran`). The paper column is the paper's frozen PPO (Table 2, Table 5) for the bare labels;\n"
      "a `{...}` label has no paper number.\n")
    for task in C.values("task"):
        w(f"## {task}\n")
        rows = []
        for bb, paradigm in BACKBONES:
            cells = C.cells_where(task=task, backbone=bb)
            if not cells and (bb, task) not in clean:
                continue
            for seed, v in clean.get((bb, task), []):
                rows.append([f"`{bb}`", paradigm, "clean (Gate 0, unwrapped)", f"seed {seed}",
                             fmt.rate(v["competence"]["interval"]), fmt.DASH, fmt.DASH, fmt.DASH,
                             paper.entry_value(numbers.by_id(f"table1.{task}.clean_success"))])
            labels = [m for m in ORDER if C.cell(task, "reference_seen", m, bb)]
            labels += [m for m in C.values("method", cells) if m not in labels]
            for m in labels:
                c = C.cell(task, "reference_seen", m, bb)
                if not c:
                    continue
                rows.append([f"`{bb}`", paradigm, f"`{m}`", probe_rule(m) if probe_rule(m) != m else fmt.DASH, fmt.cell_rate(c), fmt.per_seed(c),
                             fmt.probe_steps(c), fmt.safety(c), paper.cell_column(c)])
        w(table.markdown(["backbone", "paradigm", "label", "what ran", "success (Wilson 95 %)", "per seed",
                          "probe steps", "flagged episodes", "paper (frozen PPO)"], rows,
                         ["l", "l", "l", "l", "l", "l", "r", "l", "l"]))
        w("")
    w("## Paired differences\n")
    w("Every pair of `scripts/brittleness.pairs` in every backbone that ran both labels (candidate − baseline over the same"
      " episodes), with the promotion gate's verdict and the paper's difference where the paper gives one.\n")
    rows = []
    for cmp in C.comparisons:
        v, rule, _ = fmt.promotion(cmp)
        rows.append([cmp["task"], f"`{cmp['backbone']}`", f"`{cmp['candidate']}` − `{cmp['baseline']}`", fmt.cmp_rates(cmp),
                     fmt.cmp_diff(cmp, mark=True), fmt.per_seed_diff(cmp), paper.cmp_column(cmp), f"{v} ({rule})"])
    w(table.markdown(["task", "backbone", "pair", "success: candidate / baseline", "difference [95 %]", "per seed",
                      "paper", "promotion"], rows))
    w("")
    w("## The paper's findings\n")
    w("Status from compare's fields (scripts/pages/findings.py): a finding whose paper difference is significant is"
      " reproduced only when ours excludes 0 with the same sign (compare's `sign_agreement`).\n")
    items = [(f"the hidden contract collapses `{c['backbone']}` and the oracle restores it ({c['task']})", c)
             for c in C.comparisons_where(candidate="oracle", baseline="no_adapt")]
    items += [(f"{findings.describe(c)} (`{c['backbone']}`)", c) for c in C.comparisons
              if c.get("paper") and c["candidate"] != "oracle"]
    w(findings.findings_table(items) if items else "No pair with a paper difference was run.\n")
    w("")
    w("## The paper's Diffusion Policy numbers (§5.8)\n")
    w("The paper's imitation backbone is a Diffusion Policy (ours: the DAgger MLP). From configs/paper/numbers.json by id:\n")
    rows = [[f"`{i}`", (numbers.by_id(i) or {}).get("quantity", fmt.DASH), scalar(numbers, i),
             (numbers.by_id(i) or {}).get("note", "")] for i in DP_IDS]
    w(table.markdown(["id", "quantity", "value (source)", "note"], rows))
    w("")
    w("## Backbone identities\n")
    sha = sorted({(s["backbone"]["name"], s["task"], s["backbone"]["sha256"]) for s in specs})
    w(table.markdown(["backbone", "task", "sha256"], [[f"`{b}`", t, f"`{h}`"] for b, t, h in sha]))
    print(re.sub(r"\n{3,}", "\n\n", "\n".join(out)).rstrip("\n"))


if __name__ == "__main__":
    main()
