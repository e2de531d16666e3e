"""ActionShift from Python: hidden action-interface adaptation for robot manipulation.

The heavy lifting is native (C++, the same library as the ``actionshift`` CLI); this package adds
the Gymnasium-style environment classes. See docs/python.md.

    >>> import actionshift
    >>> env = actionshift.make("pick_cube", split="seen", index=3)   # a hidden contract
    >>> obs, info = env.reset(seed=1)
    >>> obs, reward, terminated, truncated, info = env.step(env.action_space.sample())
"""
import json as _json
import os as _os
import sys as _sys
import warnings as _warnings

import numpy as _np

from . import _identity
from . import _native
from ._native import (  # noqa: F401  (re-exported API)
    Adapter,
    Contract,
    Decoder,
    InputError,
    MAX_NUM_ENVS,
    Manifest,
    PoolBelief,
    ResponseModel,
    SelfTest,
    builtin_manifests,
    decode,
    decode_jacobian,
    encode,
    episode_seed,
    load_manifest,
    method_needs_calibration,
    method_label,
    method_needs_pool,
    method_rung,
    method_params,
    method_variants,
    methods,
    pool_sha256,
    selftest_library,
    selftest_sim_options,
    tasks,
    tcp_response,
    tcp_rotation,
    wilson_interval,
)

__version__ = _native.__version__
"""This build's version (the CMake project's; ``importlib.metadata.version("actionshift")`` of a pip install)."""
__git_commit__ = _native.__git_commit__
"""The commit checked out when CMake configured this build (None if it was not a git checkout)."""

__all__ = [
    "Adapter", "audit", "Box", "Contract", "Decoder", "Env", "InputError", "Manifest", "SelfTest", "VecEnv",
    "builtin_manifests", "decode", "decode_jacobian", "encode", "episode_seed", "evaluate", "load_manifest", "make",
    "make_adapter", "make_vec", "method_label", "method_needs_calibration", "method_needs_pool", "method_params",
    "method_rung", "PoolBelief", "ResponseModel",
    "method_variants", "methods", "pool_sha256", "selftest_library", "selftest_sim_options", "serve_method", "serve_policy", "tasks", "tcp_response", "tcp_rotation",
    "wilson_interval", "write_frames",
]

PROFILES = ("maniskill", "ideal")
"""Fidelity profiles this build's simulator accepts (``profile=`` of make/make_vec/evaluate)."""

try:  # Gymnasium is optional: with it, environments subclass gymnasium.Env and are registered
    import gymnasium as _gym
    from gymnasium import spaces as _gym_spaces
except ImportError:  # pragma: no cover - depends on the machine
    _gym = None
    _gym_spaces = None


class Box:
    """A box space (used when gymnasium is not installed): shape, low, high, dtype."""

    def __init__(self, low, high, shape, dtype=_np.float64, seed=None):
        self.shape = tuple(shape)
        self.dtype = _np.dtype(dtype)
        self.low = _np.broadcast_to(_np.asarray(low, dtype=self.dtype), self.shape).copy()
        self.high = _np.broadcast_to(_np.asarray(high, dtype=self.dtype), self.shape).copy()
        self._rng = _np.random.default_rng(seed)

    def seed(self, seed=None):
        self._rng = _np.random.default_rng(seed)
        return [seed]

    def sample(self):
        """Uniform in [low, high] where both are finite, standard normal elsewhere."""
        finite = _np.isfinite(self.low) & _np.isfinite(self.high)
        out = self._rng.standard_normal(self.shape)
        out[finite] = self._rng.uniform(self.low[finite], self.high[finite])
        return out.astype(self.dtype)

    def contains(self, x):
        x = _np.asarray(x)
        return x.shape == self.shape and bool(_np.all(x >= self.low) and _np.all(x <= self.high))

    __contains__ = contains

    def __repr__(self):
        return f"Box({self.low.min()}, {self.high.max()}, {self.shape}, {self.dtype})"


def _box(low, high, shape, dtype=_np.float64):
    if _gym_spaces is not None:
        return _gym_spaces.Box(low=low, high=high, shape=shape, dtype=dtype)
    return Box(low, high, shape, dtype=dtype)


try:  # Gymnasium >= 1.1 names the autoreset modes; the value is the same string without it
    from gymnasium.vector import AutoresetMode as _AutoresetMode
    _SAME_STEP = _AutoresetMode.SAME_STEP
except (ImportError, AttributeError):  # pragma: no cover - depends on the machine
    _SAME_STEP = "SameStep"


_EnvBase = _gym.Env if _gym is not None else object
_TASK_IDS = dict(_native._task_maniskill_ids())  # task name -> ManiSkill id (sim/task.hpp)


def _check_seed(seed, name="seed"):
    # seeds are unsigned 64-bit integers in the library (None: the next seed of a sequence)
    if seed is not None and (not isinstance(seed, (int, _np.integer)) or isinstance(seed, bool)
                             or not 0 <= seed < 2 ** 64):
        raise ValueError(f"{name}: must be an integer in [0, 2**64) (got {seed!r})")


