"""Gymnasium integration: with gymnasium importable, actionshift's environments subclass
gymnasium.Env, use gymnasium.spaces.Box and are registered as ActionShift/<Task>-v1. The real
package is used when installed; otherwise the stand-in in gymnasium_standin/ (Gymnasium's documented
API surface that actionshift touches) is put first on the path, in a subprocess so the other tests
keep seeing a machine without Gymnasium."""
import importlib.util
import os
import subprocess
import sys

CHECK = r"""
import numpy as np
import gymnasium
import actionshift
ids = sorted(k for k in gymnasium.envs.registration.registry if str(k).startswith("ActionShift/"))
assert ids == ["ActionShift/PegInsertionSide-v1", "ActionShift/PickCube-v1", "ActionShift/PullCube-v1",
               "ActionShift/PushCube-v1", "ActionShift/StackCube-v1"], ids
env = gymnasium.make("ActionShift/PushCube-v1")
base = env.unwrapped if hasattr(env, "unwrapped") else env
assert isinstance(base, gymnasium.Env) and isinstance(base, actionshift.Env), type(base)
assert base.task == "push_cube", base.task
assert isinstance(base.observation_space, gymnasium.spaces.Box)
assert isinstance(base.action_space, gymnasium.spaces.Box) and base.action_space.shape == (7,)
obs, info = env.reset(seed=3)
assert base.observation_space.contains(obs), obs.shape
obs2, reward, terminated, truncated, info = env.step(np.zeros(7))
assert obs2.shape == obs.shape and isinstance(info, dict) and "success" in info
again, _ = env.reset(seed=3)
assert np.array_equal(obs, again)
print("gymnasium ok", "real" if hasattr(gymnasium, "__version__") else "stand-in", len(ids))
"""


def test_registered_with_gymnasium():
    env = dict(os.environ)
    paths = [p for p in env.get("PYTHONPATH", "").split(os.pathsep) if p]
    if importlib.util.find_spec("gymnasium") is None:
        paths.insert(0, os.path.join(os.path.dirname(__file__), "gymnasium_standin"))
    env["PYTHONPATH"] = os.pathsep.join(paths)
    p = subprocess.run([sys.executable, "-c", CHECK], env=env, capture_output=True, text=True, timeout=120)
    assert p.returncode == 0, p.stderr
    assert "gymnasium ok" in p.stdout


def test_module_works_without_gymnasium():
    import actionshift

    if importlib.util.find_spec("gymnasium") is None:
        assert actionshift.Env.__mro__[1] is object
        env = actionshift.make("pick_cube")
        assert isinstance(env.observation_space, actionshift.Box)
