#!/usr/bin/env bash
# --obs-noise (run, calibrate, render) and run --calibration: bad values exit 2 with one line; noise is
# off by default and leaves job ids alone at 0; a noisy job is another job whose records carry the sigma;
# a calibration measured under noise is labelled, noisier, and usable by a belief method. Smoke-size.
set -euo pipefail
AS=$1
source "$(dirname "$0")/lib.sh"

common=(--task pick_cube --split reference_seen --episodes 2 --threads 1 --progress off)
for v in nan -0.001 0.5 inf abc; do
  run "$AS" run "${common[@]}" --method oracle --obs-noise "$v" --out "$TMP/bad"
  expect_rc 2 "run --obs-noise $v"
  expect_one_line_error "run --obs-noise $v"
  run "$AS" calibrate --task pick_cube --episodes 1 --steps 4 --obs-noise "$v"
  expect_rc 2 "calibrate --obs-noise $v"
  expect_one_line_error "calibrate --obs-noise $v"
done
run "$AS" run "${common[@]}" --method oracle --obs-noise nan --out "$TMP/bad"
expect_err "--obs-noise: must be a finite sigma in [0, 0.1]" "run --obs-noise nan names the option"
run "$AS" render --task pick_cube --split reference_seen --method oracle --obs-noise -1 --out "$TMP/x.png"
expect_rc 2 "render --obs-noise -1"
expect_one_line_error "render --obs-noise -1"

# off by default: --obs-noise 0 is the same job (same id, byte-identical records) as no option
run "$AS" run "${common[@]}" --method oracle --out "$TMP/clean"
expect_rc 0 "clean run"
run "$AS" run "${common[@]}" --method oracle --obs-noise 0 --out "$TMP/zero"
expect_rc 0 "--obs-noise 0 run"
clean=$(cd "$TMP/clean" && ls *.jsonl)
zero=$(cd "$TMP/zero" && ls *.jsonl)
[ "$clean" = "$zero" ] && ok || bad "--obs-noise 0 changed the job id ($clean vs $zero)"
cmp -s "$TMP/clean/$clean" "$TMP/zero/$zero" && ok || bad "--obs-noise 0 changed the records"
grep -q obs_noise "$TMP/clean/$clean" && bad "a clean record names obs_noise" || ok

# noisy: another job; every record carries the sigma; the backbone acts on the noisy pose
run "$AS" run "${common[@]}" --method oracle --obs-noise 0.01 --out "$TMP/noisy"
expect_rc 0 "noisy run"
noisy=$(cd "$TMP/noisy" && ls *.jsonl)
[ "$noisy" != "$clean" ] && ok || bad "--obs-noise 0.01 kept the clean job id"
[ "$(grep -c '"obs_noise":0.01,' "$TMP/noisy/$noisy")" = 2 ] && ok || bad "noisy records lack obs_noise"
grep -Eq '"obs_noise": ?0.01' "$TMP/noisy/${noisy%.jsonl}.summary.json" && ok || bad "the noisy job spec lacks obs_noise"
r_clean=$(grep -o '"return":[^,]*' "$TMP/clean/$clean" | tr '\n' ' ')
r_noisy=$(grep -o '"return":[^,]*' "$TMP/noisy/$noisy" | tr '\n' ' ')
[ "$r_clean" != "$r_noisy" ] && ok || bad "the noise did not reach the backbone (returns $r_clean)"

# calibrate under noise: labelled, and the translation channels lose R^2
run "$AS" calibrate --task pick_cube --episodes 2 --steps 24 --json
expect_rc 0 "clean calibration"
r2_clean=$(python3 -c 'import json,sys; c=json.loads(sys.argv[1]); print(sum(c["fit_r2"][:3]))' "$OUT")
run "$AS" calibrate --task pick_cube --episodes 2 --steps 24 --obs-noise 0.01 --out "$TMP/cal.json"
expect_rc 0 "noisy calibration"
grep -q '"profile":"maniskill\[obs_noise=0.01\]"' "$TMP/cal.json" && ok || bad "the noisy calibration is not labelled"
r2_noisy=$(python3 -c 'import json,sys; c=json.load(open(sys.argv[1])); print(sum(c["fit_r2"][:3]))' "$TMP/cal.json")
python3 -c "import sys; sys.exit(0 if $r2_noisy < $r2_clean - 0.3 else 1)" && ok || bad "noise did not lower the R^2 ($r2_noisy vs $r2_clean)"
sha=$(sed -n 's/^calibration_sha256 \([0-9a-f]*\).*/\1/p' <<<"$OUT")

# run --calibration: the file's hash becomes the job's calibration_sha256
run "$AS" run "${common[@]}" --method exact_belief --pool reference9 --obs-noise 0.01 --calibration "$TMP/cal.json" --out "$TMP/cal_run"
expect_rc 0 "belief run with --calibration"
grep -Eq "\"calibration_sha256\": ?\"$sha\"" "$TMP"/cal_run/*.summary.json && ok || bad "the job's calibration_sha256 is not the file's ($sha)"
run "$AS" run "${common[@]}" --method oracle --calibration "$TMP/cal.json" --out "$TMP/bad"
expect_rc 2 "--calibration with a method that uses none"
expect_one_line_error "--calibration with oracle"
run "$AS" run --task push_cube --split reference_seen --episodes 2 --threads 1 --progress off --method exact_belief --pool reference9 --calibration "$TMP/cal.json" --out "$TMP/bad"
expect_rc 2 "--calibration of another task"
expect_err "task: is pick_cube, not the job's push_cube" "--calibration of another task names the field"
python3 -c 'import json,sys; c=json.load(open(sys.argv[1])); c["quaternion_start"] += 1; json.dump(c, open(sys.argv[2], "w"))' \
  "$TMP/cal.json" "$TMP/shifted.json"
run "$AS" run "${common[@]}" --method exact_belief --pool reference9 --obs-noise 0.01 --calibration "$TMP/shifted.json" --out "$TMP/bad"
expect_rc 2 "--calibration with another observation layout"
expect_err "shifted.json: quaternion_start: is " "--calibration with another observation layout names the file and field"
run "$AS" run "${common[@]}" --method exact_belief --pool reference9 --calibration "$TMP/missing.json" --out "$TMP/bad"
expect_rc 2 "--calibration missing file"
expect_one_line_error "--calibration missing file"
finish
