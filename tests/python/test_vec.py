"""make_vec(): environments stepped together in C++ on worker threads, equal to single envs."""
import numpy as np
import pytest

import actionshift


def test_vector_env_equals_single_envs_and_autoresets():
    vec = actionshift.make_vec("pick_cube", num_envs=3, split="seen", index=4, threads=2)
    assert vec.threads == 2 and vec.num_envs == 3
    obs, info = vec.reset(seed=10)
    assert obs.shape == (3,) + vec.single_observation_space.shape and list(info["seed"]) == [10, 11, 12]
    singles = [actionshift.make("pick_cube", split="seen", index=4 + i) for i in range(3)]
    for i, env in enumerate(singles):
        assert np.array_equal(env.reset(seed=10 + i)[0], obs[i])
    rng = np.random.default_rng(0)
    for t in range(1, vec.horizon + 1):
        actions = rng.uniform(-0.5, 0.5, size=(3, 7))
        obs, reward, terminated, truncated, info = vec.step(actions)
        for i, env in enumerate(singles):
            o, r, te, tr, inf = env.step(actions[i])
            assert np.array_equal(info["final_obs"][i], o) and reward[i] == r
            assert terminated[i] == te and truncated[i] == tr and info["safety"][i] == inf["safety"]
        if t < vec.horizon:
            assert not info["autoreset"].any() or terminated.any()
    assert truncated.all() and info["autoreset"].all()
    # ended environments were reset: the new rows are first observations, not the final ones
    assert not np.array_equal(obs, info["final_obs"])


def test_vector_env_errors():
    with pytest.raises(ValueError, match="num_envs"):
        actionshift.make_vec("pick_cube", num_envs=0)
    # a million Bullet worlds (about 0.2 MB each) would exhaust memory: refused before any is built
    with pytest.raises(ValueError, match=f"num_envs: must be between 1 and {actionshift.MAX_NUM_ENVS}"):
        actionshift.make_vec("pick_cube", num_envs=10 ** 6)
    with pytest.raises(ValueError, match="threads"):
        actionshift.make_vec("pick_cube", num_envs=2, threads=-1)
    vec = actionshift.make_vec("pick_cube", num_envs=2)
    # environment i gets seed + i: a base seed whose last environment would wrap past 2**64 is refused
    with pytest.raises(ValueError, match=r"seed \+ num_envs - 1 must be below 2\*\*64"):
        vec.reset(seed=2 ** 64 - 1)
    with pytest.raises(ValueError, match=r"seed \+ num_envs - 1 must be below 2\*\*64"):
        vec.reset(seed=np.uint64(2 ** 64 - 1))  # numpy's own uint64 sum would wrap
    # stepping before the first reset used to segfault
    with pytest.raises(RuntimeError, match=r"step: called before reset\(\)"):
        vec.step(np.zeros((2, 7)))
    vec.reset(seed=0)
    with pytest.raises(ValueError, match=r"actions: must have shape \(2, 7\)"):
        vec.step(np.zeros((3, 7)))
