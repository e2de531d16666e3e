#!/usr/bin/env bash
# actionshift train identifier and run --method osi|probe_osi|recurrent_osi, end to end and small:
# a smoke-size training is deterministic from its seed, the committed weights run on a reference and
# a generated split with no pool in the job, and bad input is one line with exit 2.
set -euo pipefail
AS="$1"
SRC="$2"
source "$(dirname "$0")/lib.sh"

# train twice with the same seed: the same bytes (and the held-out table is printed)
for i in 1 2; do
  run "$AS" train identifier --kind recurrent_osi --max-contracts 2 --episodes 1 --train-steps 10 --threads 1 \
    --out "$TMP/r$i.asid" --verdicts "$TMP/r$i.json" --quiet
  expect_rc 0 "train identifier $i"
done
expect_out "| steps | permutation | sign | scale | target | frame | lag | gripper | exact |" "held-out table"
cmp -s "$TMP/r1.asid" "$TMP/r2.asid" && ok || bad "same seed, different weights"
grep -q '"regressor_rank"' "$TMP/r1.json" && ok || bad "verdicts hold the regressor rank"

# the committed weights: every identifier on a reference and a generated split; jobs carry no pool
for m in osi probe_osi recurrent_osi; do
  for split in reference_seen seen; do
    run "$AS" run --task pick_cube --split "$split" --method "$m" --episodes 2 --threads 1 --out "$TMP/e" --progress off
    expect_rc 0 "$m on $split"
  done
done
grep -l '"name": "probe_osi"' "$TMP"/e/*.summary.json > /dev/null && ok || bad "summary names the method"
[ "$(grep -l '"pool": null' "$TMP"/e/*.summary.json | wc -l)" = 6 ] && ok || bad "identifier jobs have no pool"
grep -q '"probe_steps":6' "$TMP"/e/*.jsonl && ok || bad "probe_osi records its 6 probe steps"
# a retrained model runs by path
run "$AS" run --task pick_cube --split reference_seen --method recurrent_osi --params "{\"weights\":\"$TMP/r1.asid\"}" \
  --episodes 2 --threads 1 --out "$TMP/p" --progress off
expect_rc 0 "run with --params weights=<file>"

# bad input: one line, exit 2
run "$AS" train identifier --kind lstm
expect_rc 2 "unknown kind"
expect_one_line_error "unknown kind"
run "$AS" train identifier --kind osi --excitation loud --max-contracts 1 --train-steps 1
expect_rc 2 "unknown excitation"
expect_one_line_error "unknown excitation"
printf 'ASIDW\0\0\1garbage' > "$TMP/bad.asid"
run "$AS" run --task pick_cube --split reference_seen --method osi --params "{\"weights\":\"$TMP/bad.asid\"}" --episodes 2 --out "$TMP/x" --progress off
expect_rc 2 "corrupt weights"
expect_one_line_error "corrupt weights"
run "$AS" run --task pick_cube --split reference_seen --method osi --params "{\"weights\":\"$TMP/r1.asid\"}" --episodes 2 --out "$TMP/x" --progress off
expect_rc 2 "weights of another kind"
expect_err "holds a recurrent_osi network, not osi" "names the kind"
run "$AS" run --task pick_cube --split reference_seen --method osi --pool reference9 --episodes 2 --out "$TMP/x" --progress off
[ "$RC" != 0 ] || grep -q '"pool": null' "$TMP"/x/*.summary.json && ok || bad "a pool never enters an identifier job"
finish
