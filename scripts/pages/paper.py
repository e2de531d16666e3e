"""The paper column. Cells and comparisons of a compare JSON carry the paper's entries (`paper` fields); pages
whose cells are not the paper's (e.g. Gate 1 on the generated splits, set beside the paper's reference
contracts) look entries up in configs/paper/numbers.json with the same matching rule compare uses. The
paper's numbers are never typed in a page script."""
import json
import os

from . import fmt

NUMBERS = os.path.join(os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))),
                       "configs", "paper", "numbers.json")


def entry_value(e, digits=3):
    """An entry's value with its interval when the paper gives one: `0.987 [0.974, 0.993]`, `6.00` for steps."""
    if not e:
        return fmt.DASH
    if e.get("unit") == "steps":
        digits = 2
    elif e.get("unit") == "m":
        digits = 4
    s = fmt.num(e["value"], digits)
    if e.get("interval"):
        s += " " + fmt.interval(e["interval"][0], e["interval"][1], digits)
    return s


def cell_entry(cell, quantity="success_once"):
    """The paper's entry compare attached to a cell for `quantity`, or None (no cell, no entry, or a `{...}` label)."""
    return None if not cell else cell.get("paper", {}).get(quantity)


def cell_column(cell, quantity="success_once", digits=3):
    """The paper column of a cell: its value with interval, or a dash."""
    return entry_value(cell_entry(cell, quantity), digits)


def diff_value(p, digits=3):
    """A comparison's paper field {value, interval, significant, ...} (oriented candidate − baseline by compare) as
    `+0.058 [+0.037, +0.082]`, `+0.025 (ns, no interval)` or `+0.058 (no interval)`."""
    if not p:
        return fmt.DASH
    s = fmt.signed(p["value"], digits)
    if p.get("interval"):
        return s + " " + fmt.interval(p["interval"][0], p["interval"][1], digits, sign=True)
    if p.get("significant") is False:
        return s + " (ns, no interval)"
    return s + " (no interval)"


def cmp_column(cmp, digits=3):
    """The paper column of a comparison."""
    return fmt.DASH if not cmp else diff_value(cmp.get("paper"), digits)


def source(e):
    """Where in the paper an entry (or a comparison's paper field) comes from."""
    if not e:
        return fmt.DASH
    e = e.get("entry", e)
    return e.get("source", fmt.DASH)


class Numbers:
    """configs/paper/numbers.json (or another file of that format)."""

    def __init__(self, path=NUMBERS):
        with open(path) as f:
            self.data = json.load(f)
        self.path = path
        self.entries = self.data["entries"]
        self._by_id = {e["id"]: e for e in self.entries}

    def by_id(self, entry_id):
        return self._by_id.get(entry_id)

    def find_cell(self, quantity, task, split, method, backbone):
        """The entry compare would attach to the cell (task, split, method, backbone): kind `cell`, no `variant`,
        an entry listing `backbone` before one listing none; None for a label with `{...}`."""
        if "{" in method:
            return None
        any_backbone = None
        for e in self.entries:
            if (e["kind"] != "cell" or e.get("variant") or e["quantity"] != quantity or e.get("task") != task
                    or e.get("split") != split or e.get("method") != method):
                continue
            bbs = e.get("backbones")
            if bbs is None:
                any_backbone = any_backbone or e
            elif backbone in bbs:
                return e
        return any_backbone

    def find_difference(self, task, split, candidate, baseline, backbone):
        """The difference entry candidate − baseline compare would attach (no `variant`; a backbone-listing entry
        first) and whether it is stored reversed (baseline − candidate); (None, False) when none."""
        if "{" in candidate or "{" in baseline:
            return None, False
        found = None
        for e in self.entries:
            if e["kind"] != "difference" or e.get("variant") or e.get("task") != task or e.get("split") != split:
                continue
            if (e["candidate"], e["baseline"]) == (candidate, baseline):
                rev = False
            elif (e["candidate"], e["baseline"]) == (baseline, candidate):
                rev = True
            else:
                continue
            bbs = e.get("backbones")
            if bbs is not None and backbone in bbs:
                return e, rev
            if bbs is None and found is None:
                found = (e, rev)
        return found or (None, False)


def entry_diff_value(e, reversed_=False, digits=3):
    """A numbers.json difference entry as `+0.058 [+0.037, +0.082]`, oriented candidate − baseline (negated when
    reversed_: a sign flip of what the paper printed, not a computation)."""
    if not e:
        return fmt.DASH
    s = -1 if reversed_ else 1
    p = {"value": s * e["value"], "significant": e.get("significant"),
         "interval": None if not e.get("interval") else sorted([s * e["interval"][0], s * e["interval"][1]])}
    return diff_value(p, digits)


def load_numbers(path=NUMBERS):
    return Numbers(path)
