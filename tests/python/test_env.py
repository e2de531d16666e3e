"""The Gymnasium API contract of actionshift.make(): types, shapes, spaces, seeding, horizon, safety."""
import math

import numpy as np
import pytest

import actionshift


def test_reset_returns_observation_of_the_declared_space():
    env = actionshift.make("pick_cube")
    obs, info = env.reset(seed=1)
    assert isinstance(obs, np.ndarray) and obs.dtype == np.float64
    assert obs.shape == env.observation_space.shape == (sum(f["width"] for f in env.layout),)
    assert env.action_space.shape == (7,)
    assert env.action_space.dtype == np.float64
    assert np.all(env.action_space.low == -1.0) and np.all(env.action_space.high == 1.0)
    assert np.all(np.isinf(env.observation_space.low)) and np.all(np.isinf(env.observation_space.high))
    assert isinstance(info, dict) and info["seed"] == 1 and info["elapsed_steps"] == 0
    assert env.horizon == 50


def test_same_seed_same_observation_other_seed_other_observation():
    a = actionshift.make("pick_cube")
    b = actionshift.make("pick_cube")
    oa, _ = a.reset(seed=7)
    ob, _ = b.reset(seed=7)
    assert np.array_equal(oa, ob)
    oc, _ = b.reset(seed=8)
    assert not np.array_equal(oa, oc)
    # seed=None continues a reproducible sequence
    a.reset(seed=5)
    n1, i1 = a.reset()
    a.reset(seed=5)
    n2, i2 = a.reset()
    assert np.array_equal(n1, n2) and i1["seed"] == i2["seed"] != 5
    # trajectories are deterministic too
    act = np.array([0.3, -0.2, 0.1, 0.0, 0.0, 0.2, 1.0])
    for env in (a, b):
        env.reset(seed=11)
    for _ in range(5):
        ra, rb = a.step(act), b.step(act)
        assert np.array_equal(ra[0], rb[0]) and ra[1] == rb[1]


def test_step_types_and_truncation_at_the_horizon():
    env = actionshift.make("push_cube")
    env.reset(seed=3)
    for t in range(1, env.horizon + 1):
        obs, reward, terminated, truncated, info = env.step(np.zeros(7))
        assert isinstance(obs, np.ndarray) and obs.shape == env.observation_space.shape
        assert isinstance(reward, float) and 0.0 <= reward <= 1.0
        assert isinstance(terminated, bool) and isinstance(truncated, bool)
        assert set(info) >= {"success", "success_once", "safety", "elapsed_steps"}
        assert info["elapsed_steps"] == t and info["safety"] == "none"
        assert truncated == (t == env.horizon)
        assert not terminated  # a resting arm does not push the cube


def test_observation_is_a_fresh_array_each_step():
    env = actionshift.make("pick_cube")
    first, _ = env.reset(seed=2)
    kept = first.copy()
    env.step(np.array([1.0, 0, 0, 0, 0, 0, 1]))
    assert np.array_equal(first, kept)


@pytest.mark.parametrize("action,flag", [
    ([math.nan, 0, 0, 0, 0, 0, 0], "nonfinite_action"),
    ([1e9, 0, 0, 0, 0, 0, 0], "action_out_of_range"),
])
def test_safety_flags_end_the_episode(action, flag):
    env = actionshift.make("pick_cube")
    env.reset(seed=1)
    obs, reward, terminated, truncated, info = env.step(np.asarray(action, dtype=float))
    assert terminated and not truncated
    assert info["safety"] == flag
    assert np.all(np.isfinite(obs))


@pytest.mark.parametrize("shape", [(6,), (8,), (0,), (), (1, 7), (7, 1), (2, 7)])
def test_every_wrong_action_shape_is_a_value_error_and_simulates_nothing(shape):
    # np.zeros(6) used to end the episode with the safety flag bad_action_shape while (1, 7) raised
    env = actionshift.make("pick_cube")
    env.reset(seed=1)
    with pytest.raises(ValueError, match=r"action: must have shape \(7,\) \(got"):
        env.step(np.zeros(shape))
    obs, reward, terminated, truncated, info = env.step(np.zeros(7))  # the episode goes on
    assert info["elapsed_steps"] == 1 and info["safety"] == "none" and not terminated


def test_hidden_contract_remaps_actions_and_is_not_observable():
    flipped = actionshift.Contract(sign=[-1, 1, 1, 1, 1, 1])
    plain = actionshift.make("pick_cube")
    hidden = actionshift.make("pick_cube", contract=flipped)
    assert not hasattr(hidden, "contract") and not hasattr(hidden._env, "contract")
    push_x = np.array([1.0, 0, 0, 0, 0, 0, 1])
    moves = []
    for env in (plain, hidden):
        obs0, _ = env.reset(seed=4)
        obs1 = env.step(push_x)[0]
        moves.append(env.field(obs1, "tcp_pose")[0] - env.field(obs0, "tcp_pose")[0])
    assert moves[0] > 0.02 and moves[1] < -0.02


