#!/usr/bin/env python3
"""Unit check of the pages' wall-time clause (scripts/pages/provenance.py, wall_text and header): a command that
found jobs already complete says how many, so a page re-made from finished runs never passes off the seconds of a
re-plan as the time the results took; without reused jobs the clause is unchanged.
usage: tests/pages/wall_text_test.py"""
import os
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
sys.path.insert(0, os.path.join(ROOT, "scripts"))
from pages import provenance  # noqa: E402

CASES = [
    (dict(wall="239", cores=2), "wall time 239 s on 2 cores"),
    (dict(wall=None), "wall time not measured (the report was regenerated from existing results)"),
    (dict(wall="7", cores=2, reused=300, jobs=321),
     "wall time 7 s on 2 cores (300 of its 321 jobs were already complete, run by earlier invocations of the same "
     "command: the wall time covers only the rest and the comparison)"),
    (dict(wall="7", cores=2, reused=5),
     "wall time 7 s on 2 cores (5 of its jobs were already complete, run by earlier invocations of the same "
     "command: the wall time covers only the rest and the comparison)"),
]


def main():
    bad = 0
    for kwargs, want in CASES:
        got = provenance.wall_text(**kwargs)
        if got != want:
            print(f"FAIL wall_text({kwargs}):\n  got  {got}\n  want {want}")
            bad += 1
    page = provenance.header("T", "s.py", "scripts/ladder results/ladder", "abc", ["results/ladder"], ["maniskill"],
                             [20260718], 100, jobs=321, wall="7", cores=2, reused=300)
    if "(300 of its 321 jobs were already complete" not in page:
        print("FAIL header(reused=300) does not name the reused jobs:\n" + page)
        bad += 1
    print(f"{len(CASES) + 1 - bad}/{len(CASES) + 1} wall-time cases pass")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
