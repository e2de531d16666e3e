"""Every public callable of the module, called with bad arguments, raises a Python exception and never
crashes the interpreter (a segfault here once came from stepping an env before reset() and from
Decoder.step_batch("x")). The calls run in a child interpreter so that a crash fails this test with
the call that caused it instead of killing pytest."""
import os
import subprocess
import sys
import textwrap

FUZZ = textwrap.dedent(r'''
    import inspect, sys
    import numpy as np
    import actionshift as A

    BAD = [None, -1, 2 ** 70, "x", float("nan"), np.full(7, np.nan), np.zeros(3), np.zeros((2, 7)), [], {},
           np.zeros((3, 3)), np.eye(3) * np.nan, object(), np.full(6, np.inf)]
    FILL = [np.zeros(7), np.zeros(6), np.eye(3)]
    CONTRACT = A.load_manifest("reference9").contracts[0]
    ALLOWED = (ValueError, TypeError, RuntimeError, KeyError, IndexError, OverflowError)

    def fresh(kind):  # a new object per call: a call must not depend on what an earlier bad call left
        if kind == "module": return A
        if kind == "contract": return CONTRACT
        if kind == "decoder": return A.Decoder(CONTRACT, num_envs=2)
        if kind == "manifest": return A.load_manifest("reference9")
        if kind == "adapter_pool": return A.make_adapter("exact_belief", pool="reference9")
        if kind == "adapter_recurrent": return A.make_adapter("recurrent_osi")
        if kind == "adapter_grammar": return A.make_adapter("grammar_belief")
        if kind == "selftest": return A.SelfTest()
        if kind == "selftest_begun":
            s = A.SelfTest()
            s.begin(np.zeros(3), np.array([1.0, 0.0, 0.0, 0.0]))
            return s
        if kind == "env": return A.make("pick_cube")
        if kind == "vec": return A.make_vec("pick_cube", 2, threads=1)
        raise AssertionError(kind)

    SKIP = {"evaluate", "serve_policy"}  # evaluate: test_evaluate.py; serve_policy reads stdin
    calls = 0
    for kind in ["module", "contract", "decoder", "manifest", "adapter_pool", "adapter_recurrent",
                 "adapter_grammar", "selftest", "selftest_begun", "env", "vec"]:
        names = [n for n in dir(fresh(kind)) if not n.startswith("_") and n not in SKIP]
        for name in names:
            if not callable(getattr(fresh(kind), name)) or inspect.isclass(getattr(fresh(kind), name)):
                continue
            for nargs in range(4):
                for pos in range(max(nargs, 1)):
                    for bad in BAD:
                        args = [bad if j == pos else FILL[j % 3] for j in range(nargs)]
                        what = f"{kind}.{name}({', '.join(type(a).__name__ for a in args)})"
                        print(what, file=sys.stderr, flush=True)
                        calls += 1
                        try:
                            getattr(fresh(kind), name)(*args)
                        except ALLOWED as e:
                            msg = str(e).strip()
                            # pybind11's own message for a wrong number or kind of arguments lists the
                            # signature on several lines; every message of ours is one line
                            if "\n" in msg and "incompatible function arguments" not in msg \
                                    and "incompatible constructor arguments" not in msg:
                                print(f"MULTILINE {what}: {msg!r}")
                        except Exception as e:
                            print(f"UNEXPECTED {what}: {type(e).__name__}: {e}")
    print(f"calls {calls}")
''')


def test_bad_arguments_to_every_public_callable_raise_and_never_crash():
    p = subprocess.run([sys.executable, "-c", FUZZ], capture_output=True, text=True, timeout=300,
                       env=dict(os.environ))
    last_call = p.stderr.strip().splitlines()[-1] if p.stderr.strip() else "(none)"
    assert p.returncode == 0, f"the interpreter died (exit {p.returncode}) in {last_call}"
    problems = [line for line in p.stdout.splitlines() if line.startswith(("MULTILINE", "UNEXPECTED"))]
    assert not problems, "\n".join(problems[:20])
    calls = int(p.stdout.strip().splitlines()[-1].split()[1])
    assert calls > 2000  # the sweep reached every object (about 5,000 calls)
