"""The envs the agents drive: srenv's ids as constants and one ``make_env`` for every caller.

``make_env`` imports srenv first, so the ids are registered in whichever process builds the env (a worker
of the rollout pool, an SB3 subprocess env, an RLlib env runner).
"""

from __future__ import annotations

from typing import Any

from srenv import ENV_ID as ENV_ID_V0
from srenv import ENV_ID_V1, ENV_ID_V2, ENV_ID_V3

__all__ = ["ENV_ID_V0", "ENV_ID_V1", "ENV_ID_V2", "ENV_ID_V3", "PLAYABLE_REPORTS", "env_tag", "make_env"]

# Whose benchmark reports' agents drive an env, its own first: v2 agents see v3's observation unchanged (v3 keeps
# v2's spaces), v1 agents v1's part of it (agents/evaluation/v1_view.py).
PLAYABLE_REPORTS: dict[str, tuple[str, ...]] = {ENV_ID_V1: (ENV_ID_V1,), ENV_ID_V2: (ENV_ID_V2, ENV_ID_V1),
                                                ENV_ID_V3: (ENV_ID_V3, ENV_ID_V2, ENV_ID_V1)}


def make_env(env_id: str = ENV_ID_V1, **kwargs: Any) -> Any:
    """``gymnasium.make(env_id, **kwargs)`` with srenv's envs registered in this process."""
    import gymnasium as gym

    from .inputs import make_kwargs

    return gym.make(env_id, **make_kwargs(kwargs))


def env_tag(env_id: str) -> str:
    """The version tag a benchmark's model files carry (``ppo_v1_seed0.zip``, ``oracle_distilled_v2_seed0.zip``):
    the id's ``-vN`` suffix, so a v2 model is never named as a v1 one."""
    tag = env_id.rsplit("-", 1)[-1]
    if not (tag.startswith("v") and tag[1:].isdigit()):
        raise ValueError(f"env_id = {env_id!r}: expected an id ending in -vN, e.g. srenv/SuckerRod-v2")
    return tag
