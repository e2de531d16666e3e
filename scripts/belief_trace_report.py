#!/usr/bin/env python3
"""Writes docs/results/belief_trace.md (the belief-trace diagnostic) from the run summaries that
scripts/belief_trace_runs.sh collects (one JSON line per scripts/belief_trace.py run, with per-episode
t* and success flags). Every rate, count, distribution and mean on the page is computed here from the
summaries file: success rates, t* distributions and conditional success from the per-episode lists,
the per-step means (|pose|, |emitted - executed|, history disagreement, fraction of steps right) and
the verification counts from the run summaries. The contract index of an episode (i mod n) and a
contract's lag come from the split manifests (manifests/<split>.json), as in the runner.

The C++ backbones' own runs (`actionshift run`, step 5 of the runs script) are not in the summaries
file. With --cli-dir DIR (the runs script's CLI_OUT_DIR: DIR/<backbone>.<split>.<method>/*.jsonl) the
verification table gets the C++ columns; without it they are left out and the page says so.

Standard library only.
usage: scripts/belief_trace_report.py SUMMARIES.jsonl [--commit SHA] [--cli-dir DIR] > docs/results/belief_trace.md
Exit 1 when the data no longer supports a conclusion the page's fixed prose states."""
import argparse
import glob
import json
import os
import statistics
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
PROFILE = "maniskill"  # scripts/belief_trace.py's run_cell default; the summaries do not record it
BUCKETS = [("0", 0, 0), ("1-4", 1, 4), ("5-9", 5, 9), ("10-19", 10, 19), ("20-29", 20, 29), ("30-49", 30, 49)]
BB = ("ppo", "ppo-delay-aware")
RS, LL = "reference_seen", "long_lag"


def die(msg):
    print(f"belief_trace_report: {msg}", file=sys.stderr)
    sys.exit(1)


def rel(path):
    a = os.path.abspath(path)
    return os.path.relpath(a, ROOT) if a.startswith(ROOT + os.sep) else path


def f2(x):
    return "—" if x is None else f"{x:.2f}"


def f3(x):
    return "—" if x is None else f"{x:.3f}"


def mean(xs):
    xs = list(xs)
    return sum(xs) / len(xs) if xs else None


def span(xs, fmt=f2):
    """'a–b' over the values as printed, or 'a' when they print the same."""
    lo, hi = fmt(min(xs)), fmt(max(xs))
    return lo if lo == hi else f"{lo}–{hi}"


def pct(x):
    return f"{100 * x:.0f} %"


def pct_span(xs):
    return span([100 * x for x in xs], lambda v: f"{v:.0f}") + " %"


# ------------------------------------------------------------------ inputs
ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
ap.add_argument("summaries")
ap.add_argument("--commit", help="the commit to state (default: git rev-parse --short HEAD of this tree)")
ap.add_argument("--cli-dir", help="the runs script's CLI_OUT_DIR, for the C++-vs-numpy columns")
args = ap.parse_args()
commit = args.commit or subprocess.run(["git", "-C", ROOT, "rev-parse", "--short", "HEAD"],
                                       capture_output=True, text=True).stdout.strip() or "unknown"

MANIFEST = {}


def manifest(name):
    if name not in MANIFEST:
        MANIFEST[name] = json.load(open(os.path.join(ROOT, "manifests", name + ".json")))
    return MANIFEST[name]


def contracts(split):
    return [c["contract"] for c in manifest(split)["test"]]


records = [json.loads(l) for l in open(args.summaries) if l.strip()]
if not records:
    die(f"{args.summaries}: no records")


def key(r):
    return (r["backbone"], r["method"], r["split"], r["pool"], r["history"], int(r.get("perturb", 0)),
            r.get("perturb_part", "all") if int(r.get("perturb", 0)) else "all", int(r["seed"]))


CELLS = {}
for r in records:
    k = key(r)
    if len(r["success_flags"]) != r["summary"]["episodes"] or len(r["t_right"]) != r["summary"]["episodes"]:
        die(f"{k}: per-episode lists do not match the episode count")
    if k in CELLS:
        # the runs script repeats a few cells (e.g. the seed-20260718 baselines); the loop is deterministic
        if CELLS[k]["success_flags"] != r["success_flags"] or CELLS[k]["t_right"] != r["t_right"]:
            die(f"{k}: two runs of the same cell disagree")
        if r.get("verify") and not CELLS[k].get("verify"):
            CELLS[k] = r
        continue
    CELLS[k] = r

tasks = sorted({r["task"] for r in records})
if len(tasks) != 1:
    die(f"one task expected, got {tasks}")
TASK = tasks[0]
EPISODES = sorted({len(r["success_flags"]) for r in records})
SEEDS = sorted({int(r["seed"]) for r in records})
verified = [r for r in CELLS.values() if r.get("verify")]
MAIN_SEEDS = sorted({int(r["seed"]) for r in verified})
if len(MAIN_SEEDS) != 1:
    die(f"the verified main cells should share one seed, got {MAIN_SEEDS}")
