#!/usr/bin/env bash
# Hostile input at the CLI boundary: every case must end in one `actionshift: error:` line and exit 2
# (3 for selftest), never a crash, a hang, a raw library message or a leftover temporary file.
# Fast: no case runs more than a handful of simulated episodes.
set -euo pipefail
AS="$1"
SRC="$2"
source "$(dirname "$0")/lib.sh"

deep() { python3 -c "import sys; n=int(sys.argv[1]); sys.stdout.write('['*n + ']'*n)" "$1"; }

# ---- deeply nested JSON: a plan's method parameters, a manifest's metadata, a JSONL record field
python3 - "$TMP" <<'PY'
import sys
d = sys.argv[1]
deep = '[' * 100000 + ']' * 100000
open(d + '/deep_plan.json', 'w').write('{"schema_version":"1","jobs":[{"method":{"params":' + deep + '}}]}')
PY
cp "$SRC/manifests/reference_seen.json" "$TMP/deep_manifest.json"
python3 - "$TMP/deep_manifest.json" <<'PY'
import sys
p = sys.argv[1]
t = open(p).read()
t = t.replace('"metadata": {}', '"metadata": {"x": ' + '[' * 100000 + ']' * 100000 + '}', 1)
open(p, 'w').write(t)
PY
run "$AS" run --plan "$TMP/deep_plan.json" --out "$TMP/o" --progress off
expect_rc 2 "deep plan"
expect_one_line_error "deep plan"
expect_err "nested deeper than" "deep plan"
run "$AS" validate "$TMP/deep_manifest.json"
expect_rc 2 "deep manifest"
expect_one_line_error "deep manifest"
expect_err "metadata" "deep manifest names the field"

