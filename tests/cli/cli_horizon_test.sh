#!/usr/bin/env bash
# --horizon (run, gate0) and the experiment key `horizon`: bad values exit 2 with one line; 0 (the default) is
# the task's horizon and leaves job ids and records alone; another horizon is another job whose episodes run
# exactly that many control steps; a plan carries it into every job. Smoke-size.
set -euo pipefail
AS=$1
source "$(dirname "$0")/lib.sh"

common=(--task push_cube --split reference_seen --method oracle --episodes 2 --threads 1 --progress off)
for v in -1 10001 abc 2.5; do
  run "$AS" run "${common[@]}" --horizon "$v" --out "$TMP/bad"
  expect_rc 2 "run --horizon $v"
  expect_one_line_error "run --horizon $v"
  run "$AS" gate0 --task push_cube --episodes 1 --horizon "$v"
  expect_rc 2 "gate0 --horizon $v"
  expect_one_line_error "gate0 --horizon $v"
done
[ ! -e "$TMP/bad" ] || [ -z "$(ls -A "$TMP/bad")" ] && ok || bad "a refused --horizon wrote results"

# the task's horizon: --horizon 0 is the same job, byte for byte, as no option; every episode runs 50 steps
run "$AS" run "${common[@]}" --out "$TMP/task"
expect_rc 0 "run at the task's horizon"
run "$AS" run "${common[@]}" --horizon 0 --out "$TMP/zero"
expect_rc 0 "run --horizon 0"
task=$(cd "$TMP/task" && ls *.jsonl)
zero=$(cd "$TMP/zero" && ls *.jsonl)
[ "$task" = "$zero" ] && ok || bad "--horizon 0 changed the job id ($task vs $zero)"
cmp -s "$TMP/task/$task" "$TMP/zero/$zero" && ok || bad "--horizon 0 changed the records"
grep -q horizon "$TMP/task/${task%.jsonl}.summary.json" && bad "a job at the task's horizon names one" || ok
[ "$(grep -c '"steps":50,' "$TMP/task/$task")" = 2 ] && ok || bad "push_cube episodes did not run 50 steps"

# another horizon: another job, episodes of exactly that many steps, the spec names it
run "$AS" run "${common[@]}" --horizon 7 --out "$TMP/seven"
expect_rc 0 "run --horizon 7"
seven=$(cd "$TMP/seven" && ls *.jsonl)
[ "$seven" != "$task" ] && ok || bad "--horizon 7 kept the task-horizon job id"
[ "$(grep -c '"steps":7,' "$TMP/seven/$seven")" = 2 ] && ok || bad "--horizon 7 episodes did not run 7 steps"
grep -Eq '"horizon": ?7' "$TMP/seven/${seven%.jsonl}.summary.json" && ok || bad "the job spec lacks horizon 7"

# an experiment's `horizon` reaches every job of its plan, with the ids `run --horizon` gives
cat > "$TMP/h.yaml" <<'YAML'
name: horizon_smoke
tasks: [push_cube]
splits: [reference_seen]
methods: [oracle]
seeds: [20260718]
episodes: 2
backbone: expert
horizon: 7
YAML
run "$AS" plan --experiment "$TMP/h.yaml" --out "$TMP/plan"
expect_rc 0 "plan with horizon"
grep -q "${seven%.jsonl}" "$TMP/plan/horizon_smoke.plan.json" && ok || bad "the plan's job is not run --horizon 7's job"
for v in -3 x 10001; do
  sed "s/^horizon: .*/horizon: $v/" "$TMP/h.yaml" > "$TMP/bad.yaml"
  run "$AS" plan --experiment "$TMP/bad.yaml" --out "$TMP/badplan"
  expect_rc 2 "plan with horizon: $v"
  expect_one_line_error "plan with horizon: $v"
  expect_err "bad.yaml:8: horizon:" "plan with horizon: $v names the file, line and key"
done

# gate0 records a horizon it was given, and only then
run "$AS" gate0 --task push_cube --episodes 1 --horizon 3 --json --progress off
grep -Eq '"horizon": 3' <<<"$OUT" && ok || bad "gate0 --horizon 3 does not record it"
grep -q "competence: success Wilson lower bound 0.0000" <<<"$OUT" && ok || bad "3 steps cannot push the cube, yet gate0 saw success"
finish