def _check_reset_options(options):
    # Gymnasium passes options through to the environment; these take none, and a silently
    # ignored option (a contract, a start pose) would make an experiment other than the one asked for
    if options is not None and (not isinstance(options, dict) or options):
        got = sorted(map(str, options)) if isinstance(options, dict) else type(options).__name__
        raise ValueError(f"options: this environment takes no reset options (got {got}); "
                         "the contract, split and profile are chosen by make()")


def _check_types(where, **values):
    # one-line TypeErrors for the constructor arguments (pybind11's own message spans many lines)
    real = (int, float, _np.integer, _np.floating)
    kinds = {"task": (str,), "split": (str, type(None)), "rotation": (str,), "profile": (str,),
             "index": (int, _np.integer), "num_envs": (int, _np.integer), "threads": (int, _np.integer),
             "robot": (str, _os.PathLike, type(None)), "packages": (dict, list, tuple, type(None)),
             "obs_noise": real, "ignore_terminations": (bool, _np.bool_), "render_mode": (str, type(None)),
             "width": (int, _np.integer), "height": (int, _np.integer), "camera": (str,),
             "dtype": (str, type, _np.dtype)}
    for name, value in values.items():
        if not isinstance(value, kinds[name]) or (isinstance(value, bool) and bool not in kinds[name]):
            want = " or ".join("None" if t is type(None) else t.__name__ for t in kinds[name])
            raise TypeError(f"{where}: {name}: expected {want} (got {type(value).__name__})")
    # ranges the native layer's integer types hold (the split's own size is checked there)
    if "index" in values and not -2 ** 62 < values["index"] < 2 ** 62:
        raise ValueError(f"{where}: index: out of range (got {values['index']})")
    if "threads" in values and not 0 <= values["threads"] <= 4096:
        raise ValueError(f"{where}: threads: must be 0 (all cores) or a count up to 4096 (got {values['threads']})")
    if "num_envs" in values and not -2 ** 31 < values["num_envs"] < 2 ** 31:
        raise ValueError(f"{where}: num_envs: must be between 1 and {MAX_NUM_ENVS} (got {values['num_envs']})")
    for side in ("width", "height"):
        if side in values and not 16 <= values[side] <= 4096:
            raise ValueError(f"{where}: {side}: must be in 16..4096 pixels, as `actionshift render --size` (got {values[side]})")
    if values.get("render_mode") not in (None, "rgb_array"):
        raise ValueError(f"{where}: render_mode: must be None or 'rgb_array' (got {values['render_mode']!r})")


_DTYPES = {"float64": _np.float64, "float32": _np.float32}


def _check_dtype(where, dtype):
    name = _np.dtype(dtype).name if isinstance(dtype, (type, _np.dtype)) else dtype
    if name not in _DTYPES:
        raise ValueError(f"{where}: dtype: must be 'float64' (the default) or 'float32' (got {dtype!r})")
    return _DTYPES[name]


def _packages_args(where, packages):
    # {name: dir} (or "NAME=DIR" strings, as --package takes them) -> "NAME=DIR" strings
    if packages is None:
        return []
    if isinstance(packages, dict):
        out = []
        for name, path in packages.items():
            if not isinstance(name, str) or not isinstance(path, (str, _os.PathLike)):
                raise TypeError(f"{where}: packages: expected {{name: directory}} with str keys and path values")
            out.append(f"{name}={_os.path.abspath(_os.fspath(path))}")
        return out
    if not all(isinstance(p, str) for p in packages):
        raise TypeError(f"{where}: packages: expected a dict {{name: directory}} or a list of 'NAME=DIR' strings")
    return [p if "=" not in p else p.split("=", 1)[0] + "=" + _os.path.abspath(p.split("=", 1)[1]) for p in packages]


def _robot_arg(robot):
    return None if robot is None else _os.path.abspath(_os.fspath(robot))


def _contract_arg(contract):
    # a pickled environment keeps its contract as canonical JSON text (make() takes it back)
    return contract.to_json() if isinstance(contract, Contract) else contract


def _check_profile(profile):
    _native.env_config_check(profile)


_EPISODE_RULE = """Episodes end at the horizon (``truncated``) or when a safety check ends them
    (``terminated``, ``info["safety"]`` names the flag); success does not end them: ``info["success"]``
    reports it at each step, ``info["success_once"]`` and ``info["success_at_end"]`` over the episode.
    This is the library's runner (what ``actionshift run`` records) and ManiSkill's evaluation setting
    (``ignore_terminations=True``). With ``ignore_terminations=False`` (ManiSkill's training default),
    success also ends the episode: ``terminated`` is True at the first successful step."""


