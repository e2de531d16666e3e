#!/usr/bin/env python3
"""Runs the Python worked example of docs/methods.md (docs/examples/separation_probes.py) on the
tournament's reference cells: the cube tasks, reference_seen and reference_unseen_composition, pool
reference9, seeds 20260718-20, 200 episodes per job, with the expert and the PPO backbone; the same jobs
(apart from the method) as configs/experiments/tournament.yaml and tournament_ppo.yaml, so every episode
pairs with the built-in methods' episode of the same seed, contract and initial state.

usage: PYTHONPATH=build/python scripts/leaderboard_methods.py OUT_DIR [THREADS]
"""
import os
import sys
import time

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "docs", "examples"))
import actionshift  # noqa: E402
from separation_probes import SeparationProbes  # noqa: E402

TASKS = ("pick_cube", "push_cube", "pull_cube", "stack_cube")
SPLITS = ("reference_seen", "reference_unseen_composition")
SEEDS = (20260718, 20260719, 20260720)
BACKBONES = ("expert", "ppo")
EPISODES = 200


def main():
    out = sys.argv[1]
    threads = int(sys.argv[2]) if len(sys.argv) > 2 else 0
    start, jobs, episodes = time.time(), 0, 0
    for backbone in BACKBONES:
        for task in TASKS:
            for split in SPLITS:
                for seed in SEEDS:
                    r = actionshift.evaluate(backbone, task=task, split=split, pool="reference9", method=SeparationProbes(),
                                             seed=seed, episodes=EPISODES, out=os.path.join(out, backbone), threads=threads)
                    jobs += 1
                    episodes += r["episodes_run"]
                    print(f"{backbone} {task} {split} {seed}: {r['job_id'][:12]} ({r['episodes_run']} run)", flush=True)
    print(f"{jobs} jobs, {episodes} episodes run, wall time {time.time() - start:.0f} s", flush=True)


if __name__ == "__main__":
    main()
