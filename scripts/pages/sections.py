"""Page sections shared by the tournament and learned-backbone pages: per-cell tables with the paper column, the
findings (every paper difference, with its status), and the promotion audit. Layout only."""
from . import findings, fmt, paper, table

# methods in page order; the project's variants sit right after the paper's rule they change
METHOD_ORDER = ["oracle", "entropy_probes", "entropy_probes{calibrated}", "dualabi", "dualabi{calibrated}",
                "fixed_probes", "random_probes", "exact_belief", "grammar_belief", "grammar_belief{probe=fixed}",
                "osi", "probe_osi", "recurrent_osi", "no_adapt"]
TASK_ORDER = ["pick_cube", "push_cube", "pull_cube", "stack_cube", "peg_insertion_side"]
SPLIT_ORDER = ["reference_seen", "reference_unseen_composition", "reference_long_lag", "seen", "unseen_composition",
               "long_lag"]
VARIANT = "{calibrated}"


def _key(order, x):
    return (order.index(x), x) if x in order else (len(order), x)


def methods(comparison, cells=None):
    """The method labels present, in page order."""
    return sorted(comparison.values("method", cells), key=lambda m: _key(METHOD_ORDER, m))


def tasks(comparison, cells=None):
    return sorted(comparison.values("task", cells), key=lambda t: _key(TASK_ORDER, t))


def splits(comparison, cells=None):
    return sorted(comparison.values("split", cells), key=lambda s: _key(SPLIT_ORDER, s))


def counterpart(comparison, cmp, variant=VARIANT):
    """The same comparison with the project's variant in place of each method that has one here
    (entropy_probes − fixed_probes -> entropy_probes{calibrated} − fixed_probes), or None."""
    def v(m):
        return m + variant if comparison.cell(cmp["task"], cmp["split"], m + variant, cmp["backbone"]) else m
    c, b = v(cmp["candidate"]), v(cmp["baseline"])
    if (c, b) == (cmp["candidate"], cmp["baseline"]):
        return None
    return comparison.comparison(c, b, cmp["task"], cmp["split"], cmp["backbone"])


def cells_table(comparison, cells, backbone_col=True):
    """One row per cell: success with Wilson interval, per-seed rates, the paper's rate and probe steps (compare's
    paper fields; none for a `{...}` label), probe steps, displacement, safety."""
    header = ["task", "split", "method"] + (["backbone"] if backbone_col else []) + [
        "success [Wilson 95 %]", "per seed", "paper", "probe steps", "paper probe steps", "displacement [m]",
        "safety: flagged (flags)"]
    rows = []
    for c in cells:
        rows.append([c["task"], c["split"], f"`{c['method']}`"] + ([c["backbone"]] if backbone_col else []) + [
            fmt.cell_rate(c), fmt.per_seed(c), paper.cell_column(c), fmt.probe_steps(c),
            paper.cell_column(c, "mean_probe_steps"), fmt.displacement(c), fmt.safety(c)])
    return table.markdown(header, rows)


def ordered_cells(comparison, backbone=None, split=None, task=None):
    kw = {k: v for k, v in (("backbone", backbone), ("split", split), ("task", task)) if v is not None}
    cs = comparison.cells_where(**kw)
    return sorted(cs, key=lambda c: (_key(TASK_ORDER, c["task"]), _key(SPLIT_ORDER, c["split"]),
                                     _key(METHOD_ORDER, c["method"]), c["backbone"]))


def paper_findings(comparison, numbers, backbones, methods_here=None):
    """Every difference of the paper-numbers file (no `variant`) whose two methods this page runs, for each backbone:
    (entry, backbone, comparison or None). methods_here: base names the page's experiment runs (default: those
    present in the comparison)."""
    here = set(methods_here or comparison.values("method"))
    out = []
    for e in numbers.entries:
        if e["kind"] != "difference" or e.get("variant") or e["candidate"] not in here or e["baseline"] not in here:
            continue
        for b in backbones:
            if e.get("backbones") is not None and b not in e["backbones"]:
                continue
            cmp = comparison.comparison(e["candidate"], e["baseline"], e["task"], e["split"], b)
            out.append((e, b, cmp))
    return out


