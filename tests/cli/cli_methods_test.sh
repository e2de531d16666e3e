#!/usr/bin/env bash
# A user method ranked against the tournament (docs/methods.md), smoke-size: the C++ plug-in example
# (docs/examples/method_plugin) runs on pick_cube/reference_seen with the PPO backbone beside
# entropy_probes, dualabi and fixed_probes; `compare` pairs it with each and `report --leaderboard`
# shows it as one more row.
set -euo pipefail
AS=$1
EXAMPLE=$2
SRC=$3
PYMOD=${4:-}
source "$(dirname "$0")/lib.sh"

common=(--task pick_cube --split reference_seen --pool reference9 --backbone ppo --episodes 9 --threads 2 --progress off)
for m in entropy_probes dualabi fixed_probes; do
  run "$AS" run "${common[@]}" --method "$m" --out "$TMP/r"
  expect_rc 0 "run $m"
done
run "$EXAMPLE" "$TMP/r" 9 ppo
expect_rc 0 "the C++ plug-in example"
LABEL='separation_probes{amplitude=0.5,budget=6}'

run "$AS" compare "$TMP/r" --pair "$LABEL vs entropy_probes" --pair "$LABEL vs dualabi" --pair "$LABEL vs fixed_probes"
expect_rc 0 "compare ranks the user method"
printf '%s\n' "$OUT" >"$TMP/cmp.json"
python3 - "$TMP/cmp.json" "$LABEL" <<'PY' && ok || bad "compare: the user method's comparisons"
import json, sys
j, label = json.load(open(sys.argv[1])), sys.argv[2]
cells = {c["method"]: c for c in j["cells"]}
assert set(cells) == {label, "entropy_probes", "dualabi", "fixed_probes"}, set(cells)
assert cells[label]["backbone"] == "ppo" and cells[label]["episodes"] == 9
assert cells[label]["mean_probe_steps"] == 6
assert len(j["comparisons"]) == 3
for k in j["comparisons"]:
    assert k["candidate"] == label and k["pairs"] == 9
    d = k["difference"]
    assert d["lower"] <= d["estimate"] <= d["upper"]
    assert k["promotion"]["verdict"] in ("promote", "reject", "prune", "extend_seeds")
    assert k["paper"] is None  # a user method has no paper number
PY

run "$AS" report "$TMP/r" --leaderboard --out "$TMP/board"
expect_rc 0 "report --leaderboard"
expect_out "4 methods, 1 cells" "leaderboard counts"
grep -qF "| $LABEL | pool | cpp |" "$TMP/board/leaderboard.md" && ok || bad "the user method is a row with its rung and kind"
grep -qF "| **entropy_probes** | pool | built-in |" "$TMP/board/leaderboard.md" && ok || bad "the reference row"
grep -qF "## pick_cube / reference_seen" "$TMP/board/leaderboard.md" && ok || bad "the cell's table"
grep -qE "^\| separation_probes\{amplitude=0.5,budget=6\} \| 0\.[0-9]{3} \[0\.[0-9]{3}, [01]\.[0-9]{3}\] n=9 \| – \| [-+][01]\.[0-9]{3} \[" "$TMP/board/leaderboard.md" \
  && ok || bad "the user method's success interval and paired difference in its cell (no paper number)"
grep -qE "^\| fixed_probes \| .* n=9 \| 0\.[0-9]{3} \|" "$TMP/board/leaderboard.md" && ok || bad "the paper's number beside a paper method"
grep -qF "separation_probes{amplitude=0.5,budget=6}</code>" "$TMP/board/leaderboard.html" && ok || bad "the HTML row"
python3 -c "import json,sys; b=json.load(open(sys.argv[1])); assert len(b['board'])==4 and b['reference']=='entropy_probes'" \
  "$TMP/board/leaderboard.json" && ok || bad "leaderboard.json"

