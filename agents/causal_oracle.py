"""``causal_oracle``: the true well model without knowledge of the future - the fair top of v2's score.

The clairvoyant :class:`agents.oracle_v1.OraclePolicy` plans on a perfect copy of the env, which includes the
future: the inflow step to come and (v2) the conditions to come. Part of its lead over any controller is
information no causal controller has. The causal oracle is model-predictive control on the same true model
with that future removed: every ``replan_every`` intervals it deep-copies ``env.unwrapped`` (the true well,
its annulus, the condition it has *now*), **freezes** the copy's future - the reservoir keeps the
deliverability it has now (the inflow estimated from what has been seen: the current multiplier) and the
condition now active persists (none starts) - and scores each candidate action (the last one, idle, steps of
``steps`` around it on each axis, ``anchors``) by simulating ``horizon`` intervals on that frozen copy. It then
plays the best for ``replan_every`` intervals. Its compute is counted in ``sim_steps``.
"""

from __future__ import annotations

import copy
import math
from collections.abc import Sequence
from typing import Any

import numpy as np

from .baselines_v1 import _batch, _out
from .oracle_v1 import OraclePolicy


def freeze_future(model: Any) -> Any:
    """Remove what a causal controller cannot know from a copy of the env: the inflow keeps its present
    multiplier, the present condition (v2) persists and no other starts."""
    ann = model.sim.annulus
    now = float(ann.rate_multiplier) if ann is not None else 1.0
    model.inflow_multiplier = lambda t_s: now
    if hasattr(model, "_schedule"):
        from srenv.task.events import Event, Schedule

        label, sev = model._condition
        model._schedule = Schedule([Event(label, 0.0, math.inf, sev)] if label is not None else [])
    return model


class CausalOraclePolicy(OraclePolicy):
    name = "causal_oracle"

    def __init__(self, horizon: int = 6, replan_every: int = 3, steps: Sequence[float] = (0.3, 0.1),
                 anchors: Sequence[Sequence[float]] = ()) -> None:
        super().__init__(mode="lookahead", horizon=horizon, steps=steps, anchors=anchors)
        if replan_every < 1:
            raise ValueError(f"causal_oracle replan_every = {replan_every!r}: expected >= 1 interval")
        self.replan_every = int(replan_every)
        self._since = 0

    def reset(self, env: Any, index: int | None = None) -> None:
        super().reset(env, index)
        self._since = 0

    def score(self, action: np.ndarray) -> float:
        model = freeze_future(copy.deepcopy(self._env))
        total = 0.0
        for _ in range(self.horizon):
            _, r, terminated, truncated, _ = model.step(action)
            self.sim_steps += 1
            total += float(r)
            if terminated or truncated:
                break
        return total

    def predict(self, observation: Any, state: Any = None, episode_start: Any = None,
                deterministic: bool = True) -> tuple[np.ndarray, Any]:
        _, n, batched = _batch(observation)
        if n != 1 or self._env is None:
            raise RuntimeError("CausalOraclePolicy: one env only, and call reset(env) after env.reset")
        if self._since % self.replan_every == 0:
            best, best_r = self._last, -math.inf
            for c in self.candidates():
                r = self.score(c)
                if r > best_r:
                    best, best_r = c, r
            self._last = best
        self._since += 1
        return _out(self._last.reshape(1, 2), batched), state

    def params(self) -> dict[str, Any]:
        return {"horizon": self.horizon, "replan_every": self.replan_every, "steps": list(self.steps),
                "anchors": [a.tolist() for a in self.anchors]}
