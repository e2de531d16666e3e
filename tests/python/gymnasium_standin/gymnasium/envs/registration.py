"""gymnasium.envs.registration: register() adds an EnvSpec to the registry dict."""
from dataclasses import dataclass, field


@dataclass
class EnvSpec:
    id: str
    entry_point: str
    kwargs: dict = field(default_factory=dict)
    max_episode_steps: int = None
    disable_env_checker: bool = False


registry = {}


def register(id, entry_point, kwargs=None, max_episode_steps=None, disable_env_checker=False, **_):
    if id in registry:
        raise ValueError(f"{id} is already registered")
    registry[id] = EnvSpec(id, entry_point, dict(kwargs or {}), max_episode_steps, disable_env_checker)
