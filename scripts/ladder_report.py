#!/usr/bin/env python3
"""Writes the privilege-ladder page (docs/results/ladder.md) from the compare runs of scripts/ladder: one
`actionshift compare` JSON per group of experiment directories (scripts/ladder_groups.py: `live`, `pool_full`,
`identity`; directories that share method labels but differ by a job option, the pool or the frame rotation, are
compared separately and merged here only for layout). Layout only: every rate, Wilson interval, per-seed rate,
probe cost, paired difference and promotion verdict is compare's; the paper's numbers are compare's paper fields
or configs/paper/numbers.json by id. Per-contract rates come from compare's `per_contract` cell field when the
compare that wrote the JSON has it.
With --learned COMPARE_JSON (the comparison of scripts/backbone_variance), a section lays the same rungs
on the learned PPO backbones (the committed file and its replicas) beside this page's scripted expert.
usage: scripts/ladder_report.py RESULTS_DIR COMPARE_DIR [--learned JSON] [--commit C --command CMD --wall S --cores N --cpu TIMES]"""
import json
import os
import re
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from pages import findings, fmt, paper, provenance, table  # noqa: E402
from pages.backbones import rung_key, training_seed  # noqa: E402
from pages.ladder_util import (PER_CONTRACT_MISSING, Groups, contract_class, contract_rate, describe, entry_text,  # noqa: E402
                               has_per_contract, manifest_contracts, paper_ids, per_contract_table)
from pages.rest_util import ROOT, commit_of, cpu_text, parser, rel, scalar  # noqa: E402

TASKS = ["pick_cube", "push_cube"]
REF_SPLITS = ["reference_seen", "reference_unseen_composition"]
GEN_SPLIT = "unseen_composition"
V1, V2 = "grammar + calibration", "grammar + calibration with the finger block"
POOL9, POOL180 = "declared 9-contract pool (reference9)", "declared 180-contract pool (full; holds no reference contract)"
OP = "grammar_belief{gripper_channel=true,probe=hold,scale_correction=true}"  # the paper's operating point
HOLD_R2_V2 = "grammar_belief{gripper_channel=true,hold_rounds=2,probe=hold,scale_correction=true}"
FLAIL_ID = "grammar_belief{after_probe=identity,hold_rounds=2,probe=hold}"
PROBE_ONLY = "grammar_belief{hold_rounds=5,probe=hold}"

# (group, label, experiment directory, privilege, paper id suffixes of configs/paper/numbers.json; None: compare's
# paper field, for the bare labels of the paper's methods)
ROWS = [
    ("live", "no_adapt", "pool_reference9", "none", None),
    ("live", "grammar_belief", "grammar_passive", V1, ["grammar_passive_v1"]),
    ("live", "grammar_belief{probe=fixed}", "grammar_fixed", V1, ["grammar_fixed_v1"]),
    ("live", "grammar_belief{probe=entropy}", "grammar_entropy", V1, []),
    ("live", "grammar_belief{probe=hold}", "grammar_hold", V1, []),
    ("live", "grammar_belief{hold_rounds=2,probe=hold}", "grammar_hold_r2", V1, []),
    ("live", "grammar_belief{probe=hold,scale_correction=true}", "grammar_hold_corrector", V1, []),
    ("live", PROBE_ONLY, "control_probe_only", V1, ["control_probe_only"]),
    ("live", FLAIL_ID, "control_flail_identity", V1, ["control_flail_identity"]),
    ("live", "grammar_belief{gripper_channel=true}", "v2_passive", V2, []),
    ("live", "grammar_belief{gripper_channel=true,probe=fixed}", "v2_fixed", V2, ["grammar_fixed_v2"]),
    ("live", "grammar_belief{gripper_channel=true,probe=hold}", "v2_hold", V2, []),
    ("live", OP, "v2_hold_corrector", V2, ["grammar_hold_v2"]),
    ("live", HOLD_R2_V2, "v2_hold_r2_corrector", V2, ["grammar_hold_r2_v2", "control_flail_belief"]),
    ("live", "exact_belief", "pool_reference9", POOL9, None),
    ("live", "entropy_probes", "pool_reference9", POOL9, None),
    ("live", "entropy_probes{calibrated}", "pool_reference9", POOL9, None),
    ("pool_full", "exact_belief", "pool_full", POOL180, []),
    ("pool_full", "entropy_probes", "pool_full", POOL180, []),
    ("pool_full", "entropy_probes{calibrated}", "pool_full", POOL180, []),
    ("live", "oracle", "pool_reference9", "the true contract", None),
]
# the generated split: (group, label, experiment directory)
GEN_ROWS = [
    ("live", "grammar_belief{probe=fixed}", "gen_fixed"),
    ("live", "grammar_belief{probe=hold}", "gen_hold"),
    ("identity", "grammar_belief{probe=hold}", "gen_hold_identity (rotation identity)"),
    ("live", OP, "gen_v2_hold_corrector"),
    ("live", PROBE_ONLY, "gen_control_probe_only"),
    ("live", FLAIL_ID, "gen_control_flail_identity"),
    ("live", "grammar_belief{hold_rounds=2,probe=hold}", "gen_control_flail_belief"),
    ("live", "exact_belief", "gen_pool_full"),
    ("live", "entropy_probes", "gen_pool_full"),
    ("live", "entropy_probes{calibrated}", "gen_pool_full"),
    ("live", "oracle", "gen_pool_full"),
]
# the tool-frame cell: (variant, label; live rotation in `live`, identity rotation in `identity`)
TOOL_ROWS = [("v1 hold h2-r1", "grammar_belief{probe=hold}"), ("v2 operating point", OP)]

