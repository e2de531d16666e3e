"""The audit's robomimic HDF5 layout (docs/audit.md, Formats) as its writers write it: the files are made
by h5py itself (Debian python3-h5py), the way robomimic and other writers call it, and read by
`actionshift audit` (the HDF5 readers are not in the Python module). The motion is synthetic: robosuite's
OSC_POSE delta convention (deltas in the frame of the logged poses, axis-angle, gripper -1 opens), so the
declaration the file carries decides the verdict."""
import json

import numpy as np
import pytest

try:
    import h5py
except ImportError:  # not a skip: these files are the only test of the layout as h5py writes it
    pytest.fail("python3-h5py is not installed (scripts/setup installs it)", pytrace=False)

# robosuite >= 1.5's composite BASIC controller as it lands in env_args (robosuite's loader flattens
# body_parts_controller_configs' "arms" into body_parts; the arm part keeps its own keys)
OSC_PART = {
    "type": "OSC_POSE", "input_max": 1, "input_min": -1,
    "output_max": [0.05, 0.05, 0.05, 0.5, 0.5, 0.5], "output_min": [-0.05, -0.05, -0.05, -0.5, -0.5, -0.5],
    "kp": 150, "damping_ratio": 1, "impedance_mode": "fixed", "kp_limits": [0, 300], "damping_ratio_limits": [0, 10],
    "position_limits": None, "orientation_limits": None, "uncouple_pos_ori": True, "control_delta": True,
    "interpolation": None, "ramp_ratio": 0.2, "gripper": {"type": "GRIP"},
}
TORSO = {"type": "JOINT_POSITION", "input_max": 1, "input_min": -1, "output_max": 0.5, "output_min": -0.5,
         "kd": 200, "kv": 200, "kp": 1000, "velocity_limits": [-1, 1], "kp_limits": [0, 1000],
         "interpolation": None, "ramp_ratio": 0.2}


def composite(**arm):
    part = dict(OSC_PART, **arm)
    part = {k: v for k, v in part.items() if v is not None or k not in arm}
    return {"type": "BASIC", "body_parts": {"right": part, "left": dict(OSC_PART), "torso": TORSO,
                                             "base": {"type": "JOINT_VELOCITY", "interpolation": "null"}}}


def env_args(controller_configs):
    return {"env_name": "Lift", "env_version": "1.5.1", "type": 1,
            "env_kwargs": {"robots": ["Panda"], "control_freq": 20, "controller_configs": controller_configs}}


def quat_mul(a, b):  # x y z w
    ax, ay, az, aw = a
    bx, by, bz, bw = b
    return np.array([aw * bx + ax * bw + ay * bz - az * by, aw * by - ax * bz + ay * bw + az * bx,
                     aw * bz + ax * by - ay * bx + az * bw, aw * bw - ax * bx - ay * by - az * bz])


def rotvec_quat(v):  # x y z w
    angle = np.linalg.norm(v)
    if angle < 1e-12:
        return np.array([0.0, 0.0, 0.0, 1.0])
    return np.concatenate([np.sin(angle / 2) * v / angle, [np.cos(angle / 2)]])


