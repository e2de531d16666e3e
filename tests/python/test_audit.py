"""The log audit from Python: arrays or an .npz recorded from the simulator under a hidden wiring,
the same report as `actionshift audit --json`, and one-line errors for bad arrays."""
import numpy as np
import pytest

import actionshift

TASK = "pick_cube"


def record(contract, episodes=8, steps=50, seed=7):
    """Smooth random raw commands through the hidden wiring: rows (episode, action, pose before it)."""
    rng = np.random.default_rng(seed)
    env = actionshift.make(TASK, contract=contract)
    ids, acts, pos, quat, fing = [], [], [], [], []
    for e in range(episodes):
        obs, _ = env.reset(seed=1000 + e)
        x = np.zeros(6)
        for _ in range(steps):
            x = np.clip(0.8 * x + 0.36 * rng.standard_normal(6), -0.6, 0.6)
            a = np.concatenate([x, [1.0]])
            tcp = env.field(obs, "tcp_pose")
            ids.append(e)
            acts.append(a)
            pos.append(tcp[:3])
            quat.append(tcp[3:])
            fing.append(env.field(obs, "qpos")[7:9])
            obs, *_ = env.step(a)
    return dict(episode=np.array(ids), actions=np.array(acts), tcp_pos=np.array(pos), tcp_quat=np.array(quat),
                fingers=np.array(fing))


def test_swapped_axes_is_a_mismatch_and_npz_gives_the_same_report(tmp_path):
    library = dict(actionshift.selftest_library())
    log = record(library["swapped-axes"])
    r = actionshift.audit(**log, declared="identity", model=TASK)
    assert r["status"] == "MISMATCH", r["reason"]
    got = r["fields"]["permutation"]["identified"].strip("()").split(", ")
    assert got[0] == "1" or got[1] == "0", got  # x and y read each other's raw channel (one at least committed)
    assert all(g in ("?", t) for g, t in zip(got, ["1", "0", "2", "3", "4", "5"]))
    assert r["exit_code"] == 1
    # the same log as an .npz
    path = tmp_path / "log.npz"
    np.savez(path, **log)
    r2 = actionshift.audit(str(path), declared="identity", model=TASK)
    assert r2["reason"] == r["reason"] and r2["evidence_t"] == r["evidence_t"]
    # declared the truth: never a MISMATCH
    r3 = actionshift.audit(**log, declared=library["swapped-axes"], model=TASK)
    assert r3["status"] in ("PASS", "INCONCLUSIVE"), r3["reason"]
    # no calibration: scale is not checked
    r4 = actionshift.audit(**log, declared="identity")
    assert r4["model_fitted"] and not r4["fields"]["scale"]["checked"]


def test_bad_arrays_are_one_line_errors(tmp_path):
    log = record(actionshift.Contract.identity(), episodes=1, steps=5)
    log["actions"][3, 2] = np.nan
    with pytest.raises(actionshift.InputError, match=r"^arrays: actions: row 3: not a finite number$"):
        actionshift.audit(**log)
    with pytest.raises(actionshift.InputError, match="must be a path to an .npz"):
        actionshift.audit(tmp_path / "x.csv")
    np.savez(tmp_path / "y.npz", actions=np.zeros((3, 7)))
    with pytest.raises(actionshift.InputError, match=r"y.npz: tcp_pos: missing array"):
        actionshift.audit(str(tmp_path / "y.npz"))
    # not numbers: one line naming the array, not numpy's ValueError
    good = record(actionshift.Contract.identity(), episodes=1, steps=5)
    with pytest.raises(actionshift.InputError, match=r"^arrays: actions: not an array of numbers \(could not convert string"):
        actionshift.audit(**dict(good, actions=np.full((5, 7), "x")))
    with pytest.raises(actionshift.InputError, match=r"^arrays: tcp_pos: not an array of numbers \(setting an array element"):
        actionshift.audit(**dict(good, tcp_pos=[[0.0, 0.0, 0.0], [0.0]] * 2 + [[0.0, 0.0, 0.0]]))
    np.savez(tmp_path / "obj.npz", **dict(good, fingers=np.array([[0.0, 0.0], None] * 2 + [[0.0, 0.0]], dtype=object)))
    with pytest.raises(actionshift.InputError, match=r"obj.npz: fingers: cannot be read \(Object arrays cannot be loaded"):
        actionshift.audit(str(tmp_path / "obj.npz"))


def test_without_fingers_the_gripper_polarity_is_not_checked(tmp_path):
    # as the CLI does for a log without finger positions (a CSV without finger_0/finger_1)
    log = record(actionshift.Contract.identity(), episodes=4)
    del log["fingers"]
    r = actionshift.audit(**log, declared="identity", model=TASK)
    g = r["fields"]["gripper_inverted"]
    assert not g["checked"] and "no finger positions" in g["reason"], g
    assert r["status"] in ("PASS", "INCONCLUSIVE"), r["reason"]
    # the same .npz without a fingers array, with and without episode ids
    np.savez(tmp_path / "nofingers.npz", **log)
    r2 = actionshift.audit(str(tmp_path / "nofingers.npz"), declared="identity", model=TASK)
    assert r2["reason"] == r["reason"] and not r2["fields"]["gripper_inverted"]["checked"]
    one = {k: v[log["episode"] == 0] for k, v in log.items() if k != "episode"}
    r3 = actionshift.audit(**one, declared="identity", model=TASK)
    assert not r3["fields"]["gripper_inverted"]["checked"], r3["fields"]["gripper_inverted"]
