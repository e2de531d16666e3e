#!/usr/bin/env python3
"""Golden test of one results page: runs `actionshift compare` on the page's fixture (tests/pages/data/<page>/,
small result files of tiny jobs made by tests/pages/make_fixtures.sh), then the page's report script with fixed
provenance arguments, and compares the page with tests/pages/golden/<page>.md byte for byte. Any change of
layout or of a number fails the test; `--update` rewrites the golden page after a deliberate change.
usage: tests/pages/run_page_test.py PAGE ACTIONSHIFT_BINARY [--update]"""
import difflib
import glob
import os
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
DATA = "tests/pages/data"
PROV = ["--commit", "0000000", "--wall", "12", "--cores", "2", "--cpu", "0m1.500s 0m0.500s"]


def compare(binary, dirs, out, pairs=None, extra=()):
    cmd = [binary, "compare", *dirs, "--out", out] + (["--pairs-from", pairs] if pairs else []) + list(extra)
    subprocess.run(cmd, check=True, cwd=ROOT)


def py(script, *args):
    return subprocess.run([sys.executable, script, *args], check=True, cwd=ROOT, capture_output=True, text=True).stdout


def page_text(page, binary, tmp):
    d = f"{DATA}/{page}"
    if page == "brittleness":
        compare(binary, [f"{d}/results"], f"{tmp}/c.json", "scripts/brittleness.pairs")
        return py("scripts/brittleness_report.py", f"{tmp}/c.json", f"{d}/results", *PROV,
                  "--command", f"THREADS=1 EPISODES=4 scripts/brittleness {d}/results")
    if page == "delayed_oracle":
        compare(binary, [f"{d}/results"], f"{tmp}/c.json", "scripts/delayed_oracle.pairs")
        return py("scripts/delayed_oracle_report.py", f"{tmp}/c.json", *PROV, "--reused", "0",
                  "--command", f"THREADS=1 EPISODES=4 scripts/delayed_oracle {d}/results")
    if page == "backbone_variance":
        compare(binary, [f"{d}/results"], f"{tmp}/c.json", "scripts/backbone_variance.pairs", ["--across-backbones"])
        return py("scripts/backbone_variance_report.py", f"{tmp}/c.json", "--commit", "0000000", "--wall", "12",
                  "--command", f"scripts/backbone_variance {d}/results")
    if page == "long_lag":
        compare(binary, [f"{d}/results"], f"{tmp}/c.json", f"{d}/pairs.txt")
        return py("scripts/long_lag_report.py", f"{tmp}/c.json", f"{d}/results", *PROV,
                  "--command", f"THREADS=1 EPISODES=4 scripts/long_lag {d}/results")
    if page == "noise_sensitivity":
        cdir = f"{tmp}/compare"
        os.makedirs(cdir)
        for lv in sorted(glob.glob(os.path.join(ROOT, d, "results", "sigma_*mm"))):
            for mode in ("matched", "noiseless_cal"):
                if os.path.isdir(os.path.join(lv, mode)):
                    compare(binary, [os.path.relpath(os.path.join(lv, mode), ROOT)],
                            f"{cdir}/{os.path.basename(lv)}.{mode}.json", "scripts/noise_sensitivity.pairs")
        return py("scripts/noise_sensitivity_report.py", f"{d}/results", cdir, *PROV,
                  "--command", f"scripts/noise_sensitivity {d}/results")
    if page == "gate0":
        out = f"{tmp}/gate0.md"
        with open(os.path.join(ROOT, d, "page.md")) as f, open(out, "w") as g:
            g.write(f.read())
        # --reused: the header counts the verdict files an earlier run wrote (a run that skips them)
        py("scripts/gate0_report.py", "--verdicts", f"{d}/verdicts", "--page", out, *PROV, "--command", "scripts/gate0",
           "--reused", "3")
        return open(out).read()
    if page == "identifiers":
        compare(binary, [f"{d}/results/eval"], f"{tmp}/c.json", "scripts/identifiers.pairs")
        return py("scripts/identifiers_report.py", f"{tmp}/c.json", f"{d}/results", *PROV,
                  "--command", f"scripts/identifiers {d}/results", "--train-wall", "3", "--eval-wall", "4")
    if page == "dualabi_pilot":
        compare(binary, [f"{d}/results"], f"{tmp}/c.json", f"{d}/pairs.txt")
        return py("scripts/dualabi_pilot", "--report", f"{tmp}/c.json", f"{d}/results", *PROV, "--page", "-")
    if page == "ladder":
        cdir = f"{tmp}/compare"
        os.makedirs(cdir)
        sys.path.insert(0, os.path.join(ROOT, "scripts"))
        from ladder_groups import groups  # noqa: E402
        for name, dirs, pairs in groups(os.path.join(ROOT, d, "results"), pairs_dir=os.path.join(ROOT, d)):
            compare(binary, [os.path.relpath(x, ROOT) for x in dirs], f"{cdir}/{name}.json",
                    os.path.relpath(pairs, ROOT) if pairs else None, ["--common-episodes"])
        # the learned-backbone section: the backbone_variance fixture's comparison
        b = f"{DATA}/backbone_variance"
        compare(binary, [f"{b}/results"], f"{tmp}/learned.json", "scripts/backbone_variance.pairs", ["--across-backbones"])
        return py("scripts/ladder_report.py", f"{d}/results", cdir, *PROV, "--command", f"scripts/ladder {d}/results",
                  "--learned", f"{tmp}/learned.json", "--learned-command", f"scripts/backbone_variance {b}/results")
    if page == "audit":
        # real audit outputs of the fixture logs (tests/selftest/data/audit_bench: five 200-transition logs of the
        # tuning set) at 50 and 200 transitions, by the audit (two tuning configurations, one evaluation) and by the
        # previous model (tests/pages/data/audit/README.md); the intervals need the build's module
        build = os.path.dirname(os.path.dirname(os.path.dirname(binary)))
        env = dict(os.environ, PYTHONPATH=os.path.join(build, "python"))
        chosen = subprocess.run([sys.executable, "scripts/audit_report.py", "--choose", f"{d}/tuning"], check=True, cwd=ROOT,
                                capture_output=True, text=True, env=env).stdout.strip()
        out = f"{tmp}/audit.md"
        subprocess.run([sys.executable, "scripts/audit_report.py", "--out", out, "--svg", f"{tmp}/audit.svg", "--tuning", f"{d}/tuning",
                        "--chosen", chosen, "--evaluation", f"{d}/evaluation", "--old", f"{d}/previous", "--old-commit", "d9c0511",
                        "--command", f"scripts/audit_benchmark {d}", "--commit", "0000000", "--wall", "12",
                        "--tuning-seeds", "20260901 20260902", "--eval-seeds", "20260921 20260922", "--lengths", "50 200",
                        "--eval-committed", "e674eac", "--spent", f"{d}/evaluation", "--first-round", f"{d}/previous",
                        "--spent-seeds", "20260911 20260912"], check=True, cwd=ROOT, env=env, capture_output=True)
        return open(out).read() + "\n<!-- svg -->\n" + open(f"{tmp}/audit.svg").read()
    raise SystemExit(f"run_page_test: unknown page {page}")


def main():
    page, binary = sys.argv[1], os.path.abspath(sys.argv[2])
    update = "--update" in sys.argv[3:]
    golden = os.path.join(ROOT, "tests", "pages", "golden", page + ".md")
    with tempfile.TemporaryDirectory() as tmp:
        text = page_text(page, binary, tmp)
    if update:
        os.makedirs(os.path.dirname(golden), exist_ok=True)
        with open(golden, "w") as f:
            f.write(text)
        print(f"pages.{page}: wrote {os.path.relpath(golden, ROOT)}")
        return 0
    want = open(golden).read() if os.path.exists(golden) else ""
    if text == want:
        print(f"pages.{page}: the page matches {os.path.relpath(golden, ROOT)}")
        return 0
    sys.stdout.writelines(difflib.unified_diff(want.splitlines(True), text.splitlines(True), "golden", "generated"))
    print(f"pages.{page}: the page differs from {os.path.relpath(golden, ROOT)} (run with --update after a deliberate change)")
    return 1


if __name__ == "__main__":
    sys.exit(main())
