#!/usr/bin/env bash
# A user method ranked against the tournament (docs/methods.md), smoke-size: the C++ plug-in example
# (docs/examples/method_plugin) runs on pick_cube/reference_seen with the PPO backbone beside
# entropy_probes, dualabi and fixed_probes; `compare` pairs it with each and `report --leaderboard`
# shows it as one more row.
set -euo pipefail
AS=$1
EXAMPLE=$2
source "$(dirname "$0")/lib.sh"

common=(--task pick_cube --split reference_seen --pool reference9 --backbone ppo --episodes 9 --threads 2 --progress off)
for m in entropy_probes dualabi fixed_probes; do
  run "$AS" run "${common[@]}" --method "$m" --out "$TMP/r"
  expect_rc 0 "run $m"
done
run "$EXAMPLE" "$TMP/r" 9 ppo
expect_rc 0 "the C++ plug-in example"
LABEL='separation_probes{amplitude=0.5,budget=6}'

run "$AS" compare "$TMP/r" --pair "$LABEL vs entropy_probes" --pair "$LABEL vs dualabi" --pair "$LABEL vs fixed_probes"
expect_rc 0 "compare ranks the user method"
printf '%s\n' "$OUT" >"$TMP/cmp.json"
python3 - "$TMP/cmp.json" "$LABEL" <<'PY' && ok || bad "compare: the user method's comparisons"
import json, sys
j, label = json.load(open(sys.argv[1])), sys.argv[2]
cells = {c["method"]: c for c in j["cells"]}
assert set(cells) == {label, "entropy_probes", "dualabi", "fixed_probes"}, set(cells)
assert cells[label]["backbone"] == "ppo" and cells[label]["episodes"] == 9
assert cells[label]["mean_probe_steps"] == 6
assert len(j["comparisons"]) == 3
for k in j["comparisons"]:
    assert k["candidate"] == label and k["pairs"] == 9
    d = k["difference"]
    assert d["lower"] <= d["estimate"] <= d["upper"]
    assert k["promotion"]["verdict"] in ("promote", "reject", "prune", "extend_seeds")
    assert k["paper"] is None  # a user method has no paper number
PY

run "$AS" report "$TMP/r" --leaderboard --out "$TMP/board"
expect_rc 0 "report --leaderboard"
expect_out "4 methods, 1 cells" "leaderboard counts"
grep -qF "| $LABEL | pool | cpp |" "$TMP/board/leaderboard.md" && ok || bad "the user method is a row with its rung and kind"
grep -qF "| **entropy_probes** | pool | built-in |" "$TMP/board/leaderboard.md" && ok || bad "the reference row"
grep -qF "## pick_cube / reference_seen" "$TMP/board/leaderboard.md" && ok || bad "the cell's table"
grep -qE "^\| separation_probes\{amplitude=0.5,budget=6\} \| 0\.[0-9]{3} \[0\.[0-9]{3}, [01]\.[0-9]{3}\] n=9 \| [-+][01]\.[0-9]{3} \[" "$TMP/board/leaderboard.md" \
  && ok || bad "the user method's success interval and paired difference in its cell"
grep -qF "separation_probes{amplitude=0.5,budget=6}</code>" "$TMP/board/leaderboard.html" && ok || bad "the HTML row"
python3 -c "import json,sys; b=json.load(open(sys.argv[1])); assert len(b['board'])==4 and b['reference']=='entropy_probes'" \
  "$TMP/board/leaderboard.json" && ok || bad "leaderboard.json"

# bad input: one line, exit 2
run "$AS" report "$TMP/r" --leaderboard --reference no_such_method --out "$TMP/board2"
expect_rc 2 "unknown reference"
expect_one_line_error "unknown reference"
expect_err "no cell holds 'no_such_method'" "unknown reference names the labels"
run "$AS" report "$TMP/r" "$TMP/r" --out "$TMP/board3"
expect_rc 2 "two directories without --leaderboard"
expect_one_line_error "two directories without --leaderboard"
finish
