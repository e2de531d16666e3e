#!/usr/bin/env python3
"""Writes docs/results/brittleness.md: per task, backbone and split, clean success (Gate 0's unwrapped runs, one
verdict file per seed), hidden with no adaptation, and restored by each adapter label, beside the paper's
numbers (its frozen PPO's for the expert, MLP and PPO rows, its Diffusion Policy's for the `dp` rows). Layout
only: every rate, interval, difference and verdict is from `actionshift compare` (the cells and the pairs of
scripts/brittleness.pairs) or from a Gate 0 verdict file; the paper's numbers from compare's paper fields or,
for the clean rates and the Diffusion Policy scalars, configs/paper/numbers.json by id; the Diffusion Policy's
inference cost from RESULTS_DIR/dp_cost.json (scripts/pages/dp_cost.py) when it exists. The §5.8 section marks each of
the paper's claims about its Diffusion Policy per task (clean, collapse, restoration to the oracle ceiling, DualABI's
probe steps) by the dp_*_status rules below.
usage: scripts/brittleness_report.py COMPARE_JSON RESULTS_DIR [--commit C --command CMD --wall S --cores N --cpu TIMES]"""
import glob
import json
import os
import re
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from pages import findings, fmt, load_comparison, paper, provenance, table  # noqa: E402
from pages.rest_util import cpu_text, commit_of, parser, probe_rule, rel, scalar  # noqa: E402

BACKBONES = [("expert", "scripted"), ("mlp", "imitation (DAgger MLP)"), ("dp", "imitation (Diffusion Policy)"),
             ("ppo", "RL (PPO)")]
SPLITS = ["reference_seen", "reference_unseen_composition"]
ORDER = ["no_adapt", "oracle", "exact_belief", "entropy_probes", "entropy_probes{calibrated}", "dualabi", "dualabi{calibrated}",
         "grammar_belief"]
DP_IDS = ["s5.8.pick_cube.diffusion_policy.clean_success", "s5.8.push_cube.diffusion_policy.clean_success",
          "s5.8.diffusion_policy.no_adapt", "abstract.no_adapt.success_once_floor_min", "abstract.no_adapt.success_once_floor_max",
          "s5.8.diffusion_policy.restored_success_min", "s5.8.diffusion_policy.restored_success_max",
          "s5.8.diffusion_policy.dualabi.probe_steps_seen"]
DP_RESTORERS = ["exact_belief", "entropy_probes", "dualabi"]  # the adapters of the paper's Diffusion Policy rows


def job_summaries(results, jobs):
    """{job id: its `<id>.summary.json`} for the jobs that have one."""
    out = {}
    for j in jobs:
        path = os.path.join(results, j + ".summary.json")
        if os.path.exists(path):
            with open(path) as f:
                out[j] = json.load(f)
    return out


def jobs_wall_per_step(C, summaries, task, dp):
    """(seconds, control steps) of the task's jobs with (dp) or without the `dp` backbone, from their summaries'
    `wall_time_s` and `mean_steps` x `episodes_run` (each job's own run; a job resumed across runs counts its last)."""
    sec = steps = 0.0
    for c in C.cells_where(task=task):
        if (c["backbone"] == "dp") != dp:
            continue
        for j in c["jobs"]:
            v = summaries.get(j)
            if v and v.get("wall_time_s") is not None:
                sec += v["wall_time_s"]
                steps += v["mean_steps"] * v["episodes_run"]
    return sec, steps


def duration(seconds):
    """`42 s`, `12.5 min` or `3.20 h`."""
    if seconds < 120:
        return f"{seconds:.0f} s"
    if seconds < 7200:
        return f"{seconds / 60:.1f} min"
    return f"{seconds / 3600:.2f} h"


def threads_of(command):
    """THREADS=N of the recorded command, or '?'."""
    m = re.search(r"THREADS=(\d+)", command or "")
    return m.group(1) if m else "?"


