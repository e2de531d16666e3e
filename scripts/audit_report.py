#!/usr/bin/env python3
"""The audit benchmark's page (docs/results/audit.md) and its coverage plot, from the JSON of
`actionshift audit --json` that scripts/audit_benchmark wrote (each with a `bench` block: the recorded
contract, split, noise, seed, length, declaration). Counting only: which verdicts committed, which were
wrong, which fields resolved and whether to the recorded value. `--choose DIR` prints the pilot's chosen
(floor, gain tolerance) pair, the only thresholds the benchmark chooses."""
import argparse
import glob
import json
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from pages import table  # noqa: E402

try:  # the statistics engine's Wilson interval (the Python module of a build: PYTHONPATH=<build>/python)
    from actionshift import wilson_interval  # noqa: E402
except ImportError:  # --choose needs no interval; the page does
    def wilson_interval(k, n):
        sys.exit("audit_report.py: the page's intervals need the actionshift module (PYTHONPATH=<build>/python)")

GRAMMAR_PER_CHANNEL = ("permutation", "sign", "scale")
FIELDS = ("permutation", "sign", "scale", "target", "frame", "lag", "gripper_inverted", "gripper_range", "rotation", "action")


def truth_value(truth, field):
    """The recorded conventions' value of a field, in the audit's identified-value format."""
    c = truth["contract"]
    if field == "permutation":
        return [str(x) for x in c["permutation"]]
    if field == "sign":
        return [str(x) for x in c["sign"]]
    if field == "scale":
        return [repr(float(x)) for x in c["scale"]]
    if field == "target":
        return c["target"]
    if field == "frame":
        return c["frame"]
    if field == "lag":
        return str(c["lag"])
    if field == "gripper_inverted":
        return "inverted (+1 closes)" if c["gripper_inverted"] else "not inverted (+1 opens)"
    if field == "gripper_range":
        return truth.get("gripper_range", "[-1, 1]")
    if field == "rotation":
        return truth.get("rotation", "axis_angle")
    return truth.get("action", "command")


def field_outcome(a, field):
    """(resolved, correct) of a checked field: per-channel fields count channels, the others are one
    value. None when the field was not checked."""
    f = a["fields"][field]
    if not f["checked"]:
        return None
    t = truth_value(a["bench"]["truth"], field)
    if field in GRAMMAR_PER_CHANNEL:
        got = [x.strip() for x in f["identified"].strip("()").split(",")]
        res = [g != "?" for g in got]
        ok = [tv in g.split("|") for g, tv in zip(got, t) if g != "?"]
        return sum(res), len(got), sum(ok), len(ok)
    return (1 if f["resolved"] else 0), 1, (1 if f["resolved"] and f["identified"] == t else 0), (1 if f["resolved"] else 0)


def verdict_wrong(a):
    """A committed verdict is wrong if PASS while a checked field of the truth differs from the
    declaration, or MISMATCH while the truth is the declaration or any resolved field (channel) is not the
    recorded value."""
    status = a["status"]
    if status == "INCONCLUSIVE":
        return None
    declared_is_truth = a["bench"]["declared_as"] == "truth"
    any_wrong = False
    for field in FIELDS:
        o = field_outcome(a, field)
        if o is not None and o[2] != o[3]:
            any_wrong = True
    if status == "PASS":
        if declared_is_truth:
            return any_wrong
        # identity declared: PASS is right only if every checked field of the truth is identity's
        for field in FIELDS:
            f = a["fields"][field]
            if f["checked"] and f["declared"] != (
                    "(" + ", ".join(truth_value(a["bench"]["truth"], field)) + ")" if field in GRAMMAR_PER_CHANNEL
                    else truth_value(a["bench"]["truth"], field)):
                return True
        return any_wrong
    return declared_is_truth or any_wrong


def load(d):
    out = []
    for p in sorted(glob.glob(os.path.join(d, "**", "*.json"), recursive=True)):
        with open(p) as f:
            out.append(json.load(f))
    return out


