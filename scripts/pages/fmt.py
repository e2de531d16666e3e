"""Formatting of compare's numbers. Nothing is computed here: each function prints fields compare wrote."""

DASH = "—"


def num(x, digits=3):
    """A number with fixed decimals; None is a dash."""
    return DASH if x is None else f"{x:.{digits}f}"


def signed(x, digits=3):
    """A signed number (+0.058, -0.010, +0.000); None is a dash."""
    return DASH if x is None else f"{x:+.{digits}f}"


def interval(lo, hi, digits=3, sign=False):
    f = signed if sign else num
    return f"[{f(lo, digits)}, {f(hi, digits)}]"


def rate(w, digits=3):
    """A Wilson interval object {rate, lower, upper, ...} as `0.987 [0.974, 0.993]`; None is a dash."""
    if not w:
        return DASH
    return f"{num(w['rate'], digits)} {interval(w['lower'], w['upper'], digits)}"


def cell_rate(cell, digits=3):
    """A compare cell's success_once with its Wilson interval; a missing cell is a dash."""
    return DASH if not cell else rate(cell["success_once"], digits)


def cell_point(cell, digits=3):
    """A compare cell's success_once point estimate."""
    return DASH if not cell else num(cell["success_once"]["rate"], digits)


def n_of(cell):
    """`k/n` successes of a cell."""
    return DASH if not cell else f"{cell['success_once']['successes']}/{cell['success_once']['total']}"


def diff(d, digits=3):
    """A paired bootstrap object {estimate, lower, upper, ...} as `+0.058 [+0.037, +0.082]`; None is a dash."""
    if not d:
        return DASH
    return f"{signed(d['estimate'], digits)} {interval(d['lower'], d['upper'], digits, sign=True)}"


def cmp_diff(cmp, digits=3, mark=False):
    """A comparison's difference; with mark, ` (excludes 0)` when compare says it does."""
    if not cmp:
        return DASH
    s = diff(cmp["difference"], digits)
    return s + (" (excludes 0)" if mark and cmp["difference"]["excludes_zero"] else "")


def cmp_rates(cmp, digits=3):
    """`candidate / baseline` success over the comparison's pairs."""
    return DASH if not cmp else f"{num(cmp['candidate_success'], digits)} / {num(cmp['baseline_success'], digits)}"


def per_seed(cell, digits=3):
    """A cell's per-seed rates `0.985 / 0.990 / 0.985` (ascending seed, as compare lists them)."""
    return DASH if not cell else " / ".join(num(s["rate"], digits) for s in cell["per_seed"])


def per_seed_diff(cmp, digits=3):
    """A comparison's per-seed differences `+0.010 / -0.005 / +0.020`."""
    return DASH if not cmp else " / ".join(signed(s["difference"], digits) for s in cmp["per_seed"])


def probe_steps(cell, digits=2):
    return DASH if not cell else num(cell["mean_probe_steps"], digits)


def displacement(cell, digits=4):
    """Mean probe displacement per episode [m]."""
    return DASH if not cell else num(cell["mean_probe_displacement"], digits)


def safety(cell, digits=3):
    """`0.012 (workspace_violation 7)`: the rate of flagged episodes and the episodes per flag; `0.000` when none."""
    if not cell:
        return DASH
    s = cell["safety"]
    flags = ", ".join(f"{k} {v['episodes']}" for k, v in sorted(s["flags"].items()))
    return num(s["rate"], digits) + (f" ({flags})" if flags else "")


def promotion(cmp):
    """(verdict, rule, reason) of a comparison's promotion gate; dashes when missing."""
    if not cmp:
        return DASH, DASH, DASH
    p = cmp["promotion"]
    return p["verdict"], p["rule"], p["reason"]


def seeds_text(seeds):
    """`20260718, 20260719, 20260720`."""
    return ", ".join(str(s) for s in seeds) if seeds else DASH


def thousands(n):
    return f"{n:,}"
