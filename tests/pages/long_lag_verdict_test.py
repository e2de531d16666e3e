#!/usr/bin/env python3
"""Unit check of the long-lag page's verdict rule on "fixed above entropy under lag turns over on the delay-aware
backbone" (scripts/long_lag_report.py, probe_claim_status): every branch of the rule the page states, on
hand-made comparison objects (made-up differences in compare's `difference` shape; the golden fixture is too
small to reach the `reproduced` branch). Each case names the status the rule gives and a phrase of its reason.
usage: tests/pages/long_lag_verdict_test.py"""
import os
import sys
from functools import partial

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
sys.path.insert(0, os.path.join(ROOT, "scripts"))
from long_lag_report import probe_claim_status  # noqa: E402
from rule_cases import run_cases  # noqa: E402


def cmp(est, lo, hi, pairs=600):
    return {"pairs": pairs, "difference": {"estimate": est, "lower": lo, "upper": hi, "excludes_zero": lo > 0 or hi < 0}}


# (d_r = entropy - fixed on the reactive backbone, d_d on the delay-aware one, the paper's printed fixed - entropy,
#  expected status, a phrase of the reason)
CASES = [
    (cmp(-0.10, -0.15, -0.05), cmp(0.05, 0.01, 0.09), None, "reproduced", "excludes 0, entropy above"),
    (cmp(-0.10, -0.15, -0.05), cmp(0.02, 0.0, 0.05), None, "reproduced", "lower bound 0"),
    (cmp(-0.02, -0.05, 0.01), cmp(0.05, 0.01, 0.09), 0.012, "reproduced", "at least the paper's printed +0.012"),
    (cmp(-0.01, -0.05, 0.03), cmp(0.05, 0.01, 0.09), 0.012, "inconclusive", "the reactive premise is not shown"),
    (cmp(-0.01, -0.05, 0.03), cmp(0.05, 0.01, 0.09), None, "inconclusive", "the reactive premise is not shown"),
    (cmp(0.05, 0.01, 0.09), cmp(0.05, 0.01, 0.09), 0.115, "contradicted", "the reactive premise (fixed above entropy) fails"),
    (cmp(-0.10, -0.15, -0.05), cmp(-0.05, -0.09, -0.01), 0.115, "contradicted", "fixed still above"),
    (cmp(-0.10, -0.15, -0.05), cmp(0.01, -0.03, 0.05), None, "inconclusive", "includes 0"),
    (cmp(-0.015, -0.035, 0.007), cmp(0.01, -0.02, 0.04), 0.012, "inconclusive", "the reactive premise holds (on `ppo`"),
    (cmp(-0.10, -0.15, -0.05), cmp(0.0, 0.0, 0.0), None, "inconclusive", "no episode differs"),
    (None, cmp(0.05, 0.01, 0.09), None, "untestable", "`ppo`"),
]


if __name__ == "__main__":
    sys.exit(run_cases("long_lag verdict rule",
                       [(want, phrase, partial(probe_claim_status, dr, dd, "ppo", "ppo-delay-aware", printed))
                        for dr, dd, printed, want, phrase in CASES]))
