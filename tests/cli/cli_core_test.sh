#!/usr/bin/env bash
# actionshift validate / contract / splits, end to end.
set -euo pipefail
AS="$1"
SRC="$2"
source "$(dirname "$0")/lib.sh"

ID='{"frame":"base","gripper_inverted":false,"lag":0,"permutation":[0,1,2,3,4,5],"scale":[1.0,1.0,1.0,1.0,1.0,1.0],"sign":[1,1,1,1,1,1],"target":"delta"}'

# golden identity hash (issue 2) from an argument and from stdin
run "$AS" contract hash "$ID"
expect_rc 0 "contract hash"
expect_out '"sha256":"6b38e10f94c37daf6ec3027f9fade885c611bbf710b732cc6f61ed134efb1eaa"' "identity hash"
run bash -c "echo '$ID' | '$AS' contract hash"
expect_out '6b38e10f94c37daf6ec3027f9fade885c611bbf710b732cc6f61ed134efb1eaa' "identity hash from stdin"

# validate the committed manifests: exit 0, reference9 pool hash shown
run "$AS" validate "$SRC/manifests"
expect_rc 0 "validate manifests/"
expect_out "b177b082925800655dee9e93c02142f26a703fd2bdf1d97be56a2cb0bf0eeea3" "reference9 pool hash"
expect_out "all checks passed over 11 manifests" "summary line"
run "$AS" validate "$SRC/manifests/seen.json" --quiet
expect_out "all checks passed over 1 manifest" "summary line of one manifest"

# a misspelt command is named, with the nearest command (CLI11 said "A subcommand is required")
run "$AS" summarise results
expect_rc 2 "misspelt command"
expect_err "unknown command 'summarise' for actionshift (did you mean 'summarize'?)" "misspelt command"
run "$AS" gate chek --expected x
expect_rc 2 "misspelt subcommand"
expect_err "unknown command 'chek' for actionshift gate (did you mean 'check'?)" "misspelt subcommand"
run "$AS" validate "$SRC/manifests/seen.json" --quiet
expect_rc 0 "a command's positional argument is not a command"
run "$AS" gate --results "$TMP"
expect_rc 2 "a command group without its command"
expect_err "actionshift gate needs a command: check, promote" "a command group without its command"
run "$AS" gate --help
expect_rc 0 "a command group's help"
# built-in copies give the same answer with no files
run "$AS" validate --quiet
expect_rc 0 "validate built-ins"

