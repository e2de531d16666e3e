#!/usr/bin/env bash
# Every committed experiment (configs/experiments/**/*.yaml) plans cleanly with this build (backbone
# weights, pools and splits resolve), and where its header comment states "= N jobs" the plan has N.
# usage: experiments_plan_test.sh ACTIONSHIFT_BINARY SOURCE_DIR
set -u
AS=${1:?usage: experiments_plan_test.sh ACTIONSHIFT_BINARY SOURCE_DIR}
SRC=${2:?}
TMP=$(mktemp -d)
trap 'rm -rf "$TMP"' EXIT
cd "$SRC" || exit 1  # an experiment names weight files relative to the repository root (mlp:configs/...)
fail=0
count=0
while IFS= read -r f; do
  name=$(basename "$f" .yaml)
  out="$TMP/$(echo "$f" | tr '/' '_')"
  if ! "$AS" plan --experiment "$f" --out "$out" > "$out.log" 2>&1; then
    echo "FAILED: $f does not plan: $(tail -1 "$out.log")" >&2
    fail=1
    continue
  fi
  count=$((count + 1))
  planned=$(grep -o "plan $name: [0-9]* jobs" "$out.log" | grep -o '[0-9]* jobs' | grep -o '[0-9]*')
  stated=$(grep -E '^#' "$f" | grep -oE '= *[0-9,]+ jobs' | head -1 | grep -oE '[0-9,]+' | tr -d ,)
  if [ -n "$stated" ] && [ "$stated" != "$planned" ]; then
    echo "FAILED: $f: its comment says $stated jobs, the plan has $planned" >&2
    fail=1
  fi
done < <(find "$SRC/configs/experiments" -name '*.yaml' | sort)
[ "$count" -ge 10 ] || { echo "FAILED: only $count experiments planned" >&2; fail=1; }
[ "$fail" = 0 ] && echo "$count experiments plan cleanly"
exit "$fail"