class Env(_EnvBase):
    __doc__ = """One Bullet Panda task under a hidden action contract, with Gymnasium's API.

    ``reset(seed=None, options=None) -> (obs, info)``; ``step(action) -> (obs, reward, terminated,
    truncated, info)``. ``info`` holds ``success``, ``success_once``, ``success_at_end``, ``safety``
    (``"none"`` or the flag that ended the episode), ``elapsed_steps``, ``episode_return`` and
    ``clipped_steps``. The contract is never observable through the env.

    """ + _EPISODE_RULE + """

    ``render_mode="rgb_array"``: ``render()`` draws the current state with the renderer and cameras of
    ``actionshift render`` (OSMesa, headless), a ``(height, width, 3)`` uint8 array.
    """

    metadata = {"render_modes": ["rgb_array"], "render_fps": 20}

    def __init__(self, task="pick_cube", contract=None, split=None, index=0, rotation="live", profile="maniskill",
                 robot=None, packages=None, obs_noise=0.0, calibration=None, ignore_terminations=True,
                 render_mode=None, width=320, height=240, camera="default", dtype="float64"):
        _check_types("make", task=task, split=split, index=index, rotation=rotation, profile=profile, robot=robot,
                     packages=packages, obs_noise=obs_noise, ignore_terminations=ignore_terminations,
                     render_mode=render_mode, width=width, height=height, camera=camera, dtype=dtype)
        self._dtype = _check_dtype("make", dtype)
        self._args = dict(task=task, contract=_contract_arg(contract), split=split, index=int(index), rotation=rotation,
                          profile=profile, robot=_robot_arg(robot), packages=packages, obs_noise=float(obs_noise),
                          calibration=None, ignore_terminations=bool(ignore_terminations), render_mode=render_mode,
                          width=int(width), height=int(height), camera=camera, dtype=_np.dtype(self._dtype).name)
        render = (int(width), int(height), camera) if render_mode == "rgb_array" else None
        self._env = _native._Env(task, contract, split, int(index), rotation, profile, self._args["robot"],
                                 _packages_args("make", packages), float(obs_noise), bool(ignore_terminations), render)
        self.calibration = None if calibration is None else _native._load_calibration(calibration, task, profile)
        """The response calibration given to make() (a dict, checked against the task and profile) for
        ``make_adapter(..., calibration=env.calibration)``; None if none was given. The simulation does
        not read it."""
        self._args["calibration"] = self.calibration
        n = self._env.obs_dim
        self.observation_space = _box(-_np.inf, _np.inf, (n,), self._dtype)
        self.action_space = _box(-1.0, 1.0, (7,), self._dtype)
        self.horizon = self._env.horizon
        self.layout = self._env.layout
        self.profile = profile
        self.rotation = rotation
        self.robot_sha256 = self._env.robot_sha256 or None
        self.obs_noise = float(obs_noise)
        self.ignore_terminations = bool(ignore_terminations)
        self.render_mode = render_mode

    def _cast(self, out):
        if self._dtype is _np.float64:
            return out
        return (out[0].astype(self._dtype),) + tuple(out[1:])

    def reset(self, *, seed=None, options=None):
        """Start an episode; the initial state is a pure function of ``seed`` (None: the next
        seed of this env's sequence, so ``reset(seed=s)`` then ``reset()`` is reproducible)."""
        _check_seed(seed)
        _check_reset_options(options)
        return self._cast(self._env.reset(None if seed is None else int(seed)))

    def step(self, action):
        return self._cast(self._env.step(action))

    def render(self):
        """The current state as a ``(height, width, 3)`` uint8 RGB array (``render_mode="rgb_array"``),
        drawn as ``actionshift render --no-overlay`` draws it; None (with a warning, as Gymnasium does)
        when the environment was made without a render mode."""
        if self.render_mode is None:
            _warnings.warn("render: this environment was made without render_mode; "
                           "use make(..., render_mode='rgb_array')", stacklevel=2)
            return None
        return self._env.render()

    @property
    def task(self):
        return self._env.task

    def field(self, obs, name):
        """The slice of an observation named ``name`` (e.g. ``"tcp_pose"``, ``"goal_pos"``)."""
        for f in self.layout:
            if f["name"] == name:
                return obs[f["offset"]:f["offset"] + f["width"]]
        raise KeyError(f"observation has no field {name!r} (fields: {[f['name'] for f in self.layout]})")

    def close(self):
        """Free the simulation (its Bullet world). Later reset/step raise RuntimeError("environment
        is closed ..."); closing again does nothing. Safe while another thread steps: calls that
        touch the world take turns (one lock per environment)."""
        self._env.close()

    def __getstate__(self):
        # by construction arguments and seed state: the unpickled environment is at an episode
        # boundary (call reset()); reset() without a seed continues the same seed sequence
        return {"args": dict(self._args), "last_seed": self._env.last_seed, "robot_sha256": self.robot_sha256}

    def __setstate__(self, state):
        Env.__init__(self, **state["args"])
        if self.robot_sha256 != state["robot_sha256"]:
            raise ValueError(f"unpickle: robot: {self._args['robot']} changed since the environment was pickled "
                             f"(content {self.robot_sha256}, was {state['robot_sha256']})")
        self._env.last_seed = state["last_seed"]

    def __repr__(self):
        return f"<actionshift.Env {self.task} rotation={self.rotation} profile={self.profile}>"


