#!/usr/bin/env bash
# actionshift run --method grammar_belief: hash-addressed and resumable on every split, its probing
# and hold variants, no pool in the job, and malformed parameters rejected with exit 2. Small: 2-4
# episodes per run.
set -euo pipefail
AS="$1"
SRC="$2"
source "$(dirname "$0")/lib.sh"

# passive, fixed and hold variants on each kind of split; a pool is never part of the job
for split in seen unseen_composition long_lag; do
  run "$AS" run --task pick_cube --split "$split" --method grammar_belief --episodes 2 --threads 1 --out "$TMP/g" --progress off
  expect_rc 0 "grammar_belief on $split"
done
run "$AS" run --task push_cube --split seen --method grammar_belief --params '{"probe":"fixed"}' --episodes 2 --threads 1 \
  --out "$TMP/g" --progress off
expect_rc 0 "grammar_belief fixed probes on push_cube"
run "$AS" run --task pick_cube --split unseen_composition --method grammar_belief --params '{"probe":"hold"}' --episodes 2 \
  --threads 1 --out "$TMP/h" --progress off
expect_rc 0 "grammar_belief hold probe"
S=$(ls "$TMP"/h/*.summary.json)
grep -q '"name": "grammar_belief"' "$S" && ok || bad "summary names the method"
grep -q '"probe": "hold"' "$S" && ok || bad "the hold parameter enters the job"
grep -q '"pool": null' "$S" && ok || bad "a grammar_belief job has no pool"
# probe steps are recorded (12 per episode for h2-r1, fewer if a safety check ended the episode)
grep -q '"probe_steps":[1-9]' "$TMP"/h/*.jsonl && ok || bad "hold probe records its probe steps"
# re-running the finished job is a no-op (hash-addressed)
before=$(sha256sum "$TMP"/h/*.jsonl)
run "$AS" run --task pick_cube --split unseen_composition --method grammar_belief --params '{"probe":"hold"}' --episodes 2 \
  --threads 1 --out "$TMP/h" --progress off
expect_out "already complete" "re-run of a finished grammar_belief job"
[ "$(sha256sum "$TMP"/h/*.jsonl)" = "$before" ] && ok || bad "re-run changed the file"
# a different schedule is a different job
run "$AS" run --task pick_cube --split unseen_composition --method grammar_belief --params '{"probe":"hold","hold_rounds":2}' \
  --episodes 2 --threads 1 --out "$TMP/h" --progress off
expect_rc 0 "hold h2-r2"
[ "$(ls "$TMP"/h/*.summary.json | wc -l)" = 2 ] && ok || bad "h2-r2 has its own job id"

# the entropy-probing variant and the scale corrector (with re-anchoring) are runnable and hash-addressed
run "$AS" run --task push_cube --split seen --method grammar_belief --params '{"probe":"entropy"}' --episodes 2 --threads 1 \
  --out "$TMP/e" --progress off
expect_rc 0 "grammar_belief entropy probes"
grep -q '"probe_steps":[1-9]' "$TMP"/e/*.jsonl && ok || bad "entropy probing records its probe steps"
run "$AS" run --task pick_cube --split unseen_composition --method grammar_belief \
  --params '{"probe":"hold","scale_correction":true,"scale_window":8}' --episodes 2 --threads 1 --out "$TMP/sc" --progress off
expect_rc 0 "grammar_belief hold + scale corrector"
grep -q '"scale_correction": true' "$TMP"/sc/*.summary.json && ok || bad "the corrector enters the job"
grep -q '"scale_window": 8' "$TMP"/sc/*.summary.json && ok || bad "the corrector's window enters the job"
run "$AS" run --task pick_cube --split unseen_composition --method grammar_belief \
  --params '{"probe":"hold","scale_correction":true,"scale_window":8}' --episodes 2 --threads 1 --out "$TMP/sc" --progress off
expect_out "already complete" "re-run of a finished scale-corrector job"
run "$AS" run --task pick_cube --split seen --method grammar_belief --params '{"reanchor_period":8}' --episodes 2 --threads 1 \
  --out "$TMP/ra" --progress off
expect_rc 0 "grammar_belief re-anchoring"

# malformed parameters: one line, exit 2
for p in '{"hold_steps":-2}' '{"hold_steps":1}' '{"holdsteps":2}' '{"probe":"wiggle"}' '{"amplitude":NaN}' \
         '{"amplitude":-0.5}' '{"budget":-1}' '{"gripper_channel":"yes"}' '[1]' '{"scale_min":-0.4}' '{"scale_max":0.5}' \
         '{"scale_max":NaN}' '{"scale_window":0}' '{"scale_floor":-1}' '{"scale_corection":true}' '{"reanchor_period":-1}' \
         '{"scale_correction":1}'; do
  run "$AS" run --task pick_cube --split seen --method grammar_belief --params "$p" --episodes 2 --out "$TMP/x" --progress off
  expect_rc 2 "params $p"
  expect_one_line_error "params $p"
done
# the finger channel needs a calibration that has it (the built-in ones do; the self-test's do not)
run "$AS" run --task pick_cube --split seen --method grammar_belief --params '{"gripper_channel":true}' --episodes 2 \
  --calibration "$SRC/configs/calibration/maniskill/selftest/pick_cube.json" --out "$TMP/x" --progress off
expect_rc 2 "gripper_channel without a finger calibration"
expect_err "gripper_channel" "names the parameter"
expect_one_line_error "gripper_channel without a finger calibration"

# calibrate --gripper-channel adds the optional "gripper" key; without it the file is unchanged
run "$AS" calibrate --task pick_cube --episodes 2 --steps 16 --gripper-channel --json
expect_rc 0 "calibrate --gripper-channel"
expect_out '"gripper":{"alpha":' "the gripper key"
run "$AS" calibrate --task pick_cube --episodes 2 --steps 16 --json
[[ "$OUT" != *gripper* ]] && ok || bad "no gripper key without --gripper-channel"
finish
