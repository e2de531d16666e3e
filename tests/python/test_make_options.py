"""make()/make_vec() take the CLI's environment options (robot, packages, obs_noise, calibration),
a float32 dtype, and pickle by construction arguments and seed state."""
import os
import pickle

import numpy as np
import pytest

import actionshift


@pytest.fixture(scope="module")
def panda_urdf(source_dir):
    return os.path.join(source_dir, "configs", "robots", "panda.urdf")


def test_robot_as_the_cli_takes_it(panda_urdf):
    embedded = actionshift.make("pick_cube")
    as_file = actionshift.make("pick_cube", robot=panda_urdf)
    assert embedded.robot_sha256 is None and len(as_file.robot_sha256) == 64
    # the embedded Panda is this file: the same description gives the same episode
    a, b = embedded.reset(seed=3)[0], as_file.reset(seed=3)[0]
    assert np.array_equal(a, b)
    act = np.array([0.4, 0.2, -0.3, 0.1, 0.0, 0.1, -1.0])
    assert np.array_equal(embedded.step(act)[0], as_file.step(act)[0])
    vec = actionshift.make_vec("pick_cube", num_envs=2, robot=panda_urdf)
    assert vec.robot_sha256 == as_file.robot_sha256
    with pytest.raises(ValueError, match="packages: need robot="):
        actionshift.make("pick_cube", packages={"franka": "/tmp"})
    with pytest.raises(ValueError) as e:
        actionshift.make("pick_cube", robot="/nonexistent/robot.urdf")
    assert "/nonexistent/robot.urdf" in str(e.value) and "\n" not in str(e.value)
    with pytest.raises(ValueError, match="--package"):
        actionshift.make("pick_cube", robot=panda_urdf, packages=["no-equals-sign"])
    with pytest.raises(TypeError, match="make: robot: expected str or PathLike or None"):
        actionshift.make("pick_cube", robot=3)


def test_obs_noise_as_the_cli_takes_it():
    clean = actionshift.make("pick_cube").reset(seed=5)[0]
    noisy1 = actionshift.make("pick_cube", obs_noise=0.01).reset(seed=5)[0]
    noisy2 = actionshift.make_vec("pick_cube", num_envs=1, obs_noise=0.01).reset(seed=5)[0][0]
    assert not np.array_equal(clean, noisy1) and np.array_equal(noisy1, noisy2)
    assert np.abs(noisy1 - clean).max() < 0.1
    for bad in (-0.1, 0.2, float("nan")):
        with pytest.raises(ValueError, match=r"make: obs_noise: must be a finite sigma in \[0, 0.1\]"):
            actionshift.make("pick_cube", obs_noise=bad)
    with pytest.raises(TypeError, match="obs_noise"):
        actionshift.make("pick_cube", obs_noise="0.01")


def test_calibration_is_checked_and_kept_for_adapters(source_dir):
    path = os.path.join(source_dir, "configs", "calibration", "maniskill", "pick_cube.json")
    env = actionshift.make("pick_cube", calibration=path)
    assert env.calibration["task"] == "pick_cube" and len(env.calibration["alpha"]) == 6
    adapter = actionshift.make_adapter("entropy_probes", task="pick_cube", pool="reference9", calibration=env.calibration)
    assert adapter.name
    assert actionshift.make("pick_cube").calibration is None
    with pytest.raises(ValueError, match="task: is pick_cube, not the environment's push_cube"):
        actionshift.make("push_cube", calibration=path)
    with pytest.raises(ValueError, match="profile"):
        actionshift.make("pick_cube", profile="ideal", calibration=path)


def test_float32_observations_and_spaces():
    env = actionshift.make("pick_cube", dtype="float32")
    obs, _ = env.reset(seed=1)
    assert obs.dtype == np.float32 and env.observation_space.dtype == np.float32
    assert env.action_space.dtype == np.float32
    assert env.step(env.action_space.sample())[0].dtype == np.float32
    ref = actionshift.make("pick_cube").reset(seed=1)[0]
    assert np.array_equal(obs, ref.astype(np.float32))
    vec = actionshift.make_vec("pick_cube", num_envs=2, dtype=np.float32)
    assert vec.single_observation_space.dtype == np.float32 and vec.single_action_space.shape == (7,)
    obs, _ = vec.reset(seed=1)
    obs, *_, info = vec.step(np.zeros((2, 7), dtype=np.float32))
    assert obs.dtype == np.float32 and info["final_obs"].dtype == np.float32
    with pytest.raises(ValueError, match="dtype: must be 'float64'"):
        actionshift.make("pick_cube", dtype="float16")


def test_environments_pickle_by_construction_arguments_and_seed_state(panda_urdf):
    env = actionshift.make("pick_cube", split="reference_seen", index=1, obs_noise=0.005, robot=panda_urdf,
                           dtype="float32", ignore_terminations=False)
    env.reset(seed=11)
    env.step(np.zeros(7))
    copy = pickle.loads(pickle.dumps(env))
    assert copy.robot_sha256 == env.robot_sha256 and copy.ignore_terminations is False
    # an unpickled environment is at an episode boundary: reset() continues the same seed sequence
    with pytest.raises(RuntimeError, match=r"before reset\(\)"):
        copy.step(np.zeros(7))
    a, ia = env.reset()
    b, ib = copy.reset()
    assert ia["seed"] == ib["seed"] and np.array_equal(a, b) and b.dtype == np.float32
    act = np.array([0.3, -0.2, 0.1, 0.0, 0.0, 0.2, 1.0])
    assert np.array_equal(env.step(act)[0], copy.step(act)[0])  # the same hidden contract
    contract = actionshift.Contract(sign=[-1, 1, 1, 1, 1, 1])
    e2 = pickle.loads(pickle.dumps(actionshift.make("pick_cube", contract=contract)))
    e3 = actionshift.make("pick_cube", contract=contract)
    e2.reset(seed=2), e3.reset(seed=2)
    assert np.array_equal(e2.step(act)[0], e3.step(act)[0])
    vec = actionshift.make_vec("pick_cube", num_envs=2, split="seen", index=3, threads=1)
    vec.reset(seed=4)
    vcopy = pickle.loads(pickle.dumps(vec))
    assert vcopy.num_envs == 2 and vcopy.threads == 1
    assert np.array_equal(vec.reset()[0], vcopy.reset()[0])