# per-contract paper numbers: (row label, task, split, contract index, numbers.json id)
PAPER_CONTRACT = [
    ("grammar_belief{probe=fixed}", "pick_cube", "reference_seen", 0, "s5.4.pick_cube.reference_seen.grammar_fixed_v1.gripper_inverted"),
    ("grammar_belief{probe=fixed}", "pick_cube", "reference_seen", 1, "ref.pick_cube.reference_seen.grammar_fixed_v1.gripper_not_inverted"),
    ("grammar_belief{probe=fixed}", "push_cube", "reference_seen", 1, "s5.4.push_cube.reference_seen.grammar_fixed_v1.clean_subcell"),
    ("grammar_belief{gripper_channel=true,probe=fixed}", "pick_cube", "reference_seen", 0, "s5.4.pick_cube.reference_seen.grammar_fixed_v2.gripper_inverted"),
    ("grammar_belief{gripper_channel=true,probe=fixed}", "pick_cube", "reference_seen", 1, "ref.pick_cube.reference_seen.grammar_fixed_v2.gripper_not_inverted"),
    (OP, "pick_cube", "reference_unseen_composition", 0, "ref.pick_cube.reference_unseen_composition.grammar_hold_v2.c0"),
    (OP, "pick_cube", "reference_unseen_composition", 1, "ref.pick_cube.reference_unseen_composition.grammar_hold_v2.c1"),
    (OP, "push_cube", "reference_unseen_composition", 0, "ref.push_cube.reference_unseen_composition.grammar_hold_v2.c0"),
    (OP, "push_cube", "reference_unseen_composition", 1, "s5.4.push_cube.reference_unseen_composition.grammar_hold_v2.c1"),
]

