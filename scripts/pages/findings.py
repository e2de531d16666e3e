"""The status of a paper finding, decided only by fields compare wrote (docs/formats.md "Comparison"):

- the paper's difference is significant (its interval excludes 0): **reproduced** when ours excludes 0 with
  the same sign (compare's `sign_agreement` is "same"); **contradicted** when ours excludes 0 with the other
  sign, or includes 0 (the reason gives both intervals);
- the paper's difference is not significant (a tie): **reproduced** when ours includes 0 too; **contradicted**
  when ours excludes 0;
- **untestable** when the cell was not run here, the paper has no difference for the pair, or the paper gives
  no interval and no significance (the reason says which).

"Same sign" is claimed only through `sign_agreement`, which compare sets only against a significant paper
difference."""
from . import fmt, paper, table

REPRODUCED, CONTRADICTED, UNTESTABLE = "reproduced", "contradicted", "untestable"
INCONCLUSIVE = "inconclusive"  # a page rule's status when its data neither reproduce nor contradict the claim


def status(cmp, missing="the cell was not run here"):
    """(status, reason) for one comparison (None: not run)."""
    if not cmp:
        return UNTESTABLE, missing
    p = cmp.get("paper")
    ours = fmt.diff(cmp["difference"])
    if not p:
        return UNTESTABLE, cmp.get("sign_agreement_reason") or "the paper has no difference for this pair here"
    theirs = paper.diff_value(p)
    excl = cmp["difference"]["excludes_zero"]
    if p.get("significant") is True:
        if cmp.get("sign_agreement") == "same":
            return REPRODUCED, f"our difference {ours} excludes 0 with the sign of the paper's {theirs}"
        if cmp.get("sign_agreement") == "different":
            return CONTRADICTED, f"our difference {ours} excludes 0 with the opposite sign of the paper's {theirs}"
        return CONTRADICTED, f"our difference {ours} includes 0 where the paper's {theirs} excludes it"
    if p.get("significant") is False:
        if not excl:
            return REPRODUCED, f"our difference {ours} includes 0, as the paper's {theirs} (a tie)"
        return CONTRADICTED, f"our difference {ours} excludes 0 where the paper's {theirs} is a tie"
    note = p.get("entry", {}).get("note", "")
    return UNTESTABLE, f"the source gives {fmt.signed(p['value'])} without an interval or significance" + (f" ({note})" if note else "")


def bold(s):
    return f"**{s}**"


def rows(items):
    """Table rows for findings. items: (finding text, comparison or None[, reason when missing]). Columns:
    finding | source | paper | candidate / baseline | ours [95 %] | per seed | status | reason."""
    out = []
    for it in items:
        text, cmp = it[0], it[1]
        st, why = status(cmp, *(it[2:3]))
        p = cmp.get("paper") if cmp else None
        out.append([text, paper.source(p) if p else fmt.DASH, paper.diff_value(p), fmt.cmp_rates(cmp),
                    fmt.cmp_diff(cmp), fmt.per_seed_diff(cmp), bold(st), why])
    return out


HEADER = ["finding", "source", "paper (cand. − base.)", "ours: candidate / baseline", "ours: difference [95 %]",
          "ours: per seed", "status", "reason"]


def findings_table(items):
    """The findings as a Markdown table (see rows)."""
    return table.markdown(HEADER, rows(items))


def paper_differences(comparison, backbone, pairs=None):
    """Every comparison of `backbone` that carries a paper difference (a paper finding testable here), in compare's
    order; with pairs (a set of (candidate, baseline)), only those."""
    return [c for c in comparison.comparisons if c["backbone"] == backbone and c.get("paper")
            and (pairs is None or (c["candidate"], c["baseline"]) in pairs)]


def describe(cmp):
    """`entropy_probes − fixed_probes, pick_cube / reference_seen`."""
    return f"{cmp['candidate']} − {cmp['baseline']}, {cmp['task']} / {cmp['split']}"
