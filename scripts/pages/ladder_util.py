"""Helpers of the ladder page (scripts/ladder_report.py): the compare runs of its groups (scripts/ladder_groups.py)
side by side, what a grammar_belief label ran (read from the label), the per-contract rates of a cell (compare's
`per_contract` field) and the paper's ladder numbers by id. Layout only: nothing here computes a statistic."""
import json
import os

from . import fmt, table
from .compare import load_comparison

PER_CONTRACT_MISSING = "per-contract rates need actionshift compare with per_contract"


class Groups:
    """One compare JSON per group (`<dir>/<group>.json`), looked up by (group, task, split, label)."""

    def __init__(self, compare_dir, order=("live", "pool_full", "identity")):
        self.by_name = {}
        for name in order:
            p = os.path.join(compare_dir, name + ".json")
            if os.path.exists(p):
                self.by_name[name] = load_comparison(p)
        if not self.by_name:
            raise SystemExit(f"ladder: no compare JSON (<group>.json) in {compare_dir}")

    def get(self, group):
        return self.by_name.get(group)

    def cell(self, group, task, split, label):
        c = self.by_name.get(group)
        return None if c is None else c.cell(task, split, label)

    def comparison(self, group, candidate, baseline, task, split):
        c = self.by_name.get(group)
        return None if c is None else c.comparison(candidate, baseline, task, split)

    def items(self):
        return list(self.by_name.items())


def params_of(label):
    """{key: value} of a label's `{...}` suffix (a named variant is a key with value '')."""
    _, _, rest = label.partition("{")
    return dict(kv.split("=", 1) if "=" in kv else (kv, "") for kv in rest.rstrip("}").split(",") if kv)


def describe(label):
    """What a label ran, in words, read from the label (docs/adapters.md, "Method names and variants")."""
    base = label.partition("{")[0]
    p = params_of(label)
    if base == "grammar_belief":
        probe = p.pop("probe", "none")
        rounds = p.pop("hold_rounds", "1")
        words = {"none": "passive (no probes)", "fixed": "6 fixed pulses", "entropy": "6 entropy-chosen pulses",
                 "hold": f"hold probe h2-r{rounds}"}.get(probe, f"probe={probe}")
        if probe != "hold" and rounds != "1":
            words += f", hold_rounds={rounds}"
        if p.pop("after_probe", None) == "identity":
            words += ", then identity (the belief never acts)"
        if p.pop("scale_correction", None) == "true":
            words += " + scale corrector"
        if p.pop("gripper_channel", None) == "true":
            words += " + finger channel (v2)"
        else:
            words += " (v1: no finger channel)"
        extra = ", ".join(f"{k}={v}" for k, v in sorted(p.items()))
        return words + (f"; {extra}" if extra else "")
    if base in ("entropy_probes", "dualabi"):
        rule = "the project's calibrated probe rule" if "calibrated" in p else "the paper's probe rule"
        return ("pool belief + 6 entropy-chosen probes, " if base == "entropy_probes" else "pool belief, DualABI, ") + rule
    return {"exact_belief": "pool belief, passive", "oracle": "the true contract inverted", "no_adapt": "no adaptation"}.get(base, label)


def per_contract(cell):
    """compare's per-contract entries of a cell ([{contract_index, contract_sha256, episodes, successes,
    success_once}]), or None when this compare does not write the field (or the cell was not run)."""
    if not cell:
        return None
    return cell.get("per_contract")


def contract_entry(cell, index):
    """The per-contract entry of one contract index, or None."""
    for e in per_contract(cell) or []:
        if e["contract_index"] == index:
            return e
    return None


def contract_rate(cell, index, have_field):
    """One contract's success with its Wilson interval and n, from per_contract; the reason when it cannot be shown."""
    if not cell:
        return "not run"
    if not have_field:
        return PER_CONTRACT_MISSING
    e = contract_entry(cell, index)
    if not e:
        return "no episode of this contract"
    return f"{fmt.rate(e['success_once'])} (n={e['episodes']})"


def has_per_contract(groups):
    """True when every cell of every group's compare JSON carries per_contract (a compare with the field)."""
    cells = [c for _, g in groups.items() for c in g.cells]
    return bool(cells) and all("per_contract" in c for c in cells)


def manifest_contracts(split, root):
    """[(sha256, contract dict)] of a split's test contracts (manifests/<split>.json), in contract-index order; []
    when the manifest is not committed."""
    p = os.path.join(root, "manifests", split + ".json")
    if not os.path.exists(p):
        return []
    with open(p) as f:
        m = json.load(f)
    return [(e["sha256"], e["contract"]) for e in m["test"]]


def contract_class(contract):
    """`tool, absolute, inverted` (frame, target, gripper)."""
    return (f"{contract['frame']}, {contract['target']}, "
            f"{'inverted' if contract['gripper_inverted'] else 'not inverted'}")


def paper_ids(numbers, task, split, suffixes):
    """The paper's entries for a row: for each id suffix, `s5.4.<task>.<split>.<suffix>` (printed in the paper) or
    `ref.<task>.<split>.<suffix>` (the reference implementation's write-up); those present, in order."""
    out = []
    for s in suffixes:
        for prefix in ("s5.4", "ref"):
            e = numbers.by_id(f"{prefix}.{task}.{split}.{s}")
            if e:
                out.append(e)
                break
    return out


def entry_text(e, digits=3):
    """`0.722 (§5.4)` or `0.697 [0.659, 0.732] (reference implementation)`."""
    s = fmt.num(e["value"], digits)
    if e.get("interval"):
        s += " " + fmt.interval(e["interval"][0], e["interval"][1], digits)
    src = e["source"]
    if src.startswith("reference implementation"):
        src = "reference implementation, not in the paper"
    return f"{s} ({src})"


def per_contract_table(rows, have_field):
    """rows: (row text, cell, contract index, contract text, paper entry or None). A table of per-contract rates from
    compare's per_contract; without the field every rate says what is needed."""
    out = []
    for text, cell, idx, ctext, pe in rows:
        out.append([text, ctext, contract_rate(cell, idx, have_field), entry_text(pe) if pe else fmt.DASH])
    return table.markdown(["row", "contract", "ours: success (Wilson 95 %)", "paper"], out)
