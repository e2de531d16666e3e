#!/usr/bin/env bash
# actionshift compare end to end on a tiny results directory made by `actionshift run` (smoke-size):
# the JSON's cells agree with the records, the paired difference with the pairs, the paper's number
# sits beside the paper's method; bad input exits 2 with one line naming the file or option.
set -euo pipefail
AS=$1
source "$(dirname "$0")/lib.sh"

common=(--task pick_cube --split reference_seen --episodes 4 --threads 1 --progress off)
for m in oracle no_adapt; do
  run "$AS" run "${common[@]}" --method "$m" --out "$TMP/r"
  expect_rc 0 "run $m"
done

run "$AS" compare "$TMP/r" --pair 'oracle vs no_adapt'
expect_rc 0 "compare"
printf '%s\n' "$OUT" >"$TMP/cmp.json"
python3 - "$TMP/cmp.json" "$TMP/r" <<'PY' && ok || bad "compare JSON disagrees with the records"
import glob, json, sys
j = json.load(open(sys.argv[1]))
recs = [json.loads(l) for f in sorted(glob.glob(sys.argv[2] + "/*.jsonl")) for l in open(f) if l.strip()]
assert j["schema_version"] == "1.0"
assert j["inputs"]["records"] == len(recs) == 8, j["inputs"]
assert j["inputs"]["paper"]["source"] == "built-in configs/paper/numbers.json"
assert j["bootstrap"] == {"samples": 10000, "seed": 20260718, "confidence": 0.95}
by = {}
for r in recs:
    by.setdefault(r["method"], {})[(r["seed"], r["contract_index"], r["episode_index"])] = r["success_once"]
cells = {c["method"]: c for c in j["cells"]}
assert set(cells) == {"oracle", "no_adapt"}
for m, c in cells.items():
    k = sum(by[m].values())
    assert c["episodes"] == 4 and c["success_once"]["successes"] == k, c
    assert abs(c["success_once"]["rate"] - k / 4) < 1e-12
    assert len(c["per_seed"]) == 1 and c["per_seed"][0]["successes"] == k
    assert "rate" in c["safety"] and "mean_probe_steps" in c and "mean_probe_displacement" in c
    # the paper's Table 2 beside the paper's methods (the expert is one of the reactive backbones)
    assert c["paper"]["success_once"]["source"] == "Table 2", c["paper"]
assert cells["oracle"]["paper"]["success_once"]["value"] == 1.0
(d,) = j["comparisons"]
keys = sorted(by["oracle"])
assert sorted(by["no_adapt"]) == keys
est = sum(by["oracle"][k] - by["no_adapt"][k] for k in keys) / len(keys)
assert d["pairs"] == 4 and abs(d["difference"]["estimate"] - est) < 1e-12, d
assert d["paper"]["entry"]["id"] == "table2.pick_cube.reference_seen.oracle_minus_no_adapt"
lo, hi = d["difference"]["lower"], d["difference"]["upper"]
if lo > 0 or hi < 0:
    assert d["sign_agreement"] == ("same" if lo > 0 else "different") and d["sign_agreement_reason"] is None
else:
    assert d["sign_agreement"] is None and "includes 0" in d["sign_agreement_reason"]
p = d["promotion"]
assert p["matched_seeds"] == 1 and p["verdict"] in ("extend_seeds", "prune") and p["reason"], p
assert p["rule"] == {"extend_seeds": "fewer_than_three_matched_seeds", "prune": "one_seed_below_prune_floor"}[p["verdict"]]
PY

# a pair across backbones: the same method on two backbones (tiny real runs), paired on the same
# (seed, contract index, episode index); per-contract cells agree with the records
for b in expert mlp; do
  run "$AS" run "${common[@]}" --method oracle --backbone "$b" --out "$TMP/x"
  expect_rc 0 "run oracle on $b"
done
run "$AS" compare "$TMP/x" --pair 'oracle@mlp vs oracle@expert'
expect_rc 0 "compare across backbones"
printf '%s\n' "$OUT" >"$TMP/cross.json"
python3 - "$TMP/cross.json" "$TMP/x" <<'PY' && ok || bad "cross-backbone compare JSON disagrees with the records"
import glob, json, sys
from statistics import mean
j = json.load(open(sys.argv[1]))
recs = [json.loads(l) for f in sorted(glob.glob(sys.argv[2] + "/*.jsonl")) for l in open(f) if l.strip()]
by = {}
for r in recs:
    by.setdefault(r["backbone"], {})[(r["seed"], r["contract_index"], r["episode_index"])] = r
assert set(by) == {"expert", "mlp"} and sorted(by["mlp"]) == sorted(by["expert"]) and len(by["mlp"]) == 4
for k in by["mlp"]:
    assert by["mlp"][k]["contract_sha256"] == by["expert"][k]["contract_sha256"], k