class VecEnv:
    __doc__ = """``num_envs`` environments stepped together in C++ on worker threads (see make_vec), with
    Gymnasium's vector API: ``single_observation_space``, ``single_action_space``, batched spaces,
    and same-step autoreset (``metadata["autoreset_mode"]``).

    """ + _EPISODE_RULE + """
    """

    metadata = {"render_modes": [], "autoreset_mode": _SAME_STEP}

    def __init__(self, task="pick_cube", num_envs=1, contract=None, split=None, index=0, rotation="live",
                 profile="maniskill", threads=0, robot=None, packages=None, obs_noise=0.0, calibration=None,
                 ignore_terminations=True, dtype="float64"):
        _check_types("make_vec", task=task, num_envs=num_envs, split=split, index=index, rotation=rotation,
                     profile=profile, threads=threads, robot=robot, packages=packages, obs_noise=obs_noise,
                     ignore_terminations=ignore_terminations, dtype=dtype)
        self._dtype = _check_dtype("make_vec", dtype)
        self._args = dict(task=task, num_envs=int(num_envs), contract=_contract_arg(contract), split=split,
                          index=int(index), rotation=rotation, profile=profile, threads=int(threads),
                          robot=_robot_arg(robot), packages=packages, obs_noise=float(obs_noise), calibration=None,
                          ignore_terminations=bool(ignore_terminations), dtype=_np.dtype(self._dtype).name)
        self._env = _native._VecEnv(task, int(num_envs), contract, split, int(index), rotation, profile, int(threads),
                                    self._args["robot"], _packages_args("make_vec", packages), float(obs_noise),
                                    bool(ignore_terminations))
        self.calibration = None if calibration is None else _native._load_calibration(calibration, task, profile)
        self._args["calibration"] = self.calibration
        self.num_envs = self._env.num_envs
        n = self._env.obs_dim
        self.single_observation_space = _box(-_np.inf, _np.inf, (n,), self._dtype)
        self.single_action_space = _box(-1.0, 1.0, (7,), self._dtype)
        self.observation_space = _box(-_np.inf, _np.inf, (self.num_envs, n), self._dtype)
        self.action_space = _box(-1.0, 1.0, (self.num_envs, 7), self._dtype)
        self.horizon = self._env.horizon
        self.threads = self._env.threads
        self.robot_sha256 = self._env.robot_sha256 or None
        self.ignore_terminations = bool(ignore_terminations)
        self.render_mode = None

    def _cast(self, out):
        if self._dtype is _np.float64:
            return out
        info = out[-1]
        if "final_obs" in info:
            info["final_obs"] = info["final_obs"].astype(self._dtype)
        return (out[0].astype(self._dtype),) + tuple(out[1:])

    def reset(self, *, seed=None, options=None):
        """Reset every environment; environment i gets seed ``seed + i``. ``info`` holds the keys of
        ``step``'s (arrays over the environments) and ``seed``."""
        _check_seed(seed)
        _check_reset_options(options)
        if seed is not None and int(seed) + self.num_envs - 1 >= 2 ** 64:
            raise ValueError(f"seed: seed + num_envs - 1 must be below 2**64 (environment i gets seed + i; got {seed})")
        return self._cast(self._env.reset(None if seed is None else int(seed)))

    def step(self, actions):
        """``actions`` (num_envs, 7) -> (obs, reward, terminated, truncated, info), arrays over envs.

        Same-step autoreset (Gymnasium's ``AutoresetMode.SAME_STEP``, as ManiSkill's vector wrapper): an
        environment whose episode ends is reset in the same call (next seed of its sequence) and its row
        of ``obs`` is the new episode's first observation; ``info["final_obs"][i]`` is the ended episode's
        last observation and ``info["final_info"]`` its info, where ``info["_final_obs"][i]`` (and
        ``_final_info``, ``autoreset``) is True. ``info`` itself describes the step just taken (for an
        ended environment, its episode's last step), as in ManiSkill."""
        return self._cast(self._env.step(actions))

    def close(self):
        """Free every environment's simulation and the worker threads; later reset/step raise
        RuntimeError("environment is closed ..."); closing again does nothing."""
        self._env.close()

    def __getstate__(self):
        # by construction arguments and seed state, as Env: the unpickled environments need reset()
        return {"args": dict(self._args), "last_seed": self._env.last_seed, "robot_sha256": self.robot_sha256}

    def __setstate__(self, state):
        VecEnv.__init__(self, **state["args"])
        if self.robot_sha256 != state["robot_sha256"]:
            raise ValueError(f"unpickle: robot: {self._args['robot']} changed since the environment was pickled "
                             f"(content {self.robot_sha256}, was {state['robot_sha256']})")
        self._env.last_seed = state["last_seed"]

    def __repr__(self):
        return f"<actionshift.VecEnv {self._args['task']} num_envs={self.num_envs} profile={self._args['profile']}>"


