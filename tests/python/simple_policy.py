"""A small deterministic numpy policy for PickCube (reach, grasp, lift), and its external-process
server: `python3 simple_policy.py` speaks actionshift-policy-v1 on stdin/stdout."""
import numpy as np

import actionshift

LAYOUT = {f["name"]: (f["offset"], f["width"]) for f in actionshift.make("pick_cube").layout}


def field(obs, name):
    o, w = LAYOUT[name]
    return obs[o:o + w]


class ReachGraspLift:
    def __init__(self):
        self.t = 0

    def reset(self):
        self.t = 0

    def __call__(self, obs):
        self.t += 1
        tcp = field(obs, "tcp_pose")[:3]
        cube = field(obs, "obj_pose")[:3]
        goal = field(obs, "goal_pos")
        a = np.zeros(7)
        if self.t < 15:
            a[:3] = np.clip((cube + [0, 0, 0.02] - tcp) * 10.0, -1, 1)
            a[6] = 1.0
        elif self.t < 22:
            a[:3] = np.clip((cube - tcp) * 10.0, -1, 1)
            a[6] = 1.0 if self.t < 19 else -1.0
        else:
            a[:3] = np.clip((goal - tcp) * 10.0, -1, 1)
            a[6] = -1.0
        return a


if __name__ == "__main__":
    actionshift.serve_policy(ReachGraspLift())