def pilot_table(pilot):
    """(floor, tolerance) -> [audits, committed, wrong]."""
    by = {}
    for a in pilot:
        key = (a["bench"]["floor"], a["bench"]["gain_tolerance"])
        w = verdict_wrong(a)
        by.setdefault(key, [0, 0, 0])
        by[key][0] += 1
        if w is not None:
            by[key][1] += 1
            by[key][2] += int(w)
    return by


def choose(pilot_dir):
    """The pair with no wrong committed pilot verdict and the highest pilot coverage (ties: the larger
    floor, then the smaller tolerance); with none clean, the fewest wrong."""
    by = pilot_table(load(pilot_dir))
    return min(by, key=lambda k: (by[k][2], -by[k][1], -k[0], k[1]))


def fmt_floor(x):
    return repr(float(x)).rstrip("0").rstrip(".") if "e" not in repr(float(x)) else repr(float(x))


def interval(k, n):
    """k/n with its Wilson 95 % interval (the statistics engine's), or a dash for n = 0."""
    if n == 0:
        return "—"
    w = wilson_interval(k, n)
    return f"{w['rate']:.3f} [{max(w['lower'], 0.0):.3f}, {min(w['upper'], 1.0):.3f}]"


def summary_rows(audits, lengths):
    rows = []
    stats = {}
    for L in lengths:
        sel = [a for a in audits if a["bench"]["length"] == L]
        n = len(sel)
        committed = [a for a in sel if a["status"] != "INCONCLUSIVE"]
        wrong = sum(1 for a in committed if verdict_wrong(a))
        passes = sum(1 for a in sel if a["status"] == "PASS")
        mism = sum(1 for a in sel if a["status"] == "MISMATCH")
        cov = len(committed) / n if n else 0.0
        stats[L] = (n, len(committed), wrong, cov)
        rows.append([str(L), str(n), str(passes), str(mism), str(n - len(committed)), interval(len(committed), n),
                     f"{wrong} / {len(committed)}", interval(wrong, len(committed))])
    return rows, stats


GROUPS = (("reference/expert", "reference splits, scripted expert"), ("reference/ppo", "reference splits, learned PPO"),
          ("generated/expert", "generated splits (the full pool's test contracts), scripted expert"))


def group_rows(audits, lengths):
    """Per group of logs and length: audits, coverage and wrong / committed with their intervals."""
    rows = []
    for g, text in GROUPS:
        for L in lengths:
            sel = [a for a in audits if a["bench"].get("group", "reference/expert") == g and a["bench"]["length"] == L]
            if not sel:
                continue
            committed = [a for a in sel if a["status"] != "INCONCLUSIVE"]
            wrong = sum(1 for a in committed if verdict_wrong(a))
            rows.append([text, str(L), str(len(sel)), interval(len(committed), len(sel)), f"{wrong} / {len(committed)}",
                         interval(wrong, len(committed))])
    return rows


def wrong_rows(audits):
    """Every wrong committed verdict: the log, the declaration, the verdict and each field it got wrong (identified
    against recorded)."""
    rows = []
    for a in audits:
        if not verdict_wrong(a):
            continue
        b = a["bench"]
        bad = []
        for f in FIELDS:
            o = field_outcome(a, f)
            if o is not None and o[2] != o[3]:
                t = truth_value(b["truth"], f)
                bad.append(f"`{f}` {a['fields'][f]['identified']} (recorded {'(' + ', '.join(t) + ')' if isinstance(t, list) else t})")
        if a["status"] == "MISMATCH" and b["declared_as"] == "truth" and not bad:
            bad.append("MISMATCH although the declaration is the recorded contract")
        rows.append([b.get("group", "reference/expert"), f"`{b['split']}` c{b['contract']}", str(b["noise"]), str(b["seed"]),
                     str(b["length"]), b["declared_as"], a["status"], "; ".join(bad) or "PASS against a different recording"])
    return rows


