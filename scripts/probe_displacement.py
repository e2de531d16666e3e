#!/usr/bin/env python3
"""Why do entropy probes move the arm more than the paper's? (diagnostic; docs/results/displacement.json)

Entropy probing spends its whole budget in the first `budget` steps of an episode, so the backbone's
intents do not enter its probes: this script runs those probe steps alone, exactly as the runner's
loop does (adapter seed, R from the observation, encode, step, response, observe), on pick_cube /
reference_seen with the reference9 pool, and records for every probe which raw channel it pulsed, which
canonical channel that is under the hidden contract (privileged, diagnostic only), and the TCP
translation it caused. It counts (no statistics): pulses that are canonical translations vs rotations,
pulses that repeat the previous pulse's raw channel and sign, and the mean translation per probe.

Configurations (each a row): the paper's rule and the `calibrated` variant, with our calibration and
with one built from the reference implementation's published PickCube gains and fit R^2 (sigma derived
as |alpha| * sqrt((1/R^2 - 1) / 3), the residual of a uniform[-1, 1] walk), rotation gains positive as
in our simulator. Fixed probes are the control (they do not depend on the calibration).

usage: PYTHONPATH=build/python python3 scripts/probe_displacement.py [--episodes N] [--out FILE]
"""
import argparse
import json
import math
import os
import sys

import numpy as np

import actionshift

SEED = 20260718  # an evaluation seed: this measures, it selects nothing
TASK = "pick_cube"
REF_ALPHA = [0.032, 0.016, 0.018, 0.035, 0.027, 0.038]  # reference implementation, PickCube v1, |alpha|
REF_R2 = [0.28, 0.11, 0.29, 0.34, 0.09, 0.26]


def splitmix64(x):
    m = (1 << 64) - 1
    z = (x + 0x9E3779B97F4A7C15) & m
    z = ((z ^ (z >> 30)) * 0xBF58476D1CE4E5B9) & m
    z = ((z ^ (z >> 27)) * 0x94D049BB133111EB) & m
    return z ^ (z >> 31)


def episode_seed(seed, block):  # src/eval/job.cpp
    return splitmix64(splitmix64(splitmix64(seed) ^ 0x696e6974737461) ^ block)


def adapter_seed(seed, block):
    return splitmix64(splitmix64(seed ^ 0x61646170746572) ^ block)


def run(method, calibration, episodes):
    split = actionshift.load_manifest("reference_seen")
    rows = []
    for ci, truth in enumerate(split.contracts):
        env = actionshift.make(TASK, contract=truth)
        for b in range(episodes):
            adapter = actionshift.make_adapter(method, task=TASK, pool="reference9", calibration=calibration)
            obs, _ = env.reset(seed=episode_seed(SEED, b))
            adapter.begin_episode(adapter_seed(SEED, b))
            prev = None
            for step in range(6):
                R = actionshift.tcp_rotation(obs, TASK)
                raw = np.asarray(adapter.encode(np.zeros(7), R))
                k = int(np.argmax(np.abs(raw[:6])))
                sign = 1 if raw[k] > 0 else -1
                canonical = truth.permutation.index(k)  # output i reads raw permutation[i]
                nobs, _, term, trunc, _ = env.step(raw)
                resp = np.asarray(actionshift.tcp_response(obs, nobs, TASK))
                adapter.observe(raw, resp, R)
                rows.append({"contract": ci, "raw_channel": k, "sign": sign, "canonical_channel": canonical,
                             "repeat": prev == (k, sign), "translation_m": float(np.linalg.norm(resp[:3]))})
                prev = (k, sign)
                obs = nobs
                if term or trunc:
                    break
    return rows


