#!/usr/bin/env bash
# A real single-node Slurm cluster (Debian's slurmctld, slurmd and munged, started without systemd in
# this test's own temporary directory, on free ports of 127.0.0.1, MaxArraySize 4): `plan --slurm`
# for a six-job experiment gives two arrays and a merge job; `bash <name>.submit.sh`, run from another
# directory, submits them; the merged summary and Gate 1 verdict must equal a local run's.
# Exit 77 (skipped, with the reason) only when the Slurm daemons are not installed or cannot start.
# usage: slurm_cluster_test.sh ACTIONSHIFT SOURCE_DIR
set -uo pipefail
AS=$(readlink -f "$1")
SRC=$2
SKIP=77
skip() { echo "SKIPPED: $*"; exit "$SKIP"; }

for b in slurmctld slurmd munged; do
  command -v "$b" >/dev/null || [ -x "/usr/sbin/$b" ] || skip "$b is not installed (scripts/setup installs slurmctld, slurmd, munge)"
done
for b in sbatch squeue scontrol python3; do command -v "$b" >/dev/null || skip "$b is not installed"; done
[ "$(id -u)" = 0 ] || skip "a single-node Slurm needs root to start slurmd (this test runs as $(id -un))"
PATH="$PATH:/usr/sbin"

T=$(mktemp -d /tmp/actionshift-slurm.XXXXXX)
chmod 755 "$T"
cleanup() {
  SLURM_CONF="$T/slurm.conf" timeout 10 scontrol shutdown >/dev/null 2>&1
  for i in $(seq 1 50); do
    alive=0
    for p in slurmctld slurmd; do [ -f "$T/$p.pid" ] && kill -0 "$(cat "$T/$p.pid")" 2>/dev/null && alive=1; done
    [ "$alive" = 0 ] && break
    sleep 0.1
  done
  for p in slurmctld slurmd; do [ -f "$T/$p.pid" ] && kill -9 "$(cat "$T/$p.pid")" 2>/dev/null; done
  [ -S "$T/munge.sock" ] && munged -s -S "$T/munge.sock" >/dev/null 2>&1
  [ -f "$T/munged.pid" ] && kill "$(cat "$T/munged.pid")" 2>/dev/null
  rm -rf "$T"
}
trap cleanup EXIT
mkdir -p "$T/state" "$T/spool" "$T/log" "$T/results" "$T/local" "$T/elsewhere"

# ---- munge
dd if=/dev/urandom of="$T/munge.key" bs=1024 count=1 2>/dev/null
chmod 400 "$T/munge.key"
munged -f --socket="$T/munge.sock" --key-file="$T/munge.key" --log-file="$T/log/munged.log" \
  --pid-file="$T/munged.pid" --seed-file="$T/munged.seed" >/dev/null 2>&1 || skip "munged did not start: $(tail -3 "$T/log/munged.log" 2>/dev/null)"

