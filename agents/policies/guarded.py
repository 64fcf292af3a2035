"""A deployment-time constraint guard: a trained policy that hands the well to a safe tuned baseline while the
field observation shows what the constraint cost prices (issue 24, ``oracle_distilled_guarded``).

Why: the oracle-distilled students earn more than every tuned baseline, but on the fresh split they paid a
higher constraint cost (``info["cost"]``: overload, rod compression, fluid pound) than the field pump-off with
alarms. The guard keeps the students as trained (no retraining) and bounds when they act: after an interval
whose card shows a cost signal, the fallback's action is played for ``hold_intervals`` intervals.

Parameters (the ``guard`` part of a ``{"kind": "guarded", ...}`` policy spec; :func:`check_guard` bounds them):

- ``above``: ``{observation name: limit}``; the guard fires when the last card's entry exceeds its limit (e.g.
  ``pprl`` - the peak polished-rod load over the unit's rating - above 0.95; ``prob_fluid_pound``, the
  classifier's probability of fluid pound, above 0.5);
- ``below``: ``{observation name: limit}``; fires when the entry is under it (e.g. ``fillage_est`` < 0.6);
- ``hold_intervals``: how many intervals (>= 1) the fallback acts once the guard fires (re-armed while it fires);
- ``follow_shut_in``: also play the fallback whenever it idles on a shut-in alarm (``alarm_pump_off``'s parted-rod
  or tubing-leak signature; its state's third entry).
- ``follow_alarms`` (issue 24, u44: alarms first; fallback ``alarm_pump_off``): play the fallback in every interval
  where one of its alarms acts - the shut-in above, or its gas alarm (the slow-down's condition on the last card);
- ``follow_idle`` ("respect pump-off's idle"): play the fallback whenever it idles (its rate entry at ``IDLE``);
- ``disagreement_above`` (u44: trusted only where the members agree; the inner must hold a seed ensemble): play the
  fallback in an interval where the ensemble's members disagree by more than the limit on the action they were asked
  for (:func:`agents.policies.ensemble.disagreement`, the largest over the entries of their std): a hard gate, the
  interval only, no hold;
- ``fresh_card_only``: the ``above`` / ``below`` limits read only a card the well pumped for in the last interval
  (``duty`` > 0), so a fallback that idles does not re-fire on the stale last card all day (b43's finding); off
  unless set, as every archived guard played it.

The spec's optional ``scale`` replaces the inner residual's scale at deployment (0 = the residual's base itself).
It reads the field observation only (the names :func:`agents.policies.field.obs_names_of` gives), so a field
controller can run it. The fallback runs on every interval (its own state - pump-off's idle timer, the first
card's load range - stays current), and only its action is switched in.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from .ensemble import EnsemblePolicy
from .field import IDLE, name_index
from .residual import _Base

GUARD_KEYS = ("above", "below", "hold_intervals", "follow_shut_in", "follow_alarms", "follow_idle",
              "disagreement_above", "fresh_card_only")
FLAGS = ("follow_shut_in", "follow_alarms", "follow_idle", "fresh_card_only")
HOLD_MAX = 144  # one v2 episode of 10-min intervals


def check_guard(guard: Mapping[str, Any], obs_names: Sequence[str] | None = None) -> None:
    """The one place the guard's parameters are bounded (spec, tests, the benchmark config)."""
    unknown = [k for k in guard if k not in GUARD_KEYS] if isinstance(guard, Mapping) else ["(not a mapping)"]
    if unknown:
        raise ValueError(f"guard.{unknown[0]}: unknown key, expected a mapping with keys {', '.join(GUARD_KEYS)}")
    for side in ("above", "below"):
        for name, lim in (guard.get(side) or {}).items():
            if isinstance(lim, bool) or not isinstance(lim, (int, float)) or not np.isfinite(lim):
                raise ValueError(f"guard.{side}.{name} = {lim!r}: expected a finite number")
            if obs_names is not None:
                name_index(obs_names, name)
    hold = guard.get("hold_intervals", 1)
    if isinstance(hold, bool) or not isinstance(hold, int) or not 1 <= hold <= HOLD_MAX:
        raise ValueError(f"guard.hold_intervals = {hold!r}: expected an integer in [1, {HOLD_MAX}]")
    for flag in FLAGS:
        if type(guard.get(flag, False)) is not bool:
            raise ValueError(f"guard.{flag} = {guard[flag]!r}: expected true or false")
    lim = guard.get("disagreement_above")
    if lim is not None and (isinstance(lim, bool) or not isinstance(lim, (int, float)) or not 0.0 <= lim <= 1.0):
        raise ValueError(f"guard.disagreement_above = {lim!r}: expected a number in [0, 1] (the members' action std)")


def ensemble_in(policy: Any) -> EnsemblePolicy:
    """The seed ensemble a policy acts through (itself, or the model of a residual or described wrapper)."""
    p = policy
    while not isinstance(p, EnsemblePolicy) and hasattr(p, "model"):
        p = p.model
    if isinstance(p, EnsemblePolicy):
        return p
    raise ValueError("guard.disagreement_above: the inner policy is not a seed ensemble")