(d,) = j["comparisons"]
assert (d["candidate"], d["baseline"], d["candidate_backbone"], d["baseline_backbone"]) == ("oracle", "oracle", "mlp", "expert"), d
assert d["backbone"] is None and d["pairs"] == 4 and d["paper"] is None and d["sign_agreement"] is None, d
est = mean(by["mlp"][k]["success_once"] - by["expert"][k]["success_once"] for k in by["mlp"])
assert abs(d["difference"]["estimate"] - est) < 1e-12, (d["difference"], est)
(p,) = j["pairs"]
assert (p["candidate_backbone"], p["baseline_backbone"], p["cells_compared"]) == ("mlp", "expert", 1), p
for c in j["cells"]:
    rs = [r for r in by[c["backbone"]].values()]
    want = {}
    for r in rs:
        e = want.setdefault(r["contract_index"], [r["contract_sha256"], 0, 0])
        e[1] += 1
        e[2] += r["success_once"]
    got = [(x["contract_index"], x["contract_sha256"], x["episodes"], x["successes"], x["success_once"]["successes"],
            x["success_once"]["total"]) for x in c["per_contract"]]
    assert got == [(i, s, n, k, k, n) for i, (s, n, k) in sorted(want.items())], (got, want)
PY
run "$AS" compare "$TMP/x" --pair 'oracle@mlp vs oracle'
expect_rc 2 "a backbone on one side only"
expect_one_line_error "a backbone on one side only"
expect_err "name a backbone on both sides" "a backbone on one side only"
run "$AS" compare "$TMP/x" --pair 'oracle@mlp vs oracle@ppo'
expect_rc 2 "cross-backbone pair with an absent cell"
expect_err "no (task, split) holds both cells (cells in the results: oracle@expert, oracle@mlp)" "absent cell lists the cells present"
mkdir -p "$TMP/xm"
cp "$TMP"/x/*.jsonl "$TMP"/x/*.summary.json "$TMP/xm/"
short=$(grep -l '"backbone":"mlp"' "$TMP"/xm/*.jsonl)
# a job stopped after 3 episodes, before it wrote its summary (records fewer than a summary covers are refused)
head -n 3 "$short" >"$short.tmp" && mv "$short.tmp" "$short" && rm "${short%.jsonl}.summary.json"
run "$AS" compare "$TMP/xm" --pair 'oracle@mlp vs oracle@expert'
expect_rc 2 "mismatched cross-backbone pairing"
expect_one_line_error "mismatched cross-backbone pairing"
expect_err "pick_cube/reference_seen: oracle@mlp vs oracle@expert: the two cells hold different episodes: 0 only in oracle@mlp, 1 only in oracle@expert" \
  "mismatched cross-backbone pairing names both cells"

# --out and --pairs-from give the same document
printf '# pairs\noracle vs no_adapt\n' >"$TMP/pairs.txt"
run "$AS" compare "$TMP/r" --pairs-from "$TMP/pairs.txt" --out "$TMP/sub/out.json"
expect_rc 0 "compare --pairs-from --out"
[ -z "$OUT" ] && ok || bad "--out also printed to stdout"
python3 -c 'import json,sys; a=json.load(open(sys.argv[1])); b=json.load(open(sys.argv[2])); sys.exit(0 if a==b else 1)' \
  "$TMP/cmp.json" "$TMP/sub/out.json" && ok || bad "--pairs-from/--out differ from --pair/stdout"

# no pair: the cells alone
run "$AS" compare "$TMP/r"
expect_rc 0 "compare without pairs"
python3 -c 'import json,sys; j=json.loads(sys.argv[1]); sys.exit(0 if len(j["cells"])==2 and j["comparisons"]==[] else 1)' "$OUT" \
  && ok || bad "compare without pairs"

# --help explains the pair syntax
run "$AS" compare --help
expect_rc 0 "compare --help"
expect_out "CANDIDATE vs BASELINE" "--help names the pair syntax"

# bad input: exit 2, one line, naming what is wrong
run "$AS" compare
expect_rc 2 "compare without a directory"
expect_one_line_error "compare without a directory"
run "$AS" compare "$TMP/missing"
expect_rc 2 "missing directory"
expect_one_line_error "missing directory"
expect_err "$TMP/missing" "missing directory is named"
run "$AS" compare "$TMP/r" --pair 'oracle,no_adapt'
expect_rc 2 "bad --pair"
expect_one_line_error "bad --pair"
expect_err "--pair: expected 'CANDIDATE vs BASELINE'" "bad --pair names the option"
run "$AS" compare "$TMP/r" --pair 'oracle vs dualabi'
expect_rc 2 "pair with an absent label"
expect_one_line_error "pair with an absent label"
expect_err "labels in the results: no_adapt, oracle" "absent label lists the labels present"
printf 'oracle vs no_adapt\nnonsense\n' >"$TMP/badpairs.txt"
run "$AS" compare "$TMP/r" --pairs-from "$TMP/badpairs.txt"
expect_rc 2 "bad pairs file"
expect_err "$TMP/badpairs.txt:2: pair:" "bad pairs file names file and line"
echo '{"schema_version": "1.0", "entries": [{"id": "x"}]}' >"$TMP/paper.json"
run "$AS" compare "$TMP/r" --paper "$TMP/paper.json"
expect_rc 2 "bad paper file"
expect_one_line_error "bad paper file"
expect_err "$TMP/paper.json: entries[0].kind: missing" "bad paper file names file and field"
run "$AS" compare "$TMP/r" --paper "$TMP"
expect_rc 2 "paper file is a directory"
expect_one_line_error "paper file is a directory"
run "$AS" compare "$TMP/r" "$TMP/r/"
expect_rc 2 "the same directory twice"
expect_err "given twice" "the same directory twice"
run "$AS" compare "$TMP/r" --out "$TMP"
expect_rc 2 "--out a directory"
expect_one_line_error "--out a directory"

# cells that do not pair exactly: an error naming the cell, not a silent drop
mkdir -p "$TMP/m"
cp "$TMP"/r/*.jsonl "$TMP"/r/*.summary.json "$TMP/m/"
short=$(grep -l '"method":"no_adapt"' "$TMP"/m/*.jsonl)
head -n 3 "$short" >"$short.tmp" && mv "$short.tmp" "$short" && rm "${short%.jsonl}.summary.json"
run "$AS" compare "$TMP/m" --pair 'oracle vs no_adapt'
expect_rc 2 "mismatched pairing"
expect_one_line_error "mismatched pairing"
expect_err "pick_cube/reference_seen/expert: oracle vs no_adapt: the two cells hold different episodes: 1 only in oracle" \
  "mismatched pairing names the cell"
# ---- --common-episodes: a 4-episode job pairs with the first 4 episodes of an 8-episode one
"$AS" run --task pick_cube --split reference_seen --method oracle --episodes 4 --out "$TMP/common" --progress off > /dev/null 2>&1
"$AS" run --task pick_cube --split reference_seen --method no_adapt --episodes 8 --out "$TMP/common" --progress off > /dev/null 2>&1
run "$AS" compare "$TMP/common" --pair 'oracle vs no_adapt'
expect_rc 2 "cells with different episode sets are refused without --common-episodes"
expect_err "hold different episodes" "the refusal names the difference"
run "$AS" compare "$TMP/common" --pair 'oracle vs no_adapt' --common-episodes
expect_rc 0 "compare --common-episodes"
[ "$(echo "$OUT" | python3 -c 'import json,sys; c=json.load(sys.stdin)["comparisons"][0]; print(c["pairs"], c["unpaired"]["candidate"], c["unpaired"]["baseline"])')" = "4 0 4" ] \
  && ok || bad "--common-episodes should pair 4 episodes and leave 4 of the baseline out"

# --across-backbones: the same pair on two backbones (expert, mlp) and two seeds: per backbone the
# cluster bootstrap over (seed, block), pooled the hierarchical one; without the flag no such block
for b in expert mlp; do
  for seed in 1 2; do
    for m in oracle no_adapt; do
      run "$AS" run --task pick_cube --split reference_seen --episodes 6 --threads 1 --progress off --seed "$seed" \
        --backbone "$b" --method "$m" --out "$TMP/xb"
      expect_rc 0 "run $m on $b, seed $seed"
    done
  done
done
run "$AS" compare "$TMP/xb" --pair 'oracle vs no_adapt' --across-backbones
expect_rc 0 "compare --across-backbones"
printf '%s\n' "$OUT" >"$TMP/xb.json"
python3 - "$TMP/xb.json" <<'PY' && ok || bad "compare --across-backbones"
import json, sys
j = json.load(open(sys.argv[1]))
(a,) = j["across_backbones"]
assert (a["candidate"], a["baseline"], a["task"], a["split"]) == ("oracle", "no_adapt", "pick_cube", "reference_seen")
assert [b["backbone"] for b in a["backbones"]] == ["expert", "mlp"], a["backbones"]
for b in a["backbones"]:
    assert b["seeds"] == 2 and b["difference"]["pairs"] == 12
    d = b["difference"]
    assert d["lower"] <= d["estimate"] <= d["upper"] and d["samples"] == 10000
p = a["pooled"]
assert p["pairs"] == 24 and p["lower"] <= p["estimate"] <= p["upper"]
assert abs(p["estimate"] - sum(b["difference"]["estimate"] for b in a["backbones"]) / 2) < 1e-12
assert a["verdict"] == "holds_on_every_backbone", a  # the oracle restores what the hidden contract breaks, on both
PY
run "$AS" compare "$TMP/xb" --pair 'oracle vs no_adapt'
[ "$(echo "$OUT" | python3 -c 'import json,sys; print("across_backbones" in json.load(sys.stdin))')" = False ] && ok \
  || bad "compare without --across-backbones should not add the block"

finish