# change one number in each manifest: exit 1, naming the file and the failed check
for f in "$SRC"/manifests/*.json; do
  name=$(basename "$f")
  mkdir -p "$TMP/t"
  rm -f "$TMP"/t/*
  cp "$SRC"/manifests/*.json "$TMP/t/"
  # first scale entry 1.0 -> 1.25 or 0.5 -> 0.6 etc: replace the first '"scale":[' number by 1.5/0.6
  python3 - "$TMP/t/$name" <<'PY'
import re, sys
p = sys.argv[1]
s = open(p).read()
m = re.search(r'"scale":\[([0-9.]+)', s)
new = "0.6" if m.group(1) != "0.6" else "0.75"
s = s[:m.start(1)] + new + s[m.end(1):]
open(p, "w").write(s)
PY
  run "$AS" validate "$TMP/t"
  expect_rc 1 "tampered $name"
  expect_out "FAIL $TMP/t/$name: record_hashes" "tampered $name names file and check"
done

# changing the seed field (not a contract) is caught by the manifest hash
cp "$SRC/manifests/seen.json" "$TMP/seen.json"
sed -i 's/"seed": 20260718/"seed": 20260719/' "$TMP/seen.json"
run "$AS" validate "$TMP/seen.json"
expect_rc 1 "tampered seed"
expect_out "FAIL $TMP/seen.json: manifest_hash" "tampered seed check"

# malformed contracts: one line, exit 2, never a crash
body() { echo "{\"frame\":\"base\",\"gripper_inverted\":false,\"lag\":$5,\"permutation\":$1,\"scale\":$3,\"sign\":$2,\"target\":\"delta\"$4}"; }
P='[0,1,2,3,4,5]'; S='[1,1,1,1,1,1]'; K='[1.0,1.0,1.0,1.0,1.0,1.0]'
declare -a CASES=(
  "|not valid JSON"
  "not json|not valid JSON"
  "$(body $P $S '[1.0,1.0,1.0,1.0,1.0,NaN]' '' 0)|not valid JSON"
  "$(body $P $S '[1.0,1.0,1.0,1.0,1.0,-1.0]' '' 0)|scale values must be finite and positive"
  "$(body '[0,1,2,3,4,4]' $S $K '' 0)|permutation must be a bijection"
  "$(body $P $S $K ',"extra":1' 0)|unknown contract fields: extra"
  "$(body $P $S $K '' 1.5)|lag must be an integer"
)
for c in "${CASES[@]}"; do
  input="${c%%|*}"
  msg="${c#*|}"
  printf '%s\n' "$input" > "$TMP/c.json"
  run "$AS" contract hash "$TMP/c.json"
  if [ -z "$input" ]; then expect_rc 2 "empty input"; expect_err "no input" "empty input"; expect_one_line_error "empty"; continue; fi
  expect_rc 2 "bad contract ($msg)"
  expect_err "$msg" "bad contract message"
  expect_one_line_error "bad contract ($msg)"
done

# malformed manifest: exit 2, one line naming the file and field
printf '{"schema_version": "actionshift-manifest/1"}' > "$TMP/bad.json"
run "$AS" validate "$TMP/bad.json"
expect_rc 2 "malformed manifest"
expect_err "$TMP/bad.json: kind: missing field" "malformed manifest names file and field"
expect_one_line_error "malformed manifest"
run "$AS" validate "$TMP/does-not-exist"
expect_rc 2 "missing path"

# decode/encode golden vectors (reference A.2)
U='{"frame":"tool","gripper_inverted":true,"lag":0,"permutation":[1,0,2,4,5,3],"scale":[0.5,2.0,1.5,0.75,1.25,0.6],"sign":[-1,1,-1,1,-1,1],"target":"absolute"}'
run "$AS" contract decode "{\"contract\":$U,\"raw\":[0.1,-0.2,0.3,-0.4,0.5,-0.6,0.7],\"rotation\":[[0,0,1],[1,0,0],[0,1,0]],\"tracked_target\":[0.01,0.02,0.03,0.04,0.05,0.06]}"
expect_rc 0 "decode"
python3 - "$OUT" <<'PY' && ok || bad "decode golden"
import json, sys
o = json.loads(sys.argv[1])
want = [-0.46, 0.08, 0.17, -0.28, 0.325, 0.69, -0.7]
assert all(abs(a - b) < 1e-12 for a, b in zip(o["canonical"], want)), o
PY
run "$AS" contract encode "{\"contract\":$U,\"canonical\":[0.05,-0.02,0.01,0.0,0.03,-0.04,-1.0],\"rotation\":[[0,0,1],[1,0,0],[0,1,0]],\"tracked_target\":[0.01,0.02,0.03,0.04,0.05,0.06]}"
python3 - "$OUT" <<'PY' && ok || bad "encode golden"
import json, sys
o = json.loads(sys.argv[1])
want = [0.02, -0.0, -0.04, 0.0666666666667, 0.1066666666667, -0.016, 1.0]
assert all(abs(a - b) < 1e-12 for a, b in zip(o["raw"], want)), o
PY
# a raw sequence is decoded statefully: identity, absolute, lag 2 (reference A.2)
L='{"frame":"base","gripper_inverted":false,"lag":2,"permutation":[0,1,2,3,4,5],"scale":[1.0,1.0,1.0,1.0,1.0,1.0],"sign":[1,1,1,1,1,1],"target":"absolute"}'
run "$AS" contract decode "{\"contract\":$L,\"raw\":[[0.1,0,0,0,0,0,0.5],[0.2,0,0,0,0,0,0.5],[0.3,0,0,0,0,0,0.5],[0.4,0,0,0,0,0,0.5]]}"
python3 - "$OUT" <<'PY' && ok || bad "stateful decode"
import json, sys
o = json.loads(sys.argv[1])["canonical"]
assert o[0] == [0.0] * 7 and o[1] == [0.0] * 7, o
assert abs(o[2][0] - 0.1) < 1e-12 and abs(o[3][0] - 0.1) < 1e-12 and o[3][6] == 0.5, o
PY
run "$AS" contract decode "{\"contract\":$U,\"raw\":[1,2,3]}"
expect_rc 2 "short raw"
expect_err "raw: must be a list of 7 numbers" "short raw message"
run "$AS" contract decode "{\"contract\":$U,\"raw\":[1,2,3,4,5,6,7],\"rotation\":[[2,0,0],[0,1,0],[0,0,1]]}"
expect_rc 2 "bad rotation"
expect_err "rotation: rotation matrix is not orthonormal" "bad rotation message"

# splits generate reproduces the committed files byte for byte
run "$AS" splits generate --out "$TMP/gen"
expect_rc 0 "splits generate"
diff -r "$TMP/gen" "$SRC/manifests" >/dev/null && ok || bad "generated manifests differ from the committed ones"

# the raw-Bullet limit: the same world stepped with the recorded controller inputs ends in the same state
run "$AS" bench env --task pick_cube --raw-bullet --steps 60 --json
expect_rc 0 "bench env --raw-bullet"
expect_out '"identical":true' "raw-bullet replay is bit-identical"
expect_out '"steps":60,"episodes":2' "raw-bullet steps and episodes"
run "$AS" bench env --task pick_cube --raw-bullet --steps 0
expect_rc 2 "bench env --raw-bullet --steps 0"

# usage errors are exit 2
run "$AS" frobnicate
expect_rc 2 "unknown subcommand"
run "$AS" --help
expect_rc 0 "help"
expect_out "validate" "help lists validate"

finish
