#!/usr/bin/env python3
"""The compare runs of the ladder page (docs/results/ladder.md). scripts/ladder writes one directory per experiment
of configs/experiments/ladder/; some of them hold cells with the same method label on the same (task, split) and
differ only by a job option that is not part of the label:

- the pool: `pool_reference9` and `pool_full` both run `exact_belief`, `entropy_probes` and
  `entropy_probes{calibrated}` on the reference splits (pool reference9 against the 180-contract pool full);
- the frame rotation: `tool_identity_hold`, `v2_tool_identity_hold_corrector` and `gen_hold_identity` run the
  labels of `grammar_hold`, `v2_hold_corrector` and `gen_hold` with `rotation_mode: identity` instead of live.

`actionshift compare` merges the records of every directory it is given into cells keyed by label, so these go
through separate compare runs, one JSON per group (the report merges them only for layout):

- `live`: every directory but the two below groups' own (pool reference9, the grammar rungs, the v2 rows, the
  causal controls, the generated split with its full-pool jobs), pairs `ladder.pairs`;
- `pool_full`: `pool_full` with the grammar directories on the reference splits (so the full pool can be paired
  with the grammar rungs), pairs `ladder.pool_full.pairs`;
- `identity`: the identity-rotation directories, pairs `ladder.identity.pairs` when that file exists (by default
  none: a pair of two labels of this group alone says nothing about the rotation).

A pairs file is looked up in `pairs_dir` (default scripts/pages/); the golden test passes its fixture directory,
whose pairs files hold only the pairs its tiny results can form (compare refuses a pair no cell holds).
usage: scripts/ladder_groups.py RESULTS_DIR [PAIRS_DIR]   prints `name<TAB>pairs file or -<TAB>dir...` per group"""
import os
import sys

PAGES = os.path.join(os.path.dirname(os.path.abspath(__file__)), "pages")
POOL_FULL = ("pool_full",)
IDENTITY = ("tool_identity_hold", "v2_tool_identity_hold_corrector", "gen_hold_identity")
REFERENCE_POOL = ("pool_reference9",)
# directories of the generated split (never in the pool_full group: its full-pool jobs, gen_pool_full, are in live)
GENERATED_PREFIX = "gen_"

# group name -> pairs file name
PAIRS = {"live": "ladder.pairs", "pool_full": "ladder.pool_full.pairs", "identity": "ladder.identity.pairs"}
ORDER = ("live", "pool_full", "identity")


def experiment_dirs(results):
    """The experiment directories under results that hold records, sorted by name."""
    out = []
    for name in sorted(os.listdir(results)):
        d = os.path.join(results, name)
        if os.path.isdir(d) and any(f.endswith(".jsonl") for f in os.listdir(d)):
            out.append(name)
    return out


def members(results):
    """{group name: [experiment directory names]} (a group without directories is left out)."""
    names = experiment_dirs(results)
    g = {
        "live": [n for n in names if n not in POOL_FULL + IDENTITY],
        "identity": [n for n in names if n in IDENTITY],
    }
    if any(n in POOL_FULL for n in names):
        g["pool_full"] = [n for n in names if n in POOL_FULL or (
            n not in IDENTITY + REFERENCE_POOL + POOL_FULL and not n.startswith(GENERATED_PREFIX))]
    return {k: v for k, v in g.items() if v}


def groups(results, pairs_dir=PAGES):
    """[(name, [directory paths], pairs file or None)] in page order."""
    m = members(results)
    out = []
    for name in ORDER:
        if name not in m:
            continue
        p = os.path.join(pairs_dir, PAIRS[name])
        out.append((name, [os.path.join(results, n) for n in m[name]], p if os.path.exists(p) else None))
    return out


def group_of(results):
    """{experiment directory name: group name}; a directory in two groups maps to its first (page order)."""
    out = {}
    m = members(results)
    for name in ORDER:
        for n in m.get(name, []):
            out.setdefault(n, name)
    return out


if __name__ == "__main__":
    for name, dirs, pairs in groups(sys.argv[1], *(sys.argv[2:3] or [PAGES])):
        print("\t".join([name, pairs or "-"] + dirs))