def clean_paper_id(backbone, task):
    """The paper's clean rate for a backbone's row: its Diffusion Policy's (§5.8) for `dp`, its frozen PPO's (Table 1)."""
    return f"s5.8.{task}.diffusion_policy.clean_success" if backbone == "dp" else f"table1.{task}.clean_success"


def horizons(cell, spec_of):
    """The control steps per episode of a cell's jobs (a job spec names its horizon only when it is not the task's)."""
    hs = sorted({str(spec_of[j].get("horizon", "task's")) for j in cell["jobs"] if j in spec_of})
    return ", ".join(hs) or fmt.DASH


def paper_backbone(cell):
    e = paper.cell_entry(cell)
    return (e or {}).get("paper_backbone", fmt.DASH)


def dp_probe_status(cell):
    """The paper's 'DualABI needs 0.0 probe steps on seen' for our `dp`: reproduced when our mean prints as 0.0 (below
    0.05 steps per episode), contradicted otherwise, untestable when the cell was not run. Rule written before any
    Diffusion Policy ran."""
    if not cell:
        return findings.UNTESTABLE, "the cell was not run here"
    m = cell["mean_probe_steps"]
    if m < 0.05:
        return findings.REPRODUCED, f"ours {m:.2f} probe steps per episode over {cell['episodes']} episodes"
    return findings.CONTRADICTED, (f"ours {m:.2f} probe steps per episode over {cell['episodes']} episodes,"
                                   " against the paper's 0.0")


def dp_clean_status(paper_rate, seeds):
    """The paper's clean rate for its Diffusion Policy against our Gate 0 runs, one Wilson interval per seed (seeds:
    [(seed, verdict cell)]): reproduced when the paper's rate lies inside the intervals of most seeds, contradicted
    otherwise (the reason says how many seeds lie above and below it), untestable without a run or a paper rate.
    Rule written after the pick_cube `dp` clean rates were first published here; it is the plain reading of a
    per-seed interval, with no threshold to choose."""
    if paper_rate is None or not seeds:
        return findings.UNTESTABLE, "no clean run here" if not seeds else "the paper gives no clean rate for this task"
    ivs = [v["competence"]["interval"] for _, v in seeds]
    inside = sum(w["lower"] <= paper_rate <= w["upper"] for w in ivs)
    above = sum(w["lower"] > paper_rate for w in ivs)
    below = sum(w["upper"] < paper_rate for w in ivs)
    why = f"the paper's {paper_rate:.3f} is inside {inside} of {len(ivs)} seeds' Wilson intervals"
    if above or below:
        why += f" (ours above it on {above}, below it on {below})"
    return (findings.REPRODUCED if 2 * inside > len(ivs) else findings.CONTRADICTED), why


def dp_collapse_status(cell, floor_max):
    """The paper's 'collapses to ~0.003, the same 0.000-0.007 floor' for our `dp` without adaptation: reproduced when
    our Wilson interval reaches the floor (its lower bound at most the floor's top, 0.007), contradicted when the
    whole interval lies above it."""
    if not cell:
        return findings.UNTESTABLE, "the cell was not run here"
    w = cell["success_once"]
    ours = f"our interval {fmt.interval(w['lower'], w['upper'])}"
    if w["lower"] <= floor_max:
        return findings.REPRODUCED, f"{ours} reaches the paper's floor (at most {floor_max:.3f})"
    return findings.CONTRADICTED, f"{ours} lies above the paper's floor (at most {floor_max:.3f})"


