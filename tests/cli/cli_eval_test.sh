#!/usr/bin/env bash
# actionshift run / plan / summarize / gate1 / gate check / gate promote / calibrate, end to end on
# the real simulator: kill-and-resume and thread-count byte equality, committed smoke verdicts,
# and one-line errors for bad input.
set -euo pipefail
AS="$1"
SRC="$2"
source "$(dirname "$0")/lib.sh"

# ---- a job is byte-identical whatever the thread count
run "$AS" run --task pick_cube --split seen --method oracle --episodes 24 --threads 1 --out "$TMP/t1" --progress off
expect_rc 0 "run 1 thread"
run "$AS" run --task pick_cube --split seen --method oracle --episodes 24 --threads 2 --out "$TMP/t2" --progress off
expect_rc 0 "run 2 threads"
ID=$(ls "$TMP/t1" | grep '\.jsonl$')
cmp -s "$TMP/t1/$ID" "$TMP/t2/$ID" && ok || bad "1-thread and 2-thread JSONL differ"
[ "$(wc -l < "$TMP/t1/$ID")" = 24 ] && ok || bad "24 records expected"
# a finished job is a no-op
before=$(sha256sum "$TMP/t1/$ID")
run "$AS" run --task pick_cube --split seen --method oracle --episodes 24 --threads 2 --out "$TMP/t1" --progress off
expect_out "already complete" "re-run of a finished job"
[ "$(sha256sum "$TMP/t1/$ID")" = "$before" ] && ok || bad "re-run changed the file"

