"""Rendering from Python: make(render_mode="rgb_array") and env.render() draw with the CLI's OSMesa
renderer and cameras, and write_frames writes the PNG and GIF `actionshift render` writes; the
files are compared byte for byte with the CLI's for the same episode."""
import json
import os
import sys
import warnings

import numpy as np
import pytest

import actionshift

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
from simple_policy import ReachGraspLift  # noqa: E402

SEED = 20260718  # the job seed of `actionshift run` / `render` by default


def test_render_returns_an_rgb_frame_of_the_chosen_size():
    assert "rgb_array" in actionshift.Env.metadata["render_modes"]
    env = actionshift.make("pick_cube", render_mode="rgb_array")
    env.reset(seed=1)
    frame = env.render()
    assert frame.shape == (240, 320, 3) and frame.dtype == np.uint8
    assert len(np.unique(frame.reshape(-1, 3), axis=0)) > 20  # a scene, not a blank image
    small = actionshift.make("pick_cube", render_mode="rgb_array", width=160, height=96, camera="top")
    small.reset(seed=1)
    assert small.render().shape == (96, 160, 3)
    # the frame follows the state: the arm moves, the picture changes
    before = frame.copy()
    for _ in range(5):
        env.step(np.array([1.0, 0, 0, 0, 0, 0, 1]))
    assert not np.array_equal(env.render(), before)


def test_render_arguments_and_modes():
    plain = actionshift.make("pick_cube")
    plain.reset(seed=1)
    with warnings.catch_warnings(record=True) as w:
        warnings.simplefilter("always")
        assert plain.render() is None
    assert any("render_mode" in str(x.message) for x in w)
    with pytest.raises(ValueError, match="render_mode: must be None or 'rgb_array'"):
        actionshift.make("pick_cube", render_mode="human")
    with pytest.raises(ValueError, match="width: must be in 16..4096"):
        actionshift.make("pick_cube", render_mode="rgb_array", width=8)
    with pytest.raises(ValueError, match="make: camera:"):
        actionshift.make("pick_cube", render_mode="rgb_array", camera="sideways")
    env = actionshift.make("pick_cube", render_mode="rgb_array")
    with pytest.raises(RuntimeError, match=r"render: called before reset\(\)"):
        env.render()


def test_write_frames_errors(tmp_path):
    frame = np.zeros((20, 30, 3), dtype=np.uint8)
    with pytest.raises(ValueError, match="must end in .gif or .png"):
        actionshift.write_frames(tmp_path / "x.jpg", [frame])
    with pytest.raises(ValueError, match="no frame"):
        actionshift.write_frames(tmp_path / "x.png", [])
    with pytest.raises(ValueError, match=r"frames\[0\]: must be a numpy uint8 array"):
        actionshift.write_frames(tmp_path / "x.png", [frame.astype(float)])
    with pytest.raises(ValueError, match=r"frames\[1\]: has another size"):
        actionshift.write_frames(tmp_path / "x.gif", [frame, np.zeros((21, 30, 3), dtype=np.uint8)])
    with pytest.raises(ValueError, match="frame: 3 is outside 0..0"):
        actionshift.write_frames(tmp_path / "x.png", [frame], frame=3)


def _python_episode(contract_index, contract_episode, size):
    """An episode of the CLI's job (job seed SEED, no_adapt, the served ReachGraspLift) replayed through
    make(): the same contract, episode seed and actions; every frame from the reset on."""
    env = actionshift.make("pick_cube", split="reference_seen", index=contract_index, render_mode="rgb_array",
                           width=size[0], height=size[1])
    policy = ReachGraspLift()
    obs, _ = env.reset(seed=actionshift.episode_seed(SEED, contract_episode))
    policy.reset()
    frames = [env.render()]
    for _ in range(env.horizon):
        obs, _, terminated, truncated, info = env.step(policy(obs))  # no_adapt: the raw action is the intent
        frames.append(env.render())
        if terminated or truncated:
            break
    return frames, info


def test_python_frames_equal_the_clis_png_and_gif(cli, tmp_path):
    backbone = f"external:{sys.executable} {os.path.join(HERE, 'simple_policy.py')}"
    job = ["--task", "pick_cube", "--split", "reference_seen", "--method", "no_adapt", "--backbone", backbone,
           "--contract", "1", "--episode", "1", "--size", "160x120", "--no-overlay"]
    r = cli("render", *job, "--out", str(tmp_path / "cli.gif"), check=0)
    record = json.loads(r.stdout)  # the episode drawn: its contract and episode index (seed) in the job
    contracts = len(actionshift.load_manifest("reference_seen").contracts)
    frames, info = _python_episode(record["contract_index"], record["episode_index"] // contracts, (160, 120))
    assert record["steps"] == info["elapsed_steps"] == len(frames) - 1
    assert record["success_once"] == info["success_once"] and record["return"] == info["episode_return"]
    actionshift.write_frames(tmp_path / "py.gif", frames)
    assert (tmp_path / "py.gif").read_bytes() == (tmp_path / "cli.gif").read_bytes()
    for k in (0, 7, -1):  # after the reset, mid-episode, the last state
        cli("render", *job, "--frame", str(k), "--out", str(tmp_path / f"cli{k}.png"), check=0)
        actionshift.write_frames(tmp_path / f"py{k}.png", frames, frame=k)
        assert (tmp_path / f"py{k}.png").read_bytes() == (tmp_path / f"cli{k}.png").read_bytes(), f"frame {k}"
