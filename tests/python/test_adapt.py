"""Adapters from Python: every registered method, driven by a Python control loop."""
import numpy as np
import pytest

import actionshift

TASK = "pick_cube"


def adapter_for(method, truth):
    pool = "reference9" if actionshift.method_needs_pool(method) else None
    return actionshift.make_adapter(method, task=TASK, pool=pool, truth=truth if method in ("oracle", "delayed_oracle") else None)


def run_episode(env, adapter, seed, steps, intent):
    """The runner's loop (src/eval/episode_fn.cpp) written in Python."""
    obs, _ = env.reset(seed=seed)
    adapter.begin_episode(seed)
    probes = 0
    for _ in range(steps):
        R = actionshift.tcp_rotation(obs, TASK)
        raw = adapter.encode(intent, R)
        probes += adapter.last_probe
        nxt, _, _, _, info = env.step(raw)
        assert info["safety"] == "none"
        adapter.observe(raw, actionshift.tcp_response(obs, nxt, TASK), R)
        obs = nxt
    return obs, probes


def test_every_registered_method_builds_and_runs():
    names = actionshift.methods()
    assert set(names) == {"oracle", "no_adapt", "exact_belief", "fixed_probes", "random_probes",
                          "entropy_probes", "dualabi", "grammar_belief", "osi", "probe_osi", "recurrent_osi",
                          "delayed_oracle"}
    truth = actionshift.load_manifest("reference9").contracts[1]
    env = actionshift.make(TASK, contract=truth)
    intent = np.array([0.2, 0.0, -0.1, 0.0, 0.0, 0.0, 1.0])
    for method in names:
        a = adapter_for(method, truth)
        assert a.name == method
        _, probes = run_episode(env, a, seed=3, steps=8, intent=intent)
        expected_probes = {"fixed_probes": 6, "random_probes": 6, "entropy_probes": 6, "probe_osi": 6}.get(method)
        if expected_probes is not None:
            assert probes == expected_probes, method
        elif method in ("oracle", "delayed_oracle", "no_adapt", "exact_belief", "grammar_belief", "osi", "recurrent_osi"):
            assert probes == 0, method


def test_oracle_inverts_the_contract():
    truth = actionshift.Contract(permutation=[1, 0, 2, 3, 4, 5], sign=[1, 1, -1, 1, 1, 1])
    a = adapter_for("oracle", truth)
    a.begin_episode(0)
    intent = np.array([0.3, -0.2, 0.1, 0.0, 0.05, 0.0, -1.0])
    raw = a.encode(intent, np.eye(3))
    assert np.allclose(actionshift.decode(truth, raw), intent)


@pytest.mark.parametrize("member", [1, 2, 7, 8])
def test_entropy_probing_identifies_a_pool_member_in_the_simulator(member):
    pool = actionshift.load_manifest("reference9").contracts
    truth = pool[member]
    assert truth.lag == 0 and truth.target == "delta"
    env = actionshift.make(TASK, contract=truth)
    a = adapter_for("entropy_probes", truth)
    obs, probes = run_episode(env, a, seed=5, steps=6, intent=np.zeros(7))
    assert probes == 6
    R = actionshift.tcp_rotation(obs, TASK)
    intent = np.array([0.3, -0.2, 0.1, 0.05, 0.0, -0.05, 1.0])
    # after the probes the adapter acts on the MAP, which is the truth: its raw action is the truth's encoding
    assert np.allclose(a.encode(intent, R), actionshift.encode(truth, intent, R), atol=1e-9)
    assert not a.last_probe


def test_adapter_errors_are_value_errors():
    with pytest.raises(ValueError, match="method"):
        actionshift.make_adapter("telepathy", task=TASK)
    with pytest.raises(ValueError, match=r"needs a pool of candidate contracts \(.*pool= in Python\)"):
        actionshift.make_adapter("entropy_probes", task=TASK)
    with pytest.raises(ValueError, match=r"needs the true contract \(.*truth= in Python\)"):
        actionshift.make_adapter("oracle", task=TASK)
    with pytest.raises(ValueError):
        actionshift.make_adapter("entropy_probes", task=TASK, pool="reference9", params={"budget": -1})
    with pytest.raises(ValueError, match="params: not a JSON object"):
        actionshift.make_adapter("no_adapt", task=TASK, params="[1, 2]")
    with pytest.raises(ValueError, match="params.budget: duplicate key"):
        actionshift.make_adapter("entropy_probes", task=TASK, pool="reference9", params='{"budget": 2, "budget": 6}')
    a = actionshift.make_adapter("no_adapt", task=TASK)
    with pytest.raises(ValueError, match="canonical: must be 7 numbers"):
        a.encode([1, 2], None)
    with pytest.raises(ValueError, match=r"canonical: must be finite"):
        a.encode(np.full(7, np.nan), None)
    # what JSON cannot hold, and integers the adapters' ints cannot (2**32 + 3 used to run as 3)
    with pytest.raises(ValueError, match=r"^params: NaN and infinity are not allowed"):
        actionshift.make_adapter("dualabi", task=TASK, pool="reference9", params={"tau": float("nan")})
    with pytest.raises(ValueError, match=r"budget: out of range \(got 4294967299\)"):
        actionshift.make_adapter("fixed_probes", task=TASK, pool="reference9", params={"budget": 2 ** 32 + 3})
    with pytest.raises(ValueError, match=r"window: must be in \[1, 1000\]"):
        actionshift.make_adapter("dualabi", task=TASK, pool="reference9", params={"window": 10 ** 7})
    with pytest.raises(ValueError, match="unknown task 'nope'"):
        actionshift.make_adapter("no_adapt", task="nope")
    with pytest.raises(TypeError, match="pool: expected a pool name, a manifest path or a list of contracts"):
        actionshift.make_adapter("exact_belief", task=TASK, pool=5)
    assert actionshift.method_params("entropy_probes")["budget"] == 6
