"""``causal_oracle``: the true well model without knowledge of the future - the fair top of v2's score.

The clairvoyant :class:`agents.policies.oracle.OraclePolicy` plans on a perfect copy of the env, which includes the
future: the inflow step to come and (v2) the conditions to come. Part of its lead over any controller is
information no causal controller has. The causal oracle is model-predictive control on the same true model
with that future removed: every ``replan_every`` intervals it deep-copies ``env.unwrapped`` (the true well,
its annulus, the condition it has *now*), **freezes** the copy's future - the reservoir keeps the
deliverability it has now (the inflow estimated from what has been seen: the current multiplier) and the
condition now active persists (none starts) - and scores each candidate action (the last one, idle, steps of
``steps`` around it on each axis, ``anchors``) by simulating ``horizon`` intervals on that frozen copy, and each
tuned field baseline in ``policies`` (``[[name, params]]``) by running it closed loop, from the state it has now
(every given baseline runs alongside all episode on the real observations), over the same horizon. It then
plays the best - the constant action, or the baseline's own actions - for ``replan_every`` intervals. On the
frozen model it is thus at least as good as each given baseline over every horizon; on the real well the
future it did not know can still make it lose. Its compute is counted in ``sim_steps``.
"""

from __future__ import annotations

import copy
import math
from collections.abc import Sequence
from typing import Any

import numpy as np

from .field import _batch, _out, make_field_baseline, obs_names_of
from .oracle import OraclePolicy


def freeze_future(model: Any) -> Any:
    """Remove what a causal controller cannot know from a copy of the env: the inflow keeps its present
    multiplier, the present condition (v2) persists, no other starts and the rods do not part."""
    ann = model.sim.annulus
    now = float(ann.rate_multiplier) if ann is not None else 1.0
    model.inflow_multiplier = lambda t_s: now
    if hasattr(model, "_schedule"):
        from srenv.task.events import Event, PartingClock, Schedule

        label, sev = model._condition
        model._schedule = Schedule([Event(label, 0.0, math.inf, sev)] if label is not None else [])
        model._parting = PartingClock(budget=math.inf)  # when the rods will part is the future too
    return model


class CausalOraclePolicy(OraclePolicy):
    name = "causal_oracle"

    def __init__(self, horizon: int = 6, replan_every: int = 3, steps: Sequence[float] = (0.3, 0.1),
                 anchors: Sequence[Sequence[float]] = (), policies: Sequence[Sequence[Any]] = ()) -> None:
        super().__init__(mode="lookahead", horizon=horizon, steps=steps, anchors=anchors, policies=policies)
        if replan_every < 1:
            raise ValueError(f"causal_oracle replan_every = {replan_every!r}: expected >= 1 interval")
        self.replan_every = int(replan_every)
        self._since = 0
        self._live: dict[str, list[Any]] = {}
        self._follow: str | None = None

    def reset(self, env: Any, index: int | None = None) -> None:
        super().reset(env, index)
        self._since, self._follow = 0, None
        self._live = {}
        for name, params in self.policies:
            pol = make_field_baseline(name, params, obs_names_of(env))
            if hasattr(pol, "reset"):
                pol.reset(env)
            self._live[name] = [pol, None, True]  # policy, its state, episode start

    def _rollout(self, action: np.ndarray | None, live: list[Any] | None, obs: np.ndarray) -> float:
        """Return over the horizon on a frozen copy: a constant action, or a live baseline from its state now."""
        model = self._model()
        pol, state, start = copy.deepcopy(live) if live is not None else (None, None, False)
        total = 0.0
        for _ in range(self.horizon):
            a = action
            if pol is not None:
                a, state = pol.predict(obs, state=state, episode_start=np.array([start]))
                start = False
            obs, r, terminated, truncated, _ = model.step(np.asarray(a, np.float32))
            self.sim_steps += 1
            total += float(r)
            if terminated or truncated:
                break
        return total

    def _model(self) -> Any:
        """The model one rollout plays on: a frozen copy of the true env (estimated_mpc plans on its own)."""
        return freeze_future(copy.deepcopy(self._env))

    def score(self, action: np.ndarray) -> float:
        return self._rollout(action, None, np.zeros(0))

    def predict(self, observation: Any, state: Any = None, episode_start: Any = None,
                deterministic: bool = True) -> tuple[np.ndarray, Any]:
        obs, n, batched = _batch(observation)
        if n != 1 or self._env is None:
            raise RuntimeError("CausalOraclePolicy: one env only, and call reset(env) after env.reset")
        if self._since % self.replan_every == 0:
            best, best_r, self._follow = self._last, -math.inf, None
            for c in self.candidates():
                r = self.score(c)
                if r > best_r:
                    best, best_r = c, r
            for name, live in self._live.items():
                r = self._rollout(None, live, obs[0])
                if r > best_r:
                    best_r, self._follow = r, name
            self._last = best
        self._since += 1
        acts = {}
        for name, live in self._live.items():  # every baseline keeps its state on the real observations
            a, live[1] = live[0].predict(obs[0], state=live[1], episode_start=np.array([live[2]]))
            live[2] = False
            acts[name] = np.asarray(a, np.float32).reshape(2)
        if self._follow is not None:
            self._last = acts[self._follow]
        return _out(self._last.reshape(1, 2), batched), state

    def params(self) -> dict[str, Any]:
        return {"horizon": self.horizon, "replan_every": self.replan_every, "steps": list(self.steps),
                "anchors": [a.tolist() for a in self.anchors], "policies": [list(p) for p in self.policies]}