def make(task="pick_cube", contract=None, split=None, index=0, profile="maniskill", rotation="live", *,
         robot=None, packages=None, obs_noise=0.0, calibration=None, ignore_terminations=True,
         render_mode=None, width=320, height=240, camera="default", dtype="float64"):
    """An environment for ``task`` under a hidden contract.

    contract: an ``actionshift.Contract``, its JSON text or dict; or ``split`` (a built-in split name
    such as ``"seen"``, or a manifest path) and ``index`` (its ``index``-th evaluation contract);
    neither: the identity contract (raw actions are canonical). rotation: ``"live"`` (tool frame =
    TCP orientation) or ``"identity"``. profile: the simulator's fidelity profile (``PROFILES``).

    As the CLI's options (docs/sim.md): ``robot`` (a URDF file: another description of the Panda,
    ``--robot``) with ``packages`` (``{name: directory}`` for ``package://`` paths, ``--package``),
    ``obs_noise`` (sensor noise sigma in [0, 0.1], ``--obs-noise``) and ``calibration`` (a response
    calibration for this task and profile, a dict or file as ``--calibration``; kept as
    ``env.calibration`` for ``make_adapter``). ``ignore_terminations``: the episode-end rule (see
    ``Env``). ``render_mode="rgb_array"`` with ``width``, ``height`` and ``camera`` (as ``actionshift
    render --size WxH --camera C``): ``env.render()``. ``dtype``: ``"float64"`` (default) or
    ``"float32"`` observations and spaces (ManiSkill's)."""
    return Env(task, contract=contract, split=split, index=index, rotation=rotation, profile=profile, robot=robot,
               packages=packages, obs_noise=obs_noise, calibration=calibration,
               ignore_terminations=ignore_terminations, render_mode=render_mode, width=width, height=height,
               camera=camera, dtype=dtype)


def make_vec(task="pick_cube", num_envs=2, contract=None, split=None, index=0, profile="maniskill",
             rotation="live", threads=0, *, robot=None, packages=None, obs_noise=0.0, calibration=None,
             ignore_terminations=True, dtype="float64"):
    """``num_envs`` environments stepped in C++ on ``threads`` worker threads (0: all cores).
    With a split, environment i runs evaluation contract ``(index + i) mod n``. The other arguments
    are make()'s; episodes end by the same rule as ``Env``'s and autoreset in the same step."""
    return VecEnv(task, num_envs=num_envs, contract=contract, split=split, index=index, rotation=rotation,
                  profile=profile, threads=threads, robot=robot, packages=packages, obs_noise=obs_noise,
                  calibration=calibration, ignore_terminations=ignore_terminations, dtype=dtype)


def write_frames(path, frames, delay_cs=10, frame=-1):
    """Write rendered frames (``env.render()`` arrays) as ``actionshift render`` writes an episode:
    ``FILE.gif`` (every frame, ``delay_cs`` hundredths of a second each, the last held for a second)
    or ``FILE.png`` (frame ``frame``; -1: the last)."""
    return _native.write_frames(_os.fspath(path), list(frames), int(delay_cs), int(frame))


def make_adapter(method, task="pick_cube", pool=None, truth=None, params=None, calibration=None):
    """An adapter by method name (``methods()``) or variant label (``"entropy_probes{calibrated}"``,
    ``method_variants()``; a bare name is the paper's method): ``begin_episode(seed)``, ``encode(canonical, R)``
    -> raw action, ``observe(raw, response, R)``. Belief methods use the task's built-in response
    calibration; pool methods need ``pool`` (a pool name such as ``"reference9"``, a manifest path,
    or a list of contracts); the oracle (and its diagnostic ``delayed_oracle``) needs ``truth``. ``params``: method parameters (dict).
    ``calibration``: a response calibration (a dict as ``actionshift calibrate --json`` writes it, or
    its file) instead of the task's built-in one, for belief methods only."""
    return _native._make_adapter(method, task, pool, truth, params, calibration)