def dp_restore_status(cmp, adapter, ceiling):
    """The paper's 'the same adapters restore it to its oracle ceiling' for one adapter, on compare's paired
    oracle − adapter (the delayed-oracle page's rule, here over every seed and split): reproduced when the difference
    does not put the adapter below its oracle (it includes 0, or the adapter is above the oracle); contradicted
    when it excludes 0 with the adapter below; untestable when either label was not run, or when the oracle itself
    does not lift the backbone above no adaptation (ceiling: oracle − no_adapt; no ceiling to restore to)."""
    if not cmp:
        return findings.UNTESTABLE, f"oracle or {adapter} was not run here"
    if not ceiling or not (ceiling["difference"]["excludes_zero"] and ceiling["difference"]["estimate"] > 0):
        return findings.UNTESTABLE, ("the oracle does not lift it above no adaptation (oracle − no_adapt "
                                     f"{fmt.diff(ceiling['difference']) if ceiling else fmt.DASH}): no ceiling to restore to")
    d = cmp["difference"]
    if not d["excludes_zero"]:
        return findings.REPRODUCED, f"oracle − {adapter} {fmt.diff(d)} includes 0"
    if d["estimate"] < 0:
        return findings.REPRODUCED, f"{adapter} is above its oracle: oracle − {adapter} {fmt.diff(d)}"
    return findings.CONTRADICTED, (f"{adapter} is below its oracle: oracle − {adapter} {fmt.diff(d)} excludes 0; how much"
                                   " of it the first steps without the contract explain is measured on"
                                   " docs/results/delayed_oracle.md")


def dp_claims(C, clean, numbers, task):
    """The rows of §5.8's claims for one task's `dp`: [claim, split, paper, ours, status, reason]."""
    rows = []
    pe = numbers.by_id(clean_paper_id("dp", task))
    seeds = clean.get(("dp", task), [])
    st, why = dp_clean_status(pe.get("value") if pe else None, seeds)
    rows.append(["a competent frozen Diffusion Policy (clean)", fmt.DASH, paper.entry_value(pe),
                 " / ".join(fmt.num(v["competence"]["interval"]["rate"]) for _, v in seeds) or fmt.DASH, st, why])
    floor_max = (numbers.by_id("abstract.no_adapt.success_once_floor_max") or {}).get("value", 0.007)
    for split in SPLITS:
        c = C.cell(task, split, "no_adapt", "dp")
        st, why = dp_collapse_status(c, floor_max)
        rows.append(["collapses to the 0.000–0.007 floor (`no_adapt`)", split.replace("reference_", ""),
                     paper.cell_column(c) if c else fmt.DASH, fmt.cell_rate(c), st, why])
    for split in SPLITS:
        for m in DP_RESTORERS:
            c, o = C.cell(task, split, m, "dp"), C.cell(task, split, "oracle", "dp")
            st, why = dp_restore_status(C.comparison("oracle", m, task, split, "dp"), m,
                                        C.comparison("oracle", "no_adapt", task, split, "dp"))
            rows.append([f"`{m}` restores it to its oracle ceiling (0.62–0.735)", split.replace("reference_", ""),
                         paper.cell_column(c) if c else fmt.DASH,
                         f"{fmt.cell_point(c)} (oracle {fmt.cell_point(o)})", st, why])
    c = C.cell(task, "reference_seen", "dualabi", "dp")
    st, why = dp_probe_status(c)
    rows.append(["DualABI's efficiency transfers: 0.0 probe steps (`dualabi`)", "seen", "0.00 (§5.8)",
                 fmt.probe_steps(c), st, why])
    return [[r[0], task] + r[1:4] + [findings.bold(r[4]), r[5]] for r in rows]


def own_runs_text(task, threads, ds, dn, step_ms, os_, on):
    """The page's own `dp` jobs (ds seconds of wall time, dn control steps, `threads` threads each) beside the
    benchmark's one-thread step_ms: like with like, the benchmark's CPU time and, spread over the job's threads,
    the wall time it would take if they never waited, against the measured wall time; then the other backbones'."""
    cpu = dn * step_ms / 1000
    text = (f"In this page's own runs ({threads} thread(s) per job; the jobs' `wall_time_s` and steps from their"
            f" summaries) the `dp` jobs of {task} took {duration(ds)} of wall time for {fmt.thousands(int(dn))} control"
            f" steps ({1000 * ds / dn:.2f} ms per step). At the benchmark's one-thread {step_ms:.2f} ms per step the"
            f" policy alone is {duration(cpu)} of CPU time")
    if str(threads).isdigit() and int(threads) > 1:
        text += f", {duration(cpu / int(threads))} of wall time if the job's {threads} threads never wait"
    text += f", against the {duration(ds)} measured"
    if on:
        text += (f"; the other backbones' jobs took {duration(os_)} for {fmt.thousands(int(on))} steps"
                 f" ({1000 * os_ / on:.3f} ms per step, adapters and simulation included)")
    return text + "."


