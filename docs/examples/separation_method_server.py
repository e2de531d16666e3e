"""The separation_probes rule (separation_probes.py) as an external method: any process that speaks
the JSON-lines protocol actionshift-method-v1 (docs/methods.md) can be a method; this one is Python.

    actionshift run --task pick_cube --split reference_seen --pool reference9 --backbone ppo \\
      --method "external:python3 docs/examples/separation_method_server.py" --method-rung pool \\
      --method-files docs/examples/separation_method_server.py docs/examples/separation_probes.py
"""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import actionshift  # noqa: E402
from separation_probes import SeparationProbes  # noqa: E402

actionshift.serve_method(SeparationProbes())