class GuardedPolicy:
    """``inner``'s action, or the ``fallback`` baseline's while the guard holds (one env)."""

    def __init__(self, inner: Any, fallback: str, fallback_params: dict[str, Any], guard: Mapping[str, Any],
                 obs_names: Sequence[str]) -> None:
        check_guard(guard, obs_names)
        self.inner, self.fallback_name, self.fallback_params = inner, fallback, dict(fallback_params)
        self.above = [(name_index(obs_names, n), float(v)) for n, v in (guard.get("above") or {}).items()]
        self.below = [(name_index(obs_names, n), float(v)) for n, v in (guard.get("below") or {}).items()]
        self.hold = int(guard.get("hold_intervals", 1))
        self.follow_shut_in = bool(guard.get("follow_shut_in", False))
        self.follow_alarms, self.follow_idle = bool(guard.get("follow_alarms", False)), bool(guard.get("follow_idle",
                                                                                                         False))
        if self.follow_alarms and fallback != "alarm_pump_off":
            raise ValueError(f"guard.follow_alarms: the fallback {fallback!r} has no alarms (expected alarm_pump_off)")
        self.disagree = guard.get("disagreement_above")
        self.ensemble = ensemble_in(inner) if self.disagree is not None else None
        self.i_duty = name_index(obs_names, "duty") if guard.get("fresh_card_only", False) else None
        self.fallback: _Base | None = None
        self.left = 0
        self.fired = 0  # intervals the fallback acted this episode (a diagnostic)

    def reset(self, env: Any, index: int | None = None) -> None:
        if index not in (None, 0):
            raise ValueError("GuardedPolicy drives one env")
        if hasattr(self.inner, "reset"):
            self.inner.reset(env)
        self.fallback = _Base(self.fallback_name, self.fallback_params, env)
        self.fallback.reset(env)
        self.left, self.fired = 0, 0

    def fires(self, obs: np.ndarray) -> bool:
        """Whether the last card shows a cost signal (the guard's limits on the field observation); with
        ``fresh_card_only``, never on a card the well did not pump for in the last interval."""
        if self.i_duty is not None and not obs[self.i_duty] > 0.0:
            return False
        return any(obs[i] > v for i, v in self.above) or any(obs[i] < v for i, v in self.below)

    def follows(self, obs: np.ndarray, safe: np.ndarray) -> bool:
        """Whether this interval is the fallback's whatever the limits say: its shut-in, its alarms, its idle, or the
        inner ensemble's members disagreeing (on the action they were just asked for)."""
        shut = (self.follow_shut_in or self.follow_alarms) and self.fallback is not None \
            and self.fallback.state is not None and float(np.asarray(self.fallback.state).reshape(-1, 4)[0, 2]) > 0.5
        gas = self.follow_alarms and bool(self.fallback.policy.gas_alarm(obs)[0])
        idle = self.follow_idle and float(safe[0]) <= IDLE
        split = self.ensemble is not None and float(np.max(self.ensemble.last_disagreement)) > float(self.disagree)
        return shut or gas or idle or split

    def predict(self, observation: Any, state: Any = None, episode_start: Any = None,
                deterministic: bool = True) -> tuple[np.ndarray, Any]:
        if self.fallback is None:
            raise RuntimeError("GuardedPolicy: call reset(env) after env.reset")
        obs = np.asarray(observation, np.float32).reshape(-1)
        safe = self.fallback.act(obs).reshape(-1)
        a, state = self.inner.predict(observation, state=state, episode_start=episode_start,
                                      deterministic=deterministic)
        if self.fires(obs):
            self.left = self.hold
        if self.left > 0 or self.follows(obs, safe):
            self.left = max(self.left - 1, 0)
            self.fired += 1
            return safe.astype(np.float32), state
        return np.asarray(a, np.float32).reshape(safe.shape), state


def guarded_spec(inner: dict[str, Any], fallback: str, fallback_params: dict[str, Any],
                 guard: Mapping[str, Any], scale: float | None = None) -> dict[str, Any]:
    """The policy spec of ``inner`` (an agent or ensemble spec, residual or not) under the guard."""
    check_guard(guard)
    if scale is not None and (isinstance(scale, bool) or not isinstance(scale, (int, float))
                              or not 0.0 <= scale <= 2.0):
        raise ValueError(f"guarded.scale = {scale!r}: expected a number in [0, 2] (0: the residual's base)")
    if scale is not None and not inner.get("residual"):
        raise ValueError("guarded.scale: the inner policy has no residual to scale")
    out = {"kind": "guarded", "inner": dict(inner), "fallback": {"name": fallback, "params": dict(fallback_params)},
           "guard": {k: (dict(v) if isinstance(v, Mapping) else v) for k, v in guard.items()}}
    if scale is not None:
        out["scale"] = float(scale)
    return out