MAIN = MAIN_SEEDS[0]
POOL = {sp: sorted({r["pool"] for r in records if r["split"] == sp and r["method"] != "oracle"}) for sp in (RS, LL)}
for sp in (RS, LL):
    if len(POOL[sp]) != 1:
        die(f"{sp}: one exact_belief pool expected, got {POOL[sp]}")
POOL = {sp: v[0] for sp, v in POOL.items()}


def pool_of(method, split):
    return POOL[split] if method != "oracle" else "-"


def get(bb, method, split, history="own", perturb=0, part="all", seed=None):
    k = (bb, method, split, pool_of(method, split), history, perturb, part if perturb else "all", MAIN if seed is None else seed)
    if k not in CELLS:
        die(f"no run for {k}")
    return CELLS[k]


def seeds_of(bb, method, split, history="own", perturb=0, part="all"):
    return [s for s in SEEDS
            if (bb, method, split, pool_of(method, split), history, perturb, part if perturb else "all", s) in CELLS]


# ------------------------------------------------------------------ per-episode quantities
def rate(r, sel=None):
    f = r["success_flags"]
    idx = range(len(f)) if sel is None else [i for i in range(len(f)) if sel(i)]
    return mean(1.0 if f[i] else 0.0 for i in idx)


def contract_of(r, i):
    return i % len(contracts(r["split"]))


def lag_of(r, i):
    return contracts(r["split"])[contract_of(r, i)]["lag"]


def by_contract(r, c):
    return rate(r, lambda i: contract_of(r, i) == c)


def by_lag(r, lag):
    return rate(r, lambda i: lag_of(r, i) == lag)


def right_from(r, t):
    return mean(1.0 if (x is not None and x <= t) else 0.0 for x in r["t_right"])


def never(r, sel=None):
    tr = r["t_right"]
    idx = range(len(tr)) if sel is None else [i for i in range(len(tr)) if sel(i)]
    return mean(1.0 if tr[i] is None else 0.0 for i in idx)


def cond(r, lo, hi):
    """(n, success rate) over the episodes whose t* is in [lo, hi] (lo None: never right)."""
    idx = [i for i, x in enumerate(r["t_right"]) if (x is None if lo is None else (x is not None and lo <= x <= hi))]
    return len(idx), (rate(r, lambda i: i in set(idx)) if idx else None)


def seed_mean(bb, method, split, history="own", perturb=0, part="all", fn=rate):
    ss = seeds_of(bb, method, split, history, perturb, part)
    if not ss:
        die(f"no runs for {(bb, method, split, history, perturb, part)}")
    return mean(fn(get(bb, method, split, history, perturb, part, s)) for s in ss)


# the contract and lag facts used in the prose, from the manifests
LAGS = sorted({c["lag"] for c in contracts(LL)})
if len(LAGS) != 2:
    die(f"{LL}: two lags expected, got {LAGS}")
for r in CELLS.values():  # the lag assignment reproduces the runs' own by-lag episode counts
    if r["split"] == LL and r.get("by_lag"):
        for L in LAGS:
            n = sum(lag_of(r, i) == L for i in range(len(r["success_flags"])))
            if r["by_lag"][str(L)]["episodes"] != n:
                die(f"{LL}: lag {L} has {n} episodes by the manifest, {r['by_lag'][str(L)]['episodes']} in the run")
    if r["split"] == RS and r["summary"].get("success_by_contract"):
        if len(r["summary"]["success_by_contract"]) != len(contracts(RS)):
            die(f"{RS}: the runs saw {len(r['summary']['success_by_contract'])} contracts, the manifest has {len(contracts(RS))}")
pool_members = {json.dumps(m["contract"], sort_keys=True) for m in manifest(POOL[RS])["members"]}
LL_IN_POOL = sum(json.dumps(c, sort_keys=True) in pool_members for c in contracts(LL))
C0 = contracts(RS)[0]
C0_TEXT = (("gripper inverted, " if C0["gripper_inverted"] else "")
           + f"scales {min(C0['scale']):g}–{max(C0['scale']):g}")

# ------------------------------------------------------------------ optional: the C++ backbones' runs
CLI = {}
CLI_COMMITS = set()
if args.cli_dir:
    for bb in BB:
        for sp in (RS, LL):
            for m in ("oracle", "exact_belief"):
                files = sorted(glob.glob(os.path.join(args.cli_dir, f"{bb}.{sp}.{m}", "*.jsonl")))
                if not files:
                    die(f"{args.cli_dir}: no {bb}.{sp}.{m}/*.jsonl")
                flags = {}
                for path in files:
                    for line in open(path):
                        rec = json.loads(line)
                        if rec["seed"] != MAIN or rec["profile"] != PROFILE:
                            die(f"{path}: seed {rec['seed']} / profile {rec['profile']}, expected {MAIN} / {PROFILE}")
                        flags[rec["episode_index"]] = bool(rec["success_once"])
                        CLI_COMMITS.add(rec.get("provenance", {}).get("git_commit", "?"))
                CLI[(bb, sp, m)] = [flags[i] for i in range(len(flags))]

