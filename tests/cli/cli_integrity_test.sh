#!/usr/bin/env bash
# Custom split and pool files, and the integrity of records and summaries (docs/results/reliability.md §1):
# - a split or pool given as a file of any name and location runs (single job, plan, resume, a moved
#   file): the job is identified by the manifest's content hash and records the file's path;
# - a record edited after its job finished, and a truncated or corrupt summary, are refused by every
#   reader (summarize, gate1, gate check, compare, report) and by a re-run, in one line.
# Smoke-size: a handful of simulated episodes.
set -euo pipefail
AS="$1"
SRC="$2"
source "$(dirname "$0")/lib.sh"

summary_field() {  # summary_field FILE PYTHON-EXPR-ON-s
  python3 -c 'import json,sys; s=json.load(open(sys.argv[1])); print(eval(sys.argv[2]))' "$1" "$2"
}

# ==== a generated split under a name and directory no built-in has
mkdir -p "$TMP/my dir"
run "$AS" splits generate --seed 7 --rule seen --rule full --out "$TMP/my dir"
expect_rc 0 "splits generate"
run "$AS" validate "$TMP/my dir/seen.json"
expect_rc 0 "validate the generated split"
cd "$TMP"
# the issue's repro: a valid generated split named like a built-in one (another seed, another hash)
run "$AS" run --task pick_cube --split "my dir/seen.json" --method oracle --episodes 1 --threads 1 --out "$TMP/gs" --progress off
expect_rc 0 "run --split FILE of a generated split"
# any name and place: validate notes a file name other than the manifest's (the name is a label) and passes
cp "$TMP/my dir/seen.json" "$TMP/my dir/custom-split.json"
mv "$TMP/my dir/full.json" "$TMP/my dir/custom pool.json"
run "$AS" validate "$TMP/my dir/custom-split.json" "$TMP/my dir/custom pool.json"
expect_rc 0 "validate a renamed split and pool"
expect_out "the name is a label, the content hash the identity" "validate notes the file name"
run "$AS" run --task pick_cube --split "my dir/custom-split.json" --method oracle --episodes 2 --threads 1 --out "$TMP/cs" --progress off
expect_rc 0 "run --split FILE (relative, with a space, named like no built-in)"
S=$(ls "$TMP"/cs/*.summary.json)
ID=$(basename "$S" .summary.json)
[ "$(summary_field "$S" 's["job"]["split"]["path"]')" = "$TMP/my dir/custom-split.json" ] && ok || bad "the job records the split file's absolute path"
[ "$(summary_field "$S" 's["job"]["split"]["name"]')" = "seen" ] && ok || bad "the split's name stays its label"
# the path is recorded, not hashed: the same split from another place is the same job
mkdir -p "$TMP/elsewhere"
cp "$TMP/my dir/custom-split.json" "$TMP/elsewhere/x.json"
run "$AS" run --task pick_cube --split "$TMP/elsewhere/x.json" --method oracle --episodes 2 --threads 1 --out "$TMP/cs" --progress off
expect_rc 0 "the moved split"
expect_out "already complete" "a moved split file is the same job"
[ "$(ls "$TMP"/cs/*.jsonl)" = "$TMP/cs/$ID.jsonl" ] && ok || bad "a moved split made another job"
# resume: a job stopped after its first episode continues from the split file
head -n 1 "$TMP/cs/$ID.jsonl" > "$TMP/one.jsonl" && mv "$TMP/one.jsonl" "$TMP/cs/$ID.jsonl" && rm "$S"
run "$AS" run --task pick_cube --split "my dir/custom-split.json" --method oracle --episodes 2 --threads 1 --out "$TMP/cs" --progress off
expect_rc 0 "resume with a split file"
[ "$(wc -l < "$TMP/cs/$ID.jsonl")" = 2 ] && ok || bad "the resumed job has 2 records"
run "$AS" summarize "$TMP/cs"
expect_rc 0 "summarize a custom split's job"
expect_out "| seen |" "summarize labels the cell by the split's name"

# ---- --pool FILE (a pool whose hash no built-in has)
run "$AS" run --task pick_cube --split "my dir/custom-split.json" --pool "my dir/custom pool.json" --method entropy_probes \
  --episodes 1 --threads 1 --out "$TMP/cp" --progress off
expect_rc 0 "run --pool FILE"
S=$(ls "$TMP"/cp/*.summary.json)
[ "$(summary_field "$S" 's["job"]["pool"]["path"]')" = "$TMP/my dir/custom pool.json" ] && ok || bad "the job records the pool file's path"

# ---- a plan of an experiment naming the split file: the plan carries the absolute path, so its jobs
# (and Slurm's array tasks) run from any directory
cp "$TMP/my dir/custom-split.json" "$TMP/my dir/custom-split2.json"
cat > "$TMP/my dir/e.yaml" <<'EOF'
name: custom
tasks: [pick_cube]
splits: [custom-split2.json]
methods: [oracle]
seeds: [3]
episodes: 1
backbone: expert
EOF
cd "$TMP/my dir"
run "$AS" plan --experiment e.yaml --out "$TMP/pl"
expect_rc 0 "plan with a split file"
cd /
run "$AS" run --plan "$TMP/pl/custom.plan.json" --job-index 0 --out "$TMP/pl" --progress off
expect_rc 0 "run a planned job of a split file from another directory"
# the file the job was made from changed: refused, naming the file and the hash check
"$AS" splits generate --seed 8 --rule seen --out "$TMP/gen8" > /dev/null
cp "$TMP/gen8/seen.json" "$TMP/my dir/custom-split2.json"
rm -f "$TMP"/pl/*.jsonl "$TMP"/pl/*.summary.json
run "$AS" run --plan "$TMP/pl/custom.plan.json" --job-index 0 --out "$TMP/pl" --progress off
expect_rc 2 "a changed split file"
expect_one_line_error "a changed split file"
expect_err "$TMP/my dir/custom-split2.json: manifest_sha256: is " "a changed split file names the file"
rm "$TMP/my dir/custom-split2.json"
run "$AS" run --plan "$TMP/pl/custom.plan.json" --job-index 0 --out "$TMP/pl" --progress off
expect_rc 2 "a removed split file"
expect_one_line_error "a removed split file"
expect_err "split.path: the split manifest the job was made from is gone" "a removed split file"
cd "$TMP"

# ==== integrity: records and their summary
run "$AS" run --task pick_cube --split reference_seen --method no_adapt --episodes 3 --threads 1 --out "$TMP/in" --progress off
expect_rc 0 "a finished job"
run "$AS" run --task pick_cube --split reference_seen --method oracle --episodes 3 --threads 1 --out "$TMP/in" --progress off
expect_rc 0 "its oracle"
JL=$(grep -l '"method":"no_adapt"' "$TMP"/in/*.jsonl)
SUM="${JL%.jsonl}.summary.json"
[ "$(summary_field "$SUM" 's["records_sha256"]')" = "$(sha256sum < "$JL" | cut -d' ' -f1)" ] && ok || bad "records_sha256 is the SHA-256 of the JSONL file's bytes"
cp "$JL" "$TMP/clean.jsonl"
cp "$SUM" "$TMP/clean.summary.json"
run "$AS" summarize "$TMP/in"
expect_rc 0 "summarize the clean results"
# one byte of a complete record: the second record's episode seed digit... its "steps" value 50 -> 59
python3 - "$JL" <<'PY'
import sys
p = sys.argv[1]
lines = open(p, 'rb').read().split(b'\n')
i = lines[1].index(b'"steps":') + len(b'"steps":') + 1
lines[1] = lines[1][:i] + (b'9' if lines[1][i:i + 1] != b'9' else b'8') + lines[1][i + 1:]
open(p, 'wb').write(b'\n'.join(lines))
PY
cmp -s "$JL" "$TMP/clean.jsonl" && bad "the edit did not change the records" || ok
for cmd in "summarize $TMP/in" "gate1 --results $TMP/in --verdict $TMP/v.json" \
           "gate check --expected $SRC/configs/gates/gate1/smoke.verdict.json --results $TMP/in" \
           "compare $TMP/in --pair oracle|vs|no_adapt --out $TMP/c.json" "report $TMP/in --out $TMP/rep"; do
  read -r -a argv <<<"$cmd"
  argv=("${argv[@]//|/ }")
  run "$AS" "${argv[@]}"
  expect_rc 2 "edited record: ${argv[0]}"
  expect_one_line_error "edited record: ${argv[0]}"
  expect_err "$JL: records_sha256: the records do not match the summary's hash" "edited record: ${argv[0]}"
done
[ ! -e "$TMP/v.json" ] && [ ! -e "$TMP/c.json" ] && ok || bad "a verdict or comparison was written from edited records"
# a re-run refuses instead of claiming the job complete, and leaves the file as it is
sha_before=$(sha256sum < "$JL")
run "$AS" run --task pick_cube --split reference_seen --method no_adapt --episodes 3 --threads 1 --out "$TMP/in" --progress off
expect_rc 2 "re-run over an edited record"
expect_one_line_error "re-run over an edited record"
expect_err "the records do not match the summary's hash" "re-run over an edited record"
grep -q "already complete" <<<"$OUT" && bad "a re-run claimed a job with an edited record complete" || ok
[ "$(sha256sum < "$JL")" = "$sha_before" ] && ok || bad "the re-run changed the edited file"
cp "$TMP/clean.jsonl" "$JL"

# ---- a truncated or corrupt summary
head -c 300 "$TMP/clean.summary.json" > "$SUM"
run "$AS" summarize "$TMP/in"
expect_rc 2 "truncated summary"
expect_one_line_error "truncated summary"
expect_err "$SUM" "truncated summary names the file"
run "$AS" run --task pick_cube --split reference_seen --method no_adapt --episodes 3 --threads 1 --out "$TMP/in" --progress off
expect_rc 2 "re-run over a truncated summary"
expect_one_line_error "re-run over a truncated summary"
python3 - "$TMP/clean.summary.json" "$SUM" <<'PY'
import json, sys
s = json.load(open(sys.argv[1]))
s["success_once"]["successes"] = 1 - min(1, s["success_once"]["successes"])  # a count its records do not hold
json.dump(s, open(sys.argv[2], "w"), indent=2)
PY
run "$AS" gate1 --results "$TMP/in" --verdict "$TMP/v.json"
expect_rc 2 "corrupt summary"
expect_one_line_error "corrupt summary"
expect_err "$SUM: success_once.successes: is " "corrupt summary names the file and field"
cp "$TMP/clean.summary.json" "$SUM"
run "$AS" summarize "$TMP/in"
expect_rc 0 "the restored files summarize again"

finish
