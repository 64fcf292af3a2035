"""v1's trained models driven from v2's observation, whose first 77 entries are v1's field observation."""

from __future__ import annotations

from typing import Any

import numpy as np

from .agent import build_policy

V1_FIELD_DIM = 77


class V1ObsView:
    """A model trained on v1's field observation, driven from v2's: it sees the first 77 entries (v1's) and
    whatever its caller appended at the end (a residual's baseline action)."""

    def __init__(self, policy: Any, model_dim: int) -> None:
        self.policy, self.model_dim = policy, int(model_dim)

    def predict(self, observation: Any, state: Any = None, episode_start: Any = None,
                deterministic: bool = True) -> tuple[np.ndarray, Any]:
        x = np.asarray(observation, np.float32)
        if x.shape[-1] != self.model_dim:
            tail = self.model_dim - V1_FIELD_DIM
            x = np.concatenate([x[..., :V1_FIELD_DIM], x[..., x.shape[-1] - tail:]], axis=-1) if tail else \
                x[..., :V1_FIELD_DIM]
        return self.policy.predict(x, state=state, episode_start=episode_start, deterministic=deterministic)


def _model_dim(spec: dict[str, Any]) -> int:
    from .model_io import read_data, space_shape

    path = spec["path"] if spec["kind"] == "agent" else spec["members"][0]["path"]
    return space_shape(read_data(path), "observation_space", path)[0]


def build_policy_any(spec: dict[str, Any], env: Any) -> Any:
    """:func:`agents.evaluation.agent.build_policy`, with v1 models viewing v2's observation through :class:`V1ObsView`."""
    policy = build_policy(spec, env)
    # a guard wraps the students of its own env version (agents/policies/guarded.py): no view
    if spec["kind"] in ("baseline", "guarded") or env.observation_space.shape[0] == V1_FIELD_DIM:
        return policy
    dim = _model_dim(spec)
    if hasattr(policy, "model") and hasattr(policy, "base_name"):  # a residual: the model sees obs + base action
        policy.model = V1ObsView(policy.model, dim)
        return policy
    return V1ObsView(policy, dim)