# ------------------------------------------------------------------ the page
out = []
P = out.append
n_ep = "/".join(str(e) for e in EPISODES)
seeds_text = ", ".join(str(s) for s in SEEDS)
summ = rel(args.summaries)
# a CLI_OUT_DIR outside the repository is named by its role only (the page names no file outside the tree)
cli_name = None
if args.cli_dir:
    cli_name = rel(args.cli_dir) if os.path.abspath(args.cli_dir).startswith(ROOT + os.sep) else "CLI_OUT_DIR"
cmd = f"bash scripts/belief_trace_runs.sh {summ}" + (f" {cli_name}" if cli_name else "")

da_or = seed_mean("ppo-delay-aware", "oracle", RS)
da_eb = seed_mean("ppo-delay-aware", "exact_belief", RS)
da_eb_ex = seed_mean("ppo-delay-aware", "exact_belief", RS, "executed")
pp_or = seed_mean("ppo", "oracle", RS)
da_p1 = seed_mean("ppo-delay-aware", "oracle", RS, "own", 1)
pp_p1 = seed_mean("ppo", "oracle", RS, "own", 1)
da_p1_ex = seed_mean("ppo-delay-aware", "oracle", RS, "executed", 1)
da_p1_z = seed_mean("ppo-delay-aware", "oracle", RS, "zero:1", 1)
drop = da_or - da_eb
recovered = [da_eb_ex - da_eb, da_p1_ex - da_p1, da_p1_z - da_p1]
main_rs = {bb: get(bb, "exact_belief", RS) for bb in BB}
main_ll = {bb: get(bb, "exact_belief", LL) for bb in BB}
t1_share = mean(1.0 if x == 1 else 0.0 for x in main_rs["ppo-delay-aware"]["t_right"])

# the qualitative claims the fixed prose makes; stop rather than print a page that contradicts its numbers
checks = [
    ("the delay-aware network's |pose| is larger on both splits",
     all(get("ppo-delay-aware", "exact_belief", sp)["summary"]["norm_first10"] > get("ppo", "exact_belief", sp)["summary"]["norm_first10"] for sp in (RS, LL))),
    ("its belief is right from step <= 5 more often on both splits",
     all(right_from(get("ppo-delay-aware", "exact_belief", sp), 5) > right_from(get("ppo", "exact_belief", sp), 5) for sp in (RS, LL))),
    ("it succeeds less often than the reactive network with t* in 1-4",
     all(cond(get("ppo-delay-aware", "exact_belief", sp), 1, 4)[1] < cond(get("ppo", "exact_belief", sp), 1, 4)[1] for sp in (RS, LL))),
    ("the history fixes recover less than half of the drop", max(recovered) < drop / 2),
    ("one wrong step under the oracle costs the delay-aware network more than the reactive one",
     da_or - da_p1 > pp_or - pp_p1),
]
for what, ok in checks:
    if not ok:
        die(f"the data no longer supports: {what}")

P("# Belief trace: why the delay-aware PPO collapses under the passive exact belief (diagnostic)")
P("")
P(f"Generated by `scripts/belief_trace_report.py` from `{summ}` at commit `{commit}` (do not edit by hand).")
P(f"Summaries: `{cmd}` ({len(records)} runs of `scripts/belief_trace.py`, one JSON line each with per-episode")
P(f"t\\* and success flags). Task {TASK}, profile `{PROFILE}`, seeds {seeds_text} (main cells {MAIN}), {n_ep} episodes")
P("per cell and seed." + (f" C++ columns: the `actionshift run` records of the runs script's step 5 (`{cli_name}`; their commit "
                          + ", ".join(f"`{c}`" for c in sorted(CLI_COMMITS)) + ")." if args.cli_dir else ""))
P("")
P(f"**Question.** `ppo-delay-aware` ({TASK}; input = observation ++ its own last 4 emitted canonical")
P("actions) keeps its success through the oracle on `reference_seen` but collapses under `exact_belief`")
P(f"(`{POOL[RS]}`), while the reactive `ppo` keeps most of its success under the same belief (docs/backbones.md,")
P("\"Delay-aware PPO\", documents the C++ figures; the same on `long_lag`). In this page's Python loop")
P(f"(seed {MAIN}) the delay-aware network reaches {f2(rate(get('ppo-delay-aware', 'oracle', RS)))} through the oracle and "
  f"{f2(rate(main_rs['ppo-delay-aware']))} under the exact belief;")
