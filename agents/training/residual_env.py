"""The residual agents' training env: ``srenv/SuckerRod-v1`` (or its shaped twin) driven by ``baseline +
scale x agent action``, the baseline's action appended to the observation (:mod:`agents.policies.residual`
says why; its :class:`~agents.policies.residual.ResidualAgentPolicy` is the evaluation twin).

Registered under ``<this module>:ResidualSuckerRod-v1`` (:data:`RESIDUAL_ENV_ID`, the module's own name, so the
id works from a checkout, ``agents...``, and from the wheel, ``srenv_agents...``), so SB3's vectorised envs
build it in any process.
"""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np

from ..envs import ENV_ID_V1, ENV_ID_V2, ENV_ID_V3, make_env
from ..policies.residual import _Base, augment, check_scales, compose
from .shaping import SHAPED_ENV_ID

ENV_ID = "ResidualSuckerRod-v1"
RESIDUAL_ENV_ID = f"{__name__}:{ENV_ID}"


class ResidualEnv(gym.Wrapper):
    """``env`` driven by ``baseline + scale * agent action``; observation = env's + the baseline action."""

    def __init__(self, env: gym.Env, base: str, base_params: dict[str, Any], scale: float = 0.3,
                 idle_scale: float | None = None) -> None:
        super().__init__(env)
        check_scales(scale, idle_scale)
        if base == "oracle":
            raise ValueError("residual base = oracle: expected a field baseline (it would see hidden state)")
        self.scale, self.idle_scale = float(scale), idle_scale
        self.base = _Base(base, base_params, env)
        low = np.concatenate([env.observation_space.low, -np.ones(2, np.float32)])
        high = np.concatenate([env.observation_space.high, np.ones(2, np.float32)])
        self.observation_space = gym.spaces.Box(low.astype(np.float32), high.astype(np.float32), dtype=np.float32)
        self.action_space = gym.spaces.Box(-1.0, 1.0, (2,), np.float32)
        self._b = np.zeros(2, np.float32)

    def reset(self, **kwargs: Any) -> tuple[np.ndarray, dict]:
        obs, info = self.env.reset(**kwargs)
        self.base.reset(self.env)
        self._b = self.base.act(obs)
        return augment(obs, self._b), info

    def step(self, action: np.ndarray) -> tuple[np.ndarray, float, bool, bool, dict]:
        obs, r, term, trunc, info = self.env.step(compose(self._b, action, self.scale, self.idle_scale))
        self._b = self.base.act(obs)
        return augment(obs, self._b), r, term, trunc, info


def make_residual_env(inner_env_id: str = ENV_ID_V1, base: str = "fillage_pi",
                      base_params: dict[str, Any] | None = None, scale: float = 0.3,
                      idle_scale: float | None = None, **env_kwargs: Any) -> ResidualEnv:
    # a fixed set: the id is a module path for gymnasium, and a training YAML must not choose what is imported
    allowed = (ENV_ID_V1, SHAPED_ENV_ID, ENV_ID_V2, ENV_ID_V3)  # v2, v3 (configs/benchmark/v2.yaml, v3.yaml): unshaped
    if inner_env_id not in allowed:
        raise ValueError(f"residual inner_env_id = {inner_env_id!r}: expected one of {', '.join(allowed)}")
    return ResidualEnv(make_env(inner_env_id, **env_kwargs), base, base_params or {}, scale, idle_scale)


if ENV_ID not in gym.registry:
    gym.register(ENV_ID, entry_point=make_residual_env)