# The paper's findings of §5.4 (and §5.2, §5.6): (finding, numbers.json ids, evidence). Evidence items are
# ("pair", group, candidate, baseline, task, split) or ("cell", group, label, task, split).
FINDINGS = [
    ("Grammar knowledge (no pool) lifts the floor: the earliest belief to succeed without a pool (§5.4)",
     ["s5.4.pick_cube.reference_seen.grammar_passive_v1", "s5.4.pick_cube.reference_seen.grammar_fixed_v1",
      "s5.4.push_cube.reference_seen.grammar_passive_v1", "s5.4.push_cube.reference_seen.grammar_fixed_v1"],
     [("pair", "live", "grammar_belief", "no_adapt", t, "reference_seen") for t in TASKS]
     + [("pair", "live", "grammar_belief{probe=fixed}", "grammar_belief", t, "reference_seen") for t in TASKS]),
    ("Wall 1 (gripper) is substantially closed by the finger channel: the probed cell 0.458 → 0.715 (§5.4)",
     ["s5.4.pick_cube.reference_seen.grammar_fixed_v1", "s5.4.pick_cube.reference_seen.grammar_fixed_v2",
      "s5.4.pick_cube.reference_seen.grammar_fixed_v1.gripper_inverted", "s5.4.pick_cube.reference_seen.grammar_fixed_v2.gripper_inverted"],
     [("pair", "live", "grammar_belief{gripper_channel=true,probe=fixed}", "grammar_belief{probe=fixed}", t, "reference_seen")
      for t in TASKS]),
    ("Wall 2 (absolute + scale) is breached by hold-probe excitation: all-absolute cells 0.005 → 0.722 (Push), 0.000 → 0.790 (Pick) (§5.4)",
     ["s5.4.push_cube.reference_unseen_composition.grammar_fixed_v2", "s5.4.push_cube.reference_unseen_composition.grammar_hold_v2",
      "s5.4.pick_cube.reference_unseen_composition.grammar_fixed_v2", "s5.4.pick_cube.reference_unseen_composition.grammar_hold_v2"],
     [("pair", "live", OP, "grammar_belief{gripper_channel=true,probe=fixed}", t, "reference_unseen_composition") for t in TASKS]
     + [("pair", "live", "grammar_belief{probe=hold}", "grammar_belief{probe=fixed}", t, s) for t in TASKS
        for s in ("reference_unseen_composition", GEN_SPLIT)]),
    ("Causal controls on Push/unseen: probe only 0.000, flail then identity 0.000, flail then belief 0.725 (§5.4)",
     ["s5.4.push_cube.reference_unseen_composition.control_probe_only", "s5.4.push_cube.reference_unseen_composition.control_flail_identity",
      "s5.4.push_cube.reference_unseen_composition.control_flail_belief"],
     [("cell", "live", PROBE_ONLY, "push_cube", "reference_unseen_composition"),
      ("cell", "live", FLAIL_ID, "push_cube", "reference_unseen_composition"),
      ("pair", "live", HOLD_R2_V2, FLAIL_ID, "push_cube", "reference_unseen_composition"),
      ("pair", "live", "grammar_belief{hold_rounds=2,probe=hold}", FLAIL_ID, "push_cube", "reference_unseen_composition")]
     + [("pair", "live", "grammar_belief{hold_rounds=2,probe=hold}", FLAIL_ID, t, GEN_SPLIT) for t in TASKS]),
    ("A 24-step probe regresses the delta cell to 0.405; 12 steps is the operating point (§5.4)",
     ["ref.pick_cube.reference_seen.grammar_hold_v2", "s5.4.pick_cube.reference_seen.grammar_hold_r2_v2"],
     [("pair", "live", HOLD_R2_V2, OP, "pick_cube", "reference_seen"),
      ("pair", "live", "grammar_belief{hold_rounds=2,probe=hold}", "grammar_belief{probe=hold}", "pick_cube", "reference_seen")]),
    ("The scale corrector alone brings no significant gain (the reference implementation; §6 only says it does not move the absolute cells alone)",
     ["ref.pick_cube.reference_seen.scale_corrector_alone.without", "ref.pick_cube.reference_seen.scale_corrector_alone.with",
      "ref.push_cube.reference_unseen_composition.scale_corrector_alone.without", "ref.push_cube.reference_unseen_composition.scale_corrector_alone.with"],
     [("pair", "live", OP, "grammar_belief{gripper_channel=true,probe=hold}", t, s) for t in TASKS for s in REF_SPLITS]
     + [("pair", "live", "grammar_belief{probe=hold,scale_correction=true}", "grammar_belief{probe=hold}", t, s)
        for t in TASKS for s in REF_SPLITS]),
    ("Active probing is not a substitute for hypothesis-space knowledge: grammar-only belief 0.458 against the pool belief 0.987 on Pick/seen (§5.2, Fig. 4)",
     ["s5.4.pick_cube.reference_seen.grammar_fixed_v1", "table5.pick_cube.reference_seen.entropy_probes.success",
      "table5.pick_cube.reference_seen.exact_belief.success"],
     [("pair", "live", "exact_belief", "grammar_belief{probe=fixed}", t, "reference_seen") for t in TASKS]
     + [("pair", "live", "entropy_probes", "grammar_belief{probe=entropy}", t, "reference_seen") for t in TASKS]
     + [("pair", "live", "exact_belief", OP, t, s) for t in TASKS for s in REF_SPLITS]
     + [("pair", "pool_full", "exact_belief", "grammar_belief{probe=fixed}", t, s) for t in TASKS for s in REF_SPLITS]),
]
TOOL_FINDING = ("The factorized belief cannot represent tool frame under live rotation (§5.6)",
                "the same label under identity and live rotation is two compare runs (rotation_mode is not part of the "
                "label), so compare has no paired identity − live difference; the per-cell rates are in the tool-frame section")


