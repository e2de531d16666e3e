"""A minimal stand-in for the parts of Gymnasium's public API that actionshift uses (Env, spaces.Box,
envs.registration.register/registry, make), so that the registration path is tested on machines
without Gymnasium (Debian 12 does not package it). It follows Gymnasium 1.x's documented
signatures; it is not Gymnasium. test_gymnasium.py puts it on sys.path only when the real package
is absent."""
import importlib

import numpy as np

from . import spaces  # noqa: F401
from .envs.registration import registry


class Env:
    """gymnasium.Env: reset(*, seed=None, options=None) seeds np_random; step is abstract."""

    metadata = {"render_modes": []}
    render_mode = None
    _np_random = None

    def reset(self, *, seed=None, options=None):
        if seed is not None:
            self._np_random = np.random.default_rng(seed)

    def step(self, action):
        raise NotImplementedError

    def close(self):
        pass


def make(env_id, **kwargs):
    spec = registry[env_id]
    module, attr = spec.entry_point.split(":")
    cls = getattr(importlib.import_module(module), attr)
    return cls(**{**spec.kwargs, **kwargs})
