#!/usr/bin/env bash
# actionshift bench adapt: JSON fields, probe counts that follow the configuration, bad input exits 2
set -euo pipefail
AS="$1"
source "$(dirname "$0")/lib.sh"
json_field() { python3 -c "import json,sys; print(json.loads(sys.argv[1])[sys.argv[2]])" "$OUT" "$1"; }

run "$AS" bench adapt --method entropy_probes --pool reference9 --episodes 2 --steps 10 --repetitions 1 --json
expect_rc 0 "entropy json"
[ "$(json_field hypotheses)" = 9 ] && ok || bad "entropy: hypotheses $(json_field hypotheses)"
[ "$(json_field probes_per_episode)" = 6.0 ] && ok || bad "entropy: budget 6 gives 6 probes, got $(json_field probes_per_episode)"
python3 -c "import json,sys; r=json.loads(sys.argv[1]); sys.exit(0 if r['first_select_us'] > 0 and r['probe_encode_us'] > 0 and r['observe_us'] > 0 and r['step_us'] > 0 and r['params']['budget'] == 6 and r['pool'] == 'reference9' else 1)" "$OUT" \
  && ok || bad "entropy: timings and resolved params ($OUT)"

run "$AS" bench adapt --method entropy_probes --pool reference9 --params '{"budget": 2}' --episodes 2 --steps 10 --repetitions 1 --json
expect_rc 0 "budget 2"
[ "$(json_field probes_per_episode)" = 2.0 ] && ok || bad "budget 2 gives 2 probes, got $(json_field probes_per_episode)"

run "$AS" bench adapt --method dualabi --pool full --episodes 1 --steps 4 --repetitions 1 --json
expect_rc 0 "dualabi full"
[ "$(json_field hypotheses)" = 180 ] && ok || bad "dualabi full: hypotheses $(json_field hypotheses)"

run "$AS" bench adapt --method no_adapt --episodes 1 --steps 5 --repetitions 1
expect_rc 0 "no_adapt text"
expect_out "per control step (encode + observe)" "no_adapt text"
expect_out "no pool (0 hypotheses)" "no_adapt text"

run "$AS" bench adapt --method nope --pool reference9
expect_rc 2 "unknown method"
expect_one_line_error "unknown method"
expect_err "unknown method" "unknown method"
run "$AS" bench adapt --method dualabi --pool reference9 --params '{"tau": -1}'
expect_rc 2 "bad tau"
expect_one_line_error "bad tau"
run "$AS" bench adapt --method dualabi --pool reference9 --params '{"tau": 1'
expect_rc 2 "params not JSON"
expect_one_line_error "params not JSON"
expect_err "--params" "params not JSON"
run "$AS" bench adapt --method entropy_probes --pool no_such_pool
expect_rc 2 "unknown pool"
expect_one_line_error "unknown pool"
run "$AS" bench adapt --method entropy_probes --pool seen
expect_rc 2 "split as pool"
expect_err "not a pool" "split as pool"
run "$AS" bench adapt --method entropy_probes --task no_such_task
expect_rc 2 "unknown task"
expect_one_line_error "unknown task"
for opt in episodes steps repetitions; do
  run "$AS" bench adapt --method entropy_probes --$opt 0
  expect_rc 2 "zero $opt"
  expect_one_line_error "zero $opt"
  expect_err "$opt: must be at least 1" "zero $opt names the option"
done
finish