def evaluate(policy, task="pick_cube", split="seen", method="no_adapt", seed=20260718, episodes=256,
             out="results", backbone=None, pool=None, params=None, rotation="live", profile="maniskill",
             progress="off", threads=1, policy_version=None, policy_files=None, *, robot=None, packages=None,
             obs_noise=0.0, calibration=None, horizon=0):
    """Run ``policy`` (a callable obs -> 7 canonical numbers; its ``reset()`` is called at each
    episode start if it has one; or the name of one of the library's backbones, ``"expert"``,
    ``"ppo"``, ``"mlp:DIR"``, as ``actionshift run --backbone`` takes it) as the backbone of one hash-addressed job, in this process,
    through the library's runner: ``<out>/<job id>.jsonl`` and ``.summary.json``, exactly as
    ``actionshift run`` writes them. Returns a dict with ``job_id``, ``jsonl_path``,
    ``summary_path``, ``episodes_run``, ``wall_time_s`` and the ``job`` spec.

    split, pool: a built-in name or a manifest file (``str`` or path-like) of any name and location.
    The job is identified by the manifest's content hash; a file's absolute path is recorded in the
    job (not hashed) and the manifest is read again from it, and checked, when the job runs.

    backbone: the backbone's name in the job. ``"external:<command>"`` gives the job (id and JSONL)
    that ``actionshift run --backbone "external:<command>"`` writes when that command serves the same
    policy (e.g. through ``serve_policy``); default ``"python:<module>.<name>"`` of the callable.

    threads: episodes run on this many worker threads (0: all cores); the records and the job are
    the same for any count. With 1 (the default) ``policy`` itself is called; with more, each worker
    calls its own ``copy.deepcopy(policy)`` (as ``actionshift run --threads N`` starts one external
    process per worker), the simulation runs in parallel and only the policy calls take turns on the
    GIL. A plain function is not copied by ``deepcopy``: it must not keep state between calls.

    method: a method name or label (``"entropy_probes{calibrated}"``), or an object of your own with
    ``begin_episode(seed)``, ``encode(canonical, R)`` (returning 7 numbers, or ``(raw, probe)``) and
    ``observe(raw, response, R)``, optionally ``setup(inputs)`` (called before each episode with what
    its rung allows) and the attributes ``name``, ``version``, ``rung`` (``"pool"``, ``"grammar"`` or
    ``"none"``, the default), ``params`` (the JSON values that configure it) and ``files``. It is run
    by the library's runner as a user method (docs/methods.md); its records and summary are those of
    a built-in method.

    robot, packages, obs_noise, calibration: as ``make()`` takes them and as ``actionshift run --robot
    URDF --package NAME=DIR --obs-noise S --calibration FILE`` does: the robot description's content
    hash, the noise and the calibration's hash enter the job (and its id), so the job is the CLI's.
    ``calibration`` (a dict as ``calibrate --json`` writes it, or its file) is for a method that uses
    one, instead of the task's built-in calibration.

    horizon: control steps per episode, 0 (the default) for the task's (50; peg_insertion_side 100), as
    ``actionshift run --horizon`` takes it: a job names a horizon only when it is not 0, so its id is the CLI's.
    The reference evaluates its Diffusion Policy at 100.

    Identity (docs/methods.md): a Python policy enters the job id by its content (its code, closure
    and global values, its attributes, ``policy_files``), so two different callables never share a
    job; ``policy_version="..."`` names it instead of its code (for a policy whose content cannot be
    hashed, such as one holding a GPU model: then also pass its weights as ``policy_files``). A method
    object enters by its class's code, its ``params`` (or, without them, its attributes), version,
    rung and ``files``.
    """
    if seed is None:
        raise ValueError("seed: must be an integer in [0, 2**64) (got None)")
    _check_seed(seed)
    if isinstance(split, _os.PathLike):
        split = _os.fspath(split)
    for name, value in (("task", task), ("split", split), ("rotation", rotation),
                        ("profile", profile), ("progress", progress)):
        if not isinstance(value, str):
            raise TypeError(f"evaluate: {name}: expected str (got {type(value).__name__})")
    if not isinstance(out, (str, _os.PathLike)):
        raise TypeError(f"evaluate: out: expected a directory path (got {type(out).__name__})")
    if backbone is not None and not isinstance(backbone, str):
        raise TypeError(f"evaluate: backbone: expected str or None (got {type(backbone).__name__})")
    if pool is not None and not isinstance(pool, (str, _os.PathLike)):
        raise TypeError(f"evaluate: pool: expected a pool name or manifest path (a job records its pool by hash, "
                        f"and the path of a file; got {type(pool).__name__})")
    if not isinstance(obs_noise, (int, float, _np.floating, _np.integer)) or isinstance(obs_noise, bool):
        raise TypeError(f"evaluate: obs_noise: expected a number (got {type(obs_noise).__name__})")
    for name, value, lo, hi, why in (("episodes", episodes, 1, 2 ** 62, "must be > 0 and at most 2**62"),
                                     ("horizon", horizon, 0, 10000, "must be 0 (the task's) or 1 to 10000 control steps"),
                                     ("threads", threads, 0, 4096, "must be 0 (all cores) or a count up to 4096")):
        if not isinstance(value, (int, _np.integer)) or isinstance(value, bool):
            raise TypeError(f"evaluate: {name}: expected int (got {type(value).__name__})")
        if not lo <= value <= hi:
            raise ValueError(f"evaluate: {name}: {why} (got {value})")
    if isinstance(policy, str):  # a backbone of the library: "expert", "ppo", "mlp:DIR", "external:<command>"
        if backbone is not None and backbone != policy:
            raise ValueError("evaluate: backbone: a backbone given by name is its own name (drop backbone=)")
        backbone = policy
    if backbone is None:
        target = policy if hasattr(policy, "__qualname__") else type(policy)
        backbone = f"python:{getattr(target, '__module__', '?')}.{target.__qualname__}"
    backbone_sha256 = None
    if not backbone.startswith("external:") and not isinstance(policy, str):
        if not callable(policy):
            raise TypeError("policy: must be callable (obs -> 7 numbers)")
        backbone_sha256, _ = _identity.policy_identity(policy, backbone, policy_version, policy_files)
    elif policy_version is not None or policy_files is not None:
        raise ValueError("evaluate: policy_version/policy_files: they name a Python callable; a backbone given by "
                         "name or as external:<command> is identified as `actionshift run --backbone` identifies it")
    method_object, method_identity = None, None
    if not isinstance(method, str):
        if params is not None:
            raise ValueError("evaluate: params: a method object carries its own `params`")
        method_object, method_identity = method, _identity.method_identity(method)
        method = method_identity["name"]
    return _native._evaluate(policy, task, split, method, int(seed), int(episodes), _os.fspath(out), backbone,
                             None if pool is None else _os.fspath(pool),
                             params, rotation, profile, progress, int(threads), method_object, method_identity,
                             backbone_sha256, _robot_arg(robot), _packages_args("evaluate", packages), float(obs_noise),
                             calibration, int(horizon))


