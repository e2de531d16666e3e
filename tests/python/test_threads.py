"""One Env or VecEnv used from several Python threads: calls that touch the Bullet world take turns
(a lock per environment, taken with the GIL released), and close() releases the world.

Each concurrent scenario runs in a subprocess, so that a crash (SIGSEGV in Bullet, as before the
lock) fails its test instead of killing pytest."""
import subprocess
import sys
import textwrap

import numpy as np
import pytest

import actionshift

_PRELUDE = textwrap.dedent("""
    import sys, threading
    import numpy as np
    import actionshift

    errors = []

    def run_threads(*bodies):
        def guard(body):
            try:
                body()
            except BaseException as e:  # any exception is a failure of the scenario
                errors.append(repr(e))
        threads = [threading.Thread(target=guard, args=(b,)) for b in bodies]
        for t in threads:
            t.start()
        for t in threads:
            t.join()
        if errors:
            print("errors:", errors)
            sys.exit(1)

    def closed_or_raise(e):
        # after close() the only allowed failure is the documented one
        if not (isinstance(e, RuntimeError) and "environment is closed" in str(e)):
            raise e
""")

_SCENARIOS = {
    "env_step_step": """
        env = actionshift.make("pick_cube")
        env.reset(seed=1)
        def stepper():
            for _ in range(100):
                obs, r, term, trunc, info = env.step(np.full(7, 0.3))
                if term or trunc:  # keep stepping the world: a step after the episode's end does not
                    env.reset()
        run_threads(stepper, stepper)
    """,
    "env_step_reset": """
        env = actionshift.make("pick_cube")
        env.reset(seed=1)
        def stepper():
            for _ in range(100):
                obs, r, term, trunc, info = env.step(np.full(7, 0.3))
                assert obs.shape == (env._env.obs_dim,)
        def resetter():
            for i in range(100):
                obs, info = env.reset(seed=i)
                assert info["seed"] == i
        run_threads(stepper, resetter)
    """,
    "env_step_close": """
        env = actionshift.make("pick_cube")
        env.reset(seed=1)
        def stepper():
            for _ in range(100):
                try:
                    env.step(np.full(7, 0.3))
                except RuntimeError as e:
                    closed_or_raise(e)
                    return
        def closer():
            for i in range(20):
                env.reset(seed=i)
            env.close()
        run_threads(stepper, stepper, closer)
        try:
            env.step(np.zeros(7))
            sys.exit("step after close did not raise")
        except RuntimeError as e:
            closed_or_raise(e)
    """,
    "vec_step_step_reset": """
        envs = actionshift.make_vec("pick_cube", num_envs=3, threads=2)
        envs.reset(seed=1)
        def stepper():
            for _ in range(100):
                obs, r, term, trunc, info = envs.step(np.full((3, 7), 0.3))
                assert obs.shape == (3, envs._env.obs_dim) and len(info["autoreset"]) == 3
        def resetter():
            for i in range(100):
                obs, info = envs.reset(seed=i)
                assert list(info["seed"]) == [i, i + 1, i + 2]
        run_threads(stepper, stepper, resetter)
    """,
    "vec_step_close": """
        envs = actionshift.make_vec("pick_cube", num_envs=3, threads=2)
        envs.reset(seed=1)
        def stepper():
            for _ in range(100):
                try:
                    envs.step(np.full((3, 7), 0.3))
                except RuntimeError as e:
                    closed_or_raise(e)
                    return
        def closer():
            envs.close()
        run_threads(stepper, stepper, closer)
    """,
}


@pytest.mark.parametrize("name", sorted(_SCENARIOS))
def test_concurrent_use_from_two_threads_does_not_crash(name):
    code = _PRELUDE + textwrap.dedent(_SCENARIOS[name]) + "\nprint('ok')\n"
    p = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=240)
    assert p.returncode == 0 and p.stdout.strip().endswith("ok"), (
        f"{name}: exit {p.returncode} (negative: killed by signal {-p.returncode})\n{p.stdout}\n{p.stderr[-2000:]}")


def test_env_close_releases_the_world_and_later_calls_raise():
    env = actionshift.make("pick_cube")
    env.reset(seed=3)
    env.step(np.zeros(7))
    env.close()
    env.close()  # closing twice is allowed (Gymnasium's wrappers may close again)
    for call in (lambda: env.reset(seed=1), lambda: env.step(np.zeros(7))):
        with pytest.raises(RuntimeError, match="environment is closed"):
            call()
    assert env.task == "pick_cube"  # fixed properties stay readable


def test_vec_env_close_releases_the_worlds_and_later_calls_raise():
    envs = actionshift.make_vec("pick_cube", num_envs=2, threads=2)
    envs.reset(seed=3)
    envs.close()
    envs.close()
    for call in (lambda: envs.reset(seed=1), lambda: envs.step(np.zeros((2, 7)))):
        with pytest.raises(RuntimeError, match="environment is closed"):
            call()
    assert envs.num_envs == 2


def test_a_closed_env_is_not_the_same_as_a_new_one():
    # closing one environment leaves the others (and the shared model cache) untouched
    a = actionshift.make("pick_cube")
    b = actionshift.make("pick_cube")
    oa, _ = a.reset(seed=5)
    a.close()
    ob, _ = b.reset(seed=5)
    assert np.array_equal(oa, ob)
    c = actionshift.make("pick_cube")
    oc, _ = c.reset(seed=5)
    assert np.array_equal(oa, oc)
