#!/usr/bin/env bash
# Golden jobs: one small job per method x task (expert backbone), one per backbone kind and task
# where its weights exist, the profiles, the rotation modes, observation noise, two safety flags,
# the job ids of a small plan, and one render frame per task. Each job's id and the SHA-256 of its
# JSONL records are compared with tests/cli/data/golden_jobs.tsv, so any change of behaviour (an
# initial state, an observation, a reward, a record byte, a job id, a scene) fails this test.
#
# Records carry a `provenance` object (the build's version and git commit, `-dirty` when the tree
# had uncommitted changes): it names the build, not the behaviour, so it is cut out of each line
# (the bytes `,"provenance":{...}`) before hashing. Nothing else is removed or re-serialised.
#
# usage: golden_jobs_test.sh ACTIONSHIFT SOURCE_DIR [--write]
#   --write rewrites the expected table from this build: only for a change of behaviour that is
#   intended, in a commit that says why.
set -euo pipefail
AS=$(readlink -f "$1")
SRC="$2"
WRITE="${3:-}"
EXPECTED="$SRC/tests/cli/data/golden_jobs.tsv"
TMP=$(mktemp -d)
trap 'rm -rf "$TMP"' EXIT
export ACTIONSHIFT_BACKBONES_DIR="$SRC/configs/backbones"
GOT="$TMP/got.tsv"
: >"$GOT"

SEED=20260801
TASKS=(pick_cube push_cube pull_cube stack_cube peg_insertion_side)
METHODS=(oracle no_adapt exact_belief fixed_probes random_probes entropy_probes dualabi grammar_belief osi probe_osi recurrent_osi)
POOL_METHODS=" exact_belief fixed_probes random_probes entropy_probes dualabi "

records_sha() {  # the job's records with the provenance object cut out of every line
  sed -E 's/,"provenance":\{[^{}]*\}//' "$1" | sha256sum | cut -d' ' -f1
}

n=0
job() {  # job LABEL ARGS...: run one job into a fresh directory, append "label id sha" to $GOT
  local label="$1"
  shift
  n=$((n + 1))
  local out="$TMP/j$n"
  if ! "$AS" run "$@" --seed "$SEED" --threads 2 --progress off --out "$out" >"$TMP/log" 2>&1; then
    echo "FAILED: $label: actionshift run $*" >&2
    cat "$TMP/log" >&2
    exit 1
  fi
  local f
  f=$(ls "$out"/*.jsonl)
  printf '%s\t%s\t%s\n' "$label" "$(basename "$f" .jsonl)" "$(records_sha "$f")" >>"$GOT"
}

# 1. every method on every task (expert backbone, the two reference_seen contracts, two blocks of episodes)
for t in "${TASKS[@]}"; do
  for m in "${METHODS[@]}"; do
    pool=()
    [[ "$POOL_METHODS" == *" $m "* ]] && pool=(--pool reference9)
    job "method $m task $t" --task "$t" --split reference_seen --method "$m" "${pool[@]}" --episodes 4
  done
done

# 2. every backbone kind on every task that has it (oracle, reference_long_lag: lags 4 and 6 for the
#    delay-aware backbones, reference_seen for the reactive ones)
for t in "${TASKS[@]}"; do
  for b in expert-delay-aware mlp mlp-delay-aware ppo ppo-delay-aware; do
    case "$b" in
      expert-*) ;;
      *) [ -f "$ACTIONSHIFT_BACKBONES_DIR/$t.$b.asmlp" ] || continue ;;
    esac
    split=reference_seen
    [[ "$b" == *delay-aware ]] && split=reference_long_lag
    job "backbone $b task $t" --task "$t" --split "$split" --method oracle --backbone "$b" --episodes 2
  done
done

# 3. the vocabularies a job carries: profile, rotation mode, observation noise
for t in pick_cube peg_insertion_side; do
  job "profile ideal task $t" --task "$t" --split reference_seen --method no_adapt --profile ideal --episodes 2
  job "rotation identity task $t" --task "$t" --split reference_seen --method oracle --rotation-mode identity --episodes 2
done
job "obs_noise 0.01 task pick_cube" --task pick_cube --split reference_seen --method entropy_probes --pool reference9 \
  --obs-noise 0.01 --episodes 2

# 4. safety flags, from an external backbone (its command string is its identity): full +z drives the
#    TCP out of the workspace box; a 1000 entry is out of range
UP='while read -r l; do case "$l" in *hello*) echo "{\"type\":\"ready\"}";; *step*) echo "{\"action\":[0,0,1,0,0,0,0]}";; esac; done'
BIG='while read -r l; do case "$l" in *hello*) echo "{\"type\":\"ready\"}";; *step*) echo "{\"action\":[1000,0,0,0,0,0,0]}";; esac; done'
job "safety workspace_violation" --task pick_cube --split reference_seen --method oracle --backbone "external:$UP" --episodes 2
job "safety action_out_of_range" --task pick_cube --split reference_seen --method no_adapt --backbone "external:$BIG" --episodes 2
for f in "$TMP"/j$((n - 1))/*.jsonl "$TMP"/j$n/*.jsonl; do
  grep -q '"safety_flags":\["' "$f" || { echo "FAILED: the safety jobs raised no flag ($f)" >&2; exit 1; }
done

# 5. the job ids of a plan (YAML vocabularies: rotation_mode, profile)
cat >"$TMP/golden.yaml" <<'EOF'
name: golden
tasks: [pick_cube, peg_insertion_side]
splits: [reference_seen, seen]
methods: [oracle, {name: entropy_probes, params: {budget: 4}}, grammar_belief]
seeds: [1, 2]
episodes: 3
backbone: expert
pool: reference9
rotation_mode: identity
profile: ideal
EOF
(cd "$TMP" && "$AS" plan --experiment golden.yaml --out "$TMP/plan" >"$TMP/log" 2>&1) || { cat "$TMP/log" >&2; exit 1; }
ids=$(grep -o '"job_id": *"[0-9a-f]*"' "$TMP/plan/golden.plan.json" | grep -o '[0-9a-f]\{64\}' | sort)
printf 'plan golden (%s jobs)\t-\t%s\n' "$(wc -l <<<"$ids")" "$(sha256sum <<<"$ids" | cut -d' ' -f1)" >>"$GOT"

# 6. one rendered frame per task (the scene: table, robot, objects, goal markers, the box with a hole)
for t in "${TASKS[@]}"; do
  "$AS" render --task "$t" --split reference_seen --method oracle --seed "$SEED" --frame 12 --no-overlay --size 96x72 \
    --out "$TMP/$t.png" >"$TMP/log" 2>&1 || { echo "FAILED: render $t" >&2; cat "$TMP/log" >&2; exit 1; }
  printf 'render frame 12 task %s\t-\t%s\n' "$t" "$(sha256sum "$TMP/$t.png" | cut -d' ' -f1)" >>"$GOT"
done

if [ "$WRITE" = "--write" ]; then
  cp "$GOT" "$EXPECTED"
  echo "wrote $EXPECTED ($(wc -l <"$GOT") rows)"
  exit 0
fi
if diff -u "$EXPECTED" "$GOT"; then
  echo "golden jobs: $(wc -l <"$GOT") rows identical"
else
  echo "FAILED: golden jobs differ from $EXPECTED (- expected, + this build)" >&2
  exit 1
fi