def dp_cost_section(path, C, summaries, threads):
    """The Diffusion Policy's inference cost against the simulator step it drives, from dp_cost.json."""
    if not os.path.exists(path):
        return ["No Diffusion Policy ran here, so its inference cost was not measured on this page (docs/backbones.md"
                " has the benchmark's figures for both networks).\n"]
    with open(path) as f:
        d = json.load(f)
    load = d.get("load_avg")
    out = [f"Measured by `scripts/brittleness` after its runs ({d['bench']}), {d.get('date', '?')}, load average "
           f"{', '.join(f'{x:.2f}' for x in load) if load else '?'} on {d.get('num_cpus', '?')} CPUs: the policy's "
           "figures are CPU time on one thread (random weights of the same shape and sampler), the simulator's one "
           "thread's control steps per second (`bench env`, a scripted grasp with contact).\n"]
    rows = []
    for t in d["tasks"]:
        rows.append([t["task"], f"`{t['weights']}`", "/".join(str(x) for x in t["down_dims"]), fmt.thousands(t["parameters"]),
                     t["sampler"], f"{t['chunk_ms']:.1f}", f"{t['control_step_ms']:.2f}", f"{t['sim_step_ms']:.3f}",
                     f"{t['ratio']:.0f}x"])
    out.append(table.markdown(["task", "weights", "U-Net", "parameters", "sampler", "one chunk [ms]",
                               "per control step [ms] (a chunk per " + str(d["tasks"][0]["act_horizon"]) + " steps)",
                               "simulator step [ms]", "policy / simulator"], rows,
                              ["l", "l", "l", "r", "l", "r", "r", "r", "r"]))
    out.append("")
    for t in d["tasks"]:
        if t["ratio"] <= 1.0:
            out.append(f"On {t['task']} a Diffusion Policy step costs less than the simulator step it drives.\n")
            continue
        out.append(
            f"On {t['task']} a Diffusion Policy control step costs **{t['ratio']:.0f} times** the simulator step it drives, "
            "so it does not meet the bar of costing less. The factor carries over to any evaluation: an episode with this "
            f"backbone costs about {t['ratio'] + 1:.0f} times one with a policy of negligible cost (the MLP and PPO "
            "backbones cost microseconds per step), because the runner spends its time in the sampler's U-Net passes; "
            "a tournament of the same episodes would take that much longer on the same cores. The paper's Diffusion "
            "Policy ran on a GPU.\n")
        ds, dn = jobs_wall_per_step(C, summaries, t["task"], True)
        os_, on = jobs_wall_per_step(C, summaries, t["task"], False)
        if dn:
            out.append(own_runs_text(t["task"], threads, ds, dn, t["control_step_ms"], os_, on) + "\n")
    out.append("")
    return out


