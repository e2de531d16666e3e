#!/usr/bin/env bash
# Every reader of a file a user names refuses an 8 GiB file at once, by its size, before reading it:
# exit 2 (3 for the self-test) within a short timeout, one `actionshift: error:` line naming the file.
# The files are sparse (`truncate -s 8G`): they take no disk space, and a reader that reads them
# anyway is killed by the timeout (exit 124) or runs out of memory.
# usage: cli_bounded_read_test.sh ACTIONSHIFT_BINARY SOURCE_DIR [PYTHON_MODULE_DIR]
set -euo pipefail
AS="$1"
SRC="$2"
PYDIR="${3:-}"
source "$(dirname "$0")/lib.sh"
T=20  # seconds: a size check answers in milliseconds; reading 8 GiB takes far longer, or fails
# a reader that does read the file must not take the shared machine's memory with it: 4 GiB of
# address space (not under AddressSanitizer, which reserves terabytes of it for its shadow memory)
ldd "$AS" 2> /dev/null | grep -q libasan || ulimit -v 4194304

big() { truncate -s 8G "$TMP/$1"; echo "$TMP/$1"; }

# bounded CODE NAME FILE CMD...: CMD ends with CODE in time, in one line that names FILE
bounded() {
  local code="$1" name="$2" file="$3"
  shift 3
  run timeout "$T" "$@"
  expect_rc "$code" "$name"
  expect_one_line_error "$name"
  expect_err "$file" "$name names the file"
  expect_err "too large" "$name says why"
}

job=(--task pick_cube --split reference_seen --episodes 1 --threads 1 --progress off --out "$TMP/res")

F=$(big contract.json);   bounded 2 "contract hash FILE" "$F" "$AS" contract hash "$F"
F=$(big contracts.jsonl); bounded 2 "contract decode FILE" "$F" "$AS" contract decode "$F"
F=$(big manifest.json);   bounded 2 "validate FILE" "$F" "$AS" validate "$F"
F=$(big split.json);      bounded 2 "run --split FILE" "$F" "$AS" run --task pick_cube --split "$F" --method oracle --episodes 1 --progress off --out "$TMP/res"
F=$(big pool.json);       bounded 2 "run --pool FILE" "$F" "$AS" run "${job[@]}" --method entropy_probes --pool "$F"
F=$(big cal.json);        bounded 2 "run --calibration FILE" "$F" "$AS" run "${job[@]}" --method exact_belief --pool reference9 --calibration "$F"
F=$(big seed);            bounded 2 "run --seed-file FILE" "$F" "$AS" run "${job[@]}" --method oracle --seed-file "$F"
F=$(big robot.urdf);      bounded 2 "run --robot FILE" "$F" "$AS" run "${job[@]}" --method oracle --robot "$F"
F=$(big policy.bin);      bounded 2 "run --policy-files FILE" "$F" "$AS" run "${job[@]}" --method oracle --backbone "external:true" --policy-files "$F"
F=$(big experiment.yaml); bounded 2 "plan --experiment FILE" "$F" "$AS" plan --experiment "$F" --out "$TMP/plan"
F=$(big plan.json);       bounded 2 "run --plan FILE" "$F" "$AS" run --plan "$F" --out "$TMP/res" --progress off
F=$(big weights.asmlp);   bounded 2 "gate0 --backbone mlp:FILE" "$F" "$AS" gate0 --backbone "mlp:$F" --task pick_cube --episodes 1
F=$(big expected.json);   bounded 3 "selftest --expected FILE" "$F" "$AS" selftest --expected "$F"
F=$(big selftest_cal.json); bounded 3 "selftest --sim --calibration FILE" "$F" "$AS" selftest --sim --task pick_cube --hidden-contract identity --calibration "$F"
mkdir -p "$TMP/results"
F=$(big results/0000000000000000000000000000000000000000000000000000000000000000.jsonl)
bounded 2 "summarize DIR (a results file)" "$F" "$AS" summarize "$TMP/results"

# a mesh named by a URDF: refused by its size before assimp opens it (the Panda with one collision
# shape replaced by the mesh)
F=$(big huge.stl)
python3 - "$SRC/configs/robots/panda.urdf" "$TMP/mesh_panda.urdf" <<'PY'
import re, sys
text = open(sys.argv[1]).read()
text = re.sub(r'<geometry>\s*<(box|sphere|cylinder)[^>]*/>\s*</geometry>', '<geometry><mesh filename="huge.stl"/></geometry>', text, count=1)
assert 'huge.stl' in text
open(sys.argv[2], 'w').write(text)
PY
bounded 2 "a mesh named by --robot's URDF" "$F" "$AS" run "${job[@]}" --method oracle --robot "$TMP/mesh_panda.urdf"

# standard input redirected from an 8 GiB file: refused by its size too
run timeout "$T" "$AS" contract decode - < "$TMP/contracts.jsonl"
expect_rc 2 "contract decode < FILE"
expect_one_line_error "contract decode < FILE"
expect_err "<stdin>" "contract decode < FILE names stdin"
expect_err "too large" "contract decode < FILE says why"

# the Python module's file readers (when it is built)
if [ -n "$PYDIR" ] && ls "$PYDIR"/actionshift/_native*.so > /dev/null 2>&1; then
  run timeout "$T" env PYTHONPATH="$PYDIR" PYTHONDONTWRITEBYTECODE=1 python3 - "$TMP/manifest.json" "$TMP/cal.json" <<'PY'
import sys
import actionshift
for call in (lambda: actionshift.load_manifest(sys.argv[1]),
             lambda: actionshift.make_adapter("exact_belief", task="pick_cube", pool="reference9", calibration=sys.argv[2])):
    try:
        call()
    except ValueError as e:
        print(e)
    else:
        print("accepted")
PY
  expect_rc 0 "python readers"
  grep -q "^$TMP/manifest.json: too large" <<<"$OUT" && ok || bad "python load_manifest: $OUT"
  grep -q "^$TMP/cal.json: too large" <<<"$OUT" && ok || bad "python calibration file: $OUT"
fi
finish