# the same rule as an external method (any language; here Python through actionshift.serve_method):
# the same decisions as the C++ plug-in, episode for episode
if [ -n "${PYMOD:-}" ]; then
  SERVER="$SRC/docs/examples/separation_method_server.py"
  run env PYTHONPATH="$PYMOD" "$AS" run "${common[@]}" --method "external:python3 $SERVER" --method-rung pool \
    --method-files "$SERVER" "$SRC/docs/examples/separation_probes.py" --out "$TMP/ext"
  expect_rc 0 "run an external method"
  python3 - "$TMP/ext" "$TMP/r" "$LABEL" <<'PY' && ok || bad "the external method's decisions equal the C++ plug-in's"
import glob, json, sys
def recs(d, label):
    out = {}
    for f in glob.glob(d + "/*.jsonl"):
        for line in open(f):
            r = json.loads(line)
            if r["method_variant"] == label:
                out[r["episode_index"]] = r
    return out
ext = recs(sys.argv[1], next(json.loads(l)["method_variant"] for f in glob.glob(sys.argv[1] + "/*.jsonl") for l in open(f)))
cpp = recs(sys.argv[2], sys.argv[3])
assert len(ext) == len(cpp) == 9, (len(ext), len(cpp))
keys = ("contract_sha256", "success_once", "success_at_end", "return", "steps", "probe_steps", "probe_displacement")
for i in cpp:
    assert {k: ext[i][k] for k in keys} == {k: cpp[i][k] for k in keys}, i
summary = json.load(open(glob.glob(sys.argv[1] + "/*.summary.json")[0]))
plugin = summary["job"]["method"]["plugin"]
assert plugin["kind"] == "external" and plugin["rung"] == "pool" and len(plugin["files"]) == 2, plugin
PY
  # a rung-none external method gets no pool: this one's setup() fails, and the run says so in one line
  run env PYTHONPATH="$PYMOD" "$AS" run "${common[@]}" --method "external:python3 $SERVER" --out "$TMP/ext2"
  [ "$RC" != 0 ] && ok || bad "a pool method declared rung none ran"
  expect_err "external method 'python3 $SERVER'" "the failing external method is named"
  # an experiment names the external method with its rung and files; the plan's job carries them, so
  # `run --plan --job-index` registers it from the job alone (as a Slurm array task does)
  mkdir -p "$TMP/exp"
  cp "$SERVER" "$SRC/docs/examples/separation_probes.py" "$TMP/exp/"
  cat > "$TMP/exp/ext.yaml" <<YAML
name: external_method
tasks: [pick_cube]
splits: [reference_seen]
methods:
  - name: "external:python3 $TMP/exp/separation_method_server.py"
    rung: pool
    version: "1"
    files: [separation_method_server.py, separation_probes.py]
  - entropy_probes
seeds: [20260718]
episodes: 9
backbone: ppo
pool: reference9
YAML
  run "$AS" plan --experiment "$TMP/exp/ext.yaml" --out "$TMP/plan"
  expect_rc 0 "plan an experiment with an external method"
  run env PYTHONPATH="$PYMOD" "$AS" run --plan "$TMP/plan/external_method.plan.json" --job-index 0 --out "$TMP/plan" --progress off
  expect_rc 0 "run the plan's external-method job from its spec alone"
  python3 - "$TMP/plan" "$TMP/ext" <<'PY' && ok || bad "the plan's external job repeats the external run's decisions"
import glob, json, sys
def outcomes(d):
    out = []
    for f in sorted(glob.glob(d + "/*.jsonl")):
        for line in open(f):
            r = json.loads(line)
            if r["method"].startswith("external:"):
                out.append((r["episode_index"], r["success_once"], r["probe_steps"], r["return"]))
    return sorted(out)
a, b = outcomes(sys.argv[1]), outcomes(sys.argv[2])
assert len(a) == 9 and a == b, (a, b)
spec = json.load(open(glob.glob(sys.argv[1] + "/*.plan.json")[0]))["jobs"][0]["spec"]
assert spec["method"]["plugin"]["version"] == "1" and spec["method"]["plugin"]["rung"] == "pool"
PY
else
  echo "skipped: the external-method case needs the Python module"
fi

