#!/usr/bin/env bash
# Error messages that were unclear (docs/results/reliability.md §1, "error messages"): each names the
# file or option, the field and the true reason, in one `actionshift: error:` line (exit 2, 3 for the
# self-test). Each case says what the message was before.
# usage: cli_messages_test.sh ACTIONSHIFT_BINARY SOURCE_DIR
set -euo pipefail
AS="$1"
SRC="$2"
source "$(dirname "$0")/lib.sh"

one() {  # one CODE NAME TEXT...: exit CODE, one line, holding every TEXT
  local code="$1" name="$2"
  shift 2
  expect_rc "$code" "$name"
  expect_one_line_error "$name"
  for t in "$@"; do expect_err "$t" "$name"; done
}
job=(--task pick_cube --split reference_seen --method oracle --episodes 1 --threads 1 --progress off)

# 1. a device as a split: was "no such manifest file and not a built-in name"
run timeout 20 "$AS" run --task pick_cube --split /dev/zero --method oracle --episodes 1 --out "$TMP/o" --progress off
one 2 "--split /dev/zero" "/dev/zero: not a regular file" "expected a manifest file"

# 2. a FIFO as a robot: was "no such URDF file"
mkfifo "$TMP/robot.urdf"
run timeout 20 "$AS" run "${job[@]}" --robot "$TMP/robot.urdf" --out "$TMP/o"
one 2 "--robot FIFO" "$TMP/robot.urdf: " "not a regular file" "expected a URDF file"

# 3. YAML nested deeper than yaml-cpp recurses: was "malformed YAML: bad file"
python3 -c "import sys; open(sys.argv[1], 'w').write('name: x\nmethods:\n' + ''.join(' ' * (i + 1) + 'a%d:\n' % i for i in range(1000)))" "$TMP/deep_block.yaml"
run "$AS" plan --experiment "$TMP/deep_block.yaml" --out "$TMP/p"
one 2 "deep block YAML" "$TMP/deep_block.yaml:" "malformed YAML: nested too deeply"
grep -qF "bad file" <<<"$ERR" && bad "deep block YAML still says 'bad file'" || ok

# 4. a job index beyond 64 bits: was read as 2**63 - 1 ("out of range ... (got 9223372036854775807)")
run "$AS" plan --experiment "$SRC/configs/experiments/smoke.yaml" --out "$TMP/smoke"
expect_rc 0 "smoke plan"
run "$AS" run --plan "$TMP/smoke/smoke.plan.json" --job-index 99999999999999999999 --out "$TMP/smoke" --progress off
one 2 "--job-index 99999999999999999999" "--job-index: out of range: '99999999999999999999' does not fit a 64-bit integer"

# 5. --job-index without --plan: was ignored (the single job ran, exit 0)
run "$AS" run "${job[@]}" --job-index 0 --out "$TMP/o"
one 2 "--job-index without --plan" "--job-index: only applies with --plan"

# 6. a full disk: the first line of the report was blank (a newline meant to end a progress bar);
# simulated by a file-size limit (writes past it fail with EFBIG, like ENOSPC, instead of a signal)
set +e
( trap '' XFSZ; ulimit -f 1; exec "$AS" run --task pick_cube --split reference_seen --method oracle --episodes 4 --threads 1 \
    --progress off --out "$TMP/full" ) > /dev/null 2> "$TMP/full.err"
RC=$?
set -e
expect_rc 2 "full disk"
first=$(head -n 1 "$TMP/full.err")
[[ "$first" == "actionshift: "* ]] && ok || bad "full disk: the first line is not a message: '$first' ($(cat "$TMP/full.err"))"
grep -q '^$' "$TMP/full.err" && bad "full disk: a blank line in: $(cat "$TMP/full.err")" || ok
grep -q '^actionshift: error: .*\.jsonl: write failed: ' "$TMP/full.err" && ok || bad "full disk: the error does not name the results file: $(cat "$TMP/full.err")"

# 7. selftest --sim --calibration accepted a layout `run --calibration` refuses: one shared check now
python3 -c 'import json,sys; c=json.load(open(sys.argv[1])); c["quaternion_start"] += 1; json.dump(c, open(sys.argv[2], "w"))' \
  "$SRC/configs/calibration/maniskill/selftest/pick_cube.json" "$TMP/shifted.json"