def findings_table(comparison, numbers, backbones, methods_here=None):
    """The findings table: one row per paper difference and backbone; status by findings.status (the paper's rule,
    bare names) and, beside it, the same pair with the project's `{calibrated}` variant (no status: it is not
    the paper's method)."""
    rows = []
    for e, b, cmp in paper_findings(comparison, numbers, backbones, methods_here):
        st, why = findings.status(cmp, f"not run here ({e['task']}/{e['split']} with `{b}` has no paired "
                                       f"{e['candidate']} and {e['baseline']} cells)")
        var = counterpart(comparison, cmp) if cmp else None
        rows.append([f"{e['candidate']} − {e['baseline']}", e["task"], e["split"], b, e["source"],
                     paper.entry_diff_value(e), fmt.cmp_rates(cmp), fmt.cmp_diff(cmp), fmt.per_seed_diff(cmp),
                     findings.bold(st), why,
                     fmt.DASH if not var else f"{var['candidate']} − {var['baseline']}: {fmt.cmp_diff(var)}"])
    return table.markdown(["pair (paper's rule)", "task", "split", "backbone", "paper source", "paper difference",
                           "ours: candidate / baseline", "ours: difference [95 %]", "ours: per seed", "status",
                           "reason", "with `{calibrated}`: difference [95 %]"], rows)


def promotion_table(comparison, comparisons=None):
    """The promotion audit: every pair × cell with its paired difference, the paper's, sign agreement and the
    promotion gate's verdict, rule and reason (all from compare)."""
    rows = []
    for x in comparison.comparisons if comparisons is None else comparisons:
        v, rule, reason = fmt.promotion(x)
        rows.append([f"`{x['candidate']}` − `{x['baseline']}`", x["task"], x["split"], x["backbone"], x["pairs"],
                     x["seeds"], fmt.cmp_rates(x), fmt.cmp_diff(x), fmt.per_seed_diff(x),
                     f"{fmt.num(x['promotion']['candidate_probe_steps'], 2)} / {fmt.num(x['promotion']['baseline_probe_steps'], 2)}",
                     paper.cmp_column(x), x.get("sign_agreement") or fmt.DASH, findings.bold(v), f"`{rule}`", reason])
    return table.markdown(["pair", "task", "split", "backbone", "pairs", "seeds", "candidate / baseline",
                           "difference [95 %]", "per seed", "probe steps (cand. / base.)", "paper difference",
                           "same sign as the paper's", "verdict", "rule", "reason"], rows)


PROMOTION_RULES = ("Promotion rules (`include/actionshift/eval/gates.hpp`, applied by compare): a one-seed result under 0.3 "
                   "is pruned; a safety regression rejects; fewer than three matched seeds asks for more seeds; otherwise "
                   "the candidate is promoted on >= 5 points over its matched baseline with the paired 95 % interval above "
                   "0, or on a success-vs-probe-cost Pareto point; else rejected. Every verdict is listed with the rule that "
                   "decided it and the gate's reason. \"Same sign\" is shown only where the paper's difference is "
                   "significant and ours excludes 0 (compare's `sign_agreement`).")

STATUS_RULE = ("Status rule (`scripts/pages/findings.py`, from compare's fields only): where the paper's difference is "
               "significant, **reproduced** when ours excludes 0 with the same sign, **contradicted** when ours includes 0 "
               "or has the other sign; where the paper's is a tie, **reproduced** when ours includes 0 too, "
               "**contradicted** when ours excludes 0; **untestable** when the cell was not run here or the paper gives "
               "no interval. Every difference of configs/paper/numbers.json whose two methods this page runs is listed; "
               "entries sourced to the reference implementation are not printed in the paper. The `{calibrated}` column "
               "is the project's corrected rule on the same pair: not the paper's method, so it gets no status.")


def headline_table(comparison, backbones, task="pick_cube", split="reference_seen"):
    """entropy − fixed probes in one cell, both probe rules, each backbone, beside the paper's difference."""
    rows = []
    for b in backbones:
        base = comparison.comparison("entropy_probes", "fixed_probes", task, split, b)
        for cand in ("entropy_probes", "entropy_probes" + VARIANT):
            x = comparison.comparison(cand, "fixed_probes", task, split, b)
            if cand == "entropy_probes":
                st, why = findings.status(x)
                st = findings.bold(st)
            else:
                st, why = fmt.DASH, "not the paper's method (no status)" if x else "not run here"
            rows.append([f"`{cand}` − `fixed_probes`", b, fmt.cmp_rates(x), fmt.cmp_diff(x), fmt.per_seed_diff(x),
                         paper.cmp_column(base), st, why])
    return table.markdown(["pair", "backbone", "candidate / baseline", "ours [95 %]", "per seed",
                           "paper (the paper's rule)", "status", "reason"], rows)
