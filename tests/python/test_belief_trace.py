"""scripts/belief_trace.py (the diagnostic behind docs/results/belief_trace.md): its Python copy of the
runner's episode loop gives the same per-episode outcomes as actionshift.evaluate() for the same numpy
policy, and its per-step "the belief is right" flag is right at every step under the oracle and wrong
at step 0 under the exact belief on a contract the identity does not match."""
import importlib.util
import os
import subprocess
import sys

SRC = os.environ.get("ACTIONSHIFT_SOURCE_DIR", os.path.join(os.path.dirname(__file__), "..", ".."))
spec = importlib.util.spec_from_file_location("belief_trace", os.path.join(SRC, "scripts", "belief_trace.py"))
bt = importlib.util.module_from_spec(spec)
spec.loader.exec_module(bt)


def test_loop_matches_evaluate_for_the_delay_aware_ppo():
    eps = bt.run_cell("push_cube", "ppo-delay-aware", "exact_belief", "reference_seen", "reference9", 20260718, 6)
    v = bt.verify("push_cube", "ppo-delay-aware", "exact_belief", "reference_seen", "reference9", 20260718, 6, eps)
    assert v["episodes"] == 6
    assert v["flags_equal"] == 6 and v["steps_equal"] == 6


def test_right_flag_under_the_oracle_and_the_exact_belief():
    oracle = bt.run_cell("push_cube", "ppo", "oracle", "reference_seen", "reference9", 20260718, 3)
    assert all(all(e["right"]) and e["t_right"] == 0 for e in oracle)
    exact = bt.run_cell("push_cube", "ppo", "exact_belief", "reference_seen", "reference9", 20260718, 3)
    # the belief starts on the pool's first hypothesis; a non-identity contract is mis-encoded at step 0
    assert any(not e["right"][0] for e in exact)


def test_bad_input_is_one_line_and_exit_2(tmp_path):
    good = os.path.join(SRC, "configs", "backbones", "push_cube.ppo.asmlp")
    truncated = tmp_path / "t.asmlp"
    truncated.write_bytes(open(good, "rb").read()[:100])
    for args in (["--backbone", str(truncated)], ["--split", "no_such_split"], ["--backbone", str(tmp_path / "missing.asmlp")]):
        r = subprocess.run([sys.executable, os.path.join(SRC, "scripts", "belief_trace.py"), "--episodes", "1", *args],
                           capture_output=True, text=True)
        assert r.returncode == 2, (args, r.stderr)
        assert len(r.stderr.strip().splitlines()) == 1 and r.stderr.startswith("belief_trace: "), r.stderr