# ---- slurm.conf on two free ports
read -r P1 P2 < <(python3 -c '
import socket
s=[socket.socket() for _ in range(2)]
for x in s: x.bind(("127.0.0.1",0))
print(*[x.getsockname()[1] for x in s])')
H=$(hostname)
cat > "$T/slurm.conf" <<CONF
ClusterName=astest
SlurmctldHost=$H(127.0.0.1)
SlurmctldPort=$P1
SlurmdPort=$P2
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
AuthInfo=socket=$T/munge.sock
CredType=cred/munge
StateSaveLocation=$T/state
SlurmdSpoolDir=$T/spool
SlurmctldPidFile=$T/slurmctld.pid
SlurmdPidFile=$T/slurmd.pid
SlurmctldLogFile=$T/log/slurmctld.log
SlurmdLogFile=$T/log/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
SwitchType=switch/none
MpiDefault=none
SchedulerType=sched/builtin
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
ReturnToService=2
SlurmdParameters=config_overrides
MaxArraySize=4
MinJobAge=300
PlugStackConfig=/dev/null
NodeName=asnode NodeAddr=127.0.0.1 NodeHostname=$H CPUs=2 RealMemory=500 State=UNKNOWN
PartitionName=astest Nodes=asnode Default=YES MaxTime=INFINITE State=UP
CONF
export SLURM_CONF="$T/slurm.conf"
slurmctld -f "$SLURM_CONF" >/dev/null 2>&1 || skip "slurmctld did not start: $(tail -3 "$T/log/slurmctld.log" 2>/dev/null)"
slurmd -f "$SLURM_CONF" -N asnode >/dev/null 2>&1 || skip "slurmd did not start: $(tail -3 "$T/log/slurmd.log" 2>/dev/null)"
up=0
for i in $(seq 1 100); do
  state=$(sinfo -h -n asnode -o %t 2>/dev/null || true)
  [ "$state" = idle ] && { up=1; break; }
  sleep 0.2
done
[ "$up" = 1 ] || skip "the node did not come up (state '$state'): $(tail -3 "$T/log/slurmd.log" 2>/dev/null)"

# ---- from here on a failure is a failure
PASS=0
FAIL=0
ok() { PASS=$((PASS + 1)); }
bad() { FAIL=$((FAIL + 1)); echo "FAILED: $*" >&2; }

cat > "$T/exp.yaml" <<'YAML'
name: tiny
tasks: [pick_cube]
splits: [seen]
methods: [oracle, no_adapt]
seeds: [20260718, 20260719, 20260720]
episodes: 3
backbone: expert
# the Slurm mechanics under test do not depend on the simulator's fidelity; on the ideal profile the
# oracle solves these nine episodes, so the merge job's Gate 1 passes and the job COMPLETES (on the
# default profile one of them fails, and the merge job correctly exits 1)
profile: ideal
YAML
# MaxArraySize comes from `scontrol show config` (4): six jobs in two arrays
"$AS" plan --experiment "$T/exp.yaml" --out "$T/results" --slurm --cpus-per-task 1 --time 5 >"$T/plan.out" 2>&1 \
  && ok || bad "plan --slurm: $(cat "$T/plan.out")"
grep -qF "2 arrays under MaxArraySize 4" "$T/plan.out" && ok || bad "MaxArraySize read from scontrol: $(cat "$T/plan.out")"

(cd "$T/elsewhere" && bash "$T/results/tiny.submit.sh") >"$T/submit.out" 2>&1 && ok || bad "submit: $(cat "$T/submit.out")"
MERGE=$(sed -n 's/^merge job: //p' "$T/submit.out")
[ -n "$MERGE" ] && ok || bad "submit printed no merge job id"

# wait (bounded) until no job of ours is pending or running
done_=0
for i in $(seq 1 450); do
  [ -z "$(squeue -h -o %i 2>/dev/null)" ] && { done_=1; break; }
  sleep 0.2
done
[ "$done_" = 1 ] && ok || bad "jobs still queued after 90 s: $(squeue 2>&1)"
mstate=$(scontrol show job "$MERGE" 2>/dev/null | sed -n 's/.*JobState=\([A-Z_]*\).*/\1/p')
[ "$mstate" = COMPLETED ] && ok || bad "merge job state '$mstate': $(cat "$T"/results/slurm-merge-*.log 2>/dev/null | tail -5)"

# the same plan locally
"$AS" run --plan "$T/results/tiny.plan.json" --out "$T/local" --progress off >/dev/null 2>"$T/local.err" \
  && ok || bad "local run: $(cat "$T/local.err")"
n=0
for f in "$T"/local/*.jsonl; do
  n=$((n + 1))
  cmp -s "$f" "$T/results/$(basename "$f")" && ok || bad "$(basename "$f") differs between Slurm and the local run"
done
[ "$n" = 6 ] && ok || bad "expected 6 local jobs, found $n"
"$AS" summarize "$T/local" --out "$T/local.summary.json" >/dev/null && ok || bad "local summarize"
python3 - "$T/local.summary.json" "$T/results/tiny.summary.json" <<'PY' && ok || bad "merged summary differs from the local run's"
import json, sys
a, b = (json.load(open(p)) for p in sys.argv[1:3])
def strip(x):  # directory names differ; everything else must agree
    if isinstance(x, dict): return {k: strip(v) for k, v in x.items() if k not in ("dir", "results_dir", "files", "source")}
    if isinstance(x, list): return [strip(v) for v in x]
    return x
sys.exit(0 if strip(a) == strip(b) else 1)
PY
[ -s "$T/results/tiny.summary.md" ] && ok || bad "merge wrote no Markdown summary"
"$AS" gate1 --results "$T/local" --verdict "$T/local.verdict.json" >/dev/null 2>&1
python3 - "$T/local.verdict.json" "$T/results/gate1.verdict.json" <<'PY' && ok || bad "Slurm Gate 1 verdict differs from the local one"
import json, sys
a, b = (json.load(open(p)) for p in sys.argv[1:3])
def strip(x):
    if isinstance(x, dict): return {k: strip(v) for k, v in x.items() if k not in ("results_dir", "source", "dir")}
    if isinstance(x, list): return [strip(v) for v in x]
    return x
sys.exit(0 if strip(a) == strip(b) else 1)
PY

echo "$PASS passed, $FAIL failed"
[ "$FAIL" = 0 ]