def _json_lines(fin):
    """The JSON objects of a JSON-lines stream (blank lines skipped): the requests of the runner."""
    for line in fin:
        line = line.strip()
        if line:
            yield _json.loads(line)


def _reply(fout, obj):
    fout.write(_json.dumps(obj) + "\n")
    fout.flush()


def serve_policy(policy, stdin=None, stdout=None):
    """Serve ``policy`` (a callable, or a factory ``task -> callable`` if it has attribute
    ``from_task``) over the external-policy protocol (actionshift-policy-v1, docs/backbones.md) on
    stdin/stdout, so ``actionshift run --backbone "external:python3 my_policy.py"`` runs it."""
    fout = stdout or _sys.stdout
    current = policy
    for msg in _json_lines(stdin or _sys.stdin):
        kind = msg.get("type")
        if kind == "hello":
            if hasattr(policy, "from_task"):
                current = policy.from_task(msg["task"])
            _reply(fout, {"type": "ready"})
        elif kind == "reset":
            if hasattr(current, "reset"):
                current.reset()
        elif kind == "step":
            action = _np.asarray(current(_np.asarray(msg["obs"], dtype=_np.float64)), dtype=_np.float64)
            _reply(fout, {"action": [float(x) for x in action.reshape(-1)]})


def serve_method(method, stdin=None, stdout=None):
    """Serve a method object (as ``evaluate(method=...)`` takes one: ``setup``, ``begin_episode``,
    ``encode``, ``observe``) over the external-method protocol (actionshift-method-v1,
    docs/methods.md) on stdin/stdout, so ``actionshift run --method "external:python3 my_method.py"
    --method-rung RUNG`` runs it in its own process. ``setup(inputs)`` is called before each episode
    with the inputs of the hello (those of the rung the command line declared)."""
    fout = stdout or _sys.stdout
    inputs = None
    for msg in _json_lines(stdin or _sys.stdin):
        kind = msg.get("type")
        if kind == "hello":
            given = msg.get("inputs") or {}
            cal = given.get("calibration")
            inputs = {"task": msg.get("task"), "rung": msg.get("rung"), "params": msg.get("params") or {},
                      "pool": None if given.get("pool") is None else [Contract.from_json(_json.dumps(c)) for c in given["pool"]],
                      "calibration": None if cal is None else ResponseModel(cal["alpha"], cal["sigma"], cal["gripper_alpha"],
                                                                             cal["gripper_sigma"]),
                      "grammar": given.get("grammar")}
            _reply(fout, {"type": "ready"})
        elif kind == "begin_episode":
            if hasattr(method, "setup"):
                method.setup(inputs)
            method.begin_episode(msg["seed"])
        elif kind == "encode":
            out = method.encode(_np.asarray(msg["canonical"], dtype=_np.float64),
                                _np.asarray(msg["R"], dtype=_np.float64).reshape(3, 3))
            probe = False
            if isinstance(out, tuple):
                out, probe = out
            _reply(fout, {"raw": [float(x) for x in _np.asarray(out, dtype=_np.float64).reshape(-1)], "probe": bool(probe)})
        elif kind == "observe":
            if hasattr(method, "observe_fingers") and msg.get("finger_delta") is not None:
                method.observe_fingers(msg["finger_delta"])
            if hasattr(method, "observe"):
                method.observe(_np.asarray(msg["raw"], dtype=_np.float64), _np.asarray(msg["response"], dtype=_np.float64),
                               _np.asarray(msg["R"], dtype=_np.float64).reshape(3, 3))


def _register_gymnasium():
    if _gym is None:
        return
    from gymnasium.envs.registration import register, registry

    for task, name in _TASK_IDS.items():
        env_id = f"ActionShift/{name}"
        if env_id not in registry:
            register(id=env_id, entry_point="actionshift:Env", kwargs={"task": task},
                     max_episode_steps=None, disable_env_checker=True)


_register_gymnasium()


def _one_line(e, limit=120):
    """An exception's message as one short line (numpy's can span lines)."""
    text = " ".join(str(e).split()) or type(e).__name__
    return text if len(text) <= limit else text[:limit] + "..."