P(f"the reactive one {f2(rate(main_rs['ppo']))} under the exact belief. Two candidate causes:")
P("")
P("- **(H) history mismatch**: while the belief is wrong the executed actions differ from the emitted")
P("  ones, a history the network never saw in training;")
P("- **(E) weak excitation**: the delay-aware network's actions are smaller or less varied, so the belief")
P("  identifies the contract later or never.")
P("")
P(f"**Answer in one line.** Neither, as stated: (E) is refuted, and (H) accounts for only about {span(recovered)} of the")
P(f"{f2(drop)} drop ({pct_span([x / drop for x in recovered])}). The belief identifies the contract *as fast or faster* for the delay-aware network")
P(f"(after exactly one wrong step in {pct(t1_share)} of reference_seen episodes). What breaks the delay-aware")
P("network is that **single wrong step of pose motion at step 0**: replaying it under the oracle, with")
P(f"nothing else wrong, reproduces the collapse ({f2(da_or)} → {f2(da_p1)}), while the reactive network loses little")
P(f"({f2(pp_or)} → {f2(pp_p1)}). Replacing the mismatched history with the executed actions, or clearing it, brings")
P(f"the delay-aware network back only to about {span([da_p1_ex, da_p1_z])} ({len(seeds_of('ppo-delay-aware', 'oracle', RS, 'own', 1))}-seed means).")
P("")
P("## How it was measured")
P("")
P("`scripts/belief_trace.py` loads the `.asmlp` file in numpy and evaluates it as the C++")
P("`MlpPolicy` does (float32 forward pass, tanh hidden layers, output clipped to [−1, 1], a delay-aware")
P("file gets its own last 4 outputs, most recent first, zeros at episode start). It runs the runner's")
P("episode loop (`src/eval/episode_fn.cpp`, `Context::run`) in Python with the module's adapters:")
P("episode i runs contract i mod n, environment seed `episode_seed(seed, i mod n, i)`, adapter seed")
P("`adapter_episode_seed(seed, i div n)`, a new adapter per episode. Each step it acts, reads R from")
P("the observation, encodes, steps, stops on a safety flag, observes the TCP response, and stops at the")
P("horizon. The finger channel is not fed: `observe_fingers` is a no-op for `oracle` and `exact_belief`.")
P("Success is `success_once`.")
P("")
P("Per step it records these privileged, diagnostic-only quantities:")
P("")
P("- **belief right**: the adapter's raw action equals `encode(true contract, intent, R, true tracked")
P("  target)` within 1e-9. The contract's lag is ignored, because no encoding can undo it. t\\* is the")
P("  step from which the belief is right at every remaining step;")
P("- **|pose|**: the norm of the emitted canonical pose action (6 channels);")
P("- **history disagreement**: the norm of the 4 × 7 history the network reads minus the executed history. Executed")
P("  = `clip(decode(true contract, raw, R, true tracked target), −1, 1)`, the canonical action entering")
P("  the lag pipeline. That is what the training history holds.")
P("")
P("Experiments that separate the causes (`--history`, `--perturb`):")
P("")
P("- `executed`: the network's history holds the executed canonical actions instead of its own")
P("  outputs, so the history agrees with the observed motion;")
P("- `zero:K`: the history is cleared before step K;")
P("- `random:K` and `wrongid:K`: under the oracle (correct execution), the history entries of the first")
P("  K steps are replaced by uniform noise, or by `decode(true contract, intent)` (the action the intent")
P("  would execute if sent unencoded). So the history is wrong but the execution is right;")
P("- `--perturb K [--perturb-part pose|gripper]`: under the oracle, the first K steps send the intent")
P("  unencoded. This is exactly what `exact_belief` sends before any evidence, when its MAP is the")
P("  pool's first hypothesis, the identity. The execution is wrong for K steps and right afterwards,")
P("  with no belief involved.")
P("")
P(f"Commands (all runs and this page: `scripts/belief_trace_runs.sh`; summaries, one JSON line per run with")
P(f"per-episode t\\* and success flags: `{summ}`):")
P("")
P("```")
P(f"{cmd}")
P("# one cell, e.g. (the runs script sets PYTHONPATH and ACTIONSHIFT_BACKBONES_DIR this way when unset):")
P(f"PYTHONPATH=build/python ACTIONSHIFT_BACKBONES_DIR=configs/backbones python3 scripts/belief_trace.py --task {TASK} \\")
P(f"    --backbone ppo-delay-aware --method exact_belief --split {RS} --pool {POOL[RS]} --episodes {EPISODES[0]} --seed {MAIN} --verify")
P("```")
P("")
sep_seeds = [s for s in SEEDS if s != MAIN]
P(f"Each cell uses {n_ep} episodes. The main cells use seed {MAIN}. The separating experiments on")
P(f"reference_seen use seeds {SEEDS[0]}–{SEEDS[-1]} where marked. Pools are `{POOL[RS]}` for")
P(f"`{RS}` and **`{POOL[LL]}`** for `{LL}`. The `{LL}` contracts are not in `{POOL[RS]}`")
P(f"({LL_IN_POOL} of {len(contracts(LL))}, by manifests/{LL}.json and manifests/{POOL[RS]}.json), so over that pool the belief could never be right. `{POOL[LL]}` is what the")
P("long-lag page (docs/results/long_lag.md) uses for its exact-belief cells. The summaries file does not record the commit of")
P("the build that produced it, nor wall times; the results are deterministic for a given build.")
P("")
P("## Verification of the Python loop")
P("")
main_cells = [(bb, sp, m) for bb in BB for sp in (RS, LL) for m in ("oracle", "exact_belief")]
V = [get(bb, m, sp)["verify"] for bb, sp, m in main_cells]
if any(v is None for v in V):
    die("a main cell has no --verify record")
