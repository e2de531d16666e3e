"""One episode-end rule for Env, VecEnv and the library's runner: episodes end at the horizon or at a
safety flag (success does not end them; ignore_terminations=True, the default), or also at the first
success (ignore_terminations=False). The same seeds stepped through Env and VecEnv give the same
observations, rewards, flags and info keys, and the runner's records (evaluate()) equal what Env reports."""
import json
import os
import sys

import numpy as np
import pytest

import actionshift

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from simple_policy import ReachGraspLift  # noqa: E402

INFO_KEYS = {"success", "success_once", "success_at_end", "safety", "elapsed_steps", "episode_return", "clipped_steps"}


def _compare(info_vec, i, info_env):
    for k in INFO_KEYS:
        a, b = info_vec[k][i], info_env[k]
        assert (a == b) if not isinstance(b, float) else a == pytest.approx(b, abs=0), (k, a, b)


@pytest.mark.parametrize("ignore_terminations", [True, False])
def test_env_and_vec_env_step_the_same_seeds_alike(ignore_terminations):
    n, seed = 3, 40
    vec = actionshift.make_vec("pick_cube", num_envs=n, threads=2, ignore_terminations=ignore_terminations)
    envs = [actionshift.make("pick_cube", ignore_terminations=ignore_terminations) for _ in range(n)]
    pols_vec = [ReachGraspLift() for _ in range(n)]
    pols_env = [ReachGraspLift() for _ in range(n)]
    obs, info = vec.reset(seed=seed)
    assert INFO_KEYS | {"seed"} <= set(info)
    singles = [e.reset(seed=seed + i) for i, e in enumerate(envs)]
    for i, (o, inf) in enumerate(singles):
        assert np.array_equal(obs[i], o)
        _compare(info, i, inf)
    single_obs = [o for o, _ in singles]
    ends, successes_ending = 0, 0
    for t in range(2 * envs[0].horizon + 5):  # through an autoreset of every environment
        actions = np.stack([p(obs[i]) for i, p in enumerate(pols_vec)])
        obs, reward, terminated, truncated, info = vec.step(actions)
        assert INFO_KEYS <= set(info)
        for i, env in enumerate(envs):
            a = pols_env[i](single_obs[i])
            assert np.array_equal(a, actions[i])
            o, r, te, tr, inf = env.step(a)
            assert set(inf) == INFO_KEYS
            assert reward[i] == r and terminated[i] == te and truncated[i] == tr
            _compare(info, i, inf)
            if ignore_terminations:
                assert not te, "success must not end an episode under ignore_terminations=True"
            elif inf["success"]:
                assert te
            if te or tr:
                ends += 1
                successes_ending += int(te and inf["success"])
                assert info["_final_obs"][i] and info["autoreset"][i] and info["_final_info"][i]
                assert np.array_equal(info["final_obs"][i], o)
                _compare(info["final_info"], i, inf)
                # the vector env reset it at once with the next seed of its sequence; Env's reset() does the same
                o, _ = env.reset()
                pols_env[i].reset()
                pols_vec[i].reset()
            else:
                assert not info["_final_obs"][i]
                assert np.array_equal(info["final_obs"][i], o)
            assert np.array_equal(obs[i], o)
            single_obs[i] = o
    assert ends >= n
    if ignore_terminations:
        assert successes_ending == 0
    else:
        assert successes_ending >= 1, "the policy should succeed at least once (it lifts the cube)"


def test_ignore_terminations_true_runs_to_the_horizon_after_success():
    env = actionshift.make("pick_cube")
    pol = ReachGraspLift()
    obs, _ = env.reset(seed=41)
    seen_success, steps = False, 0
    while True:
        obs, _, terminated, truncated, info = env.step(pol(obs))
        steps += 1
        seen_success = seen_success or info["success"]
        if terminated or truncated:
            break
    assert seen_success and truncated and not terminated and steps == env.horizon
    assert info["success_once"] and info["elapsed_steps"] == env.horizon
    # with ignore_terminations=False the same episode ends at its first success
    env2 = actionshift.make("pick_cube", ignore_terminations=False)
    pol.reset()
    obs, _ = env2.reset(seed=41)
    while True:
        obs, _, terminated, truncated, info2 = env2.step(pol(obs))
        if terminated or truncated:
            break
    assert terminated and info2["success"] and info2["elapsed_steps"] < env.horizon
    # stepping an ended episode returns its last result again
    again = env2.step(np.zeros(7))
    assert again[2] and again[4]["elapsed_steps"] == info2["elapsed_steps"]


def test_the_runner_records_what_env_reports(tmp_path):
    """evaluate() runs the library's runner (what `actionshift run` records); Env replaying the same
    contract, episode seed and actions reports the same success, return and steps."""
    seed, episodes = 7, 4
    r = actionshift.evaluate(ReachGraspLift(), task="pick_cube", split="reference_seen", method="oracle",
                             seed=seed, episodes=episodes, out=str(tmp_path), threads=1)
    records = [json.loads(line) for line in open(r["jsonl_path"])]
    assert len(records) == episodes
    contracts = actionshift.load_manifest("reference_seen").contracts
    n = len(contracts)
    succeeded = 0
    for rec in records:
        c, k = rec["contract_index"], rec["episode_index"] // n
        env = actionshift.make("pick_cube", split="reference_seen", index=c)
        adapter = actionshift.make_adapter("oracle", task="pick_cube", truth=contracts[c])
        pol = ReachGraspLift()
        obs, _ = env.reset(seed=actionshift.episode_seed(seed, k))
        adapter.begin_episode(0)
        while True:
            R = actionshift.tcp_rotation(obs, "pick_cube")
            raw = adapter.encode(pol(obs), R)
            nxt, _, terminated, truncated, info = env.step(raw)
            adapter.observe(raw, actionshift.tcp_response(obs, nxt, "pick_cube"), R)
            obs = nxt
            if terminated or truncated:
                break
        assert info["success_once"] == rec["success_once"] and info["success_at_end"] == rec["success_at_end"], rec
        assert info["elapsed_steps"] == rec["steps"] and info["episode_return"] == rec["return"], rec
        assert (info["safety"] == "none") == (rec["safety_flags"] == [])
        succeeded += rec["success_once"]
    assert succeeded >= 1  # episodes that succeed ran on to the horizon in both
