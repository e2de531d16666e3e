"""A probing rule of your own, in Python, entered into the benchmark (docs/methods.md).

For `budget` steps send the ±amplitude basis pulse whose calibrated, lag-aware previews separate the
two likeliest pool hypotheses most (in units of the response noise); then act on the MAP hypothesis.
The same rule as a C++ plug-in is docs/examples/method_plugin/separation_probes.hpp; both make the
same decisions step for step. Run:  python3 separation_probes.py OUT [EPISODES]  (PYTHONPATH: the build's python/ directory)
"""
import sys

import numpy as np

import actionshift


class SeparationProbes:
    name, version, rung = "separation_probes", "1", "pool"   # rung: what the runner may hand it

    def __init__(self, budget=6, amplitude=0.5):
        self.params = {"budget": budget, "amplitude": amplitude}

    def setup(self, inputs):  # before each episode: the pool rung's inputs (never the contract)
        self.belief = actionshift.PoolBelief(inputs["pool"], inputs["calibration"])
        self.scale = inputs["calibration"].alpha / inputs["calibration"].sigma

    def begin_episode(self, seed):
        self.belief.reset()
        self.t = 0

    def encode(self, canonical, R):
        self.t += 1
        if self.t > self.params["budget"]:
            return self.belief.map_encode(canonical, R), False
        a, b = np.argsort(-self.belief.log_probs, kind="stable")[:2]   # the two likeliest
        pulses = [s * self.params["amplitude"] * np.eye(7)[c] for c in range(6) for s in (1.0, -1.0)]
        seps = [float((((p := self.belief.preview(raw, R, lag_aware=True)[:, :6])[a] * self.scale
                        - p[b] * self.scale) ** 2).sum()) for raw in pulses]
        return pulses[int(np.argmax(seps))], True   # the first of equal separations

    def observe(self, raw, response, R):
        self.belief.update(raw, response, R)


if __name__ == "__main__":  # run on the PPO backbone's reference cell; rank with `actionshift compare`
    r = actionshift.evaluate("ppo", split="reference_seen", pool="reference9", method=SeparationProbes(),
                             episodes=int(sys.argv[2]) if len(sys.argv) > 2 else 18,
                             out=sys.argv[1] if len(sys.argv) > 1 else "results")
    print(r["job_id"], r["jsonl_path"])
