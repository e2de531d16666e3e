#!/usr/bin/env bash
# The runs behind docs/results/belief_trace.md (diagnostic; see scripts/belief_trace.py), and the page.
# Usage: bash scripts/belief_trace_runs.sh OUT.jsonl [CLI_OUT_DIR]
# Writes one summary line per cell to OUT.jsonl (emptied first: the page is generated from this file and
# must describe one run of this script), then regenerates docs/results/belief_trace.md from it with
# scripts/belief_trace_report.py. With CLI_OUT_DIR it also runs the C++ backbones through
# `actionshift run` (one thread) for the numpy-vs-C++ comparison of the main cells (step 5), and the
# page gets those columns.
# Environment (all optional): ACTIONSHIFT_BUILD_DIR (default build, relative to the source tree) for
# PYTHONPATH (<build>/python, unless PYTHONPATH is set) and the CLI (<build>/apps/actionshift/actionshift,
# or AS); ACTIONSHIFT_BACKBONES_DIR (default configs/backbones of this tree).
set -euo pipefail
cd "$(dirname "$0")/.."
J=${1:?OUT.jsonl}
CLI_OUT=${2:-}
BUILD=${ACTIONSHIFT_BUILD_DIR:-build}
AS=${AS:-$BUILD/apps/actionshift/actionshift}
export PYTHONPATH=${PYTHONPATH:-$BUILD/python}
export ACTIONSHIFT_BACKBONES_DIR=${ACTIONSHIFT_BACKBONES_DIR:-$PWD/configs/backbones}
P="nice -n 10 python3 scripts/belief_trace.py --task push_cube --episodes 100"
: > "$J"

# 1. the main cells, each verified against actionshift.evaluate() (seed 20260718)
for bb in ppo ppo-delay-aware; do
  for sp in "reference_seen reference9" "long_lag full"; do
    set -- $sp
    for m in oracle exact_belief; do
      $P --seed 20260718 --backbone $bb --method $m --split $1 --pool $2 --verify --json "$J"
    done
  done
done
# 2. exact belief with the privileged executed history; oracle with a wrong history (no wrong execution)
for seed in 20260718 20260719 20260720; do
  for h in own executed; do
    $P --seed $seed --backbone ppo-delay-aware --method exact_belief --split reference_seen --pool reference9 --history $h --json "$J"
    $P --seed $seed --backbone ppo-delay-aware --method exact_belief --split long_lag --pool full --history $h --json "$J"
  done
done
for h in random:1 random:2 random:5 random:10 wrongid:1 wrongid:2 wrongid:5 wrongid:10; do
  $P --seed 20260718 --backbone ppo-delay-aware --method oracle --split reference_seen --history $h --json "$J"
done
for h in random:5 wrongid:5; do
  $P --seed 20260718 --backbone ppo-delay-aware --method oracle --split long_lag --history $h --json "$J"
done
# 3. oracle with the first K steps sent unencoded (wrong execution), history own / executed / cleared
for seed in 20260718 20260719 20260720; do
  for K in 2 4; do
    $P --seed $seed --method oracle --split reference_seen --backbone ppo --perturb $K --json "$J"
    for h in own executed zero:$K; do
      $P --seed $seed --method oracle --split reference_seen --backbone ppo-delay-aware --history $h --perturb $K --json "$J"
    done
  done
done
$P --seed 20260718 --method oracle --split long_lag --backbone ppo --perturb 4 --json "$J"
for h in own executed zero:4; do
  $P --seed 20260718 --method oracle --split long_lag --backbone ppo-delay-aware --history $h --perturb 4 --json "$J"
done
# 4. one wrong step (step 0): all channels, pose only, gripper only; plus baselines
for seed in 20260718 20260719 20260720; do
  for part in all pose gripper; do
    $P --seed $seed --method oracle --split reference_seen --backbone ppo --perturb 1 --perturb-part $part --json "$J"
    $P --seed $seed --method oracle --split reference_seen --backbone ppo-delay-aware --perturb 1 --perturb-part $part --json "$J"
  done
  $P --seed $seed --method oracle --split reference_seen --backbone ppo-delay-aware --history executed --perturb 1 --json "$J"
  $P --seed $seed --method oracle --split reference_seen --backbone ppo-delay-aware --history zero:1 --perturb 1 --json "$J"
  $P --seed $seed --method oracle --split reference_seen --backbone ppo-delay-aware --history wrongid:1 --json "$J"
  $P --seed $seed --method oracle --split reference_seen --backbone ppo-delay-aware --json "$J"
  $P --seed $seed --method oracle --split reference_seen --backbone ppo --json "$J"
done
# 5. the C++ backbones on the main cells (numpy forward vs MlpPolicy)
if [ -n "$CLI_OUT" ]; then
  for bb in ppo ppo-delay-aware; do
    for sp in "reference_seen reference9" "long_lag full"; do
      set -- $sp
      for m in oracle exact_belief; do
        pa=(); [ $m = exact_belief ] && pa=(--pool $2)
        nice -n 10 "$AS" run --task push_cube --split $1 --method $m "${pa[@]}" --backbone $bb --episodes 100 \
          --seed 20260718 --threads 1 --progress off --out "$CLI_OUT/$bb.$1.$m" >/dev/null
      done
    done
  done
fi
# 6. the page, generated from the summaries (and the C++ records when CLI_OUT_DIR was given)
python3 scripts/belief_trace_report.py "$J" --commit "$(git rev-parse --short HEAD)" ${CLI_OUT:+--cli-dir "$CLI_OUT"} \
  > docs/results/belief_trace.md.tmp
mv docs/results/belief_trace.md.tmp docs/results/belief_trace.md