def main():
    ap = parser(__doc__)
    ap.add_argument("compare")
    ap.add_argument("results")
    a = ap.parse_args()
    C = load_comparison(a.compare)
    numbers = paper.load_numbers()
    res = rel(a.results)
    summaries = job_summaries(a.results, C.jobs())
    spec_of = {j: v["job"] for j, v in summaries.items()}
    specs = list(spec_of.values())
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
        bootstrap=C.bootstrap(), reused=a.reused,
        extra=[f"CPU: {cpu_text(a.cpu)[2:] or 'not measured'}.",
               "Clean: Gate 0's unwrapped run (`actionshift gate0 --seed S`, one verdict file per seed in "
               f"`{res}/clean/`), shown per seed with the Wilson interval the verdict file holds (compare does not read "
               "verdict files, so no pooled clean rate is shown)."])]
    w = out.append
    w("The paper's claim (§5.8): brittleness is interface-semantic, not paradigm-specific. A frozen imitation policy\n"
      "(Diffusion Policy) collapses under the same hidden contracts that zero the frozen PPO policy, and the same\n"
      "policy-agnostic adapters restore it to its own oracle ceiling. Here each backbone runs clean, behind the hidden\n"
      "contracts of `reference_seen` and `reference_unseen_composition` with no adaptation, and through the same\n"
      "adapters: the oracle, the exact pool belief, entropy probing and DualABI over the `reference9` pool (the probing\n"
      "ones with the paper's probe rule, the bare name, and the project's `{calibrated}` rule, docs/adapters.md), and\n"
      "the pool-free grammar belief. What each label ran is read from the label (column `what ran`). The Diffusion\n"
      "Policy (`dp`) runs at horizon 100, as the reference evaluates it; the others at the task's (50 control steps\n"
      "here). The paper column holds the paper's number for the row's paradigm, named in the next column: its frozen\n"
      "PPO (Table 2, Table 5) beside `expert`, `mlp` and `ppo`, its Diffusion Policy (the reference implementation's\n"
      "imitation report, horizon 100) beside `dp`; a `{...}` label has no paper number.\n")
    for task in C.values("task"):
        w(f"## {task}\n")
        rows = []
        for bb, paradigm in BACKBONES:
            cells = C.cells_where(task=task, backbone=bb)
            if not cells and (bb, task) not in clean:
                continue
            ce = numbers.by_id(clean_paper_id(bb, task))
            for seed, v in clean.get((bb, task), []):
                rows.append([f"`{bb}`", paradigm, fmt.DASH, str(v.get("horizon", "task's")), "clean (Gate 0, unwrapped)",
                             f"seed {seed}", fmt.rate(v["competence"]["interval"]), fmt.DASH, fmt.DASH, fmt.DASH,
                             paper.entry_value(ce), (ce or {}).get("paper_backbone", fmt.DASH)])
            for split in SPLITS + [x for x in C.values("split", cells) if x not in SPLITS]:
                labels = [m for m in ORDER if C.cell(task, split, m, bb)]
                labels += [m for m in C.values("method", C.cells_where(task=task, split=split, backbone=bb))
                           if m not in labels]
                for m in labels:
                    c = C.cell(task, split, m, bb)
                    rows.append([f"`{bb}`", paradigm, split.replace("reference_", ""), horizons(c, spec_of), f"`{m}`",
                                 probe_rule(m) if probe_rule(m) != m else fmt.DASH, fmt.cell_rate(c), fmt.per_seed(c),
                                 fmt.probe_steps(c), fmt.safety(c), paper.cell_column(c), paper_backbone(c)])
        w(table.markdown(["backbone", "paradigm", "split", "horizon", "label", "what ran", "success (Wilson 95 %)",
                          "per seed", "probe steps", "flagged episodes", "paper", "paper's backbone"], rows,
                         ["l", "l", "l", "r", "l", "l", "l", "l", "r", "l", "l", "l"]))
        w("")
    w("## Paired differences\n")
    w("Every pair of `scripts/brittleness.pairs` in every backbone and split that ran both labels (candidate − baseline"
      " over the same episodes), with the promotion gate's verdict and the paper's difference where the paper gives one.\n")
    rows = []
    for cmp in C.comparisons:
        v, rule, _ = fmt.promotion(cmp)
        rows.append([cmp["task"], cmp["split"].replace("reference_", ""), f"`{cmp['backbone']}`",
                     f"`{cmp['candidate']}` − `{cmp['baseline']}`", fmt.cmp_rates(cmp), fmt.cmp_diff(cmp, mark=True),
                     fmt.per_seed_diff(cmp), paper.cmp_column(cmp), f"{v} ({rule})"])
    w(table.markdown(["task", "split", "backbone", "pair", "success: candidate / baseline", "difference [95 %]",
                      "per seed", "paper", "promotion"], rows))
    w("")
    w("## The paper's findings\n")
    w("Status from compare's fields (scripts/pages/findings.py): a finding whose paper difference is significant is"
      " reproduced only when ours excludes 0 with the same sign (compare's `sign_agreement`). For `dp` the paper's"
      " differences are those of its Diffusion Policy's printed cells (their notes say how).\n")
    items = [(f"the hidden contract collapses `{c['backbone']}` and the oracle restores it ({c['task']} / {c['split']})", c)
             for c in C.comparisons_where(candidate="oracle", baseline="no_adapt")]
    items += [(f"{findings.describe(c)} (`{c['backbone']}`)", c) for c in C.comparisons
              if c.get("paper") and c["candidate"] != "oracle"]
    w(findings.findings_table(items) if items else "No pair with a paper difference was run.\n")
    w("")
    if any(c["backbone"] == "dp" for _, c in items):
        w("For `dp` a row above tests only that an adapter lifts the backbone above no adaptation, with the paper's"
          " sign. §5.8 claims restoration *to the oracle ceiling*, which the claims table of the next section tests"
          " on the oracle − adapter pairs: a `dp` row marked reproduced here can be contradicted there.\n")
    w("## The Diffusion Policy (§5.8)\n")
    w("The paper's imitation backbone is a Diffusion Policy; ours are the DAgger MLP (`mlp`) and, where a weight file"
      " is adopted (docs/backbones.md), a Diffusion Policy trained here from the scripted expert's demonstrations"
      " (`dp`). Its rows and paired differences are above; the findings table above tests only the sign of each"
      " difference from no adaptation. §5.8 claims more: a competent clean policy, a collapse to the 0.000–0.007"
      " floor, restoration *to its oracle ceiling* and DualABI's 0.0 probe steps on seen. Each claim per task, by the"
      " rules of scripts/brittleness_report.py (`dp_clean_status`, `dp_collapse_status`, `dp_restore_status`: the"
      " delayed-oracle page's rule on the oracle − adapter pairs, `dp_probe_status`):\n")
    rows = []
    for task in C.values("task"):
        if not C.cells_where(task=task, backbone="dp") and ("dp", task) not in clean:
            continue
        rows += dp_claims(C, clean, numbers, task)
    w(table.markdown(["claim (§5.8)", "task", "split", "paper", "ours", "status", "reason"], rows)
      if rows else "No `dp` backbone ran here: no Diffusion Policy weight file is adopted yet (docs/backbones.md).\n")
    w("")
    if rows:
        w("Where restoration falls short of the oracle, docs/results/delayed_oracle.md (`scripts/delayed_oracle`, each"
          " task's seen contracts) measures how much of the gap the first steps without the contract explain: an oracle"
          " that starts late, before any adapter could know the contract.\n")
    w("The paper's scalars (configs/paper/numbers.json by id):\n")
    rows = [[f"`{i}`", (numbers.by_id(i) or {}).get("quantity", fmt.DASH), scalar(numbers, i),
             (numbers.by_id(i) or {}).get("note", "")] for i in DP_IDS]
    w(table.markdown(["id", "quantity", "value (source)", "note"], rows))
    w("")
    w("### Inference cost\n")
    out.extend(dp_cost_section(os.path.join(a.results, "dp_cost.json"), C, summaries, threads_of(a.command)))
    w("## Backbone identities\n")
    sha = sorted({(s["backbone"]["name"], s["task"], s["backbone"]["sha256"]) for s in specs})
    w(table.markdown(["backbone", "task", "sha256"], [[f"`{b}`", t, f"`{h}`"] for b, t, h in sha]))
    print(re.sub(r"\n{3,}", "\n\n", "\n".join(out)).rstrip("\n"))


if __name__ == "__main__":
    main()
