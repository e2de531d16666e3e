#!/usr/bin/env python3
"""Unit check of the ladder page's per-contract path (compare's `per_contract` cell field, not yet written by the
compare on main): runs compare on the ladder fixture's groups, adds a hand-made `per_contract` list to every cell
of a copy of each JSON (the field's documented shape; the numbers are made up, 1 success of 2 episodes per
contract, so the check does not depend on a compare with the field), writes the page and checks that the
per-contract sections show those rates and no longer say the field is missing.
usage: tests/pages/ladder_per_contract_test.py ACTIONSHIFT_BINARY"""
import json
import os
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
sys.path.insert(0, os.path.join(ROOT, "scripts"))
from ladder_groups import groups  # noqa: E402
from pages.ladder_util import PER_CONTRACT_MISSING  # noqa: E402

D = os.path.join(ROOT, "tests", "pages", "data", "ladder")
WILSON = {"successes": 1, "total": 2, "rate": 0.5, "lower": 0.0946, "upper": 0.9054, "confidence": 0.95}


def main():
    binary = os.path.abspath(sys.argv[1])
    with tempfile.TemporaryDirectory() as tmp:
        for name, dirs, pairs in groups(os.path.join(D, "results"), pairs_dir=D):
            out = os.path.join(tmp, name + ".json")
            subprocess.run([binary, "compare", *dirs, "--out", out] + (["--pairs-from", pairs] if pairs else []),
                           check=True, cwd=ROOT)
            with open(out) as f:
                data = json.load(f)
            for c in data["cells"]:
                n = 2 if c["split"].startswith("reference_") else 32
                c["per_contract"] = [{"contract_index": i, "contract_sha256": "0" * 64, "episodes": 2, "successes": 1,
                                      "success_once": WILSON} for i in range(n)]
            with open(out, "w") as f:
                json.dump(data, f)
        page = subprocess.run([sys.executable, "scripts/ladder_report.py", os.path.join(D, "results"), tmp, "--commit", "0"],
                              check=True, cwd=ROOT, capture_output=True, text=True).stdout
    want = "0.500 [0.095, 0.905] (n=2)"
    problems = []
    if PER_CONTRACT_MISSING in page:
        problems.append("the page still says the per_contract field is missing")
    for section in ("## Per contract", "## The tool-frame cell", "## The generated split"):
        body = page.split(section, 1)[1].split("\n## ", 1)[0] if section in page else ""
        if want not in body:
            problems.append(f"{section!r} does not show the per-contract rate {want}")
    if "tool, absolute" not in page:
        problems.append("the contract classes of the manifests are not shown")
    for p in problems:
        print("ladder_per_contract:", p)
    print("ladder_per_contract:", "FAIL" if problems else "ok")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
