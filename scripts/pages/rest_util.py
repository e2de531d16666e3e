"""Helpers of the ladder, long-lag, brittleness, noise-sensitivity, Gate 0, identifiers and DualABI-pilot
pages that the shared modules do not have: the common command line of their report scripts (fixed
provenance arguments, so a golden test can pin the page), the probe rule a grammar_belief label ran, and
lookups of scalar entries of configs/paper/numbers.json by id. Nothing here computes a statistic."""
import argparse
import os
import subprocess

from . import fmt

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def parser(doc):
    """The arguments every report script of these pages takes: the compare JSON(s) come first (per script),
    then the provenance, all given by the shell script (or fixed by a golden test)."""
    p = argparse.ArgumentParser(description=doc, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--commit", help="commit the results were produced at (default: git rev-parse --short HEAD)")
    p.add_argument("--command", help="the shell command that produced the results and this page")
    p.add_argument("--wall", help="wall time of the runs in s (empty: not measured)")
    p.add_argument("--cores", help="cores of the machine the runs used")
    p.add_argument("--cpu", default="", help="the `times` line of the runs (user and system time of the children)")
    p.add_argument("--reused", type=int, default=0,
                   help="jobs the command found already complete (run by an earlier invocation); the wall time omits them")
    return p


def commit_of(args):
    if args.commit:
        return args.commit
    return subprocess.run(["git", "-C", ROOT, "rev-parse", "--short", "HEAD"], capture_output=True, text=True).stdout.strip()


def rel(path):
    """A path relative to the repository root when it lies inside it (pages never name a machine's absolute paths)."""
    a = os.path.abspath(path)
    return os.path.relpath(a, ROOT) if a.startswith(ROOT + os.sep) else path


def probe_rule(label):
    """What a method label ran, in words, read from the label itself (docs/adapters.md, *Method names and
    variants*): `grammar_belief` is passive (no probes); `{probe=fixed}`, `{probe=entropy}` and `{probe=hold}`
    are its probing variants; other parameters are listed as written."""
    base, _, rest = label.partition("{")
    params = dict(kv.split("=", 1) if "=" in kv else (kv, "") for kv in rest.rstrip("}").split(",") if kv)
    if base == "grammar_belief":
        probe = params.pop("probe", None)
        words = {None: "passive (no probes)", "fixed": "6 fixed pulses", "entropy": "6 entropy-chosen pulses",
                 "hold": "hold probe"}.get(probe, f"probe={probe}")
    elif base in ("entropy_probes", "dualabi"):
        words = "the paper's probe rule" if "calibrated" not in params else "the project's calibrated probe rule"
        params.pop("calibrated", None)
    else:
        return label
    extra = ", ".join(f"{k}={v}" if v else k for k, v in sorted(params.items()))
    return words + (f"; {extra}" if extra else "")


def scalar(numbers, entry_id, digits=3):
    """A numbers.json entry by id as `0.545 (§5.4)`; a dash when the file has no such id."""
    e = numbers.by_id(entry_id)
    if not e:
        return fmt.DASH
    return f"{fmt.num(e['value'], digits)} ({e['source']})"


def value(numbers, entry_id, digits=3):
    """A numbers.json entry's value by id, formatted; a dash when absent."""
    e = numbers.by_id(entry_id)
    return fmt.DASH if not e else fmt.num(e["value"], digits)


def cpu_text(times_line):
    """`, CPU time N s (user + system)` from a bash `times` line ("2m19.630s 0m10.540s"), or ''."""
    import re
    t = re.findall(r"(\d+)m([\d.]+)s", times_line or "")
    return "" if not t else f", CPU time {sum(int(m) * 60 + float(x) for m, x in t):.0f} s (user + system)"
