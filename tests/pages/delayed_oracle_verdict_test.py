#!/usr/bin/env python3
"""Unit check of the delayed-oracle page's rule on "the same adapters restore the backbone to its oracle"
(scripts/delayed_oracle_report.py, rule): every branch, on hand-made comparison objects (made-up differences in
compare's `difference` shape; the golden fixture's tiny runs reach only the `reproduced` branch). Each case names
the status the rule gives and a phrase of its reason.
usage: tests/pages/delayed_oracle_verdict_test.py"""
import os
import sys
from functools import partial

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
sys.path.insert(0, os.path.join(ROOT, "scripts"))
from delayed_oracle_report import rule  # noqa: E402
from rule_cases import run_cases  # noqa: E402


def cmp(est, lo, hi):
    return {"difference": {"estimate": est, "lower": lo, "upper": hi, "excludes_zero": lo > 0 or hi < 0}}


GAP = cmp(0.40, 0.30, 0.50)  # oracle well above the adapter
ZERO = cmp(0.0, -0.05, 0.05)
# (gap, [(label, oracle - label, label - exact_belief)], status, a phrase of the reason)
CASES = [
    (cmp(0.02, -0.03, 0.07), [], "reproduced", "includes 0"),
    (cmp(-0.10, -0.15, -0.05), [], "contradicted", "above its oracle"),
    (None, [], "untestable", "not run"),
    (GAP, [("delayed_oracle", cmp(0.38, 0.28, 0.48), ZERO)], "contradicted", "accounts for the adapter's loss: `delayed_oracle` costs"),
    (GAP, [("delayed_oracle", cmp(0.20, 0.10, 0.30), cmp(0.20, 0.10, 0.30))], "contradicted",
     "accounts for part of the loss"),
    (GAP, [("delayed_oracle", ZERO, cmp(0.40, 0.30, 0.50)), ("delayed_oracle{delay=1}", None, None)], "contradicted",
     "the cause is not found here"),
    # a delay that makes the oracle better is no cost
    (GAP, [("delayed_oracle", cmp(-0.2, -0.3, -0.1), cmp(0.6, 0.5, 0.7))], "contradicted", "the cause is not found here"),
    # the whole and a part: the whole is named first
    (GAP, [("delayed_oracle{delay=1}", cmp(0.1, 0.02, 0.18), cmp(0.3, 0.2, 0.4)), ("delayed_oracle", cmp(0.38, 0.28, 0.48), ZERO)],
     "contradicted", "accounts for the adapter's loss: `delayed_oracle` costs the oracle +0.380 [+0.280, +0.480] and delayed_oracle − exact_belief is +0.000 [-0.050, +0.050], which includes 0; `delayed_oracle{delay=1}`"),
]


if __name__ == "__main__":
    sys.exit(run_cases("delayed-oracle rule", [(want, phrase, partial(rule, gap, delayed))
                                              for gap, delayed, want, phrase in CASES]))
