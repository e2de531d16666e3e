#!/usr/bin/env bash
# scripts/brittleness end to end with a Diffusion Policy (tiny: U-Net 32/64/128 trained 2 iterations on 2
# demonstrations, DDIM-10 so an episode of 100 steps takes a fraction of a second; one split, one episode per
# job): the jobs run, the cost step writes its benchmark files in OUT/bench/ (never OUT/*.jsonl, which
# `actionshift compare` reads as result files: a bench file there once stopped the page step), the cost file
# names the network, and the page is written where PAGE says, with the Diffusion Policy's cost section.
# usage: tests/pages/brittleness_dp_script_test.sh BUILD_DIR WORK_DIR
set -euo pipefail
BUILD="$(cd "$1" && pwd)"
WORK="$2"
cd "$(dirname "$0")/../.."
AS="$BUILD/apps/actionshift/actionshift"
rm -rf "$WORK"
mkdir -p "$WORK/backbones"
committed=$(sha256sum < docs/results/brittleness.md)
"$AS" train dp --task pick_cube --demos 2 --iterations 2 --batch 4 --down-dims 32,64,128 --ddim-steps 10 --threads 2 \
    --progress off --out "$WORK/backbones/pick_cube.dp.asdp" > /dev/null
ACTIONSHIFT_BUILD_DIR="$BUILD" ACTIONSHIFT_BACKBONES_DIR="$WORK/backbones" BACKBONES=dp TASKS=pick_cube \
    SPLITS=reference_seen EPISODES=1 THREADS=2 PAGE="$WORK/page.md" DP_BENCH_FILTER='BM_Dp(ControlStep|Chunk)/1/10' \
    scripts/brittleness "$WORK/out" > "$WORK/log" 2>&1 || { cat "$WORK/log"; exit 1; }
fail() { echo "brittleness_dp_script_test: $*"; exit 1; }
test -s "$WORK/out/bench/dp_bench.json" || fail "no OUT/bench/dp_bench.json"
test -s "$WORK/out/bench/env_bench.jsonl" || fail "no OUT/bench/env_bench.jsonl"
for f in "$WORK"/out/*.jsonl; do
  python3 -c "import json,sys; json.loads(open(sys.argv[1]).readline())['job_id']" "$f" 2> /dev/null \
      || fail "$f is not a result file, yet compare reads it"
done
python3 -c "import json,sys; t=json.load(open(sys.argv[1]))['tasks']; sys.exit(0 if len(t)==1 and t[0]['down_dims']==[32,64,128] \
and t[0]['sampler']=='DDIM-10' and t[0]['control_step_ms']>0 and t[0]['sim_step_ms']>0 else 1)" "$WORK/out/dp_cost.json" \
    || fail "dp_cost.json does not describe the 32/64/128 DDIM-10 network"
grep -q "wrote $WORK/page.md" "$WORK/log" || fail "the page did not go where PAGE says"
grep -qi "inference cost" "$WORK/page.md" || fail "the page has no inference cost section"
grep -q 'BACKBONES="dp" TASKS="pick_cube"' "$WORK/page.md" || fail "the page does not name the selection"
test "$(sha256sum < docs/results/brittleness.md)" = "$committed" || fail "docs/results/brittleness.md was rewritten"
echo "brittleness_dp_script_test: ok"