def audit(log=None, *, actions=None, tcp_pos=None, tcp_quat=None, fingers=None, episode=None, declared="identity",
          model=None, confidence_floor=0.99, misspec_ratio=25.0, gain_tolerance=5.0):
    """Audit a log: the action contract of recorded data (docs/audit.md). Returns the report as a dict
    (the keys of `actionshift audit --json`: status PASS/MISMATCH/INCONCLUSIVE, reason, fields, ...).

    The log is a path to an `.npz` (arrays `actions`, `tcp_pos`, `tcp_quat` and optionally `fingers`,
    `episode`) or the arrays themselves: `actions` N x 7 (or N x 6 without gripper), `tcp_pos` N x 3 and
    `tcp_quat` N x 4 (w, x, y, z) measured before each action, `fingers` N x 2, `episode` N integers
    (consecutive equal ids form an episode). Without `episode`, tcp arrays of N + 1 rows add the final pose.
    `declared`: a library contract name, a Contract, or a conventions dict {"contract": ..., "rotation": ...,
    "gripper_range": ..., "action": ...}. `model`: a task name (its built-in calibration), a ResponseModel,
    or None (gains fitted from the log; scale is then reported relative to them, unchecked)."""
    source = "arrays"
    if log is not None:
        if not isinstance(log, (str, _os.PathLike)):
            raise InputError(f"audit: log must be a path to an .npz file (got a {type(log).__name__}); pass arrays by keyword")
        source = repr(str(log))[1:-1]  # one line whatever the path holds
        if not str(log).endswith(".npz"):
            raise InputError(f"audit: log must be a path to an .npz file (got '{source}'); pass arrays by keyword")
        try:
            z = _np.load(log)
        except (OSError, ValueError) as e:
            raise InputError(f"{source}: cannot read the .npz file ({type(e).__name__})") from None
        with z:
            missing = [k for k in ("actions", "tcp_pos", "tcp_quat") if k not in z.files]
            if missing:
                raise InputError(f"{source}: {missing[0]}: missing array")
            arrays = {}
            for k in ("actions", "tcp_pos", "tcp_quat", "fingers", "episode"):
                if k in z.files:
                    try:
                        arrays[k] = z[k]
                    except (OSError, ValueError) as e:  # e.g. an object array (pickled): not loaded
                        raise InputError(f"{source}: {k}: cannot be read ({_one_line(e)})") from None
            actions, tcp_pos, tcp_quat = arrays["actions"], arrays["tcp_pos"], arrays["tcp_quat"]
            fingers, episode = arrays.get("fingers"), arrays.get("episode")
    if actions is None or tcp_pos is None or tcp_quat is None:
        raise InputError("audit: actions, tcp_pos and tcp_quat are required")

    def numbers(name, x):
        try:
            return _np.asarray(x, dtype=float)
        except (TypeError, ValueError) as e:  # strings, ragged lists
            raise InputError(f"{source}: {name}: not an array of numbers ({_one_line(e)})") from None

    a = numbers("actions", actions)
    p = numbers("tcp_pos", tcp_pos)
    q = numbers("tcp_quat", tcp_quat)
    f = None if fingers is None else numbers("fingers", fingers)
    for name, arr in (("actions", a), ("tcp_pos", p), ("tcp_quat", q), ("fingers", f)):
        if arr is not None and not _np.all(_np.isfinite(arr)):
            row = int(_np.argwhere(~_np.isfinite(arr))[0][0])
            raise InputError(f"{source}: {name}: row {row}: not a finite number")
    if a.ndim != 2:
        raise InputError(f"{source}: actions: must be an N x 7 (or N x 6) array")
    episodes = []
    if episode is None:
        if len(p) not in (len(a), len(a) + 1):
            raise InputError(f"{source}: tcp_pos: {len(p)} rows for {len(a)} actions (need as many, or one more)")
        episodes.append((a, p, q, f))
    else:
        ids = _np.asarray(episode).reshape(-1)
        if len(ids) != len(a) or len(p) != len(a) or len(q) != len(a):
            raise InputError(f"{source}: episode: actions, tcp_pos, tcp_quat and episode must have the same rows")
        starts = [0] + [i for i in range(1, len(ids)) if ids[i] != ids[i - 1]] + [len(ids)]
        seen = set()
        for s, e in zip(starts[:-1], starts[1:]):
            if ids[s] in seen:
                raise InputError(f"{source}: episode: episode {ids[s]} appears again after another episode")
            seen.add(ids[s])
            episodes.append((a[s:e], p[s:e], q[s:e], None if f is None else f[s:e]))
    if isinstance(declared, Contract):
        declared = _json.dumps({"contract": declared.to_dict()})
    elif isinstance(declared, dict):
        declared = _json.dumps(declared)
    return _native._audit(episodes, str(declared), model, float(confidence_floor), float(misspec_ratio), float(gain_tolerance),
                          a.shape[1] == 7, source)
