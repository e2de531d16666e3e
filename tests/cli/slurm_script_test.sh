#!/usr/bin/env bash
# `actionshift plan --slurm` without a cluster: absolute paths (the executable defaults to this
# binary, a relative one is made absolute), chunked arrays, the merge and submit scripts, and bad
# --time / --mem / --executable as one-line errors with exit 2.
# usage: slurm_script_test.sh ACTIONSHIFT SOURCE_DIR
set -euo pipefail
AS=$1
SRC=$2
source "$SRC/tests/cli/lib.sh"
ASABS=$(readlink -f "$AS")

cat > "$TMP/exp.yaml" <<'YAML'
name: tiny
tasks: [pick_cube]
splits: [seen]
methods: [oracle, no_adapt]
seeds: [1, 2, 3]
episodes: 2
backbone: expert
YAML

# default executable: this binary, absolute; the plan and output are absolute even when given relative
mkdir -p "$TMP/cwd"
(cd "$TMP/cwd" && "$AS" plan --experiment ../exp.yaml --out rel --slurm --max-array-size 4 --time 10) >"$TMP/out" 2>"$TMP/err" && ok || bad "plan --slurm: $(cat "$TMP/err")"
S="$TMP/cwd/rel/tiny.sbatch"
[ -f "$S" ] && [ -f "$TMP/cwd/rel/tiny.merge.sbatch" ] && [ -f "$TMP/cwd/rel/tiny.submit.sh" ] && ok || bad "three scripts written"
grep -qF "exec '$ASABS' run --plan '$TMP/cwd/rel/tiny.plan.json'" "$S" && ok || bad "absolute executable and plan: $(grep exec "$S")"
grep -qF -- "--out '$TMP/cwd/rel'" "$S" && ok || bad "absolute out dir"
grep -qF "#SBATCH --output=$TMP/cwd/rel/slurm-%A_%a.log" "$S" && ok || bad "absolute log path"
grep -q "#SBATCH --array" "$S" && bad "6 jobs under MaxArraySize 4 need two arrays, not one directive" || ok
grep -qF "2 arrays under MaxArraySize 4" "$TMP/out" && ok || bad "plan output names the chunks: $(cat "$TMP/out")"
SUB="$TMP/cwd/rel/tiny.submit.sh"
grep -qF -- "--array=0-3 --export=ALL,ACTIONSHIFT_JOB_OFFSET=0 " "$SUB" && ok || bad "first chunk"
grep -qF -- "--array=0-1 --export=ALL,ACTIONSHIFT_JOB_OFFSET=4 " "$SUB" && ok || bad "second chunk"
grep -qF -- "--dependency=afterok:" "$SUB" && ok || bad "merge depends on the arrays"
grep -qF "'$ASABS' gate1 --results '$TMP/cwd/rel'" "$TMP/cwd/rel/tiny.merge.sbatch" && ok || bad "merge runs gate1"
grep -qF "'$ASABS' summarize '$TMP/cwd/rel'" "$TMP/cwd/rel/tiny.merge.sbatch" && ok || bad "merge runs summarize"
bash -n "$SUB" && bash -n "$S" && bash -n "$TMP/cwd/rel/tiny.merge.sbatch" && ok || bad "scripts are valid bash"

# a relative --executable is made absolute; a single chunk carries its own --array directive
(cd "$(dirname "$ASABS")" && "$AS" plan --experiment "$TMP/exp.yaml" --out "$TMP/one" --slurm --max-array-size 1001 \
  --executable "./$(basename "$ASABS")" --mem 2G) >/dev/null 2>"$TMP/err" && ok || bad "relative --executable: $(cat "$TMP/err")"
grep -qF "exec '$ASABS' run" "$TMP/one/tiny.sbatch" && ok || bad "relative executable made absolute: $(grep exec "$TMP/one/tiny.sbatch")"
grep -qF "#SBATCH --array=0-5" "$TMP/one/tiny.sbatch" && ok || bad "one chunk: --array directive"
grep -qF "#SBATCH --mem=2G" "$TMP/one/tiny.sbatch" && ok || bad "--mem directive"

# bad input: one line, exit 2
run "$AS" plan --experiment "$TMP/exp.yaml" --out "$TMP/bad" --slurm --time 2h
expect_rc 2 "bad --time"
expect_one_line_error "bad --time"
expect_err "--time: 2h: not a Slurm time" "bad --time message"
run "$AS" plan --experiment "$TMP/exp.yaml" --out "$TMP/bad" --slurm --mem 4GB
expect_rc 2 "bad --mem"
expect_one_line_error "bad --mem"
run "$AS" plan --experiment "$TMP/exp.yaml" --out "$TMP/bad" --slurm --max-array-size 0
expect_rc 2 "--max-array-size 0"
expect_err "--max-array-size: must be at least 1" "--max-array-size 0 message"
run "$AS" plan --experiment "$TMP/exp.yaml" --out "$TMP/bad" --slurm --executable no-such-actionshift-binary
expect_rc 2 "missing --executable"
expect_err "not found on PATH" "missing --executable message"
run "$AS" plan --experiment "$TMP/exp.yaml" --out "$TMP/bad" --slurm --executable "$TMP/exp.yaml"
expect_rc 2 "non-executable --executable"
# a line break in a path would start a line of its own after "#SBATCH --output=" (run by the shell): refused
run "$AS" plan --experiment "$TMP/exp.yaml" --out "$TMP/bad
touch $TMP/injected" --slurm
expect_rc 2 "--out with a line break"
expect_one_line_error "--out with a line break"
expect_err "contains a control character" "--out with a line break message"
# none of the refused Slurm options left a file behind (the plan is checked before it is written)
[ ! -e "$TMP/bad" ] && ok || bad "a refused Slurm option left files: $(ls -R "$TMP/bad" 2>&1)"
finish
