"""scripts/belief_trace_report.py (writes docs/results/belief_trace.md from the belief-trace run summaries):
the committed page is what the report prints for the committed summaries file (byte for byte, apart from
the commit it states), and the page's numbers follow the per-episode data (altering one cell's success
flags changes that cell's number on the page). Standard library and pytest only; no module needed."""
import json
import os
import re
import subprocess
import sys

SRC = os.environ.get("ACTIONSHIFT_SOURCE_DIR", os.path.join(os.path.dirname(__file__), "..", ".."))
REPORT = os.path.join(SRC, "scripts", "belief_trace_report.py")
SUMMARIES = os.path.join(SRC, "docs", "results", "belief_trace", "summaries.jsonl")
PAGE = os.path.join(SRC, "docs", "results", "belief_trace.md")
COMMIT = re.compile(r"at commit `[^`]*`")


def report(summaries):
    p = subprocess.run([sys.executable, REPORT, summaries, "--commit", "TESTCOMMIT"], capture_output=True,
                       text=True, timeout=120)
    assert p.returncode == 0, p.stderr
    return p.stdout


def normalised(text):
    return COMMIT.sub("at commit `X`", text)


def table_row(text, prefix):
    rows = [l for l in text.splitlines() if l.startswith(prefix)]
    assert len(rows) == 1, (prefix, rows)
    return rows[0]


def test_committed_page_is_the_report_of_the_committed_summaries():
    page = open(PAGE, encoding="utf-8").read()
    assert len(COMMIT.findall(page)) == 1
    assert normalised(report(SUMMARIES)) == normalised(page)


def test_page_names_no_file_outside_the_repository():
    page = open(PAGE, encoding="utf-8").read()
    assert "/work/" not in page and "/tmp/" not in page and "the brief" not in page


def test_altered_success_flags_change_the_table(tmp_path):
    lines = open(SUMMARIES).read().splitlines()
    # the main cell ppo / long_lag / oracle (seed 20260718): flip its first 10 failures to successes
    target = None
    for i, line in enumerate(lines):
        r = json.loads(line)
        if (r["backbone"], r["split"], r["method"], r["history"], r["seed"]) == ("ppo", "long_lag", "oracle", "own", 20260718) \
                and not r.get("perturb") and r.get("verify"):
            target = i
            break
    assert target is not None
    r = json.loads(lines[target])
    before = sum(r["success_flags"]) / len(r["success_flags"])
    flipped = 0
    for j, f in enumerate(r["success_flags"]):
        if not f and flipped < 10:
            r["success_flags"][j] = True
            flipped += 1
    assert flipped == 10
    after = sum(r["success_flags"]) / len(r["success_flags"])
    lines[target] = json.dumps(r)
    altered = tmp_path / "summaries.jsonl"
    altered.write_text("\n".join(lines) + "\n")

    orig = report(SUMMARIES)
    new = report(str(altered))
    # the verification table (Python loop column) and the t* table (success column) both start with the rate
    prefix = "| ppo | long_lag | oracle | "
    assert [l for l in orig.splitlines() if l.startswith(prefix)] == \
        [l for l in orig.splitlines() if l.startswith(f"{prefix}{before:.2f} |")] != []
    assert len([l for l in new.splitlines() if l.startswith(f"{prefix}{after:.2f} |")]) == 2
    # the long-lag separating table: success and the lag columns
    assert table_row(orig, "| ppo | oracle | — | — |") != table_row(new, "| ppo | oracle | — | — |")
    assert f"| {after:.2f} |" in table_row(new, "| ppo | oracle | — | — |")
    assert normalised(new) != normalised(orig)