# wait_for_records DIR N: until the job's JSONL in DIR has N records (at most 4 s)
wait_for_records() {
  local n
  for _ in $(seq 1 200); do
    n=$(cat "$1"/*.jsonl 2>/dev/null | wc -l || true)
    [ "${n:-0}" -ge "$2" ] && return
    sleep 0.02
  done
}

# ---- SIGKILL mid-run, resume, compare with the uninterrupted run
"$AS" run --task pick_cube --split seen --method entropy_probes --pool full --episodes 96 --threads 2 \
  --out "$TMP/full" --progress off > /dev/null 2>&1
"$AS" run --task pick_cube --split seen --method entropy_probes --pool full --episodes 96 --threads 2 \
  --out "$TMP/kill" --progress off > /dev/null 2>&1 &
PID=$!
wait_for_records "$TMP/kill" 10
kill -9 "$PID" 2>/dev/null || true
wait "$PID" 2>/dev/null || true
KID=$(ls "$TMP/full" | grep '\.jsonl$')
killed_lines=$(wc -l < "$TMP/kill/$KID" || echo 0)
[ "$killed_lines" -lt 96 ] && ok || bad "the job finished before it was killed ($killed_lines lines)"
run "$AS" run --task pick_cube --split seen --method entropy_probes --pool full --episodes 96 --threads 1 \
  --out "$TMP/kill" --progress off
expect_rc 0 "resume after SIGKILL"
cmp -s "$TMP/full/$KID" "$TMP/kill/$KID" && ok || bad "resumed JSONL differs from the uninterrupted run"

# ---- SIGTERM (what Slurm sends; Ctrl-C's SIGINT takes the same path) stops the job after the
# finished episodes: exit 130, the summary says where, and the same command resumes
"$AS" run --task pick_cube --split seen --method entropy_probes --pool full --episodes 96 --threads 2 \
  --out "$TMP/term" --progress off > "$TMP/term.out" 2> "$TMP/term.err" &
PID=$!
wait_for_records "$TMP/term" 10
kill -TERM "$PID" 2>/dev/null || true
rc=0; wait "$PID" || rc=$?
[ "$rc" = 130 ] && ok || bad "SIGTERM: exit $rc, expected 130 ($(cat "$TMP/term.err"))"
term_lines=$(wc -l < "$TMP/term/$KID" || echo 0)
[ "$term_lines" -lt 96 ] && ok || bad "the job finished before SIGTERM ($term_lines lines)"
grep -qx "actionshift: interrupted after $term_lines of 96 episodes; re-run the same command to resume" "$TMP/term.err" \
  && ok || bad "SIGTERM message: $(cat "$TMP/term.err")"
grep -q "\"message\": \"interrupted after $term_lines of 96 episodes; re-run to resume\"" "$TMP/term/${KID%.jsonl}.summary.json" \
  && ok || bad "the summary does not say where the job stopped"
run "$AS" run --task pick_cube --split seen --method entropy_probes --pool full --episodes 96 --threads 2 \
  --out "$TMP/term" --progress off
expect_rc 0 "resume after SIGTERM"
cmp -s "$TMP/full/$KID" "$TMP/term/$KID" && ok || bad "JSONL resumed after SIGTERM differs from the uninterrupted run"

# ---- smoke plan, Gate 1 and the committed expected verdicts
run "$AS" plan --experiment "$SRC/configs/experiments/smoke.yaml" --out "$TMP/smoke"
expect_rc 0 "plan smoke"
run "$AS" run --plan "$TMP/smoke/smoke.plan.json" --out "$TMP/smoke" --progress off
expect_rc 0 "run smoke plan"
run "$AS" gate1 --results "$TMP/smoke"
expect_out "pick_cube" "gate1 table"
run "$AS" gate check --expected "$SRC/configs/gates/gate1/smoke.verdict.json" --results "$TMP/smoke"
expect_rc 0 "gate check smoke"
expect_out "no verdict regressions" "gate check smoke output"
# a regression is exit 1: remove the oracle's successes from the results
mkdir -p "$TMP/broken"
for f in "$TMP"/smoke/*.jsonl; do sed 's/"success_once":true/"success_once":false/' "$f" > "$TMP/broken/$(basename "$f")"; done
run "$AS" gate check --expected "$SRC/configs/gates/gate1/smoke.verdict.json" --results "$TMP/broken"
expect_rc 1 "gate check regression"
expect_out "REGRESSION" "gate check names the regression"

# ---- tournament smoke: promotion verdicts recomputed from a few tournament cells and checked
# against the committed expectations (configs/gates/promotion/)
run "$AS" plan --experiment "$SRC/configs/experiments/tournament_smoke.yaml" --out "$TMP/tsmoke"
expect_rc 0 "plan tournament smoke"
run "$AS" run --plan "$TMP/tsmoke/tournament_smoke.plan.json" --out "$TMP/tsmoke" --progress off
expect_rc 0 "run tournament smoke"
for v in "$SRC"/configs/gates/promotion/smoke.*.json; do
  run "$AS" gate check --expected "$v" --results "$TMP/tsmoke"
  expect_rc 0 "gate check $(basename "$v")"
  expect_out "no verdict regressions" "gate check $(basename "$v") output"
done
# a verdict resting on fewer episodes than its expectation is a regression: keep one seed's job only
mkdir -p "$TMP/tsmall"
for f in "$TMP"/tsmoke/*.jsonl; do grep -q '"seed":20260718' "$f" && cp "$f" "${f%.jsonl}.summary.json" "$TMP/tsmall/"; done
v1=$(ls "$SRC"/configs/gates/promotion/smoke.*.json | head -1)
run "$AS" gate check --expected "$v1" --results "$TMP/tsmall"
expect_rc 1 "gate check on fewer episodes"
expect_out "fewer than the expected verdict's" "gate check names the missing episodes"
# the smoke's reference CLI default profile: the same job with --profile ideal is another job
run "$AS" run --task pick_cube --split seen --method oracle --episodes 4 --profile ideal --out "$TMP/prof" --progress off
expect_rc 0 "run --profile ideal"
grep -q '"profile":"ideal"' "$TMP"/prof/*.jsonl && ok || bad "records do not carry the profile"
run "$AS" run --task pick_cube --split seen --method oracle --episodes 4 --profile physx --out "$TMP/prof" --progress off
expect_rc 2 "unknown profile"
expect_err "profile" "unknown profile message"

# ---- summarize and promote
run "$AS" summarize "$TMP/smoke" --json
expect_rc 0 "summarize"
run "$AS" gate promote --candidate oracle --baseline no_adapt --results "$TMP/smoke"
expect_rc 0 "gate promote"
expect_out "extend_seeds" "one seed: more seeds needed"

# ---- method variants: the bare name is the paper's rule; a variant is its own job and its own cell
run "$AS" run --task pick_cube --split reference_seen --method entropy_probes --pool reference9 --episodes 4 --out "$TMP/var" --progress off
expect_rc 0 "run entropy_probes (the paper's rule)"
run "$AS" run --task pick_cube --split reference_seen --method 'entropy_probes{calibrated}' --pool reference9 --episodes 4 --out "$TMP/var" --progress off
expect_rc 0 "run entropy_probes{calibrated}"
[ "$(ls "$TMP"/var/*.jsonl | wc -l)" = 2 ] && ok || bad "two variants should be two jobs"
# the variant spelled out parameter by parameter is the same job
run "$AS" run --task pick_cube --split reference_seen --method entropy_probes --pool reference9 --episodes 4 --out "$TMP/var" --progress off \
  --params '{"calibrated_preview":true,"lag_aware_preview":true,"entropy_tolerance":0.001,"motion_tiebreak":true}'
expect_out "already complete" "a spelled-out variant is the named variant's job"
python3 - "$TMP/var" <<'PY' && ok || bad "the default job does not run the paper's rule, or its records do not carry the variant"
import glob, json, sys
d = sys.argv[1]
variants = {}
for f in glob.glob(d + "/*.summary.json"):
    s = json.load(open(f))
    p = s["job"]["method"]["params"]
    recs = [json.loads(l) for l in open(f.replace(".summary.json", ".jsonl"))]
    variants[recs[0]["method_variant"]] = p
    assert all(r["method"] == "entropy_probes" for r in recs)
assert set(variants) == {"entropy_probes", "entropy_probes{calibrated}"}, variants
ref = variants["entropy_probes"]
assert (ref["calibrated_preview"], ref["lag_aware_preview"], ref["entropy_tolerance"], ref["motion_tiebreak"]) == (False, False, 0.0, False), ref
cal = variants["entropy_probes{calibrated}"]
assert (cal["calibrated_preview"], cal["lag_aware_preview"], cal["entropy_tolerance"], cal["motion_tiebreak"]) == (True, True, 0.001, True), cal
PY
run "$AS" summarize "$TMP/var" --json
expect_rc 0 "summarize two variants"
[ "$(echo "$OUT" | python3 -c 'import json,sys; print(sorted(c["method"] for c in json.load(sys.stdin)["cells"]))')" = "['entropy_probes', 'entropy_probes{calibrated}']" ] \
  && ok || bad "two variants of one method should summarize to two cells"
run "$AS" gate promote --candidate 'entropy_probes{calibrated_preview=true,lag_aware_preview=true,entropy_tolerance=0.001,motion_tiebreak=true}' \
  --baseline entropy_probes --results "$TMP/var"
expect_rc 0 "gate promote between two variants (the candidate spelled out)"
[ -e "$TMP/var/promotion.entropy_probes{calibrated}.vs.entropy_probes.json" ] && ok || bad "the verdict file should carry the canonical labels"
run "$AS" run --task pick_cube --split reference_seen --method 'entropy_probes{precise}' --pool reference9 --out "$TMP/x" --progress off
expect_rc 2 "unknown variant"
expect_one_line_error "unknown variant"
expect_err "unknown variant (known: calibrated)" "unknown variant message"
run "$AS" run --task pick_cube --split reference_seen --method 'entropy_probes{budget=3}' --params '{"budget":4}' --pool reference9 --out "$TMP/x" --progress off
expect_rc 2 "label and params disagree"
expect_one_line_error "label and params disagree"

# ---- an evaluator's undisclosed seed: --seed-file is the same job as --seed, off the command line
echo 424242 > "$TMP/seed.txt"
run "$AS" run --task pick_cube --split reference_seen --method no_adapt --episodes 2 --seed-file "$TMP/seed.txt" --out "$TMP/sf" --progress off
expect_rc 0 "run --seed-file"
run "$AS" run --task pick_cube --split reference_seen --method no_adapt --episodes 2 --seed 424242 --out "$TMP/sf" --progress off
expect_out "already complete" "--seed-file names the job --seed names"
echo "seven" > "$TMP/badseed.txt"
run "$AS" run --task pick_cube --split reference_seen --method no_adapt --episodes 2 --seed-file "$TMP/badseed.txt" --out "$TMP/sf" --progress off
expect_rc 2 "malformed seed file"
expect_one_line_error "malformed seed file"
expect_err "badseed.txt: seed: must hold one integer" "malformed seed file message"

# ---- bad input: one line, exit 2, nothing written over
run "$AS" run --task pick_cube --split seen --method telepathy --out "$TMP/x" --progress off
expect_rc 2 "unknown method"
expect_one_line_error "unknown method"
expect_err "unknown method" "unknown method message"
run "$AS" run --task pick_cube --split no_such_split --method oracle --out "$TMP/x" --progress off
expect_rc 2 "missing manifest"
expect_one_line_error "missing manifest"
run "$AS" run --task pick_cube --split seen --method entropy_probes --out "$TMP/x" --progress off
expect_rc 2 "pool method without a pool"
expect_err "needs a pool" "pool method without a pool message"
cp "$TMP/t1/$ID" "$TMP/corrupt.jsonl"
sed -i '5s/.*/{"this is": "not a record"}/' "$TMP/t1/$ID"
before=$(sha256sum "$TMP/t1/$ID")
run "$AS" run --task pick_cube --split seen --method oracle --episodes 24 --threads 2 --out "$TMP/t1" --progress off
expect_rc 2 "corrupt results file"
expect_one_line_error "corrupt results file"
[ "$(sha256sum "$TMP/t1/$ID")" = "$before" ] && ok || bad "a corrupt results file was modified"

# ---- calibrate reproduces the committed calibrations (the benchmark's: ManiSkill walks with the finger
# channel; the self-test's: open walks)
run "$AS" calibrate --task pick_cube --gripper-channel --json
expect_rc 0 "calibrate"
[ "$(echo "$OUT" | python3 -c 'import json,sys; r=json.load(sys.stdin)["fit_r2"]; print(sum(r)/6 <= 0.5)')" = True ] && ok || bad "default calibration's mean R^2 above 0.5"
[ "$OUT" = "$(cat "$SRC/configs/calibration/maniskill/pick_cube.json")" ] && ok || bad "calibrate does not reproduce configs/calibration/maniskill/pick_cube.json"
run "$AS" calibrate --task pick_cube --protocol reference_walk --json
[ "$OUT" = "$(cat "$SRC/configs/calibration/maniskill/selftest/pick_cube.json")" ] && ok || bad "calibrate --protocol reference_walk does not reproduce configs/calibration/maniskill/selftest/pick_cube.json"
# ManiSkill walks reset at the 50-step horizon: shorter walks never reach it and equal the open walks;
# 64-step walks include the reset jump, so every channel's residual grows
short_m=$("$AS" calibrate --task push_cube --episodes 2 --steps 40 --json | python3 -c 'import json,sys; d=json.load(sys.stdin); print(d["alpha"], d["sigma"])')
short_o=$("$AS" calibrate --task push_cube --episodes 2 --steps 40 --protocol reference_walk --json | python3 -c 'import json,sys; d=json.load(sys.stdin); print(d["alpha"], d["sigma"])')
[ -n "$short_m" ] && [ "$short_m" = "$short_o" ] && ok || bad "walks shorter than the horizon differ between maniskill_walk and reference_walk"
"$AS" calibrate --task push_cube --episodes 2 --steps 64 --json > "$TMP/msw.json"
"$AS" calibrate --task push_cube --episodes 2 --steps 64 --protocol reference_walk --json > "$TMP/open.json"
python3 - "$TMP/msw.json" "$TMP/open.json" <<'PY' && ok || bad "the auto-reset sample does not raise every channel's sigma"
import json, sys
m, o = (json.load(open(p)) for p in sys.argv[1:])
assert m["protocol"] == "maniskill_walk" and o["protocol"] == "reference_walk", (m["protocol"], o["protocol"])
assert all(a > b for a, b in zip(m["sigma"], o["sigma"])), (m["sigma"], o["sigma"])
PY
run "$AS" calibrate --task push_cube --protocol sideways
expect_rc 2 "unknown protocol"
expect_one_line_error "unknown protocol"

# ---- an external policy starts once per worker: not when the job is planned or resolved, and not
# once more for a prototype that only gets cloned
cat > "$TMP/counting.sh" <<EOF
echo started >> "$TMP/starts.txt"
read l; echo '{"type":"ready"}'
while read l; do case "\$l" in *'"step"'*) echo '{"action":[0,0,0,0,0,0,0]}';; esac; done
EOF
printf 'name: ext\ntasks: [pick_cube]\nsplits: [reference_seen]\nmethods: [no_adapt]\nseeds: [1, 2]\nepisodes: 2\nbackbone: "external:sh %s"\n' \
  "$TMP/counting.sh" > "$TMP/ext.yaml"
rm -f "$TMP/starts.txt"
run "$AS" plan --experiment "$TMP/ext.yaml" --out "$TMP/extplan"
expect_rc 0 "plan with an external backbone"
[ ! -e "$TMP/starts.txt" ] && ok || bad "planning started the external policy $(wc -l < "$TMP/starts.txt") times"
run "$AS" run --task pick_cube --split reference_seen --method no_adapt --episodes 2 --threads 1 \
  --backbone "external:sh $TMP/counting.sh" --out "$TMP/ext1" --progress off
expect_rc 0 "external job, 1 thread"
[ "$(wc -l < "$TMP/starts.txt")" -eq 1 ] && ok || bad "1 worker started the policy $(wc -l < "$TMP/starts.txt") times"
rm -f "$TMP/starts.txt"
run "$AS" run --task pick_cube --split reference_seen --method no_adapt --episodes 4 --threads 2 \
  --backbone "external:sh $TMP/counting.sh" --out "$TMP/ext2" --progress off
expect_rc 0 "external job, 2 threads"
[ "$(wc -l < "$TMP/starts.txt")" -eq 2 ] && ok || bad "2 workers started the policy $(wc -l < "$TMP/starts.txt") times"

finish
