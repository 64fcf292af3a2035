"""What every policy of this package is: Stable-Baselines3's ``predict`` interface, so baselines, trained
models (SB3, RLlib, ensembles, residuals) and the oracle drop in wherever one of them is run."""

from __future__ import annotations

from typing import Any, Protocol, runtime_checkable

import numpy as np


@runtime_checkable
class Policy(Protocol):
    """``predict(obs, state, episode_start, deterministic) -> (action, state)`` for one flat observation or
    a batch ``(n_envs, obs_dim)``, answered in the shape asked. A policy whose action depends on the well
    may also have ``reset(env, index=None)``, called after every ``env.reset``."""

    def predict(self, observation: np.ndarray, state: Any = None, episode_start: np.ndarray | None = None,
                deterministic: bool = True) -> tuple[np.ndarray, Any]: ...
