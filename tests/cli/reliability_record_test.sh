#!/usr/bin/env bash
# scripts/reliability_record.py writes a fuzz table and a sanitizer summary between the page's
# markers, leaves the rest of the page alone, and refuses a log without figures (exit 1, one line).
set -uo pipefail
SRC="$1"
TMP=$(mktemp -d); trap 'rm -rf "$TMP"' EXIT
fails=0; ok() { :; }; bad() { echo "FAILED: $*"; fails=$((fails + 1)); }
REC="$SRC/scripts/reliability_record.py"
printf 'before\n<!-- fuzz:begin -->\nold\n<!-- fuzz:end -->\nmiddle\n<!-- sanitize:begin -->\nold\n<!-- sanitize:end -->\nafter\n' > "$TMP/page.md"
export ACTIONSHIFT_RELIABILITY_PAGE="$TMP/page.md"
printf '%-14s %14s %10s %9s\n' target executions exec/s findings contract 1234567 4115 0 urdf 2000 6 1 > "$TMP/fuzz.txt"
python3 "$REC" fuzz "$TMP/fuzz.txt" 300 2> /dev/null || bad "fuzz record failed"
grep -q '^| contract | 1,234,567 | 4115 | 0 |$' "$TMP/page.md" && ok || bad "fuzz row missing"
grep -q 'In all 1,236,567 executions over 2 targets, 1 findings.' "$TMP/page.md" && ok || bad "fuzz total missing"
grep -q '^old$' "$TMP/page.md" && ok || bad "the sanitize block was touched by a fuzz record"
printf '99%% tests passed, 1 tests failed out of 120\n\nTotal Test time (real) = 321.5 sec\n\nThe following tests FAILED:\n\t 17 - sim.robot (Failed)\n' > "$TMP/ctest.log"
python3 "$REC" sanitize "$TMP/ctest.log" 2> /dev/null || bad "sanitize record failed"
grep -q '119/120 tests passed' "$TMP/page.md" && ok || bad "sanitize count missing"
grep -q '`sim.robot`' "$TMP/page.md" && ok || bad "failed test not named"
[ "$(head -1 "$TMP/page.md")" = before ] && [ "$(tail -1 "$TMP/page.md")" = after ] && grep -q '^middle$' "$TMP/page.md" && ok || bad "text outside the markers changed"
echo "nothing here" > "$TMP/empty.log"
err=$(python3 "$REC" sanitize "$TMP/empty.log" 2>&1); rc=$?
[ "$rc" = 1 ] && [ "$(echo "$err" | wc -l)" = 1 ] && echo "$err" | grep -q "no ctest summary" && ok || bad "a log without figures: rc $rc, '$err'"
[ "$fails" = 0 ] && echo "reliability_record: all ok" || exit 1