# a hostile external method (rung none) logs everything it can reach: the protocol's messages, its
# environment and the command lines of its ancestors up to the runner. None of it names a contract of
# the split or the job's seed (given by --seed-file, so it is not on the runner's command line either)
cat > "$TMP/hostile.py" <<'PY'
import json, os, sys
log = open(os.environ["HOSTILE_LOG"], "w")
def ancestors():
    pid, out = os.getpid(), []
    for _ in range(6):
        try:
            out.append(open(f"/proc/{pid}/cmdline", "rb").read().decode(errors="replace"))
            pid = int(open(f"/proc/{pid}/stat").read().rsplit(")", 1)[1].split()[1])
        except OSError:
            break
    return out
log.write(json.dumps({"environ": dict(os.environ), "cmdlines": ancestors(), "argv": sys.argv}) + "\n")
for line in sys.stdin:
    log.write(line)
    msg = json.loads(line)
    if msg["type"] == "hello":
        print('{"type":"ready"}', flush=True)
    elif msg["type"] == "encode":
        print(json.dumps({"raw": msg["canonical"], "probe": False}), flush=True)
PY
echo 987654321987 > "$TMP/seed"
run env HOSTILE_LOG="$TMP/hostile.log" "$AS" run --task pick_cube --split reference_seen --backbone expert --episodes 9 \
  --threads 1 --progress off --seed-file "$TMP/seed" --method "external:python3 $TMP/hostile.py" --out "$TMP/hostile"
expect_rc 0 "the hostile external method runs"
python3 - "$TMP/hostile.log" "$SRC/manifests/reference_seen.json" <<'PY' && ok || bad "a hostile external method reached the contract or the seed"
import json, sys
text = open(sys.argv[1]).read()
split = json.load(open(sys.argv[2]))
secrets = {"987654321987"}
for c in split["test"]:
    secrets.add(json.dumps(c, sort_keys=True, separators=(",", ":")))
leaks = [s for s in secrets if s in text]
assert not leaks, leaks
lines = [json.loads(l) for l in text.splitlines()]
hello = next(l for l in lines if l.get("type") == "hello")
assert hello["rung"] == "none" and hello["inputs"] == {"pool": None, "calibration": None, "grammar": None}, hello
assert set(hello) == {"type", "protocol", "task", "rung", "params", "inputs"}, set(hello)
keys = {k for l in lines[1:] for k in l}
assert keys <= {"type", "seed", "canonical", "R", "raw", "response", "finger_delta", "protocol", "task", "rung", "params", "inputs"}, keys
assert not any("contract" in k for k in keys)
PY
# contract hashes of the split appear nowhere either (the records name them; the method never sees them)
python3 - "$TMP/hostile.log" "$TMP/hostile" <<'PY' && ok || bad "a contract hash reached the hostile method"
import glob, json, sys
text = open(sys.argv[1]).read()
hashes = {json.loads(l)["contract_sha256"] for f in glob.glob(sys.argv[2] + "/*.jsonl") for l in open(f)}
assert len(hashes) >= 2 and not any(h in text for h in hashes)
PY

# bad input: one line, exit 2
run "$AS" report "$TMP/r" --leaderboard --reference no_such_method --out "$TMP/board2"
expect_rc 2 "unknown reference"
expect_one_line_error "unknown reference"
expect_err "no cell holds 'no_such_method'" "unknown reference names the labels"
run "$AS" run "${common[@]}" --method entropy_probes --method-rung pool --out "$TMP/r"
expect_rc 2 "--method-rung with a built-in method"
expect_one_line_error "--method-rung with a built-in method"
run "$AS" run "${common[@]}" --method 'external:python3 {x}.py' --out "$TMP/r"
expect_rc 2 "an external method command with braces"
expect_one_line_error "an external method command with braces"
printf 'name: x\ntasks: [pick_cube]\nsplits: [seen]\nmethods:\n  - {name: no_adapt, rung: pool}\nseeds: [1]\nepisodes: 1\nbackbone: expert\n' > "$TMP/bad.yaml"
run "$AS" plan --experiment "$TMP/bad.yaml" --out "$TMP/badplan"
expect_rc 2 "rung on a built-in method in YAML"
expect_err "rung, version and files apply to an external:<command> method only" "rung on a built-in method in YAML"
run "$AS" report "$TMP/r" "$TMP/r" --out "$TMP/board3"
expect_rc 2 "two directories without --leaderboard"
expect_one_line_error "two directories without --leaderboard"
finish
