#!/usr/bin/env python3
"""Golden test of one results page: `actionshift compare` (and `actionshift gate1` for the verdicts) on the
committed fixtures in tests/pages/data/, the page script with fixed provenance, and an exact comparison with
tests/pages/golden/<page>.md. --update rewrites the golden. Exit 0 on a match, 1 on a difference.
usage: run_test.py --page gate1|tournament|learned_backbone|learned_backbone_ppo --binary ACTIONSHIFT --source ROOT [--update]"""
import argparse
import difflib
import os
import subprocess
import sys
import tempfile

ap = argparse.ArgumentParser()
ap.add_argument("--page", required=True, choices=["gate1", "tournament", "learned_backbone", "learned_backbone_ppo"])
ap.add_argument("--binary", required=True)
ap.add_argument("--source", required=True)
ap.add_argument("--update", action="store_true")
a = ap.parse_args()
binary = os.path.abspath(a.binary)
os.chdir(a.source)  # relative paths, so the page names the fixtures the same way everywhere
D = "tests/pages/data"
FIXED = ["--commit", "fixture", "--wall", "", "--cores", ""]
tmp = tempfile.mkdtemp(prefix="pages_test_")


def run(cmd, ok=(0,)):
    r = subprocess.run(cmd, capture_output=True, text=True)
    if r.returncode not in ok:
        sys.exit(f"{' '.join(cmd)}: exit {r.returncode}\n{r.stderr}")
    return r.stdout


def compare(name, dirs, pairs):
    out = os.path.join(tmp, name + ".json")
    run([binary, "compare", *dirs, "--pairs-from", pairs, "--out", out])
    return out


def gate1_verdict(name, d):
    out = os.path.join(tmp, name + ".verdict.json")
    run([binary, "gate1", "--results", d, "--verdict", out], ok=(0, 1))  # 1: a gated cell failed (still a verdict)
    return out


if a.page == "gate1":
    page = run([sys.executable, "scripts/gate1_report.py", "--compare", compare("gate1", [f"{D}/gate1"], "scripts/pages/gate1.pairs"),
                "--verdict", gate1_verdict("gate1", f"{D}/gate1"), "--command", f"scripts/gate1 {D}/gate1", *FIXED])
elif a.page == "tournament":
    dirs = [f"{D}/tournament", f"{D}/learned_backbone_ppo/tournament_ppo"]
    across = os.path.join(tmp, "across.json")  # the across-backbones summary: the backbone_variance fixture
    run([binary, "compare", f"{D}/backbone_variance/results", "--pairs-from", "scripts/backbone_variance.pairs",
         "--across-backbones", "--out", across])
    page = run([sys.executable, "scripts/tournament_report.py", "--compare", compare("tournament", dirs, "scripts/pages/tournament.pairs"),
                "--displacement", "tests/pages/displacement.json", "--across", across,
                "--command", f"PPO_RESULTS={dirs[1]} scripts/tournament {dirs[0]}", *FIXED])
else:
    L = "ppo" if a.page == "learned_backbone_ppo" else "mlp"
    out = f"{D}/{a.page}"
    g = compare("gate1", [f"{D}/gate1", f"{out}/gate1_{L}"], "scripts/pages/gate1.pairs")
    t = compare("tournament", [f"{D}/tournament", f"{out}/tournament_{L}"], "scripts/pages/learned_backbone.pairs")
    page = run([sys.executable, "scripts/learned_backbone_report.py", "--learned", L, "--gate1-compare", g,
                "--tournament-compare", t, "--gate1-verdict", gate1_verdict("learned", f"{out}/gate1_{L}"),
                "--command", f"LEARNED={L} scripts/learned_backbone {out} {D}/gate1 {D}/tournament", *FIXED])

golden = os.path.join("tests/pages/golden", a.page + ".md")
if a.update:
    os.makedirs(os.path.dirname(golden), exist_ok=True)
    with open(golden, "w") as f:
        f.write(page)
    print(f"wrote {golden}")
    sys.exit(0)
with open(golden) as f:
    want = f.read()
if page != want:
    sys.stdout.writelines(difflib.unified_diff(want.splitlines(True), page.splitlines(True), golden, "generated"))
    print(f"\npages.{a.page}: the page differs from {golden} (layout or numbers changed); if intended, re-run with --update")
    sys.exit(1)
print(f"pages.{a.page}: matches {golden}")