run "$AS" selftest --sim --task pick_cube --hidden-contract identity --calibration "$TMP/shifted.json"
one 3 "selftest --calibration with another layout" "$TMP/shifted.json: quaternion_start: is " "pick_cube's observation has it at"

# 8. a second YAML document: was silently ignored
printf 'name: smoke2\ntasks: [pick_cube]\nsplits: [reference_seen]\nmethods: [oracle]\nseeds: [1]\nepisodes: 1\nbackbone: expert\n---\nname: other\n' \
  > "$TMP/two_docs.yaml"
run "$AS" plan --experiment "$TMP/two_docs.yaml" --out "$TMP/p"
one 2 "two YAML documents" "$TMP/two_docs.yaml:" "more than one YAML document"

# 9. zero-mass and 1e30 kg links: were accepted
sed '0,/<mass value="4.970684"\/>/s//<mass value="0"\/>/' "$SRC/configs/robots/panda.urdf" > "$TMP/massless.urdf"
sed '0,/<mass value="4.970684"\/>/s//<mass value="1e30"\/>/' "$SRC/configs/robots/panda.urdf" > "$TMP/heavy.urdf"
run "$AS" run "${job[@]}" --robot "$TMP/massless.urdf" --out "$TMP/o"
one 2 "massless moving link" "massless.urdf: link panda_link1: inertial mass: must be > 0 on a link moved by a joint"
run "$AS" run "${job[@]}" --robot "$TMP/heavy.urdf" --out "$TMP/o"
one 2 "1e30 kg link" "heavy.urdf: link panda_link1: inertial mass: 1e+30 kg is more than 1e6 kg"

# 10. integers: "010" was octal (seed 8), "0x10" hex, "1x" a CLI11 "Could not convert"
run "$AS" run "${job[@]}" --seed 010 --out "$TMP/octal"
expect_rc 0 "--seed 010"
expect_out "seed 10:" "--seed 010 is ten"
run "$AS" run --task pick_cube --split reference_seen --method oracle --episodes 1 --threads 0x1 --out "$TMP/o"
one 2 "--threads 0x1" "--threads: must be an integer in [0, 2**64) (got '0x1')"
run "$AS" run --task pick_cube --split reference_seen --method oracle --episodes 1x --out "$TMP/o"
one 2 "--episodes 1x" "--episodes: expected a decimal integer (got '1x')"

# 11. empty values given on purpose: `contract hash ''` read stdin ("<stdin>: no input"), `--task ''`
# said --task was missing, `validate ''`/`summarize ''`/`plan --experiment ''` named no file
run "$AS" contract hash ''
one 2 "contract hash ''" "input: must not be empty"
run "$AS" run --task '' --split reference_seen --method oracle --episodes 1 --out "$TMP/o"
one 2 "--task ''" "--task: must not be empty"
run "$AS" validate ''
one 2 "validate ''" "paths: must not be empty"
run "$AS" summarize ''
one 2 "summarize ''" "dir: must not be empty"
run "$AS" plan --experiment '' --out "$TMP/p"
one 2 "plan --experiment ''" "--experiment: must not be empty"

# 12. calibrate --steps 0 or -5: was "calibration needs at least two steps per episode", no option named
run "$AS" calibrate --task pick_cube --episodes 1 --steps -5
one 2 "calibrate --steps -5" "--steps: " "-5"

# 13. a missing contract file: was "cannot open file"
run "$AS" contract hash "$TMP/missing.json"
one 2 "contract hash MISSING" "$TMP/missing.json: no such file (expected a contract input file)"

# 14. a record naming a safety flag the simulator does not have (a renamed flag): was accepted as any
#     [a-z0-9_.-] name and counted as a flag of its own
"$AS" run --task pick_cube --split reference_seen --method oracle --episodes 2 --threads 1 --progress off --out "$TMP/flags" > /dev/null 2>&1
rec=$(ls "$TMP"/flags/*.jsonl)
rm -f "$TMP"/flags/*.summary.json
sed -i '2s/"safety_flags":\[\]/"safety_flags":["workspace_exit"]/' "$rec"
run "$AS" summarize "$TMP/flags"
one 2 "summarize with an unknown safety flag" "$rec:2: safety_flags: unknown safety flag 'workspace_exit' (valid: "
finish