def split_rows(audits, length):
    """The generated group per split at one length: which kinds of contract the audit commits on."""
    rows = []
    for split in sorted({a["bench"]["split"] for a in audits if a["bench"].get("group") == "generated/expert"}):
        sel = [a for a in audits if a["bench"].get("group") == "generated/expert" and a["bench"]["split"] == split
               and a["bench"]["length"] == length]
        committed = [a for a in sel if a["status"] != "INCONCLUSIVE"]
        wrong = sum(1 for a in committed if verdict_wrong(a))
        contracts = len({a["bench"]["contract"] for a in sel})
        rows.append([f"`{split}`", str(contracts), str(len(sel)), interval(len(committed), len(sel)), f"{wrong} / {len(committed)}"])
    return rows


def field_rows(audits, lengths):
    rows = []
    for field in FIELDS:
        r = [f"`{field}`"]
        for L in lengths:
            res = tot = ok = okn = 0
            for a in audits:
                if a["bench"]["length"] != L:
                    continue
                o = field_outcome(a, field)
                if o is None:
                    continue
                res += o[0]
                tot += o[1]
                ok += o[2]
                okn += o[3]
            if tot == 0:
                r.append("not checked")
            else:
                r.append(f"{res / tot:.2f} resolved, {ok} / {okn} right")
        rows.append(r)
    return rows


