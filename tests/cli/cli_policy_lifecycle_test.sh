#!/usr/bin/env bash
# The lifecycle of an external policy's processes around `actionshift run`: SIGTERM reaches a policy
# that blocks in a step at once (not after --step-timeout), a second SIGTERM or a SIGKILL of the
# runner does not leave the policy's process group running, and a child that the policy moved to its own session
# (setsid) does not outlive a normal run. These cases run unsandboxed (--sandbox off: they read the
# policy's pids, which a sandbox's PID namespace would renumber); the last runs sandboxed. Every check
# has a bound, so a regression fails instead of hanging; every process the policy starts is killed at the end whatever happens.
set -euo pipefail
AS="$1"
SRC="$2"
source "$(dirname "$0")/lib.sh"

# The policy: records its pid/process group and starts a `sleep` in its group (and, when the flag
# file setsid exists, a `setsid sleep` in a session of its own); answers every step with zeros, except
# that when the flag file `block` holds N it blocks forever (sleep) in the first step after N resets.
cat > "$TMP/policy.py" <<'PY'
import json, os, subprocess, sys, time
state = sys.argv[1]
with open(f"{state}/policy.pid", "w") as f:
    f.write(f"{os.getpid()} {os.getpgrp()}\n")
# a sandboxed run's pids are its PID namespace's: such a run names its sleeps by a unique duration instead
tag = open(f"{state}/tag").read().strip() if os.path.exists(f"{state}/tag") else "1000"
member = subprocess.Popen(["sleep", tag])
with open(f"{state}/member.pid", "w") as f:
    f.write(f"{member.pid}\n")
if os.path.exists(f"{state}/setsid"):
    escaped = subprocess.Popen(["setsid", "sleep", tag])
    with open(f"{state}/escaped.pid", "w") as f:
        f.write(f"{escaped.pid}\n")
block_after = None
if os.path.exists(f"{state}/block"):
    block_after = int(open(f"{state}/block").read())
resets = 0
for line in sys.stdin:
    kind = json.loads(line).get("type")
    if kind == "hello":
        print('{"type":"ready"}', flush=True)
    elif kind == "reset":
        resets += 1
    elif kind == "step":
        if block_after is not None and resets > block_after:
            open(f"{state}/blocked", "w").close()
            time.sleep(1000)
        print('{"action":[0,0,0,0,0,0,0]}', flush=True)
PY

# alive PID: the process exists and is not a zombie (whoever reaps orphans here may not)
alive() { local s; s=$(ps -o stat= -p "$1" 2>/dev/null || true); [ -n "$s" ] && [[ "$s" != Z* ]]; }
# group_alive PGID: some process of the group exists and is not a zombie
group_alive() { ps -e -o pgid=,stat= | awk -v g="$1" '$1 == g && $2 !~ /^Z/ { found = 1 } END { exit !found }'; }
# every process a policy of this test started, killed whatever the outcome (never a broad match)
cleanup_state() {
  local d=$1 p
  for f in "$d/policy.pid" "$d/member.pid" "$d/escaped.pid"; do
    [ -f "$f" ] || continue
    for p in $(cat "$f"); do kill -KILL "$p" 2>/dev/null || true; done
  done
}
STATES=()
trap 'for d in "${STATES[@]}"; do cleanup_state "$d"; done; rm -rf "$TMP"' EXIT
# wait_for FILE SECONDS
wait_for() {
  local i
  for ((i = 0; i < $2 * 20; ++i)); do
    [ -e "$1" ] && return 0
    sleep 0.05
  done
  return 1
}
now_ms() { date +%s%3N; }
# start_run NAME EPISODES: the runner in the background (RUN_PID), its policy state in $TMP/NAME
start_run() {
  local st="$TMP/$1"
  mkdir -p "$st"
  STATES+=("$st")
  "$AS" run --task pick_cube --split reference_seen --method no_adapt --episodes "$2" --threads 1 \
    --backbone "external:python3 $TMP/policy.py $TMP/state" --step-timeout 30 --out "$TMP/out_$1" --progress off \
    --sandbox "${SANDBOX:-off}" >"$st/run.out" 2>"$st/run.err" &
  RUN_PID=$!
}
# the policy command names $TMP/state (one job id for all runs): point it at this run's state
use_state() { rm -f "$TMP/state"; ln -s "$TMP/$1" "$TMP/state"; }
# wait_exit PID SECONDS: sets RC (124 if it did not exit in time)
wait_exit() {
  local i
  for ((i = 0; i < $2 * 20; ++i)); do
    if ! kill -0 "$1" 2>/dev/null; then
      set +e
      wait "$1"
      RC=$?
      set -e
      return 0
    fi
    sleep 0.05
  done
  RC=124
}

