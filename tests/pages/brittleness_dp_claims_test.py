#!/usr/bin/env python3
"""Unit check of the brittleness page's rules for the paper's §5.8 claims about its Diffusion Policy
(scripts/brittleness_report.py: dp_clean_status, dp_collapse_status, dp_restore_status, dp_probe_status): every
branch, on hand-made verdict cells, compare cells and comparisons (made-up numbers in the shapes compare and Gate 0
write; the golden fixture's tiny runs reach only some branches). Each case names the status the rule gives and a
phrase of its reason.
usage: tests/pages/brittleness_dp_claims_test.py"""
import os
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
sys.path.insert(0, os.path.join(ROOT, "scripts"))
from brittleness_report import dp_clean_status, dp_collapse_status, dp_probe_status, dp_restore_status  # noqa: E402
from rule_cases import run_cases  # noqa: E402


def seed(lo, hi, rate):
    return (20260718, {"competence": {"interval": {"lower": lo, "upper": hi, "rate": rate}}})


def cell(lo, hi, rate=0.0, probes=0.0, episodes=150):
    return {"success_once": {"lower": lo, "upper": hi, "rate": rate}, "mean_probe_steps": probes, "episodes": episodes}


def cmp(est, lo, hi):
    return {"difference": {"estimate": est, "lower": lo, "upper": hi, "excludes_zero": lo > 0 or hi < 0}}


LIFT = cmp(0.7, 0.6, 0.8)  # oracle − no_adapt: the oracle restores the backbone
# (status the rule gives, a phrase of its reason, the call)
CASES = [
    ("reproduced", "inside 2 of 3", lambda: dp_clean_status(0.58, [seed(0.6, 0.8, 0.7), seed(0.5, 0.7, 0.6), seed(0.4, 0.6, 0.5)])),
    ("contradicted", "inside 1 of 3 seeds' Wilson intervals (ours above it on 2, below it on 0)",
     lambda: dp_clean_status(0.58, [seed(0.6, 0.8, 0.7), seed(0.5, 0.7, 0.6), seed(0.65, 0.85, 0.75)])),
    ("contradicted", "below it on 2", lambda: dp_clean_status(0.58, [seed(0.3, 0.5, 0.4), seed(0.2, 0.4, 0.3)])),
    ("untestable", "no clean run", lambda: dp_clean_status(0.58, [])),
    ("untestable", "no clean rate", lambda: dp_clean_status(None, [seed(0.6, 0.8, 0.7)])),
    ("reproduced", "reaches the paper's floor", lambda: dp_collapse_status(cell(0.0, 0.025), 0.007)),
    ("reproduced", "reaches", lambda: dp_collapse_status(cell(0.007, 0.03, 0.013), 0.007)),
    ("contradicted", "lies above the paper's floor", lambda: dp_collapse_status(cell(0.02, 0.09, 0.05), 0.007)),
    ("untestable", "not run", lambda: dp_collapse_status(None, 0.007)),
    ("reproduced", "includes 0", lambda: dp_restore_status(cmp(0.02, -0.03, 0.07), "dualabi", LIFT)),
    ("reproduced", "above its oracle", lambda: dp_restore_status(cmp(-0.1, -0.15, -0.05), "exact_belief", LIFT)),
    ("contradicted", "exact_belief is below its oracle: oracle − exact_belief +0.400 [+0.300, +0.500] excludes 0",
     lambda: dp_restore_status(cmp(0.4, 0.3, 0.5), "exact_belief", LIFT)),
    ("untestable", "oracle or dualabi was not run", lambda: dp_restore_status(None, "dualabi", LIFT)),
    # an oracle that does not lift the backbone above no adaptation leaves no ceiling: equal zeros are not a restoration
    ("untestable", "no ceiling to restore to", lambda: dp_restore_status(cmp(0.0, 0.0, 0.0), "dualabi", cmp(0.0, 0.0, 0.0))),
    ("untestable", "no ceiling to restore to", lambda: dp_restore_status(cmp(0.0, -0.1, 0.1), "dualabi", None)),
    ("reproduced", "ours 0.00 probe steps", lambda: dp_probe_status(cell(0, 0, probes=0.0))),
    ("contradicted", "against the paper's 0.0", lambda: dp_probe_status(cell(0, 0, probes=0.96))),
    ("untestable", "not run", lambda: dp_probe_status(None)),
]


if __name__ == "__main__":
    sys.exit(run_cases("brittleness page, §5.8 Diffusion Policy claims", CASES))