def cell_row(G, numbers, group, label, task, split, paper_suffixes):
    c = G.cell(group, task, split, label)
    if paper_suffixes is None:
        pap = fmt.DASH if not c else paper.cell_column(c)
        if c and paper.cell_entry(c):
            pap += f" ({paper.source(paper.cell_entry(c))})"
    else:
        pap = "; ".join(f"{entry_text(e)}: {e.get('variant', '')}" for e in paper_ids(numbers, task, split, paper_suffixes)) or fmt.DASH
    return c, pap


def split_table(G, numbers, split):
    rows, missing = [], []
    for group, label, exp, priv, suffixes in ROWS:
        ran = False
        for t in TASKS:
            c, pap = cell_row(G, numbers, group, label, t, split, suffixes)
            if not c:
                continue
            ran = True
            rows.append([f"`{label}`", exp, describe(label), priv, t, fmt.cell_rate(c), fmt.n_of(c), fmt.per_seed(c),
                         fmt.probe_steps(c), fmt.safety(c), pap])
        if not ran:
            missing.append(f"`{label}` ({exp})")
    return table.markdown(["label", "experiment", "what ran", "privilege", "task", "success (Wilson 95 %)", "k/n", "per seed",
                           "probe steps", "flagged episodes", "paper"], rows), missing


def evidence_row(G, ev):
    if ev[0] == "cell":
        _, group, label, task, split = ev
        c = G.cell(group, task, split, label)
        what = f"`{label}` ({group}), {task} / {split}"
        if not c:
            return [what, fmt.DASH, fmt.DASH, fmt.DASH, findings.bold(findings.UNTESTABLE), "the cell was not run here"]
        return [what, fmt.cell_rate(c), "(a level)", fmt.per_seed(c), findings.bold(findings.UNTESTABLE),
                "a level, not a difference: the paper's backbone (frozen PPO) and simulator differ from ours, so levels are not compared"]
    _, group, cand, base, task, split = ev
    x = G.comparison(group, cand, base, task, split)
    what = f"`{cand}` − `{base}` ({group}), {task} / {split}"
    st, why = findings.status(x)
    if x and st == findings.UNTESTABLE and not x.get("paper"):
        why = (f"compare: {x.get('sign_agreement_reason') or 'no paper difference'}; the paper prints cell rates, not a paired "
               f"difference with an interval, so no sign is claimed. Ours {fmt.cmp_diff(x)}"
               + (" excludes 0" if x["difference"]["excludes_zero"] else " includes 0"))
    return [what, fmt.cmp_rates(x), fmt.cmp_diff(x), fmt.per_seed_diff(x), findings.bold(st), why]


def learned_section(w, G, path, command):
    """The rungs of the learned backbones' comparison, one column per PPO backbone, beside this page's expert."""
    with open(path) as f:
        cells = json.load(f)["cells"]
    tasks = sorted({c["task"] for c in cells})
    w("## The ladder on learned backbones, beside the expert's\n")
    w(f"The same rungs with the task's PPO backbones instead of the scripted expert: the committed file (training seed "
      f"20260718) and the replicas trained by its recipe with other training seeds, each with the pool `reference9` "
      f"(`{command}`, {fmt.thousands(sum(c['episodes'] for c in cells))} episodes; per-backbone effects, pooled "
      f"intervals and verdicts: docs/results/backbone_variance.md, which also draws this ladder per backbone). The "
      f"expert column is this page's cell of the same label (— where this page did not run it: the expert's fixed "
      f"probes, DualABI and oracle are on docs/results/tournament.md). success_once "
      f"[Wilson 95 %] over the seeds {', '.join(map(str, sorted({s['seed'] for c in cells for s in c['per_seed']})))}; "
      f"the paper's number is for its one PPO checkpoint.\n")
    for t in tasks:
        backbones = sorted({c["backbone"] for c in cells if c["task"] == t}, key=training_seed)
        for split in REF_SPLITS:
            cs = [c for c in cells if c["task"] == t and c["split"] == split]
            if not cs:
                continue
            rows = []
            for m in sorted({c["method"] for c in cs}, key=rung_key):
                e = G.cell("live", t, split, m) if t in TASKS else None
                row = [f"`{m}`", fmt.cell_rate(e) if e else fmt.DASH]
                pap = None
                for b in backbones:
                    c = next((c for c in cs if c["method"] == m and c["backbone"] == b), None)
                    row.append(fmt.cell_rate(c) if c else fmt.DASH)
                    pap = pap or ((c or {}).get("paper") or {}).get("success_once")
                row.append(f"{fmt.num(pap['value'])} ({pap['source']})" if pap else fmt.DASH)
                rows.append(row)
            w(f"### {t} / `{split}`\n")
            w(table.markdown(["method", "expert"] + [f"PPO seed {training_seed(b)}" for b in backbones] + ["paper (its PPO)"],
                             rows))


