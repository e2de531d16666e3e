"""Shared layout for the docs/results pages: every number comes from `actionshift compare` (docs/formats.md,
"Comparison"), `summarize --json` or a verdict file; nothing here computes a statistic (no Wilson interval, no
bootstrap, no mean over records). Standard library only.

    import sys, os; sys.path.insert(0, os.path.join(ROOT, "scripts"))
    from pages import load_comparison, fmt, paper, provenance, findings, table

Modules:
  compare     load a compare JSON and index its cells and comparisons
  fmt         a rate with its Wilson interval, a difference with its interval, per-seed rates, probe cost, safety
  paper       the paper column: compare's paper fields, or configs/paper/numbers.json looked up by id / cell
  provenance  the header every page starts with (command, commit, profile, seeds, episodes, wall time)
  findings    the status of a paper finding (reproduced / contradicted / untestable) from compare's fields
  table       a Markdown table writer
"""
from . import compare, fmt, paper, provenance, findings, table  # noqa: F401
from .compare import Comparison, load_comparison  # noqa: F401