# ---- a small real job, then hostile edits of its JSONL
run "$AS" run --task pick_cube --split reference_seen --method oracle --episodes 3 --threads 1 --out "$TMP/r" --progress off
expect_rc 0 "small job"
JL=$(ls "$TMP"/r/*.jsonl)
cp "$JL" "$TMP/clean.jsonl"
mkdir -p "$TMP/deep" "$TMP/ovf"
python3 - "$JL" "$TMP/deep/a.jsonl" "$TMP/ovf/a.jsonl" <<'PY'
import sys
src, deep, ovf = sys.argv[1:4]
lines = open(src).read().splitlines()
first = lines[0]
open(deep, 'w').write(first[:-1] + ',"x":' + '[' * 100000 + ']' * 100000 + '}\n')
import re
open(ovf, 'w').write(re.sub(r'"return":[^,}]+', '"return":1e999', first) + '\n')
PY
run "$AS" summarize "$TMP/deep"
expect_rc 2 "deep record"
expect_one_line_error "deep record"
expect_err "nested deeper than" "deep record"
run "$AS" summarize "$TMP/ovf"
expect_rc 2 "overflowing record"
expect_one_line_error "overflowing record"
expect_err ": return: number out of range" "overflowing record names the field"
expect_err "out of range" "overflowing record says why"
# a complete (newline-terminated) last line that does not parse is not a torn write: a resume
# refuses it, naming file and line, and leaves the file byte for byte as it was
# (the job's summary is removed first: a summary covering the line would refuse it as an edited record)
rm "${JL%.jsonl}.summary.json"
python3 - "$JL" <<'PY'
import re, sys
p = sys.argv[1]
lines = open(p).read().splitlines()
lines[-1] = re.sub(r'"backbone_sha256":"[0-9a-f]*"', '"backbone_sha256":1e999', lines[-1])
open(p, 'w').write('\n'.join(lines) + '\n')
PY
BEFORE=$(sha256sum "$JL" | cut -d' ' -f1)
run "$AS" run --task pick_cube --split reference_seen --method oracle --episodes 3 --threads 1 --out "$TMP/r" --progress off
expect_rc 2 "resume over a complete 1e999 last line"
expect_one_line_error "resume over a complete 1e999 last line"
expect_err "$JL:3: backbone_sha256" "complete unparsable last line names file, line and field"
[ "$(sha256sum "$JL" | cut -d' ' -f1)" = "$BEFORE" ] && ok || bad "a complete unparsable last line was changed"
# an unterminated last line (no newline: a torn write) is repaired, with nothing else lost
python3 - "$JL" "$TMP/clean.jsonl" <<'PY'
import sys
lines = open(sys.argv[2]).read().splitlines()
open(sys.argv[1], 'w').write('\n'.join(lines[:-1]) + '\n' + lines[-1][:len(lines[-1]) // 2])
PY
run "$AS" run --task pick_cube --split reference_seen --method oracle --episodes 3 --threads 1 --out "$TMP/r" --progress off
expect_rc 0 "resume over an unterminated last line"
expect_err "repaired a torn last line" "resume logs the repair"
cmp -s "$JL" "$TMP/clean.jsonl" && ok || bad "the repaired JSONL differs from the clean run"

# ---- run --split FILE verifies the stored hashes; the clean copy still runs
sed 's/"scale":\[0.5,/"scale":[0.25,/' "$SRC/manifests/reference_seen.json" > "$TMP/tampered.json"
cmp -s "$TMP/tampered.json" "$SRC/manifests/reference_seen.json" && bad "tamper did not change the file" || ok
run "$AS" run --task pick_cube --split "$TMP/tampered.json" --method oracle --episodes 1 --out "$TMP/tam" --progress off
expect_rc 2 "tampered split"
expect_one_line_error "tampered split"
expect_err "_hash" "tampered split names the failed check"
[ ! -e "$TMP/tam" ] || [ -z "$(ls -A "$TMP/tam")" ] && ok || bad "tampered split wrote results"

# ---- output paths are checked before any work
touch "$TMP/afile"
run "$AS" run --task pick_cube --split reference_seen --method oracle --episodes 1 --out "$TMP/afile" --progress off
expect_rc 2 "run --out FILE"
expect_one_line_error "run --out FILE"
expect_err "not a directory" "run --out FILE"
mkdir -p "$TMP/outdir"
# 0 solver iterations is refused, not read as "the profile's default"
run "$AS" calibrate --task pick_cube --episodes 1 --steps 2 --solver-iterations 0
expect_rc 2 "calibrate --solver-iterations 0"
expect_one_line_error "calibrate --solver-iterations 0"
expect_err "--solver-iterations: must be in 1..1000 (got 0)" "calibrate --solver-iterations 0 message"
run "$AS" calibrate --task pick_cube --episodes 1 --steps 2 --out "$TMP/outdir"
expect_rc 2 "calibrate --out DIR"
expect_one_line_error "calibrate --out DIR"
[ -z "$(ls -A "$TMP" | grep '\.tmp' || true)" ] && ok || bad "calibrate left a .tmp behind: $(ls "$TMP")"
run "$AS" gate0 --backbone "mlp:$TMP/outdir" --task pick_cube --episodes 1
expect_rc 2 "gate0 mlp:DIR"
expect_one_line_error "gate0 mlp:DIR"
expect_err "directory" "gate0 mlp:DIR"

# ---- an oversized experiment file is refused before it is read
head -c 2000000 /dev/zero | tr '\0' 'a' > "$TMP/big.yaml"
run "$AS" plan --experiment "$TMP/big.yaml" --out "$TMP/bigplan"
expect_rc 2 "oversized YAML"
expect_one_line_error "oversized YAML"
expect_err "too large" "oversized YAML"
# a small experiment whose grid is too large: refused from its list sizes before any job is made
# (an 80 KB experiment expanded to 180,000 jobs and a 220 MB plan)
python3 - "$TMP/grid.yaml" <<'PY'
import sys
seeds = ', '.join(str(s) for s in range(10001))
open(sys.argv[1], 'w').write('name: grid\ntasks: [pick_cube, push_cube, pull_cube, stack_cube, peg_insertion_side]\n'
                             'splits: [seen, unseen_value]\nmethods: [oracle]\nseeds: [' + seeds + ']\nepisodes: 1\nbackbone: expert\n')
PY
run timeout 20 "$AS" plan --experiment "$TMP/grid.yaml" --out "$TMP/gridplan"
expect_rc 2 "experiment of 100,010 jobs"
expect_one_line_error "experiment of 100,010 jobs"
expect_err "$TMP/grid.yaml: the experiment expands to 100010 jobs (5 tasks x 2 splits x 1 methods x 10001 seeds), at most 100000" \
  "experiment of 100,010 jobs names the file and the count"
[ ! -e "$TMP/gridplan" ] && ok || bad "a refused experiment left a plan directory"
printf 'name: x\nmethods: %s\n' "$(deep 100000)" > "$TMP/deep.yaml"
run "$AS" plan --experiment "$TMP/deep.yaml" --out "$TMP/deepplan"
expect_rc 2 "deep YAML"
expect_one_line_error "deep YAML"

# ---- selftest contract arguments: bad input is exit 3, one line
run "$AS" selftest --expected "{\"a\":$(deep 50000)}"
expect_rc 3 "selftest deep contract"
expect_one_line_error "selftest deep contract"
run "$AS" selftest --expected "reference_seen:99999999999999999999999"
expect_rc 3 "selftest huge index"
expect_one_line_error "selftest huge index"

# ---- an external policy that floods replies ends the job with a protocol error, quickly
cat > "$TMP/flood.py" <<'PY'
import sys
for line in sys.stdin:
    if '"hello"' in line:
        print('{"type":"ready"}', flush=True)
    elif '"step"' in line:
        for _ in range(50):
            sys.stdout.write('{"action":[0,0,0,0,0,0,0]}\n')
        sys.stdout.flush()
PY
start=$(date +%s)
run timeout 120 "$AS" run --task pick_cube --split reference_seen --method oracle --episodes 1 --threads 1 \
  --backbone "external:python3 $TMP/flood.py" --step-timeout 5 --out "$TMP/flood" --progress off
expect_rc 2 "flooding policy"
expect_err "protocol error" "flooding policy"
[ $(( $(date +%s) - start )) -lt 100 ] && ok || bad "flooding policy took too long"
cat > "$TMP/mute.py" <<'PY'
import sys, time
sys.stdin.readline()
print('{"type":"ready"}', flush=True)
time.sleep(60)
PY
run timeout 60 "$AS" run --task pick_cube --split reference_seen --method oracle --episodes 1 --threads 1 \
  --backbone "external:python3 $TMP/mute.py" --step-timeout 0.5 --out "$TMP/mute" --progress off
expect_rc 2 "a policy that stops reading"
expect_err "timeout" "a policy that stops reading"

# ---- special files: an input that is a device or FIFO is refused (reading /dev/zero used to grow to
# gigabytes, a FIFO to block), and an output never replaces one (summarize --out /dev/full replaced
# the device node); each with `timeout` so a regression fails instead of hanging the suite
mkfifo "$TMP/fifo"
for args in "contract hash /dev/zero" "validate /dev/zero" "plan --experiment /dev/zero --out $TMP/pz" \
            "run --plan /dev/zero" "validate $TMP/fifo"; do
  # shellcheck disable=SC2086  # the words are the arguments
  run timeout 20 "$AS" $args
  expect_rc 2 "special input: $args"
  expect_one_line_error "special input: $args"
  expect_err "not a regular file" "special input: $args"
done
run timeout 20 "$AS" run --task pick_cube --split reference_seen --method oracle --episodes 2 \
  --backbone mlp:/dev/zero --out "$TMP/mz" --progress off
expect_rc 2 "weight file /dev/zero"
expect_err "not a regular file" "weight file /dev/zero"
mkdir -p "$TMP/rz"
ln -s /dev/zero "$TMP/rz/$(basename "$JL")"
run timeout 20 "$AS" run --task pick_cube --split reference_seen --method oracle --episodes 3 --threads 1 --out "$TMP/rz" --progress off
expect_rc 2 "results file on /dev/zero"
expect_err "is a symbolic link" "results file on /dev/zero"
# a results file that links to a regular file elsewhere: refused, and the link's target is untouched
mkdir -p "$TMP/rl"
cp "$TMP/clean.jsonl" "$TMP/outside.jsonl"
ln -s "$TMP/outside.jsonl" "$TMP/rl/$(basename "$JL")"
sha_target=$(sha256sum < "$TMP/outside.jsonl")
run timeout 20 "$AS" run --task pick_cube --split reference_seen --method oracle --episodes 3 --threads 1 --out "$TMP/rl" --progress off
expect_rc 2 "results file linked outside --out"
expect_one_line_error "results file linked outside --out"
expect_err "is a symbolic link" "results file linked outside --out"
[ "$(sha256sum < "$TMP/outside.jsonl")" = "$sha_target" ] && ok || bad "a run through a symlinked results file changed its target"
run timeout 20 "$AS" summarize "$TMP/r" --out "$TMP/fifo"
expect_rc 2 "summarize --out a FIFO"
expect_err "not a regular file (refusing to replace it)" "summarize --out a FIFO"
[ -p "$TMP/fifo" ] && ok || bad "summarize replaced the FIFO with a regular file"

# ---- a results file with a long unreadable tail is reported, not cut (a torn write is under one line)
cp "$TMP/clean.jsonl" "$TMP/r/$(basename "$JL")"
head -c 2000000 /dev/zero >> "$TMP/r/$(basename "$JL")"
sha_before=$(sha256sum < "$TMP/r/$(basename "$JL")")
run "$AS" run --task pick_cube --split reference_seen --method oracle --episodes 3 --threads 1 --out "$TMP/r" --progress off
expect_rc 2 "2 MB tail"
expect_err "too many for a torn write" "2 MB tail"
[ "$(sha256sum < "$TMP/r/$(basename "$JL")")" = "$sha_before" ] && ok || bad "the 2 MB tail was cut"
cp "$TMP/clean.jsonl" "$TMP/r/$(basename "$JL")"

# ---- numbers the option parser would wrap or saturate
for seed in -1 18446744073709551616; do
  run "$AS" run --task pick_cube --split reference_seen --method oracle --episodes 1 --seed "$seed" --out "$TMP/sd" --progress off
  expect_rc 2 "seed $seed"
  expect_err "must be an integer in [0, 2**64)" "seed $seed"
done
run "$AS" run --task pick_cube --split reference_seen --method oracle --episodes 99999999999999999999 --out "$TMP/sd" --progress off
expect_rc 2 "episodes beyond int64"
expect_err "--episodes: out of range: '99999999999999999999' does not fit a 64-bit integer" "episodes beyond int64"
run "$AS" run --task pick_cube --split reference_seen --method oracle --episodes 1 --step-timeout nan --out "$TMP/sd" --progress off
expect_rc 2 "step-timeout nan"
[ ! -e "$TMP/sd" ] || [ -z "$(ls -A "$TMP/sd")" ] && ok || bad "a refused run wrote results"

# ---- plan --slurm: the partition is written into the scripts, so a shell line there is refused
cat > "$TMP/tiny.yaml" <<'YAML'
name: tiny
tasks: [pick_cube]
splits: [reference_seen]
methods: [oracle]
seeds: [1]
episodes: 1
backbone: expert
pool: null
YAML
run "$AS" plan --experiment "$TMP/tiny.yaml" --out "$TMP/sl" --slurm --partition $'p\nrm -rf /'
expect_rc 2 "partition with a newline"
expect_one_line_error "partition with a newline"
[ ! -e "$TMP/sl" ] && ok || bad "plan wrote files for a refused partition"

# ---- montage: a 35-byte GIF declaring a 65535 x 65535 image (giflib's int raster size wraps: a crash)
printf 'GIF89a\xff\xff\xff\xff\x80\x00\x00\x00\x00\x00\xff\xff\xff\x2c\x00\x00\x00\x00\xff\xff\xff\xff\x00\x02\x02\x44\x01\x00\x3b' > "$TMP/huge.gif"
run timeout 20 "$AS" montage "$TMP/huge.gif" --out "$TMP/m.gif"
expect_rc 2 "huge GIF"
expect_one_line_error "huge GIF"
expect_err "larger than 8192 pixels" "huge GIF"

# ---- a copied results file is refused by every reader (gate1 counted its episodes twice)
mkdir -p "$TMP/dup"
cp "$TMP/clean.jsonl" "$TMP/dup/$(basename "$JL")"
cp "$TMP/clean.jsonl" "$TMP/dup/copy.jsonl"
for cmd in summarize gate1; do
  if [ "$cmd" = summarize ]; then run "$AS" summarize "$TMP/dup"; else run "$AS" gate1 --results "$TMP/dup" --verdict "$TMP/dup.verdict.json"; fi
  expect_rc 2 "$cmd over a copied jsonl"
  expect_err "is also in" "$cmd over a copied jsonl"
done
# ---- gate check: an expectation with no cells would pass whatever the results say
printf '{"gate":"gate1","cells":{}}' > "$TMP/empty.verdict.json"
run "$AS" gate check --expected "$TMP/empty.verdict.json" --actual "$TMP/empty.verdict.json"
expect_rc 2 "gate check with no cells"
expect_err "no verdicts to check" "gate check with no cells"
# ---- a zero quaternion used to decode as the identity rotation
run "$AS" contract decode '{"contract":{"frame":"tool","gripper_inverted":false,"lag":0,"permutation":[0,1,2,3,4,5],"scale":[1,1,1,1,1,1],"sign":[1,1,1,1,1,1],"target":"delta"},"raw":[0.5,0.2,0.1,0,0,0,1],"quat_wxyz":[0,0,0,0]}'
expect_rc 2 "zero quaternion"
expect_err "quat_wxyz" "zero quaternion"

# ---- a long command checks its --out before the work, not after it (train bc wrote nowhere after its DAgger run)
for args in "train bc --task pick_cube --iterations 1 --episodes 1" "train ppo --task pick_cube --total-steps 1024" \
            "train dp --task pick_cube --demos 1 --iterations 1" \
            "gate0 --task pick_cube --episodes 2"; do
  start=$(date +%s)
  # shellcheck disable=SC2086  # the words are the arguments
  run timeout 60 "$AS" $args --out "$TMP/no/such/dir/out"
  expect_rc 2 "$args into a missing directory"
  expect_err "is not a directory" "$args into a missing directory"
  [ $(( $(date +%s) - start )) -lt 10 ] && ok || bad "$args worked before refusing its --out"
done

# ---- option values that used to be accepted: a negative --job-index ran the whole plan
run "$AS" run --plan "$TMP/none.plan.json" --job-index -1 --out "$TMP/ji" --progress off
expect_rc 2 "negative job index"
expect_err "must be a job index >= 0" "negative job index"
run "$AS" train ppo --task pick_cube --target-kl nan --out "$TMP/kl.asmlp"
expect_rc 2 "target-kl nan"
run "$AS" montage "$TMP/huge.gif" --out "$TMP/m.gif" --delay 0
expect_rc 2 "montage delay 0"
expect_err "--delay: Value 0 not in range 1 to 1000" "montage delay 0"
run "$AS" render --task pick_cube --split reference_seen --method no_adapt --episodes 1 --out "$TMP/r.gif" --delay 1001
expect_rc 2 "render delay 1001"
expect_err "--delay: Value 1001 not in range 1 to 1000" "render delay 1001"

# ---- amplification: thread counts and calibration walks are bounded (10,000 threads made 7,939 OS threads)
run "$AS" run --task pick_cube --split reference_seen --method oracle --threads 10000 --out "$TMP/th" --progress off
expect_rc 2 "run --threads 10000"
expect_one_line_error "run --threads 10000"
expect_err "--threads: Value 10000 not in range 0 to 1024" "run --threads 10000 message"
[ ! -e "$TMP/th" ] && ok || bad "a refused --threads left a results directory"
run "$AS" calibrate --task pick_cube --episodes 2000000000
expect_rc 2 "calibrate --episodes 2e9"
expect_err "--episodes: Value 2000000000 not in range 1 to 100000" "calibrate --episodes 2e9 message"

# ---- a repeated key: the second value used to win silently (JSON) or be ignored (YAML)
run "$AS" contract hash '{"frame":"base","gripper_inverted":false,"lag":0,"permutation":[0,1,2,3,4,5],"scale":[1,1,1,1,1,1],"sign":[1,1,1,1,1,1],"target":"delta","lag":2}'
expect_rc 2 "contract with a repeated key"
expect_one_line_error "contract with a repeated key"
expect_err "lag: duplicate key in one object" "contract with a repeated key"
# the duplicate-key check is one hash set per object: 200,000 distinct keys (2.6 MB) parse at once (each key
# was compared with all before it: > 60 s), and a duplicate at the end is still found
python3 -c 'import json; d={f"k{i:07d}": i for i in range(200000)}; print(json.dumps(d))' > "$TMP/manykeys.json"
run timeout 20 "$AS" contract hash "$TMP/manykeys.json"
expect_rc 2 "a 200,000-key object is parsed (within the timeout) and refused as a contract"
expect_one_line_error "a 200,000-key object"
python3 -c 'import json; d={f"k{i:07d}": i for i in range(200000)}; print(json.dumps(d)[:-1] + ", \"k0000007\": 1}")' > "$TMP/manykeys_dup.json"
run timeout 20 "$AS" contract hash "$TMP/manykeys_dup.json"
expect_rc 2 "a duplicate key after 200,000 keys"
expect_err "k0000007: duplicate key in one object" "a duplicate key after 200,000 keys"
run "$AS" run --task pick_cube --split reference_seen --method entropy_probes --pool reference9 \
  --params '{"budget":1,"budget":2}' --episodes 1 --out "$TMP/dupparams" --progress off
expect_rc 2 "--params with a repeated key"
expect_err "command line: --params.budget: duplicate key in one object" "--params with a repeated key"
printf 'name: dup\ntasks: [pick_cube]\nsplits: [reference_seen]\nmethods: [oracle]\nseeds: [1]\nepisodes: 2\nepisodes: 2000\nbackbone: expert\n' > "$TMP/dup.yaml"
run "$AS" plan --experiment "$TMP/dup.yaml" --out "$TMP/dupplan"
expect_rc 2 "experiment with a repeated key"
expect_err "dup.yaml:7: episodes: duplicate key" "experiment with a repeated key"
[ ! -e "$TMP/dupplan" ] && ok || bad "a refused experiment left a plan directory"

# ---- splits generate --out: raw std::filesystem messages, and a FIFO in the way was replaced
touch "$TMP/plainfile"
run "$AS" splits generate --out "$TMP/plainfile"
expect_rc 2 "splits generate into a file"
expect_one_line_error "splits generate into a file"
expect_err "plainfile: --out: exists and is not a directory" "splits generate into a file"
mkdir -p "$TMP/gen_fifo" && mkfifo "$TMP/gen_fifo/seen.json"
run timeout 20 "$AS" splits generate --out "$TMP/gen_fifo" --rule seen
expect_rc 2 "splits generate over a FIFO"
expect_err "seen.json" "splits generate over a FIFO"
[ -p "$TMP/gen_fifo/seen.json" ] && ok || bad "splits generate replaced a FIFO"
[ -z "$(find "$TMP/gen_fifo" -name '*.tmp')" ] && ok || bad "splits generate left a temporary file"

# ---- report: a verdict cell that is not an object was nlohmann's raw type_error 306
mkdir -p "$TMP/rep" && cp "$TMP/clean.jsonl" "$TMP/rep/"
echo '{"gate":"gate1","cells":{"pick_cube/reference_seen":"pass"}}' > "$TMP/rep/gate1.verdict.json"
run "$AS" report "$TMP/rep" --out "$TMP/rep/out"
expect_rc 2 "report with a malformed verdict cell"
expect_one_line_error "report with a malformed verdict cell"
expect_err "gate1.verdict.json: cells.pick_cube/reference_seen: expected an object" "report with a malformed verdict cell"

# ---- a FIFO named like a job summary beside its records: summarize must not block on it (and, as any
# summary that is not one, it is refused in one line)
mkdir -p "$TMP/fifo_sum" && cp "$TMP/clean.jsonl" "$TMP/fifo_sum/"
mkfifo "$TMP/fifo_sum/$(basename "$TMP/clean.jsonl" .jsonl).summary.json"
run timeout 20 "$AS" summarize "$TMP/fifo_sum"
expect_rc 2 "summarize beside a FIFO summary"
expect_one_line_error "summarize beside a FIFO summary"
expect_err "not a regular file" "summarize beside a FIFO summary"

# ---- selftest --sim --calibration of another task read the pose at that task's offsets
run "$AS" selftest --sim --task push_cube --hidden-contract identity \
  --calibration "$SRC/configs/calibration/maniskill/selftest/pick_cube.json"
expect_rc 3 "selftest with another task's calibration"
expect_err "pick_cube.json: task: is pick_cube, not --task push_cube" "selftest with another task's calibration"
run "$AS" selftest --sim --task pick_cube --profile ideal --hidden-contract identity \
  --calibration "$SRC/configs/calibration/maniskill/selftest/pick_cube.json"
expect_rc 3 "selftest with another profile's calibration"
expect_err "profile: was measured on maniskill, not on --profile ideal" "selftest with another profile's calibration"

# ---- run --plan: a failing job is named by its plan entry, also with --progress off
cat > "$TMP/dies.py" <<'PY'
import sys
for line in sys.stdin:  # answers the hello, then exits at the first step
    if '"hello"' in line:
        print('{"type":"ready"}', flush=True)
    elif '"step"' in line:
        sys.exit(1)
PY
printf 'name: failing\ntasks: [pick_cube]\nsplits: [reference_seen]\nmethods: [oracle]\nseeds: [1]\nepisodes: 1\nbackbone: "external:python3 %s"\n' "$TMP/dies.py" > "$TMP/failing.yaml"
run "$AS" plan --experiment "$TMP/failing.yaml" --out "$TMP/failing"
expect_rc 0 "plan of an external backbone"
run timeout 60 "$AS" run --plan "$TMP/failing/failing.plan.json" --out "$TMP/failing" --progress off
expect_rc 2 "run --plan with a failing job"
expect_one_line_error "run --plan with a failing job"
expect_err "failing.plan.json: jobs[0] (" "run --plan with a failing job names the entry"
grep -qF 'step 0: process exited with status 1 before replying); re-run to resume' "$TMP"/failing/*.summary.json \
  && ok || bad "a failed job's summary does not say why it stopped"
run "$AS" summarize "$TMP/failing"
expect_rc 2 "summarize a job that stopped before its first episode"
expect_err "its .jsonl file is empty (a job that stopped before its first episode says why in its .summary.json)" \
  "summarize a job that stopped before its first episode"

# ---- --profile is checked while parsing: selftest had blamed a missing calibration, bench env printed no option
run "$AS" bench env --task pick_cube --steps 5 --profile bogus
expect_rc 2 "bench env --profile bogus"
expect_err "--profile: unknown fidelity profile 'bogus' (valid: maniskill, ideal)" "bench env --profile bogus"
run "$AS" selftest --sim --task pick_cube --hidden-contract identity --profile bogus
expect_rc 3 "selftest --profile bogus"
expect_err "unknown fidelity profile 'bogus'" "selftest --profile bogus"
# the report names its task: an unknown one is refused with or without --sim
for sim in "" --sim; do
  run "$AS" selftest $sim --task pick_cubes --hidden-contract identity
  expect_rc 3 "selftest $sim --task pick_cubes"
  expect_one_line_error "selftest $sim --task pick_cubes"
  expect_err "--task: unknown task 'pick_cubes' (valid: pick_cube," "selftest $sim --task pick_cubes message"
done

finish