def svg(stats_by_group, lengths, path):
    """Coverage against log length (log-scaled x), one line per group."""
    w, h, ml, mr, mt, mb = 560, 320, 60, 150, 20, 45
    import math
    xs = [math.log10(L) for L in lengths]
    x0, x1 = min(xs), max(xs)
    px = lambda L: ml + (math.log10(L) - x0) / (x1 - x0 or 1) * (w - ml - mr)
    py = lambda c: mt + (1 - c) * (h - mt - mb)
    colors = ["#1f77b4", "#d62728", "#2ca02c", "#9467bd", "#ff7f0e", "#8c564b"]
    out = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{w}" height="{h}" font-family="sans-serif" font-size="12">',
           f'<rect width="{w}" height="{h}" fill="white"/>']
    for c in (0, 0.25, 0.5, 0.75, 1.0):
        out.append(f'<line x1="{ml}" x2="{w - mr}" y1="{py(c):.1f}" y2="{py(c):.1f}" stroke="#ddd"/>')
        out.append(f'<text x="{ml - 6}" y="{py(c) + 4:.1f}" text-anchor="end">{c:.2f}</text>')
    for L in lengths:
        out.append(f'<text x="{px(L):.1f}" y="{h - mb + 16}" text-anchor="middle">{L}</text>')
    out.append(f'<text x="{(ml + w - mr) / 2:.1f}" y="{h - 8}" text-anchor="middle">log length (transitions)</text>')
    out.append(f'<text x="14" y="{(mt + h - mb) / 2:.1f}" transform="rotate(-90 14 {(mt + h - mb) / 2:.1f})" text-anchor="middle">coverage (committed verdicts)</text>')
    for k, (name, stats) in enumerate(stats_by_group):
        col = colors[k % len(colors)]
        pts = " ".join(f"{px(L):.1f},{py(stats[L][3]):.1f}" for L in lengths if L in stats)
        out.append(f'<polyline points="{pts}" fill="none" stroke="{col}" stroke-width="2"/>')
        for L in lengths:
            if L in stats:
                out.append(f'<circle cx="{px(L):.1f}" cy="{py(stats[L][3]):.1f}" r="3" fill="{col}"/>')
        out.append(f'<text x="{w - mr + 10}" y="{mt + 16 + 18 * k}" fill="{col}">{name}</text>')
    out.append("</svg>")
    with open(path, "w") as f:
        f.write("\n".join(out) + "\n")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--choose")
    ap.add_argument("--tolerance")
    ap.add_argument("--tolerances", default="")
    ap.add_argument("--out")
    ap.add_argument("--svg")
    ap.add_argument("--pilot")
    ap.add_argument("--evaluation")
    ap.add_argument("--floor")
    ap.add_argument("--command", default="")
    ap.add_argument("--commit", default="")
    ap.add_argument("--wall", default="")
    ap.add_argument("--wall-note", default="", help="how the wall time was measured, when not by one uninterrupted run")
    ap.add_argument("--pilot-seeds", default="")
    ap.add_argument("--eval-seeds", default="")
    ap.add_argument("--lengths", default="")
    ap.add_argument("--noises", default="")
    ap.add_argument("--floors", default="")
    a = ap.parse_args()
    if a.choose:
        fl, tol = choose(a.choose)
        print(fmt_floor(fl), fmt_floor(tol))
        return
    lengths = [int(x) for x in a.lengths.split()]
    ev = load(a.evaluation)
    pilot = load(a.pilot)
    rows, stats = summary_rows(ev, lengths)
    groups = []
    for name, pred in (("all", lambda x: True), ("reference, expert", lambda x: x["bench"].get("group") == "reference/expert"),
                       ("reference, PPO", lambda x: x["bench"].get("group") == "reference/ppo"),
                       ("generated, expert", lambda x: x["bench"].get("group") == "generated/expert"),
                       ("sensor noise", lambda x: x["bench"]["noise"] > 0),
                       ("declared = truth", lambda x: x["bench"]["declared_as"] == "truth")):
        groups.append((name, summary_rows([x for x in ev if pred(x)], lengths)[1]))
    svg(groups, lengths, a.svg)
    # the pilot's grid
    pilot_rows = []
    for (fl, tol), (n, com, wrong) in sorted(pilot_table(pilot).items()):
        pilot_rows.append([fmt_floor(fl), fmt_floor(tol), str(n), f"{com / n:.3f}", f"{wrong} / {com}"])
    pt = pilot_table(pilot)
    key = next((k for k in pt if fmt_floor(k[0]) == fmt_floor(float(a.floor)) and fmt_floor(k[1]) == fmt_floor(float(a.tolerance))), None)
    chosen_committed, chosen_wrong = (pt[key][1], pt[key][2]) if key else (0, 0)
    worst = max((stats[L][2] / stats[L][1] if stats[L][1] else 0.0) for L in lengths)
    worst_upper = max((min(wilson_interval(stats[L][2], stats[L][1])["upper"], 1.0) if stats[L][1] else 1.0) for L in lengths)
    n_contracts = len({(a["bench"]["split"], a["bench"]["contract"]) for a in ev})
    n_logs = len({(a["bench"].get("backbone", "expert"), a["bench"]["split"], a["bench"]["contract"], a["bench"]["noise"],
                   a["bench"]["seed"]) for a in ev})
    lines = []
    lines.append("# Audit benchmark: identifying a log's action contract, with abstention\n")
    lines.append(f"Written by `scripts/audit_benchmark` → `scripts/audit_report.py`; command `{a.command}`, commit `{a.commit[:12]}`, "
                 f"wall time {a.wall} s{' (' + a.wall_note + ')' if a.wall_note else ''}. Do not edit by hand.\n")
    lines.append("**Question.** Given a log of commanded actions and measured TCP poses (no probing), does `actionshift audit` "
                 "name the contract the log was recorded under, or abstain, and how often is a committed verdict wrong? "
                 "Target: at most 1 % wrong among committed verdicts at every length.\n")
    lines.append("**Logs.** `actionshift record --task pick_cube --method oracle` (the oracle makes the backbone succeed while "
                 "the log holds the raw numbers the hidden contract decodes), observation noise σ ∈ {"
                 + ", ".join(a.noises.split()) + "} (m, rad), 5,000 transitions per (contract, backbone, noise, seed); shorter "
                 "lengths are prefixes of the same log (`audit --max-steps`). Three groups: every contract of `reference_seen` "
                 "and `reference_unseen_composition` (2 + 2) with the scripted expert and with the committed learned backbone "
                 "(`ppo`, configs/backbones/pick_cube.ppo.asmlp) under every seed; and every test contract of the five "
                 "generated splits (`seen`, `unseen_composition`, `unseen_value`, `long_lag`, `task_transfer`: 160 of the "
                 "`full` pool's 180 members, its other 20 being identity and distractors) with the expert, each contract under "
                 "one evaluation seed (round robin) and every fourth under one pilot seed. Each log is audited twice: declared = "
                 "the recorded contract (right answer PASS) and declared = identity (right answer MISMATCH naming the recorded "
                 f"contract). Response model: the task's built-in calibration (`--task pick_cube`). Evaluation: {n_logs} logs of "
                 f"{n_contracts} contracts.\n")
    lines.append(f"**Seeds.** Pilot (choose the confidence floor and the gain tolerance): {a.pilot_seeds}. Evaluation (this page): {a.eval_seeds}; "
                 "both registered in `configs/seeds.yaml` and checked disjoint (initial states included) by "
                 "`tests/eval/seed_registry_test.cpp`.\n")
    lines.append(f"**Thresholds.** The confidence floor (grid {{{', '.join(a.floors.split())}}}) and the gain tolerance (grid "
                 f"{{{', '.join(a.tolerances.split())}}}) are the pair with no wrong committed verdict among the pilot audits and the "
                 f"highest pilot coverage, or, when no pair is clean, the one with the fewest wrong: **floor {a.floor}, gain "
                 f"tolerance {a.tolerance}**" + (f" ({chosen_wrong} of its {chosen_committed} committed pilot verdicts wrong: no pair "
                 f"was clean)" if chosen_wrong else " (clean on the pilot)") + ". The misspecification ratio (25) and the "
                 "minimum excitation (0.1) are the defaults, fixed before the run (not tuned).\n")
    lines.append("**Wrong.** A committed verdict is wrong if it is PASS while a checked field of the recorded conventions differs "
                 "from the declaration, or MISMATCH while the declaration is the truth or any resolved field (per output "
                 "channel for permutation, sign and scale) is not the recorded value.\n")
    lines.append("## Coverage and error rate per log length (evaluation seeds)\n")
    lines.append("Coverage and error rate with their Wilson 95 % intervals (the statistics engine's, `actionshift.wilson_interval`).\n")
    lines.append(table.markdown(["transitions", "audits", "PASS", "MISMATCH", "INCONCLUSIVE", "coverage", "wrong / committed",
                                 "error rate"], rows))
    lines.append("")
    lines.append(f"Largest error rate among committed verdicts over the lengths: **{worst:.3f}** (target ≤ 0.010); the largest "
                 f"upper bound of its interval: {worst_upper:.3f}, what these counts can rule out.\n")
    lines.append("![coverage against log length](audit_coverage.svg)\n")
    lines.append("## Per group of logs\n")
    lines.append(table.markdown(["logs", "transitions", "audits", "coverage", "wrong / committed", "error rate"], group_rows(ev, lengths)))
    lines.append("")
    wr = wrong_rows(ev)
    lines.append("### The wrong committed verdicts\n")
    lines.append(table.markdown(["logs", "contract", "noise", "seed", "transitions", "declared", "verdict", "what it got wrong"], wr)
                 if wr else "None.\n")
    lines.append("")
    lines.append(f"The generated splits per split at {lengths[-1]} transitions:\n")
    lines.append(table.markdown(["split", "contracts", "audits", "coverage", "wrong / committed"], split_rows(ev, lengths[-1])))
    lines.append("")
    lines.append("## Per field: how often resolved, and right when resolved\n")
    lines.append("Per-channel fields count output channels; `not checked` means the log cannot tell (e.g. the rotation "
                 "representation at these rotation sizes: the representations differ at second order only).\n")
    lines.append(table.markdown(["field"] + [f"{L} transitions" for L in lengths], field_rows(ev, lengths)))
    lines.append("")
    lines.append("## Pilot (the grid of floors and gain tolerances)\n")
    lines.append(table.markdown(["floor", "gain tolerance", "audits", "coverage", "wrong / committed"], pilot_rows))
    lines.append("")
    lines.append("Scale is checked against the task's calibrated response gain. Without a calibration the audit fits the gain "
                 "from the log and reports scale relative to it (unchecked): a log cannot separate a contract's scale from "
                 "the robot's response gain. See docs/audit.md.\n")
    with open(a.out, "w") as f:
        f.write("\n".join(lines))


if __name__ == "__main__":
    main()