def tally(rows, episodes):
    n = len(rows)
    tr = [r for r in rows if r["canonical_channel"] < 3]
    ro = [r for r in rows if r["canonical_channel"] >= 3]
    return {
        "probe_steps": n,
        "translation_pulses": len(tr),
        "rotation_pulses": len(ro),
        "repeated_pulses": sum(r["repeat"] for r in rows),
        "displacement_per_episode_m": sum(r["translation_m"] for r in rows) / (2 * episodes),
        "translation_per_translation_pulse_m": (sum(r["translation_m"] for r in tr) / len(tr)) if tr else 0.0,
        "translation_per_rotation_pulse_m": (sum(r["translation_m"] for r in ro) / len(ro)) if ro else 0.0,
        "raw_channel_counts": [sum(1 for r in rows if r["raw_channel"] == c) for c in range(6)],
    }


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--episodes", type=int, default=25, help="episodes per contract (default 25)")
    ap.add_argument("--out", default="docs/results/displacement.json")
    args = ap.parse_args()
    ours = json.load(open("configs/calibration/maniskill/pick_cube.json"))
    ref = dict(ours)
    ref["alpha"] = REF_ALPHA
    ref["sigma"] = [a * math.sqrt((1 / r - 1) / 3) for a, r in zip(REF_ALPHA, REF_R2)]
    configs = [
        ("fixed_probes", "ours", None),
        ("entropy_probes", "ours", None),
        ("entropy_probes{calibrated}", "ours", None),
        ("entropy_probes", "reference gains", ref),
        ("entropy_probes{calibrated}", "reference gains", ref),
    ]
    out = {"command": "PYTHONPATH=build/python python3 scripts/probe_displacement.py --episodes %d" % args.episodes,
           "task": TASK, "split": "reference_seen", "pool": "reference9", "seed": SEED,
           "episodes_per_contract": args.episodes, "rows": []}
    for method, cal_name, cal in configs:
        rows = run(method, cal, args.episodes)
        t = tally(rows, args.episodes)
        t.update({"method": method, "calibration": cal_name})
        out["rows"].append(t)
        print(json.dumps(t), file=sys.stderr)
    by = {(r["method"], r["calibration"]): r for r in out["rows"]}
    fx, ep, ec = by[("fixed_probes", "ours")], by[("entropy_probes", "ours")], by[("entropy_probes{calibrated}", "ours")]
    rp, rc = by[("entropy_probes", "reference gains")], by[("entropy_probes{calibrated}", "reference gains")]
    n = fx["probe_steps"]
    out["summary"] = (
        f"A probe moves the TCP when it is a canonical *translation* pulse ({fx['translation_per_translation_pulse_m']:.4f} m on "
        f"average for the fixed sweep) and hardly when it is a rotation pulse ({fx['translation_per_rotation_pulse_m']:.4f} m). "
        f"The fixed sweep pulses each channel once, so {fx['translation_pulses']} of its {n} pulses translate "
        f"({fx['displacement_per_episode_m']:.4f} m per episode, as the paper's reference implementation: 0.0656 m). Entropy probing "
        f"picks the pulses its criterion scores most informative, and with our calibration that is translation: "
        f"{ep['translation_pulses']} of {n} pulses under the paper's rule ({ep['displacement_per_episode_m']:.4f} m per episode) and "
        f"{ec['translation_pulses']} of {n} under `{{calibrated}}` ({ec['displacement_per_episode_m']:.4f} m), on "
        f"{sum(1 for k in ep['raw_channel_counts'] if k)} and {sum(1 for k in ec['raw_channel_counts'] if k)} of the 6 raw "
        f"channels. The preview rule is not the cause; the **response calibration** is: run with the gains and fit R² the "
        f"reference implementation published for ManiSkill's PickCube (σ derived from them), the paper's rule picks rotation for "
        f"{rp['rotation_pulses']} of {n} pulses and moves the arm {rp['displacement_per_episode_m']:.4f} m per episode, "
        f"{rp['displacement_per_episode_m'] / ep['displacement_per_episode_m']:.0%} of what it moves with ours (the `{{calibrated}}` "
        f"variant: {rc['displacement_per_episode_m']:.4f} m). Our simulator's translation channels have a higher gain-to-noise "
        f"ratio than ManiSkill's (our calibration: configs/calibration/maniskill/pick_cube.json), so the entropy criterion "
        f"prefers them. The rest of the gap to the paper's 0.0229 m (our rotation pulses still translate the TCP "
        f"{rp['translation_per_rotation_pulse_m']:.4f} m each) is not explained by these runs. Measured by "
        f"`{out['command']}` ({args.episodes} episodes per contract, seed {SEED}, the probe steps alone: entropy probes do not depend "
        f"on the backbone).")
    out["rows"] = [{"method": f"`{r['method']}`", "calibration": r["calibration"],
                    "translation / rotation pulses": f"{r['translation_pulses']} / {r['rotation_pulses']}",
                    "raw channels pulsed (0..5)": " ".join(str(k) for k in r["raw_channel_counts"]),
                    "m per translation pulse": f"{r['translation_per_translation_pulse_m']:.4f}",
                    "m per rotation pulse": f"{r['translation_per_rotation_pulse_m']:.4f}",
                    "displacement per episode [m]": f"{r['displacement_per_episode_m']:.4f}"} for r in out["rows"]]
    os.makedirs(os.path.dirname(args.out) or ".", exist_ok=True)
    with open(args.out, "w") as f:
        json.dump(out, f, indent=1)
        f.write("\n")


if __name__ == "__main__":
    main()
