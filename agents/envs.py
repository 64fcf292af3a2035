"""The envs the agents drive: srenv's ids as constants and one ``make_env`` for every caller.

``make_env`` imports srenv first, so the ids are registered in whichever process builds the env (a worker
of the rollout pool, an SB3 subprocess env, an RLlib env runner).
"""

from __future__ import annotations

from typing import Any

from srenv import ENV_ID as ENV_ID_V0
from srenv import ENV_ID_V1, ENV_ID_V2

__all__ = ["ENV_ID_V0", "ENV_ID_V1", "ENV_ID_V2", "make_env"]


def make_env(env_id: str = ENV_ID_V1, **kwargs: Any) -> Any:
    """``gymnasium.make(env_id, **kwargs)`` with srenv's envs registered in this process."""
    import gymnasium as gym

    return gym.make(env_id, **kwargs)