# ---- SIGTERM while the policy blocks in a step: the runner stops at once (not after the 30 s step
# timeout), kills the policy's process group, keeps the records already written and resumes
mkdir -p "$TMP/term"
echo 2 > "$TMP/term/block"
use_state term
start_run term 6
if wait_for "$TMP/term/blocked" 120; then
  ok
  sleep 0.3  # the two finished episodes reach the JSONL
  t0=$(now_ms)
  kill -TERM "$RUN_PID"
  wait_exit "$RUN_PID" 40
  ms=$(($(now_ms) - t0))
  echo "SIGTERM to exit: $ms ms (step timeout 30 s)"
  [ "$RC" = 130 ] && ok || bad "SIGTERM: exit $RC, expected 130 ($(cat "$TMP/term/run.err"))"
  [ "$ms" -lt 3000 ] && ok || bad "SIGTERM: the runner took $ms ms to exit (a blocked policy must not delay it)"
  read -r ppid pgid < "$TMP/term/policy.pid"
  sleep 0.5
  ! alive "$ppid" && ok || bad "SIGTERM: the policy process $ppid survived the runner"
  ! group_alive "$pgid" && ok || bad "SIGTERM: the policy's process group $pgid survived the runner"
  lines=$(cat "$TMP/out_term"/*.jsonl | wc -l)
  [ "$lines" = 2 ] && ok || bad "SIGTERM: $lines records written, expected the 2 finished before the policy blocked"
  cp "$TMP/out_term"/*.jsonl "$TMP/term/before.jsonl"
  grep -qF "interrupted after 2 of 6 episodes" "$TMP/out_term"/*.summary.json && ok \
    || bad "SIGTERM: the summary does not say where the job stopped"
  # resume with a policy that answers: the first records are untouched, the job completes
  rm -f "$TMP/term/block" "$TMP/term/blocked"
  run timeout 300 "$AS" run --task pick_cube --split reference_seen --method no_adapt --episodes 6 --threads 1 \
    --backbone "external:python3 $TMP/policy.py $TMP/state" --step-timeout 30 --out "$TMP/out_term" --progress off \
    --sandbox off
  expect_rc 0 "resume after SIGTERM"
  # the policy's `sleep` died with its group: it is no leftover
  ! grep -qF "left behind" <<<"$ERR" && ok || bad "resume after SIGTERM: a member of the policy's group counted as a leftover: $ERR"
  [ "$(cat "$TMP/out_term"/*.jsonl | wc -l)" = 6 ] && ok || bad "resume after SIGTERM: not 6 records"
  head -n 2 "$TMP/out_term"/*.jsonl | cmp -s - "$TMP/term/before.jsonl" && ok \
    || bad "resume after SIGTERM: the records written before the signal changed"
else
  bad "SIGTERM: the policy never blocked ($(cat "$TMP/term/run.err"))"
fi
cleanup_state "$TMP/term"

# ---- two SIGTERMs in a row: the second ends the runner at once; the policy's group goes with it
mkdir -p "$TMP/term2"
echo 0 > "$TMP/term2/block"
use_state term2
start_run term2 2
if wait_for "$TMP/term2/blocked" 120; then
  ok
  t0=$(now_ms)
  kill -TERM "$RUN_PID"
  sleep 0.05  # two signals sent at once would arrive as one
  kill -TERM "$RUN_PID" 2>/dev/null || true
  wait_exit "$RUN_PID" 40
  ms=$(($(now_ms) - t0))
  echo "two SIGTERMs to exit: $ms ms (exit $RC)"
  [ "$RC" = 130 ] || [ "$RC" = 143 ] && ok || bad "two SIGTERMs: exit $RC, expected 130 or 143"
  [ "$ms" -lt 3000 ] && ok || bad "two SIGTERMs: the runner took $ms ms to exit"
  read -r ppid pgid < "$TMP/term2/policy.pid"
  gone=0
  for _ in $(seq 1 60); do
    if ! alive "$ppid" && ! group_alive "$pgid"; then gone=1; break; fi
    sleep 0.05
  done
  [ "$gone" = 1 ] && ok || bad "two SIGTERMs: the policy ($ppid) or its process group ($pgid) survived the runner"
else
  bad "two SIGTERMs: the policy never blocked ($(cat "$TMP/term2/run.err"))"
fi
cleanup_state "$TMP/term2"

# ---- SIGKILL of the runner: the policy's group dies with it (PR_SET_PDEATHSIG reaches the group's
# leader, a wrapper shell that then kills its group: the policy and the `sleep` it started)
mkdir -p "$TMP/kill"
echo 0 > "$TMP/kill/block"
use_state kill
start_run kill 2
if wait_for "$TMP/kill/blocked" 120; then
  ok
  t0=$(now_ms)
  kill -KILL "$RUN_PID"
  wait_exit "$RUN_PID" 10
  read -r ppid pgid < "$TMP/kill/policy.pid"
  member=$(cat "$TMP/kill/member.pid")
  gone=0
  for _ in $(seq 1 100); do
    if ! alive "$ppid" && ! alive "$member" && ! group_alive "$pgid"; then gone=1; break; fi
    sleep 0.05
  done
  echo "SIGKILL of the runner to the policy group gone: $(($(now_ms) - t0)) ms (gone: $gone)"
  [ "$gone" = 1 ] && ok || bad "SIGKILL of the runner: the policy $ppid or its group $pgid is still running 5 s later"
else
  bad "SIGKILL: the policy never blocked ($(cat "$TMP/kill/run.err"))"
fi
cleanup_state "$TMP/kill"

# ---- a child that left the policy's process group with setsid does not outlive a normal run: the
# runner is its subreaper while it runs and kills what is left of the policy's descendants at the end
mkdir -p "$TMP/escape"
touch "$TMP/escape/setsid"
use_state escape
run timeout 300 "$AS" run --task pick_cube --split reference_seen --method no_adapt --episodes 1 --threads 1 \
  --backbone "external:python3 $TMP/policy.py $TMP/state" --step-timeout 30 --out "$TMP/out_escape" --progress off \
  --sandbox off
expect_rc 0 "a policy with a setsid child"
if [ -f "$TMP/escape/escaped.pid" ]; then
  esc=$(cat "$TMP/escape/escaped.pid")
  member=$(cat "$TMP/escape/member.pid")
  ! alive "$member" && ok || bad "normal run: the policy's child $member (its group) survived"
  ! alive "$esc" && ok || bad "normal run: the policy's setsid child $esc survived the run"
  expect_err "killed 1 process an external policy left behind" "a policy with a setsid child: the runner says it killed it"
else
  bad "the policy did not start its setsid child"
fi
cleanup_state "$TMP/escape"

# ---- sandboxed (--sandbox on): a SIGKILL of the runner ends the whole PID namespace, the policy, its
# group's `sleep` and its setsid child with it. Inside the namespace pids mean nothing out here, so the
# processes are found by the unique duration of their sleeps and the policy's unique path.
if unshare -Urmpf --mount-proc true 2>/dev/null; then
  tag="1000.$RANDOM$RANDOM"
  mkdir -p "$TMP/boxed"
  echo 0 > "$TMP/boxed/block"
  echo "$tag" > "$TMP/boxed/tag"
  touch "$TMP/boxed/setsid"
  trap 'pkill -KILL -f "sleep $tag" 2>/dev/null || true; for d in "${STATES[@]}"; do cleanup_state "$d"; done; rm -rf "$TMP"' EXIT
  use_state boxed
  mkdir -p "$TMP/boxed_run"
  st="$TMP/boxed_run"
  "$AS" run --task pick_cube --split reference_seen --method no_adapt --episodes 2 --threads 1 \
    --backbone "external:python3 $TMP/policy.py $TMP/state" --step-timeout 30 --out "$TMP/out_boxed" --progress off \
    --sandbox on >"$st/run.out" 2>"$st/run.err" &
  RUN_PID=$!
  if wait_for "$TMP/boxed/blocked" 120; then
    pgrep -f "sleep $tag" >/dev/null && ok || bad "sandboxed: the policy's sleeps are not visible from outside"
    [ "$(pgrep -fc "sleep $tag")" = 2 ] && ok || bad "sandboxed: expected the policy's two sleeps"
    t0=$(now_ms)
    kill -KILL "$RUN_PID"
    wait_exit "$RUN_PID" 10
    gone=0
    for _ in $(seq 1 100); do
      if ! pgrep -f "sleep $tag" >/dev/null && ! pgrep -f "$TMP/policy.py" >/dev/null; then gone=1; break; fi
      sleep 0.05
    done
    echo "sandboxed: SIGKILL of the runner to every policy process gone (setsid child included): $(($(now_ms) - t0)) ms"
    [ "$gone" = 1 ] && ok || bad "sandboxed: SIGKILL of the runner left the policy or its sleeps running"
  else
    bad "sandboxed: the policy never blocked ($(cat "$st/run.err"))"
  fi
  pkill -KILL -f "sleep $tag" 2>/dev/null || true
else
  echo "SKIPPED: this machine makes no user/mount/PID namespaces: the sandboxed case did not run"
fi

finish