v_eq = sum(v["flags_equal"] for v in V)
v_st = sum(v["steps_equal"] for v in V)
v_n = sum(v["episodes"] for v in V)
all_eq = v_eq == v_n and v_st == v_n
n_cells_eq = sum(v["flags_equal"] == v["episodes"] and v["steps_equal"] == v["episodes"] for v in V)
P("Each main cell was run twice with the same numpy policy: through the Python loop, and through")
P("`actionshift.evaluate()` (the library's runner). Per-episode success flags and step counts are")
if all_eq:
    P(f"**identical in all {len(V)} cells ({v_eq}/{v_n} episodes)**. The numpy forward pass is not bit-identical to the")
else:
    P(f"identical in {n_cells_eq} of {len(V)} cells (flags {v_eq}/{v_n}, step counts {v_st}/{v_n} episodes). The numpy forward pass is not bit-identical to the")
P("C++ `MlpPolicy`: summation order and the float tanh differ in the last bits, and contact dynamics")
if CLI:
    agree = [sum(a == b for a, b in zip(CLI[(bb, sp, m)], get(bb, m, sp)["success_flags"])) for bb, sp, m in main_cells]
    dr = max(abs(mean(CLI[(bb, sp, m)]) - rate(get(bb, m, sp))) for bb, sp, m in main_cells)
    P("amplify this. So the C++ backbones run through `actionshift run --threads 1` agree with it in")
    P(f"{span(agree, str)} of {EPISODES[0]} episodes, with rates within {f2(dr)}. The C++ runs give "
      f"{f2(mean(CLI[('ppo-delay-aware', RS, 'oracle')]))} / {f2(mean(CLI[('ppo-delay-aware', RS, 'exact_belief')]))} / "
      f"{f2(mean(CLI[('ppo', RS, 'exact_belief')]))} for the")
    P("figures docs/backbones.md documents (delay-aware oracle, delay-aware exact belief, reactive exact belief on reference_seen).")
else:
    P("amplify this, so the C++ backbones can differ from it in single episodes. That comparison (`actionshift run")
    P("--threads 1` on the main cells) is step 5 of `scripts/belief_trace_runs.sh`, run when it is given a CLI_OUT_DIR;")
    P("its records are not part of the summaries file and this page was generated without them (the report's")
    P("`--cli-dir` adds the C++ columns to the table below).")
P("")
hdr = "| backbone | split | method (pool) | Python loop | evaluate(), same numpy policy | flags equal |"
sep = "|---|---|---|---:|---:|---:|"
if CLI:
    hdr += " C++ backbone (`actionshift run`) | C++ vs numpy flags equal |"
    sep += "---:|---:|"
P(hdr)
P(sep)
for bb, sp, m in main_cells:
    r = get(bb, m, sp)
    v = r["verify"]
    row = (f"| {bb} | {sp} | {m}{'' if m == 'oracle' else f' ({POOL[sp]})'} | {f2(rate(r))} | {f2(v['evaluate_rate'])} | "
           f"{v['flags_equal']}/{v['episodes']} (steps {v['steps_equal']}/{v['episodes']}) |")
    if CLI:
        c = CLI[(bb, sp, m)]
        row += f" {f2(mean(c))} | {sum(a == b for a, b in zip(c, r['success_flags']))}/{len(c)} |"
    P(row)
