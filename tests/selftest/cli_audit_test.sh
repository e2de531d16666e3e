#!/usr/bin/env bash
# actionshift record and audit end to end: a log of reference_seen contract 0 recorded from the
# simulator in every format (1,500 transitions) is audited (MISMATCH against identity naming the contract's routing; no
# MISMATCH against the truth); the learned backbone's log under a tool-frame absolute contract while
# its TCP turns; exit codes 0/1/2/3; bad input is one line naming the file and field.
set -euo pipefail
AS="$1"
T="$(mktemp -d)"
trap 'rm -rf "$T"' EXIT
fail() { echo "FAIL: $*" >&2; exit 1; }

for f in csv jsonl h5; do
  "$AS" record --task pick_cube --split reference_seen --method oracle --backbone expert --seed 20260718 \
    --episodes 60 --contract 0 --out "$T/log.$f" --truth "$T/truth.json" > "$T/rec.$f.json"
  grep -q '"transitions":1500' "$T/rec.$f.json" || fail "record $f: $(cat "$T/rec.$f.json")"
  set +e
  "$AS" audit "$T/log.$f" --task pick_cube --declared identity --json > "$T/a.$f.json"; rc=$?
  set -e
  [ $rc -eq 1 ] || fail "audit $f vs identity: exit $rc (expected 1, MISMATCH)"
  python3 - "$T/a.$f.json" <<'PY'
import json, sys
a = json.load(open(sys.argv[1]))
assert a["status"] == "MISMATCH", a["status"]
got = a["fields"]["permutation"]["identified"].strip("()").split(", ")
truth = ["1", "0", "2", "4", "5", "3"]
assert all(g in ("?", t) for g, t in zip(got, truth)), got          # never a wrong channel
assert sum(g != "?" for g in got) >= 2, got                         # 1,500 transitions of the expert decide some
assert a["fields"]["gripper_inverted"]["identified"] == "inverted (+1 closes)"
assert any(s in a["reason"] for s in ("raw channel 1, declared 0", "raw channel 0, declared 1", "wired (1, 0, 2, 4, 5, 3)")), a["reason"]
PY
  set +e
  "$AS" audit "$T/log.$f" --task pick_cube --declared "$T/truth.json" > "$T/t.$f.txt"; rc=$?
  set -e
  [ $rc -eq 0 ] || [ $rc -eq 3 ] || fail "audit $f vs the truth: exit $rc (expected PASS or INCONCLUSIVE)"
done
# the HDF5 file's sidecar declares pd_ee_delta_pose's conventions
grep -q "Declared: control_mode pd_ee_delta_pose" <("$AS" audit "$T/log.h5" --task pick_cube || true) || fail "h5 declaration"
"$AS" record --task pick_cube --split reference_seen --method oracle --backbone expert --episodes 4 --contract 0 \
  --out "$T/robo.h5" --layout robomimic > /dev/null
set +e
"$AS" audit "$T/robo.h5" > "$T/robo.txt"; rc=$?
set -e
[ $rc -le 3 ] && [ $rc -ne 2 ] || fail "robomimic audit: exit $rc"
grep -q "Declared: robomimic env_args controller OSC_POSE; response model: fitted from the log" "$T/robo.txt" || fail "robomimic declaration: $(tail -1 "$T/robo.txt")"

# the learned backbone under a tool-frame absolute contract (reference_unseen_composition c0), the
# audit benchmark's log whose TCP turns furthest: reading both targets of a step under the current
# rotation named it base frame with four signs flipped (a wrong MISMATCH against the truth)
"$AS" record --task pick_cube --split reference_unseen_composition --method oracle --backbone ppo --seed 20260801 \
  --episodes 20 --contract 0 --out "$T/turn.csv" --truth "$T/turn.truth.json" > /dev/null
for decl in "$T/turn.truth.json" identity; do
  set +e
  "$AS" audit "$T/turn.csv" --task pick_cube --declared "$decl" --json > "$T/turn.json"; rc=$?
  set -e
  [ $rc -ne 2 ] || fail "audit of the turning log failed"
  python3 - "$T/turn.json" "$decl" <<'PY' || fail "the turning log against $decl: $(head -c 600 "$T/turn.json")"
import json, sys
a = json.load(open(sys.argv[1]))
truth = sys.argv[2] != "identity"
assert a["fields"]["frame"]["identified"] == "tool", a["fields"]["frame"]
if truth:
    assert a["status"] != "MISMATCH", a["reason"]
else:
    assert a["status"] == "MISMATCH", a["status"]
    got = a["fields"]["sign"]["identified"].strip("()").split(", ")
    assert all(g in ("?", t) for g, t in zip(got, ["-1", "1", "-1", "1", "-1", "1"])), got
PY
done

# bad input: exit 2, one line, the file and the field named
printf 'action_0,action_1\n1,2\n' > "$T/bad.csv"
set +e
"$AS" audit "$T/bad.csv" 2> "$T/err"; rc=$?
set -e
[ $rc -eq 2 ] || fail "bad csv: exit $rc"
[ "$(wc -l < "$T/err")" -eq 1 ] || fail "bad csv: not one line"
grep -q "^actionshift: error: $T/bad.csv: header: missing column action_2$" "$T/err" || fail "bad csv: $(cat "$T/err")"
sed 's/^0,3,\([^,]*\),/0,3,nan,/' "$T/log.csv" > "$T/nan.csv"
set +e
"$AS" audit "$T/nan.csv" 2> "$T/err"; rc=$?
set -e
[ $rc -eq 2 ] && grep -q "nan.csv: line 5: column action_0: not a finite number ('nan')" "$T/err" || fail "nan: $(cat "$T/err")"
set +e
"$AS" audit "$T/log.csv" --task no_such_task 2> "$T/err"; rc=$?
set -e
[ $rc -eq 2 ] || fail "unknown task: exit $rc"
echo "cli.audit: ok"
