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

# a hostile external method (rung none) logs everything it can reach, at its start and at every
# episode: the protocol's messages, its environment, the command line and environment of every
# process it can see in /proc, the targets of its open descriptors, and the results directory and
# seed file (whose paths a method could guess; the test hands them over). Sandboxed (the default
# where the machine allows it), none of it names a contract of the split, a contract hash of the
# records or the job's seed (given by --seed-file, so it is not on the runner's command line either).
# With --sandbox off the same method finds the seed and the records: the routes are real.
cat > "$TMP/hostile.py" <<'PY'
import json, os, sys
log = open(os.environ["HOSTILE_LOG"], "w")
peek = os.environ["HOSTILE_PEEK"].split(":")
def read(path):
    try:
        return open(path, "rb").read().decode(errors="replace")
    except OSError:
        return None
def snoop():
    found = {"environ": dict(os.environ), "argv": sys.argv, "procs": {}, "fds": {}, "files": {}}
    for pid in filter(str.isdigit, os.listdir("/proc")):
        for what in ("cmdline", "environ"):
            text = read(f"/proc/{pid}/{what}")
            if text is not None:
                found["procs"][f"{pid}/{what}"] = text
    for fd in os.listdir("/proc/self/fd"):
        try:
            found["fds"][fd] = os.readlink(f"/proc/self/fd/{fd}")
        except OSError:
            pass
    for p in peek:
        for root, _, files in os.walk(p):
            for f in files:
                found["files"][os.path.join(root, f)] = read(os.path.join(root, f))
        if os.path.isfile(p):
            found["files"][p] = read(p)
    log.write(json.dumps({"snoop": found}) + "\n")
    log.flush()
snoop()
for line in sys.stdin:
    log.write(line)
    msg = json.loads(line)
    if msg["type"] == "hello":
        print('{"type":"ready"}', flush=True)
    elif msg["type"] == "begin_episode":
        snoop()
    elif msg["type"] == "encode":
        print(json.dumps({"raw": msg["canonical"], "probe": False}), flush=True)
PY
echo 987654321987 > "$TMP/seed"
sandbox_possible=1
unshare -Urmpf --mount-proc true 2>/dev/null || sandbox_possible=0
run_hostile() {  # run_hostile OUT_NAME [run options...]
  local name=$1
  shift
  run env HOSTILE_LOG="$TMP/$name.log" HOSTILE_PEEK="$TMP/$name:$TMP/seed" "$AS" run --task pick_cube --split reference_seen \
    --backbone expert --episodes 9 --threads 1 --progress off --seed-file "$TMP/seed" \
    --method "external:python3 $TMP/hostile.py" --out "$TMP/$name" "$@"
}
if [ "$sandbox_possible" = 1 ]; then
  run_hostile hostile --sandbox on
  expect_rc 0 "the hostile external method runs in the sandbox"
  python3 - "$TMP/hostile.log" "$SRC/manifests/reference_seen.json" "$TMP/hostile" <<'PY' && ok || bad "a sandboxed hostile external method reached the contract, the seed or the records"
import glob, json, sys
text = open(sys.argv[1]).read()
split = json.load(open(sys.argv[2]))
secrets = {"987654321987"}
for c in split["test"]:
    secrets.add(json.dumps(c, sort_keys=True, separators=(",", ":")))
hashes = {json.loads(l)["contract_sha256"] for f in glob.glob(sys.argv[3] + "/*.jsonl") for l in open(f)}
assert len(hashes) >= 2
secrets |= hashes
leaks = [s for s in secrets if s in text]
assert not leaks, leaks
lines = [json.loads(l) for l in text.splitlines()]
snoops = [l["snoop"] for l in lines if "snoop" in l]
assert len(snoops) == 10, len(snoops)  # at its start and at each of the 9 episodes
for s in snoops:
    assert all(v in ("", None) for v in s["files"].values()), s["files"]  # the results and seed file: empty
    # no runner in sight: only the sandbox's own processes (its leader, sh -c and python)
    assert not any("--seed-file" in v or "--out" in v for v in s["procs"].values()), s["procs"]
    assert len({k.split("/")[0] for k in s["procs"]}) <= 3, sorted(s["procs"])
    assert set(s["fds"]) <= {"0", "1", "2", "3", "4"}, s["fds"]  # stdio, the log, the listing itself
hello = next(l for l in lines if l.get("type") == "hello")
assert hello["rung"] == "none" and hello["inputs"] == {"pool": None, "calibration": None, "grammar": None}, hello
assert set(hello) == {"type", "protocol", "task", "rung", "params", "inputs"}, set(hello)
keys = {k for l in lines if "snoop" not in l for k in l}
assert keys <= {"type", "seed", "canonical", "R", "raw", "response", "finger_delta", "protocol", "task", "rung", "params", "inputs"}, keys
assert not any("contract" in k for k in keys)
PY
  # the same method without the sandbox reads the seed file, other episodes' records and the runner's
  # command line: what the sandbox closes
  run_hostile open --sandbox off
  expect_rc 0 "the hostile external method runs without the sandbox"
  python3 - "$TMP/open.log" "$TMP/open" <<'PY' && ok || bad "without the sandbox the hostile method should see the seed and the records (the test would prove nothing)"
import glob, json, sys
text = open(sys.argv[1]).read()
hashes = {json.loads(l)["contract_sha256"] for f in glob.glob(sys.argv[2] + "/*.jsonl") for l in open(f)}
assert "987654321987" in text
assert any(h in text for h in hashes)
snoops = [json.loads(l)["snoop"] for l in text.splitlines() if l.startswith('{"snoop"')]
assert any("actionshift" in v and "--seed-file" in v for s in snoops for v in s["procs"].values())
PY
  # the default (auto) is the sandbox where the machine allows it: no warning, the same closure
  run_hostile auto
  expect_rc 0 "the hostile external method runs with --sandbox auto"
  expect_no_err "without a sandbox" "auto uses the sandbox here"
  python3 -c "import sys; t=open(sys.argv[1]).read(); assert '987654321987' not in t" "$TMP/auto.log" && ok || bad "auto left the seed file readable"
else
  echo "SKIPPED: this machine makes no user/mount/PID namespaces (unshare -Urmpf failed): the sandbox cases did not run"
  run_hostile hostile --sandbox on
  expect_rc 2 "--sandbox on where no sandbox can be made"
  expect_one_line_error "--sandbox on where no sandbox can be made"
fi

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
