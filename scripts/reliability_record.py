#!/usr/bin/env python3
"""Writes a run of scripts/fuzz or scripts/sanitize into docs/results/reliability.md, between the
page's <!-- fuzz:begin/end --> or <!-- sanitize:begin/end --> markers, with the command, the commit,
the date, the machine's cores and load average: the page's figures come from the run's own output,
never typed by hand. Called by both scripts at their end; also usable on a saved log.
usage: scripts/reliability_record.py fuzz LOG SECONDS      (LOG: scripts/fuzz's printed table)
       scripts/reliability_record.py sanitize LOG          (LOG: ctest's output under sanitizers)"""
import datetime, os, re, subprocess, sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
PAGE = os.environ.get("ACTIONSHIFT_RELIABILITY_PAGE", os.path.join(ROOT, "docs/results/reliability.md"))


def context():
    commit = subprocess.run(["git", "-C", ROOT, "rev-parse", "--short", "HEAD"], capture_output=True, text=True).stdout.strip()
    dirty = subprocess.run(["git", "-C", ROOT, "status", "--porcelain", "--untracked-files=no"], capture_output=True, text=True).stdout.strip()
    load = os.getloadavg()
    return (f"commit `{commit or 'unknown'}`{' (with uncommitted changes)' if dirty else ''}, "
            f"{datetime.datetime.now(datetime.timezone.utc):%Y-%m-%d %H:%M} UTC, {os.cpu_count()} cores, "
            f"load average at the end {load[0]:.1f} / {load[1]:.1f} / {load[2]:.1f}")


def fuzz_block(log, seconds):
    rows = []
    for line in open(log):
        f = line.split()
        if len(f) == 4 and f[0] != "target" and re.fullmatch(r"[a-z_]+", f[0]):
            rows.append(f)
    if not rows:
        sys.exit(f"reliability_record: error: {log}: no fuzz table (target executions exec/s findings) in it")
    total = sum(int(r[1]) for r in rows if r[1].isdigit())
    findings = sum(int(r[3]) for r in rows if r[3].isdigit())
    out = [f"`scripts/fuzz {seconds}` ({seconds} s per target; {context()}):", "",
           "| target | executions | exec/s | findings |", "|---|---:|---:|---:|"]
    out += [f"| {r[0]} | {int(r[1]):,} | {r[2]} | {r[3]} |" if r[1].isdigit() else f"| {r[0]} | {r[1]} | {r[2]} | {r[3]} |" for r in rows]
    out += ["", f"In all {total:,} executions over {len(rows)} targets, {findings} findings."]
    return "\n".join(out)


def sanitize_block(log):
    text = open(log).read()
    m = re.search(r"(\d+)% tests passed, (\d+) tests? failed out of (\d+)", text)
    t = re.search(r"Total Test time \(real\) = *([0-9.]+) sec", text)
    if not m:
        sys.exit(f"reliability_record: error: {log}: no ctest summary line in it")
    failed, total = int(m.group(2)), int(m.group(3))
    names = re.findall(r"^\s*\d+ - (\S+) \(", text[text.find("The following tests FAILED"):], re.M) if failed else []
    out = [f"`scripts/sanitize` ({context()}): **{total - failed}/{total} tests passed** under AddressSanitizer +",
           f"UndefinedBehaviorSanitizer (`-fno-sanitize-recover=all`, leak detection on)"
           + (f" in {float(t.group(1)):.0f} s of ctest." if t else ".")]
    if names:
        out.append("Failed: " + ", ".join(f"`{n}`" for n in names) + " (see the run's log).")
    return "\n".join(out)


def main():
    if len(sys.argv) < 3 or sys.argv[1] not in ("fuzz", "sanitize") or (sys.argv[1] == "fuzz" and len(sys.argv) != 4):
        sys.exit(__doc__)
    kind, log = sys.argv[1], sys.argv[2]
    if not os.path.isfile(log):
        sys.exit(f"reliability_record: error: {log}: no such file")
    block = fuzz_block(log, sys.argv[3]) if kind == "fuzz" else sanitize_block(log)
    page = open(PAGE).read()
    begin, end = f"<!-- {kind}:begin -->", f"<!-- {kind}:end -->"
    if begin not in page or end not in page:
        sys.exit(f"reliability_record: error: {PAGE}: no {begin} ... {end} markers")
    head, rest = page.split(begin, 1)
    _, tail = rest.split(end, 1)
    open(PAGE, "w").write(head + begin + "\n" + block + "\n" + end + tail)
    print(f"reliability_record: wrote the {kind} figures into {PAGE}", file=sys.stderr)


if __name__ == "__main__":
    main()