def test_split_contract_by_index_matches_the_explicit_contract():
    seen = actionshift.load_manifest("seen")
    a = actionshift.make("pick_cube", split="seen", index=5)
    b = actionshift.make("pick_cube", contract=seen.contracts[5])
    raw = np.array([0.4, -0.3, 0.2, 0.1, -0.1, 0.2, -1.0])
    a.reset(seed=9)
    b.reset(seed=9)
    for _ in range(3):
        assert np.array_equal(a.step(raw)[0], b.step(raw)[0])


def test_bad_arguments_raise_value_errors():
    with pytest.raises(ValueError, match="task"):
        actionshift.make("pick_banana")
    with pytest.raises(ValueError, match="index: out of range"):
        actionshift.make("pick_cube", split="seen", index=10_000)
    with pytest.raises(ValueError, match="profile"):
        actionshift.make("pick_cube", profile="no_such_profile")
    with pytest.raises(ValueError, match="rotation"):
        actionshift.make("pick_cube", rotation="sideways")
    env = actionshift.make("pick_cube")
    with pytest.raises(ValueError, match="seed"):
        env.reset(seed=-1)
    env.reset(seed=0)
    with pytest.raises(ValueError, match="action"):
        env.step(np.zeros((2, 7)))


def one_line(excinfo):
    return "\n" not in str(excinfo.value)


def test_actions_must_be_real_numbers():
    # numpy's forcecast turned complex actions into their real part and "0.5" into 0.5
    env = actionshift.make("pick_cube")
    env.reset(seed=0)
    for bad in (np.zeros(7, dtype=complex), ["0.5"] * 7, np.array(["0"] * 7), [object()] * 7):
        with pytest.raises(ValueError, match="action: must hold real numbers") as e:
            env.step(bad)
        assert one_line(e)
    for good in (np.zeros(7, dtype=np.float32), [0] * 7, np.zeros(7, dtype=np.int8), (0.0,) * 7):
        env.step(good)
    envs = actionshift.make_vec("pick_cube", 2)
    envs.reset(seed=0)
    with pytest.raises(ValueError, match="actions: must hold real numbers"):
        envs.step(np.zeros((2, 7), dtype=complex))
    adapter = actionshift.make_adapter("no_adapt", task="pick_cube")
    with pytest.raises(ValueError, match="canonical: must hold real numbers"):
        adapter.encode(["1"] * 7, None)


def test_step_before_reset_raises_instead_of_crashing():
    # a fresh env has no robot in its Bullet world until the first reset (this used to segfault)
    env = actionshift.make("push_cube")
    with pytest.raises(RuntimeError, match=r"step: called before reset\(\)") as e:
        env.step(np.zeros(7))
    assert one_line(e)
    env.reset(seed=1)
    assert env.step(np.zeros(7))[4]["safety"] == "none"


@pytest.mark.parametrize("seed", [-1, 2 ** 64, 1.5, "7", True, np.zeros(3)])
def test_out_of_range_or_non_integer_seeds_are_one_line_value_errors(seed):
    env = actionshift.make("pick_cube")
    with pytest.raises(ValueError, match=r"seed: must be an integer in \[0, 2\*\*64\)") as e:
        env.reset(seed=seed)
    assert one_line(e)
    with pytest.raises(ValueError, match=r"episode_seed: must be an integer") as e:
        actionshift.make_adapter("no_adapt").begin_episode(seed)
    assert one_line(e)


def test_largest_seed_and_numpy_integer_seeds_are_accepted():
    env = actionshift.make("pick_cube")
    assert env.reset(seed=2 ** 64 - 1)[1]["seed"] == 2 ** 64 - 1
    assert np.array_equal(env.reset(seed=np.int64(5))[0], env.reset(seed=5)[0])
    actionshift.make_adapter("no_adapt").begin_episode(np.uint64(3))


@pytest.mark.parametrize("options", [{"contract": "identity"}, {"x": 1, "a": 2}, "seed=3", [1]])
def test_reset_options_are_refused_not_ignored(options):
    env = actionshift.make("pick_cube")
    vec = actionshift.make_vec("pick_cube", 2)
    for e in (env, vec):
        with pytest.raises(ValueError, match=r"options: this environment takes no reset options") as err:
            e.reset(seed=1, options=options)
        assert one_line(err)
    assert np.array_equal(env.reset(seed=1, options={})[0], env.reset(seed=1, options=None)[0])
    vec.reset(seed=1, options={})


@pytest.mark.parametrize("kwargs, error, pattern", [
    ({"task": None}, TypeError, "make: task: expected str"),
    ({"split": 3}, TypeError, "make: split: expected str or None"),
    ({"index": "0"}, TypeError, "make: index: expected int"),
    ({"split": "seen", "index": 2 ** 70}, ValueError, "make: index: out of range"),
    ({"index": 3}, ValueError, "make: index: selects a split's contract: give split= too"),
])
def test_constructor_arguments_of_the_wrong_type_are_one_line_errors(kwargs, error, pattern):
    args = {"task": "pick_cube", **kwargs}
    with pytest.raises(error, match=pattern) as e:
        actionshift.make(**args)
    assert one_line(e)


def test_gymnasium_registration_when_available():
    gym = pytest.importorskip("gymnasium", reason="gymnasium is not installed (optional; the module works without it)")
    env = gym.make("ActionShift/PickCube-v1")
    assert isinstance(env.unwrapped, gym.Env)
    obs, _ = env.reset(seed=1)
    assert obs.shape == env.observation_space.shape