def main():
    ap = parser(__doc__)
    ap.add_argument("results")
    ap.add_argument("compare_dir")
    ap.add_argument("--learned", help="compare JSON of scripts/backbone_variance (the ladder on learned backbones)")
    ap.add_argument("--learned-command", default="scripts/backbone_variance results/backbone_variance",
                    help="the command that produced --learned")
    a = ap.parse_args()
    G = Groups(a.compare_dir)
    numbers = paper.load_numbers()
    res = rel(a.results)
    have_pc = has_per_contract(G)
    # the cells the page lays out: each group's own (the pool_full group also holds the grammar cells of `live`)
    layout = []
    for name, C in G.items():
        cs = C.cells if name != "pool_full" else [c for c in C.cells if not c["method"].startswith("grammar_belief")]
        layout += cs
    jobs = sorted({j for c in layout for j in c["jobs"]})
    dirs = [os.path.join(a.results, d) for d in sorted(os.listdir(a.results)) if os.path.isdir(os.path.join(a.results, d))]
    specs = provenance.job_specs(dirs, jobs)
    live = G.get("live") or next(iter(G.by_name.values()))
    group_text = "; ".join(f"`{n}`: {', '.join(sorted({os.path.basename(d['dir'].rstrip('/')) for d in C.data['inputs']['results_dirs']}))}"
                           for n, C in G.items())
    out = [provenance.header(
        "The privilege ladder: grammar knowledge between no adaptation and the pool",
        "scripts/ladder_report.py", a.command or f"scripts/ladder {res}", commit_of(a), [res],
        provenance.spec_values(specs, "profile"), live.seeds(layout), sum(c["episodes"] for c in layout), jobs=len(jobs),
        episodes_per_seed=live.episodes_per_seed(layout), wall=a.wall, cores=a.cores, paper_source=live.paper_source(),
        bootstrap=live.data["bootstrap"], reused=a.reused,
        extra=[f"CPU: {cpu_text(a.cpu)[2:] or 'not measured'}.",
               "Compare runs (scripts/ladder_groups.py; one JSON per group, merged here only for layout, because "
               "directories that differ by the pool or the frame rotation share method labels): " + group_text + ".",
               "Rotation modes: " + ", ".join(provenance.spec_values(specs, "rotation_mode")) + "; pools: "
               + ", ".join(provenance.pools(specs)) + "; backbone: " + ", ".join(sorted({s['backbone']['name'] for s in specs})) + "."])]
    w = out.append
    w("The paper's ladder (§5.2, §5.4, Fig. 4): between no adaptation (the floor) and the pool belief sits a belief that\n"
      "knows only the contract grammar and the response calibration, no pool. v1 rows run it without the finger channel\n"
      "(the gripper inversion is unobservable and executed inverted), v2 rows (`gripper_channel=true`) with the paper's\n"
      "finger evidence channel. What each row ran is read from its method label (docs/adapters.md, \"Method names and\n"
      "variants\"): `grammar_belief` is passive, `{probe=fixed}` 6 fixed pulses, `{probe=hold}` the hold probe,\n"
      "`entropy_probes` the paper's probe rule and `entropy_probes{calibrated}` the project's. The paper's numbers are for\n"
      "frozen PPO on ManiSkill, ours for the scripted expert on the Bullet Panda: levels are not expected to match; the\n"
      "orderings and the walls are what is compared. The paper column of a grammar row is configs/paper/numbers.json by\n"
      "id (each entry names its variant); of a bare label, compare's paper field; the full-pool rows have none (the\n"
      "paper's pool is reference9).\n")
    cal = {}
    for t in TASKS:
        p = os.path.join(ROOT, "configs", "calibration", "maniskill", t + ".json")
        if os.path.exists(p):
            with open(p) as f:
                cal[t] = json.load(f).get("gripper")
    w("Finger block of the committed calibrations (configs/calibration/maniskill/): "
      + ", ".join(f"{t} R² {fmt.num(cal[t]['fit_r2'])}" if cal.get(t) else f"{t} none" for t in TASKS)
      + f"; the paper's finger channel R² {scalar(numbers, 's5.4.gripper_channel_r2')}.\n")
    for split in REF_SPLITS:
        w(f"## `{split}`\n")
        t_, missing = split_table(G, numbers, split)
        if len(missing) == len(ROWS):
            w("No cell of this split was run.\n")
            continue
        w(t_)
        if missing:
            w("Not run on this split: " + ", ".join(missing) + ".\n")
    if a.learned:
        learned_section(w, G, a.learned, a.learned_command)
    w("## Per contract\n")
    w("Each reference split has two contracts (episodes alternate). `reference_seen`: c0 delta, base frame, gripper inverted;"
      " c1 delta, gripper not inverted. `reference_unseen_composition`: c0 absolute, tool frame; c1 absolute, base frame;"
      " both invert the gripper, so v1 rows fail them for a reason unrelated to the pose fields (the paper's gripper wall).\n")
    if not have_pc:
        w(f"**{PER_CONTRACT_MISSING}** (the compare JSON of this page has no `per_contract` cell field); the paper's"
          " per-contract numbers are listed with our column left open.\n")
    rows = []
    for label, t, s, idx, pid in PAPER_CONTRACT:
        rows.append((f"`{label}`, {t} / {s}", G.cell("live", t, s, label), idx, f"c{idx}", numbers.by_id(pid)))
    w(per_contract_table(rows, have_pc))
    if have_pc:
        rows = []
        for split in REF_SPLITS:
            mc = manifest_contracts(split, ROOT)
            for group, label, exp, _, _ in ROWS:
                for t in TASKS:
                    c = G.cell(group, t, split, label)
                    for e in (c or {}).get("per_contract", []):
                        cls = contract_class(mc[e["contract_index"]][1]) if e["contract_index"] < len(mc) else fmt.DASH
                        rows.append([f"`{label}` ({exp})", t, split, f"c{e['contract_index']} ({cls})",
                                     f"{fmt.rate(e['success_once'])} (n={e['episodes']})"])
        w("Every row per contract (compare's `per_contract`):\n")
        w(table.markdown(["row", "task", "split", "contract", "success (Wilson 95 %)"], rows))
    w("## The tool-frame cell under live rotation\n")
    w("The factorized belief collapses the frame to base; under live rotation a tool-frame contract is outside its hypothesis"
      " space (§5.6). The same label with the rotation held at the identity (tool = base) isolates the frame. The two runs"
      " share the label, so they are two compare runs (`live`, `identity`) and compare gives no paired identity − live"
      " difference; per-contract rates (c0 tool frame, c1 base frame) from `per_contract`.\n")
    rows = []
    split = "reference_unseen_composition"
    for variant, label in TOOL_ROWS:
        for t in TASKS:
            lc, ic = G.cell("live", t, split, label), G.cell("identity", t, split, label)
            if not lc and not ic:
                continue
            rows.append([variant, f"`{label}`", t, fmt.cell_rate(lc), fmt.cell_rate(ic),
                         contract_rate(lc, 0, have_pc), contract_rate(ic, 0, have_pc),
                         fmt.cell_rate(G.cell("live", t, split, "exact_belief")), fmt.cell_rate(G.cell("live", t, split, "oracle"))])
    w(table.markdown(["variant", "label", "task", "live rotation", "identity rotation", "c0 (tool), live", "c0 (tool), identity",
                      "pool exact (reference9), live", "oracle, live"], rows) if rows else "Not run.\n")
    w(f"## The generated split (`{GEN_SPLIT}`)\n")
    w("Both all-absolute reference contracts invert the gripper; the generated split (32 contracts, 13 with the gripper not"
      " inverted) shows what the pose fields alone allow. Whole-split cells; by contract class below.\n")
    rows = []
    for group, label, exp in GEN_ROWS:
        for t in TASKS:
            c = G.cell(group, t, GEN_SPLIT, label)
            if c:
                rows.append([f"`{label}`", exp, describe(label), t, fmt.cell_rate(c), fmt.n_of(c), fmt.per_seed(c), fmt.probe_steps(c)])
    w(table.markdown(["label", "experiment", "what ran", "task", "success (Wilson 95 %)", "k/n", "per seed", "probe steps"], rows)
      if rows else "Not run.\n")
    if rows:
        if not have_pc:
            w(f"By contract class (frame, target, gripper): **{PER_CONTRACT_MISSING}**.\n")
        else:
            mc = manifest_contracts(GEN_SPLIT, ROOT)
            for t in TASKS:
                present = [(g, lab, exp) for g, lab, exp in GEN_ROWS if G.cell(g, t, GEN_SPLIT, lab)]
                if not present:
                    continue
                w(f"Per contract, {t} (compare's `per_contract`; rows sorted by class):\n")
                order = sorted(range(len(mc)), key=lambda i: (contract_class(mc[i][1]), i))
                body = [[f"c{i}", contract_class(mc[i][1])] + [contract_rate(G.cell(g, t, GEN_SPLIT, lab), i, True)
                                                               for g, lab, _ in present] for i in order]
                w(table.markdown(["contract", "class"] + [f"`{lab}` ({exp})" for _, lab, exp in present], body))
    w("## Paired differences\n")
    w("Every pair of the group's pairs file (scripts/pages/ladder.pairs, scripts/pages/ladder.pool_full.pairs) in every"
      " cell that ran both labels: candidate − baseline over the same episodes, with the promotion gate's verdict.\n")
    rows = []
    for name, C in G.items():
        for x in C.comparisons:
            v, rule, _ = fmt.promotion(x)
            rows.append([name, x["task"], x["split"], f"`{x['candidate']}` − `{x['baseline']}`", x["pairs"], fmt.cmp_rates(x),
                         fmt.cmp_diff(x, mark=True), fmt.per_seed_diff(x), paper.cmp_column(x), f"{v} (`{rule}`)"])
    w(table.markdown(["group", "task", "split", "pair", "pairs", "candidate / baseline", "difference [95 %]", "per seed",
                      "paper", "promotion (rule)"], rows) if rows else "No pair was run.\n")
    w("## Which of the paper's findings reproduce\n")
    w("Status (scripts/pages/findings.py, from compare's fields only): where the paper gives a paired difference with an"
      " interval (Table 2's oracle − no adaptation, carried by compare), **reproduced** / **contradicted** by its rule, and"
      " \"same sign\" only where the paper's difference is significant (compare's `sign_agreement`). The ladder's §5.4"
      " findings are printed as cell rates without a paired interval: each is listed with our paired difference and"
      " marked **untestable** (no sign claim), with the measured difference in the reason.\n")
    rows = []
    for text, ids, evidence in FINDINGS:
        pap = "; ".join(f"{entry_text(numbers.by_id(i))} {numbers.by_id(i).get('variant') or numbers.by_id(i).get('method', '')}".strip()
                        for i in ids if numbers.by_id(i))
        shown = [ev for ev in evidence if ev[0] == "cell" or G.comparison(*ev[1:])]
        if not shown:
            rows.append([text, pap, fmt.DASH, fmt.DASH, fmt.DASH, fmt.DASH, findings.bold(findings.UNTESTABLE),
                         "none of its cells was run here"])
        for k, ev in enumerate(shown):
            rows.append([text if k == 0 else "″", pap if k == 0 else "″"] + evidence_row(G, ev))
    rows.append([TOOL_FINDING[0], fmt.DASH, fmt.DASH, fmt.DASH, fmt.DASH, fmt.DASH, findings.bold(findings.UNTESTABLE), TOOL_FINDING[1]])
    for name, C in G.items():
        for x in C.comparisons:
            if x.get("paper"):
                st, why = findings.status(x)
                rows.append([f"{findings.describe(x)} ({name})", f"{paper.diff_value(x['paper'])} ({paper.source(x['paper'])})",
                             f"`{x['candidate']}` − `{x['baseline']}`", fmt.cmp_rates(x), fmt.cmp_diff(x), fmt.per_seed_diff(x),
                             findings.bold(st), why])
    w(table.markdown(["paper's finding", "paper (configs/paper/numbers.json)", "our test", "ours: candidate / baseline",
                      "ours: difference [95 %]", "ours: per seed", "status", "reason"], rows))
    notes = [n for _, C in G.items() for n in C.notes()]
    if notes:
        w("## Notes from compare\n")
        w("\n".join(f"- {n}" for n in notes) + "\n")
    print(re.sub(r"\n{3,}", "\n\n", "\n".join(out)).rstrip("\n"))


if __name__ == "__main__":
    main()