P("")
P(f"## When the belief becomes right (seed {MAIN})")
P("")
P("The t columns give the fraction of episodes whose belief is right from step t onward. The last three")
P("columns are means over the first 10 steps of each episode.")
P("")
P("| backbone | split | method | success | t≤0 | t≤5 | t≤10 | t≤20 | t≤30 | never | steps right | \\|pose\\| | \\|emitted − executed\\| | history disagreement |")
P("|---|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
for bb, sp, m in main_cells:
    r = get(bb, m, sp)
    s = r["summary"]
    P(f"| {bb} | {sp} | {m} | {f2(rate(r))} | " + " | ".join(f2(right_from(r, t)) for t in (0, 5, 10, 20, 30))
      + f" | {f2(never(r))} | {f2(s['frac_steps_right'])} | {f2(s['norm_first10'])} | {f2(s['adis_first10'])} | {f2(s['hdis_first10'])} |")
P("")


def tstar_text(r):
    tr = r["t_right"]
    parts = []
    for t in (0, 1, 2):
        k = sum(x == t for x in tr)
        if k:
            txt = f"t\\* = {t} in {k}" + (" episodes" if not parts else "")
            if t == 1:
                k0 = sum(x == 1 and contract_of(r, i) == 0 for i, x in enumerate(tr))
                n0 = sum(contract_of(r, i) == 0 for i in range(len(tr)))
                txt += f" ({'all ' + str(n0) if k0 == n0 else f'{k0} of {n0}'} on contract 0)"
            parts.append(txt)
    later = sum(x is not None and x > 2 for x in tr)
    nev = sum(x is None for x in tr)
    if later:
        parts.append(f"later in {later}")
    if nev:
        parts.append(f"{nev} never")
    return ", ".join(parts[:-1]) + (", and " if len(parts) > 2 else " and ") + parts[-1] if len(parts) > 1 else parts[0]


P(f"On reference_seen the exact t\\* distribution under exact_belief is:")
P("")
for i, bb in enumerate(BB):
    P(f"- `{bb}`: {tstar_text(main_rs[bb])}{';' if i + 1 < len(BB) else '.'}")
P("")
early = {bb: mean(1.0 if x in (1, 2) else 0.0 for x in main_rs[bb]["t_right"]) for bb in BB}
P("So on reference_seen the belief is wrong only at step 0, or at steps 0–1, in "
  + " and ".join(f"{pct(early[bb])} (`{bb}`)" for bb in BB) + " of episodes.")
P("")
P(f"On long_lag (lag {LAGS[0]} / lag {LAGS[1]}), success under exact_belief is:")
P("")
for i, bb in enumerate(BB):
    r = main_ll[bb]
    P(f"- `{bb}`: {f2(by_lag(r, LAGS[0]))} / {f2(by_lag(r, LAGS[1]))}, never right in "
      f"{f2(never(r, lambda j: lag_of(r, j) == LAGS[0]))} / {f2(never(r, lambda j: lag_of(r, j) == LAGS[1]))}"
      + (" of episodes;" if i == 0 else "."))
P("")
P("Success conditional on t\\*, the step from which the belief stays right (n in brackets):")
P("")
P("| backbone | split | t\\*=0 | 1–4 | 5–9 | 10–19 | 20–29 | 30–49 | never |")
P("|---|---|---:|---:|---:|---:|---:|---:|---:|")
for sp in (RS, LL):
    for bb in BB:
        r = get(bb, "exact_belief", sp)
        cells = [cond(r, lo, hi) for _, lo, hi in BUCKETS] + [cond(r, None, None)]
        P(f"| {bb} | {sp} | " + " | ".join(f"{f2(p)} ({n})" for n, p in cells) + " |")
P("")
nf = {(bb, sp): get(bb, "exact_belief", sp)["summary"]["norm_first10"] for bb in BB for sp in (RS, LL)}
rf5 = {(bb, sp): right_from(get(bb, "exact_belief", sp), 5) for bb in BB for sp in (RS, LL)}
c14 = {(bb, sp): cond(get(bb, "exact_belief", sp), 1, 4)[1] for bb in BB for sp in (RS, LL)}
D, R_ = "ppo-delay-aware", "ppo"
P("**Against (E).** The delay-aware network's emitted pose actions are *larger* than the reactive one's")
P(f"(|pose| {f2(nf[(D, RS)])} vs {f2(nf[(R_, RS)])} over the first 10 steps on reference_seen, {f2(nf[(D, LL)])} vs {f2(nf[(R_, LL)])} on long_lag). Its")
P("belief becomes right earlier and more often: right from step ≤ 5 in "
  f"{f2(rf5[(D, RS)])} vs {f2(rf5[(R_, RS)])} of episodes on")
P(f"reference_seen, {f2(rf5[(D, LL)])} vs {f2(rf5[(R_, LL)])} on long_lag; never right in {f2(never(main_ll[D]))} vs {f2(never(main_ll[R_]))} on long_lag. Its failures")
P("are also not the late-identification episodes. With the belief right from step 1–4 it still")
P(f"succeeds in only {f2(c14[(D, RS)])} (reference_seen) and {f2(c14[(D, LL)])} (long_lag) of episodes, against {f2(c14[(R_, RS)])} and {f2(c14[(R_, LL)])} for")
P("the reactive network.")
P("")
P("## Separating the causes")
P("")
P(f"All rows run {n_ep} episodes per seed. \"Contract 0 / 1\" is the mean success on the two contracts of")
P(f"reference_seen. Contract 0 ({C0_TEXT}) is where the collapse is concentrated.")
P("")
# (backbone, method, history shown, history key, K shown, perturb, part, bold mean)
O, E = "oracle", "exact_belief"
ROWS = [
    (R_, O, "—", "own", "—", 0, "all", False),
    (D, O, "own", "own", "—", 0, "all", False),
    (D, E, "own", "own", "—", 0, "all", True),
    (D, E, "**executed**", "executed", "—", 0, "all", True),
    (R_, O, "—", "own", "**1, all channels**", 1, "all", True),
    (D, O, "own", "own", "**1, all channels**", 1, "all", True),
    (D, O, "executed", "executed", "1, all channels", 1, "all", False),
    (D, O, "zero:1 (cleared)", "zero:1", "1, all channels", 1, "all", False),
    (R_, O, "—", "own", "1, pose only", 1, "pose", False),
    (D, O, "own", "own", "1, pose only", 1, "pose", False),
    (R_, O, "—", "own", "1, gripper only", 1, "gripper", False),
    (D, O, "own", "own", "1, gripper only", 1, "gripper", False),
    (D, O, "wrongid:1 (history wrong, execution right)", "wrongid:1", "—", 0, "all", False),
] + [(D, O, f"wrongid:{k}", f"wrongid:{k}", "—", 0, "all", False) for k in (2, 5, 10)] \
  + [(D, O, f"random:{k}", f"random:{k}", "—", 0, "all", False) for k in (1, 2, 5, 10)]
for K in (2, 4):
    ROWS += [(R_, O, "—", "own", f"{K}, all channels", K, "all", False),
             (D, O, "own", "own", f"{K}, all channels", K, "all", False),
             (D, O, "executed", "executed", f"{K}, all channels", K, "all", False),
             (D, O, f"zero:{K}", f"zero:{K}", f"{K}, all channels", K, "all", False)]
P("| backbone | split | method | history | first K steps unencoded | " + " | ".join(str(s) for s in SEEDS) + " | mean | contract 0 / 1 |")
P("|---|---|---|---|---|" + "---:|" * len(SEEDS) + "---:|---|")
ranges = []
for bb, m, hs, hk, ks, K, part, bold in ROWS:
    ss = seeds_of(bb, m, RS, hk, K, part)
    vals = {s: rate(get(bb, m, RS, hk, K, part, s)) for s in ss}
    if len(ss) > 1:
        ranges.append(max(vals.values()) - min(vals.values()))
    mu = mean(vals.values())
    c0 = seed_mean(bb, m, RS, hk, K, part, fn=lambda r: by_contract(r, 0))
    c1 = seed_mean(bb, m, RS, hk, K, part, fn=lambda r: by_contract(r, 1))
    cells = " | ".join(f2(vals[s]) if s in vals else "" for s in SEEDS)
    P(f"| {bb} | {RS} | {m} | {hs} | {ks} | {cells} | {('**' + f3(mu) + '**') if bold else f3(mu)} | {f2(c0)} / {f2(c1)} |")
P("")
P(f"On long_lag (seed {MAIN} unless several values are given; lag {LAGS[0]} / lag {LAGS[1]} in the last column):")
P("")
LROWS = [
    (R_, O, "—", "own", "—", 0, False),
    (D, O, "own", "own", "—", 0, False),
    (D, E, "own", "own", "—", 0, False),
    (D, E, "**executed**", "executed", "—", 0, False),
    (R_, O, "—", "own", "4, all channels", 4, False),
    (D, O, "own", "own", "4, all channels", 4, False),
    (D, O, "executed", "executed", "4, all channels", 4, False),
    (D, O, "zero:4", "zero:4", "4, all channels", 4, False),
    (D, O, "random:5", "random:5", "—", 0, False),
    (D, O, "wrongid:5", "wrongid:5", "—", 0, False),
]
P("| backbone | method | history | first K steps unencoded | success | " + f"lag {LAGS[0]} / lag {LAGS[1]} |")
P("|---|---|---|---|---:|---|")
for bb, m, hs, hk, ks, K, _ in LROWS:
    ss = seeds_of(bb, m, LL, hk, K)
    rs_ = [get(bb, m, LL, hk, K, "all", s) for s in ss]
    l0 = mean(by_lag(r, LAGS[0]) for r in rs_)
    l1 = mean(by_lag(r, LAGS[1]) for r in rs_)
    mt = m if m == O else f"{m} ({POOL[LL]})"
    if len(rs_) > 1:
        succ = ", ".join(f2(rate(r)) for r in rs_) + f" (mean {f3(mean(rate(r) for r in rs_))})"
        lg = f"{f2(l0)} / {f2(l1)} (mean)"
    else:
        succ, lg = f2(rate(rs_[0])), f"{f2(l0)} / {f2(l1)}"
    P(f"| {bb} | {mt} | {hs} | {ks} | {succ} | {lg} |")
P("")


def ll_rate(bb, m, hk="own", K=0):
    return seed_mean(bb, m, LL, hk, K)


da_gr = seed_mean(D, O, RS, "own", 1, "gripper")
da_po = seed_mean(D, O, RS, "own", 1, "pose")
c0_fix = [seed_mean(D, E, RS, "executed", fn=lambda r: by_contract(r, 0)),
          seed_mean(D, O, RS, "executed", 1, fn=lambda r: by_contract(r, 0)),
          seed_mean(D, O, RS, "zero:1", 1, fn=lambda r: by_contract(r, 0))]
wr1 = seed_mean(D, O, RS, "wrongid:1")
wr2 = seed_mean(D, O, RS, "wrongid:2")
n_p1 = len(seeds_of(D, O, RS, "own", 1))
ll4 = [ll_rate(D, O, h, 4) for h in ("own", "executed", "zero:4")]
P("## Conclusion")
P("")
P("1. **Weak excitation (E) is refuted.** The delay-aware network emits larger actions and is")
P("   identified earlier than the reactive one. On reference_seen its belief is wrong only at step 0,")
P(f"   or at steps 0–1, in {pct(early[D])} of episodes. It fails anyway: with t\\* in 1–4 it succeeds in {f2(c14[(D, RS)])} of episodes, against {f2(c14[(R_, RS)])}")
P("   for the reactive network.")
P("2. **The exact-belief collapse is reproduced by the wrong first step alone.** Under the oracle,")
P(f"   sending only step 0 unencoded (what the exact belief sends before any evidence) gives {f3(da_p1)}")
P(f"   ({n_p1} seeds), within {f3(abs(da_p1 - da_eb))} of exact_belief's {f3(da_eb)}. The pose channels carry it: pose only gives {f3(da_po)};")
P(f"   gripper only gives {f3(da_gr)}, against {f3(da_or)} without the wrong step. The same single wrong step costs the reactive network")
P(f"   {f2(pp_or - pp_p1)} ({f2(pp_or)} → {f2(pp_p1)}).")
P("3. **The history mismatch (H) is a real but minor part.** It can be removed while keeping the wrong")
P("   step, in two ways:")
P("   - give the network the executed actions as its history, which then agrees with the observed")
P(f"     motion: exact_belief {f2(da_eb)} → {f2(da_eb_ex)}; one wrong step under the oracle {f2(da_p1)} → {f2(da_p1_ex)};")
P(f"   - clear the history after the wrong step: {f2(da_p1_z)}.")
P("")
P(f"   Either way about {span(recovered)} of the {f2(drop)} drop is recovered, and contract 0 stays at {span(c0_fix)}. The")
P("   network is sensitive to a wrong history even when the execution is right (one wrong history")
P(f"   entry: {f2(da_or)} → {f2(wr1)}; two: {f2(wr2)}). But this is not what drives the exact-belief collapse: once the")
P(f"   history is consistent or clean, the state after one wrong step still leaves the network at {span([da_p1_ex, da_p1_z])},")
P(f"   against {f2(da_or)} under the oracle.")
P("4. **What the data supports** is a third cause, neither (H) nor (E): the delay-aware PPO is")
P("   **brittle to the state perturbation of one or two off-policy pose steps at the start of an")
P("   episode**. The reactive PPO tolerates such a step. The size of the wrong step is about the same")
P(f"   for both networks: a mean |emitted − executed| of {f2(main_rs[D]['summary']['adis_first10'])} vs "
  f"{f2(main_rs[R_]['summary']['adis_first10'])} over the first 10 steps. So the")
P(f"   difference is the network's sensitivity, not a larger perturbation. On long_lag the picture is")
P(f"   the same: executed history gives {f2(ll_rate(D, E, 'executed'))} vs own {f2(ll_rate(D, E))}. Four unencoded steps under the oracle take")
P(f"   the delay-aware network from {f2(ll_rate(D, O))} to {span(ll4)} whatever its history, and leave the reactive")
P(f"   network at {f2(ll_rate(R_, O, 'own', 4))} (oracle {f2(ll_rate(R_, O))}). Here the slower identification (belief right by step 5 in only")
P(f"   {pct(rf5[(D, LL)])} of episodes) adds more wrong steps.")
P("")
se = max((0.25 / e) ** 0.5 for e in EPISODES)
P("This is a diagnostic. The loop is a Python copy of the runner, verified against `evaluate()` for the")
P(f"same numpy policy: {v_eq}/{v_n} identical episode outcomes."
  + (f" The numpy forward pass matches the C++ MLP's rates but not every episode ({pct_span([a / EPISODES[0] for a in agree])})."
     if CLI else " The numpy forward pass is compared with the C++ MLP only by the runs script's optional step 5."))
P("The separating experiments are interventions in that loop (privileged history, forced unencoded")
P(f"steps), not benchmark methods. Their finer differences are within the seed-to-seed spread of {n_ep}-episode")
P(f"cells: over the rows with several seeds, a row's success varies across seeds by {f2(statistics.median(ranges))} (median; up to")
P(f"{f2(max(ranges))}), and the binomial standard error of one cell is up to {f2(se)}.")
sys.stdout.write("\n".join(out) + "\n")
