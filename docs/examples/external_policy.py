#!/usr/bin/env python3
"""Example external policy for ActionShift (protocol actionshift-policy-v1, docs/backbones.md).

A scripted PickCube policy in plain Python (standard library only): it reads the observation by
field name from the layout sent in the hello message, so it does not hard-code offsets.

Run it through the CLI:
    actionshift gate0 --backbone "external:python3 docs/examples/external_policy.py" \
        --task pick_cube --episodes 20

Protocol: one JSON object per line on stdin/stdout.
    <- {"type":"hello","task":...,"layout":{"size":N,"fields":[{"name","offset","width"},...]},...}
    -> {"type":"ready"}
    <- {"type":"reset","episode":k,...}          (no reply)
    <- {"type":"step","t":i,"obs":[N numbers]}
    -> {"action":[7 numbers]}                    (dx dy dz rx ry rz gripper, +-1 = 0.1 m / 0.1 rad)
Anything on stderr is passed through; stdout carries protocol lines only.
"""
import json
import math
import sys


def quat_to_matrix(w, x, y, z):
    n = math.sqrt(w * w + x * x + y * y + z * z) or 1.0
    w, x, y, z = w / n, x / n, y / n, z / n
    return [
        [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
        [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
        [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
    ]


def matmul(a, b):
    return [[sum(a[i][k] * b[k][j] for k in range(3)) for j in range(3)] for i in range(3)]


def transpose(a):
    return [[a[j][i] for j in range(3)] for i in range(3)]


def so3_log(r):
    """Rotation vector of a rotation matrix."""
    c = max(-1.0, min(1.0, (r[0][0] + r[1][1] + r[2][2] - 1) / 2))
    angle = math.acos(c)
    v = [r[2][1] - r[1][2], r[0][2] - r[2][0], r[1][0] - r[0][1]]
    if angle < 1e-9:
        return [0.5 * e for e in v]
    if math.pi - angle < 1e-6:
        # near pi: axis from the diagonal
        axis = [math.sqrt(max(0.0, (r[i][i] + 1) / 2)) for i in range(3)]
        return [angle * a for a in axis]
    s = angle / (2 * math.sin(angle))
    return [s * e for e in v]


def yaw(r):
    return math.atan2(r[1][0], r[0][0])


def down(yaw_rad):
    c, s = math.cos(yaw_rad), math.sin(yaw_rad)
    rz = [[c, -s, 0], [s, c, 0], [0, 0, 1]]
    return matmul(rz, [[1, 0, 0], [0, -1, 0], [0, 0, -1]])


def move_to(tcp_p, tcp_r, p, r, gripper, gain=2.0):
    a = [max(-1.0, min(1.0, gain * (p[i] - tcp_p[i]) / 0.1)) for i in range(3)]
    rv = [gain * e / 0.1 for e in so3_log(matmul(r, transpose(tcp_r)))]
    n = math.sqrt(sum(e * e for e in rv))
    if n > 1.0:
        rv = [e / n for e in rv]
    return a + rv + [gripper]


class PickCube:
    def __init__(self, layout):
        self.f = {f["name"]: f for f in layout["fields"]}

    def field(self, obs, name):
        f = self.f[name]
        return obs[f["offset"]:f["offset"] + f["width"]]

    def act(self, obs):
        tcp = self.field(obs, "tcp_pose")
        cube = self.field(obs, "obj_pose")
        goal = self.field(obs, "goal_pos")
        grasped = self.field(obs, "is_grasped")[0] > 0.5
        qpos = self.field(obs, "qpos")
        opening = qpos[7] + qpos[8]
        tp, tr = tcp[:3], quat_to_matrix(*tcp[3:])
        cp, cr = cube[:3], quat_to_matrix(*cube[3:])
        hold = down(yaw(tr))
        if grasped:  # carry the cube to the goal
            target = [tp[i] + goal[i] - cp[i] for i in range(3)]
            return move_to(tp, tr, target, hold, -1.0)
        hand = yaw(tr)
        r = down(hand + math.remainder(yaw(cr) - hand, math.pi / 2))
        to = [cp[i] - tp[i] for i in range(3)]
        dist = math.sqrt(sum(e * e for e in to))
        xy = math.hypot(to[0], to[1])
        near = dist < 0.012
        if near and 0.025 < opening < 0.075:  # closing on the cube
            return move_to(tp, tr, cp, r, -1.0)
        if opening <= 0.025:  # closed on nothing: open again
            return move_to(tp, tr, [tp[0], tp[1], tp[2] + 0.01], r, 1.0)
        yaw_err = abs(math.remainder(yaw(r) - hand, 2 * math.pi))
        if xy < 0.008 and yaw_err < 0.25:  # descend, close at the cube centre
            return move_to(tp, tr, cp, r, -1.0 if near else 1.0)
        hover = cp[2] + (0.06 if xy > 0.03 else 0.03)
        z = max(hover, min(tp[2], hover + 0.05)) if xy > 0.03 else hover
        return move_to(tp, tr, [cp[0], cp[1], z], r, 1.0)


def main():
    policy = None
    for line in sys.stdin:
        msg = json.loads(line)
        kind = msg.get("type")
        if kind == "hello":
            if msg["task"] != "pick_cube":
                print(f"external_policy.py: only pick_cube is implemented, got {msg['task']}", file=sys.stderr)
                return 1
            policy = PickCube(msg["layout"])
            reply = {"type": "ready"}
        elif kind == "reset":
            continue
        elif kind == "step":
            reply = {"action": policy.act(msg["obs"])}
        else:
            print(f"external_policy.py: unknown message type {kind!r}", file=sys.stderr)
            return 1
        sys.stdout.write(json.dumps(reply) + "\n")
        sys.stdout.flush()
    return 0


if __name__ == "__main__":
    sys.exit(main())
