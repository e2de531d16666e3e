#!/usr/bin/env bash
# The ladder end to end at smoke size (scripts/ladder with LADDER_SMOKE: 2 episodes, one seed, PickCube only):
# every experiment of configs/experiments/ladder/ plans and runs, the v2 (finger channel) experiments run with
# {"gripper_channel": true} on a calibration that has the finger block, and the page shows their rows.
# usage: ladder_smoke_test.sh OUT_DIR BUILD_DIR SOURCE_DIR
set -euo pipefail
out="$1"; build="$2"; src="$3"
rm -rf "$out"
LADDER_SMOKE=1 ACTIONSHIFT_BUILD_DIR="$build" bash "$src/scripts/ladder" "$out" > "$out.log" 2>&1 \
  || { tail -20 "$out.log"; echo "FAIL: scripts/ladder exited non-zero"; exit 1; }
python3 - "$out" "$src" <<'PY'
import glob, json, os, sys
out, src = sys.argv[1], sys.argv[2]
fail = []
names = sorted(os.path.basename(f)[:-5] for f in glob.glob(os.path.join(src, "configs/experiments/ladder/*.yaml")))
isv2 = lambda n: n.startswith("v2_") or n.startswith("gen_v2_")
v2 = [n for n in names if n.startswith("v2_")]
if len(v2) < 5:
    fail.append(f"expected the v2 experiments (passive, fixed, hold, hold + corrector, h2-r2 + corrector), found {v2}")
cal = json.load(open(os.path.join(src, "configs/calibration/maniskill/pick_cube.json")))
if "gripper" not in cal:
    fail.append("the committed pick_cube calibration has no finger block: the v2 rows cannot run")
for n in names:
    sums = [json.load(open(p)) for p in glob.glob(os.path.join(out, n, "*.summary.json"))]
    if not sums:
        fail.append(f"{n}: no job ran")
    for s in sums:
        if not s["complete"] or s["episodes_done"] != 2:
            fail.append(f"{n}: job {s['job_id'][:12]} incomplete ({s['episodes_done']} episodes)")
        params = s["job"]["method"].get("params") or {}
        if isv2(n) and params.get("gripper_channel") is not True:
            fail.append(f"{n}: job {s['job_id'][:12]} runs without the finger channel")
        if isv2(n) and not s["job"].get("calibration_sha256"):
            fail.append(f"{n}: job {s['job_id'][:12]} has no calibration")
        if not isv2(n) and params.get("gripper_channel") is True:
            fail.append(f"{n}: a v1 experiment runs with the finger channel")
page = open(os.path.join(out, "ladder.md")).read()
# the split tables: one row per v2 experiment on each reference split, its label carrying the finger channel
for exp in ("v2_passive", "v2_fixed", "v2_hold", "v2_hold_corrector", "v2_hold_r2_corrector"):
    rows = [l for l in page.splitlines() if l.startswith("| `grammar_belief{") and f"| {exp} |" in l]
    if len(rows) != 2:
        fail.append(f"page: {len(rows)} rows for {exp} in the split tables, expected 2")
    for l in rows:
        cols = [c.strip() for c in l.split("|")]
        if "gripper_channel=true" not in cols[1]:
            fail.append(f"page: {exp}: label {cols[1]} lacks the finger channel")
        if not cols[7].endswith("/2"):
            fail.append(f"page: {exp}: k/n '{cols[7]}' (expected 2 episodes)")
tool = [l for l in page.splitlines() if l.startswith("| v2 operating point | `grammar_belief{gripper_channel=true")]
if len(tool) != 1 or any("[" not in c for c in [x.strip() for x in tool[0].split("|")][4:6]):
    fail.append(f"page: the v2 tool-frame row is missing or empty: {tool}")
if "committed calibrations have no finger" in page:
    fail.append("page: still says the committed calibrations have no finger block")
for f in fail:
    print("FAIL:", f)
sys.exit(1 if fail else 0)
PY
echo "ok: $(ls -d "$out"/*/ | wc -l) ladder experiments ran at smoke size"