def demos(episodes=8, steps=50, seed=3, gripper=True, rotate=True):
    """Per demo (actions T x 7, eef_pos T+1 x 3, eef_quat T+1 x 4 (x y z w), gripper_qpos T+1 x 2)."""
    rng = np.random.default_rng(seed)
    out = []
    for _ in range(episodes):
        a = np.zeros((steps, 7))
        x = np.zeros(6)
        for t in range(steps):
            x = np.clip(0.8 * x + 0.36 * rng.standard_normal(6), -0.6, 0.6)
            a[t, :6] = x if rotate else np.concatenate([x[:3], np.zeros(3)])
            a[t, 6] = 1.0 if (t // 10) % 2 else -1.0
        pos = [np.array([-0.1, 0.0, 1.0])]
        quat = [np.array([1.0, 0.0, 0.0, 0.0])]  # x y z w: gripper pointing down
        fing = [np.array([0.02, -0.02])]
        for t in range(steps):
            pos.append(pos[-1] + 0.03 * a[t, :3] + 1e-4 * rng.standard_normal(3))
            q = quat_mul(rotvec_quat(0.05 * a[t, 3:6] + 1e-4 * rng.standard_normal(3)), quat[-1])
            quat.append(q / np.linalg.norm(q))
            f = 0.02 - 0.015 * a[t, 6] + 2e-4 * rng.standard_normal()  # -1 opens: fingers apart
            fing.append(np.array([f, -f]))
        out.append((a if gripper else a[:, :6], np.array(pos), np.array(quat), np.array(fing)))
    return out


def write_robomimic(path, episodes, env_args_value=None, dtype=np.float64, next_obs=True, gripper_qpos=True):
    """A robomimic-layout file as robomimic's dataset writers make it with h5py."""
    with h5py.File(path, "w") as f:
        data = f.create_group("data")
        if env_args_value is not None:
            data.attrs["env_args"] = env_args_value
        data.attrs["total"] = sum(len(e[0]) for e in episodes)
        for i, (a, pos, quat, fing) in enumerate(episodes):
            g = data.create_group(f"demo_{i}")
            g.attrs["num_samples"] = len(a)
            g.create_dataset("actions", data=a.astype(dtype))
            for name, rows in (("obs", slice(0, len(a))), ("next_obs", slice(1, len(a) + 1))):
                if name == "next_obs" and not next_obs:
                    continue
                o = g.create_group(name)
                o.create_dataset("robot0_eef_pos", data=pos[rows].astype(dtype))
                o.create_dataset("robot0_eef_quat", data=quat[rows].astype(dtype))
                if gripper_qpos:
                    o.create_dataset("robot0_gripper_qpos", data=fing[rows].astype(dtype))
    return str(path)


def audit(cli, path, *args):
    p = cli("audit", path, "--json", *args)
    assert p.returncode in (0, 1, 3), f"exit {p.returncode}: {p.stderr}"
    return json.loads(p.stdout)


def input_error(cli, path, *args):
    p = cli("audit", path, *args)
    assert p.returncode == 2, f"exit {p.returncode}, expected an input error\n{p.stdout}{p.stderr}"
    lines = p.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("actionshift: error: "), p.stderr
    return lines[0][len("actionshift: error: "):]


# ---- 1. env_args as h5py writes it


def test_env_args_as_a_python_str_is_read(cli, tmp_path):
    # robomimic: f["data"].attrs["env_args"] = json.dumps(env_meta): h5py stores a variable-length UTF-8 string
    path = write_robomimic(tmp_path / "vlen.hdf5", demos(), json.dumps(env_args({"type": "OSC_POSE"})))
    with h5py.File(path) as f:
        tid = f["data"].attrs.get_id("env_args").get_type()
        assert tid.is_variable_str() and tid.get_cset() == h5py.h5t.CSET_UTF8
    r = audit(cli, path)
    assert r["declared_from"] == "robomimic env_args controller OSC_POSE", r["declared_from"]
    assert r["status"] == "PASS", r["reason"]


def test_env_args_as_numpy_bytes_is_read(cli, tmp_path):
    # other writers: a fixed-length ASCII string exactly as long as the text (no terminating NUL)
    path = write_robomimic(tmp_path / "fixed.hdf5", demos(), np.bytes_(json.dumps(env_args({"type": "OSC_POSE"}))))
    with h5py.File(path) as f:
        tid = f["data"].attrs.get_id("env_args").get_type()
        assert not tid.is_variable_str() and tid.get_size() == len(json.dumps(env_args({"type": "OSC_POSE"})))
    r = audit(cli, path)
    assert r["declared_from"] == "robomimic env_args controller OSC_POSE", r["declared_from"]
    assert r["status"] == "PASS", r["reason"]


def test_env_args_that_is_not_a_json_string_is_a_one_line_error(cli, tmp_path):
    where = "data attribute env_args"
    p = write_robomimic(tmp_path / "int.hdf5", demos(1, 5), 42)
    assert input_error(cli, p) == f"{p}: {where}: not a string (an HDF5 integer attribute)"
    p = write_robomimic(tmp_path / "text.hdf5", demos(1, 5), "not json {")
    assert input_error(cli, p).startswith(f"{p}: {where}: not valid JSON: ")
    p = write_robomimic(tmp_path / "list.hdf5", demos(1, 5), json.dumps([1, 2]))
    assert input_error(cli, p) == f"{p}: {where}: not a JSON object"
    p = write_robomimic(tmp_path / "two.hdf5", demos(1, 5), [json.dumps(env_args({})), "x"])
    assert input_error(cli, p) == f"{p}: {where}: 2 strings, expected one"


# ---- 2. robosuite's controllers: before 1.5 the arm's own config, from 1.5 a composite controller


def declared_from(cli, path):
    return audit(cli, path)["declared_from"]


def test_composite_controller_declares_from_its_arm_part(cli, tmp_path):
    log = demos()
    # robomimic's released 1.5 datasets: control_delta true, input_ref_frame world
    p = write_robomimic(tmp_path / "world.hdf5", log, json.dumps(env_args(composite(input_ref_frame="world"))))
    r = audit(cli, p)
    assert r["declared_from"] == "robomimic env_args controller BASIC, arm part 'right': OSC_POSE, input_ref_frame world"
    assert r["status"] == "PASS", r["reason"]
    # robosuite 1.5's own default part config: input_type delta, input_ref_frame base
    p = write_robomimic(tmp_path / "base.hdf5", log,
                        json.dumps(env_args(composite(control_delta=None, input_type="delta", input_ref_frame="base"))))
    r = audit(cli, p)
    assert r["declared_from"] == "robomimic env_args controller BASIC, arm part 'right': OSC_POSE, input_ref_frame base"
    assert r["status"] == "PASS", r["reason"]
    # a robot with its left arm only
    cc = composite()
    cc["body_parts"] = {"left": cc["body_parts"]["left"]}
    p = write_robomimic(tmp_path / "left.hdf5", log, json.dumps(env_args(cc)))
    assert declared_from(cli, p) == "robomimic env_args controller BASIC, arm part 'left': OSC_POSE"
    # the flat config before 1.5, also as a one-robot list
    p = write_robomimic(tmp_path / "flat.hdf5", log, json.dumps(env_args([dict(OSC_PART, type="OSC_POSE")])))
    assert declared_from(cli, p) == "robomimic env_args controller OSC_POSE"


def test_absolute_targets_are_not_declared(cli, tmp_path):
    log = demos()
    refused = ("default (identity); robomimic env_args controller BASIC, arm part 'right': OSC_POSE{frame}: not declared: "
               "absolute targets ({key}): robosuite's is a pose in metres and axis-angle in the base or world frame, which "
               "neither the grammar's absolute target (normalised, from the episode's start) nor next_state (the next logged "
               "pose) states exactly; pass --declared")
    p = write_robomimic(tmp_path / "abs.hdf5", log,
                        json.dumps(env_args(composite(control_delta=None, input_type="absolute", input_ref_frame="world"))))
    r = audit(cli, p)
    assert r["declared_from"] == refused.format(frame=", input_ref_frame world", key="input_type absolute")
    # identity declared instead: the fingers show robosuite's inverted gripper
    assert r["status"] == "MISMATCH" and "gripper polarity differs" in r["reason"], r["reason"]
    p = write_robomimic(tmp_path / "cd.hdf5", log, json.dumps(env_args(composite(control_delta=False))))
    assert declared_from(cli, p) == refused.format(frame="", key="control_delta false")
    # the flat config before 1.5
    p = write_robomimic(tmp_path / "flat.hdf5", log, json.dumps(env_args(dict(OSC_PART, control_delta=False))))
    assert declared_from(cli, p).startswith(
        "default (identity); robomimic env_args controller OSC_POSE: not declared: absolute targets (control_delta false)")


def test_osc_position_and_other_controllers(cli, tmp_path):
    # OSC_POSITION: translation + gripper (4 columns), the orientation held
    log = [(a[:, [0, 1, 2, 6]], p, q, f) for a, p, q, f in demos(rotate=False)]
    p = write_robomimic(tmp_path / "pos.hdf5", log, json.dumps(env_args(composite(type="OSC_POSITION"))))
    r = audit(cli, p)
    assert r["declared_from"] == "robomimic env_args controller BASIC, arm part 'right': OSC_POSITION"
    assert r["status"] != "MISMATCH", r["reason"]
    # a width the controller does not take
    p = write_robomimic(tmp_path / "width.hdf5", log, json.dumps(env_args(composite())))
    assert declared_from(cli, p) == ("default (identity); robomimic env_args controller BASIC, arm part 'right': OSC_POSE: "
                                     "not declared: 4-column actions, but OSC_POSE takes 7 (or 6 without gripper); pass --declared")
    log = demos(2, 20)
    p = write_robomimic(tmp_path / "joint.hdf5", log, json.dumps(env_args(composite(type="JOINT_VELOCITY"))))
    assert declared_from(cli, p) == ("default (identity); robomimic env_args controller BASIC, arm part 'right': JOINT_VELOCITY: "
                                     "not declared: the audit reads robosuite's end-effector controllers OSC_POSE and "
                                     "OSC_POSITION; pass --declared")
    p = write_robomimic(tmp_path / "frame.hdf5", log, json.dumps(env_args(composite(input_ref_frame="eef"))))
    assert declared_from(cli, p).endswith("input_ref_frame eef: not declared: input_ref_frame 'eef' is neither base nor world; "
                                          "pass --declared")
    cc = composite()
    del cc["body_parts"]["right"], cc["body_parts"]["left"]
    p = write_robomimic(tmp_path / "noarm.hdf5", log, json.dumps(env_args(cc)))
    assert declared_from(cli, p) == ("default (identity); robomimic env_args controller BASIC: not declared: "
                                     "body_parts has no arm part (right or left); pass --declared")
    p = write_robomimic(tmp_path / "type.hdf5", log, json.dumps(env_args(composite(input_type="relative"))))
    assert input_error(cli, p) == (f"{p}: data attribute env_args: env_kwargs.controller_configs.body_parts.right.input_type: "
                                   "'relative' is neither delta nor absolute")


# ---- 4. plausible files: read, or one line naming the file, the dataset and the reason


def test_plausible_files_are_read(cli, tmp_path):
    ea = json.dumps(env_args({"type": "OSC_POSE"}))
    # demos of one step among longer ones, with next_obs (one transition each) and without (none)
    log = demos(6) + demos(2, 1, seed=5)
    r = audit(cli, write_robomimic(tmp_path / "t1.hdf5", log, ea))
    assert r["status"] == "PASS" and r["episodes"] == 8 and r["transitions"] == 6 * 50 + 2, (r["reason"], r["transitions"])
    r = audit(cli, write_robomimic(tmp_path / "t1_no_next.hdf5", log, ea, next_obs=False))
    assert r["status"] == "PASS" and r["transitions"] == 6 * 49, (r["reason"], r["transitions"])
    # float32 datasets throughout
    r = audit(cli, write_robomimic(tmp_path / "f32.hdf5", demos(), ea, dtype=np.float32))
    assert r["status"] == "PASS", r["reason"]
    # actions T x 6 (no gripper channel): the gripper fields are not checked
    r = audit(cli, write_robomimic(tmp_path / "cols6.hdf5", demos(gripper=False), ea))
    assert r["status"] == "PASS" and not r["fields"]["gripper_inverted"]["checked"], r["reason"]
    # no robot0_gripper_qpos: the polarity is not checked, the range still is
    r = audit(cli, write_robomimic(tmp_path / "nogrip.hdf5", demos(), ea, gripper_qpos=False))
    assert r["status"] == "PASS" and not r["fields"]["gripper_inverted"]["checked"], r["reason"]
    assert r["fields"]["gripper_range"]["checked"]


def test_implausible_files_are_one_line_errors(cli, tmp_path):
    ea = json.dumps(env_args({"type": "OSC_POSE"}))
    p = write_robomimic(tmp_path / "empty.hdf5", [], ea)
    assert input_error(cli, p) == f"{p}: data: no demo_N groups"
    p = write_robomimic(tmp_path / "t1only.hdf5", demos(2, 1), ea, next_obs=False)
    assert input_error(cli, p) == f"{p}: no transition (an episode needs two poses and an action between them)"
    # a demo_N that is not a group
    p = write_robomimic(tmp_path / "member.hdf5", demos(2, 10), ea)
    with h5py.File(p, "r+") as f:
        f["data/demo_7"] = np.zeros(3)
    assert input_error(cli, p) == f"{p}: data/demo_7: not a group"
    # a Robotiq gripper's six joints are not two finger positions
    log = [(a, pos, quat, np.concatenate([fing] * 3, axis=1)) for a, pos, quat, fing in demos(2, 10)]
    p = write_robomimic(tmp_path / "robotiq.hdf5", log, ea)
    assert input_error(cli, p) == (f"{p}: data/demo_0/obs/robot0_gripper_qpos: 10 x 6, expected 10 x 2 "
                                   "(two finger positions, one row per action)")
    # h5py's own lzf compression: libhdf5 has no such filter
    p = write_robomimic(tmp_path / "lzf.hdf5", demos(2, 10), ea)
    with h5py.File(p, "r+") as f:
        a = f["data/demo_0/actions"][()]
        del f["data/demo_0/actions"]
        f["data/demo_0"].create_dataset("actions", data=a, compression="lzf")
    assert input_error(cli, p) == (f"{p}: data/demo_0/actions: cannot be read as numbers (compressed with HDF5 filter 32000 "
                                   "'lzf', which this HDF5 library does not have; re-save the file with gzip compression or none)")
