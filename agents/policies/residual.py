"""Residual agents: a learned correction on top of a tuned baseline controller (residual policy learning).

The agent's action ``r`` in [-1, 1]^2 moves the baseline's action ``b``: the env receives
``clip(b + scale * r, -1, 1)``; the agent also sees ``b`` (two observation entries appended). With
``idle_scale`` set, the rate entry's scale is ``idle_scale`` in an interval the baseline idles (``b0 = -1``):
``idle_scale = 2`` gives the agent the whole rate range there, so it can replace a pump-off stop by slow
continuous pumping, while ``r0 <= 0`` still idles. With
``r = 0`` it IS the baseline, so training starts from the tuned controller and learns only what improves
on it. Training uses :class:`agents.training.residual_env.ResidualEnv`; evaluation drives the plain env with
:class:`ResidualAgentPolicy`, which composes the same two parts (:func:`compose`, :func:`augment`) in the
same order.

A residual's correction may be bounded (``cap``, issue 24 f24: a correction chosen at no higher constraint cost):
``{"correction_scale": s, "spm_cap": c}`` multiplies the model's output by ``s`` and then caps its rate entry
at ``c`` (0: the correction may slow the pump or stop it, never speed it up); each key optional, no cap = the
model's output as it is (:func:`bound_correction`).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .factory import make_baseline
from .field import IDLE, obs_names_of
from .history import History

# the tuned field baselines a residual may sit on (not the oracle: it sees hidden state)
RESIDUAL_BASES = ("best_constant", "pump_off", "fillage_pi")


def check_scales(scale: Any, idle_scale: Any = None) -> None:
    """The one bound on a residual's scales (wrapper, evaluation policy, benchmark config, replay)."""
    for name, v in (("scale", scale), ("idle_scale", idle_scale)):
        if v is not None and (isinstance(v, bool) or not isinstance(v, (int, float)) or not 0.0 < v <= 2.0):
            raise ValueError(f"residual.{name} = {v!r}: expected a number in (0, 2] (a fraction of the action box)")


# the correction bound's fields, declared once: (lower, upper, lower bound included)
CAP_FIELDS = {"correction_scale": (0.0, 1.0, False), "spm_cap": (-1.0, 1.0, True)}


def check_cap(cap: Any) -> None:
    """The one bound on a residual's ``cap`` (evaluation policy, pilots, tests): a dict of :data:`CAP_FIELDS`."""
    if cap is None:
        return
    if not isinstance(cap, dict) or not cap or set(cap) - set(CAP_FIELDS):
        raise ValueError(f"residual.cap = {cap!r}: expected a mapping of {', '.join(CAP_FIELDS)}")
    for k, v in cap.items():
        lo, hi, closed = CAP_FIELDS[k]
        if (isinstance(v, bool) or not isinstance(v, (int, float)) or not (lo <= v if closed else lo < v)
                or not v <= hi):
            raise ValueError(f"residual.cap.{k} = {v!r}: expected a number in {'[' if closed else '('}{lo:g}, {hi:g}]")


def bound_correction(residual: np.ndarray, cap: dict[str, float] | None) -> np.ndarray:
    """The model's correction ``residual`` times ``cap['correction_scale']``, its rate entry at most
    ``cap['spm_cap']``; ``cap`` None: ``residual`` itself (the same array)."""
    if cap is None:
        return residual
    r = np.asarray(residual, np.float32) * np.float32(cap.get("correction_scale", 1.0))
    if "spm_cap" in cap:
        r[..., 0] = np.minimum(r[..., 0], np.float32(cap["spm_cap"]))
    return r


def compose(base_action: np.ndarray, residual: np.ndarray, scale: float,
            idle_scale: float | None = None) -> np.ndarray:
    b = np.asarray(base_action, np.float32)
    s = np.full(b.shape, float(scale), np.float32)
    if idle_scale is not None:
        # the rate entry of an interval the baseline idles: the agent may pump there instead
        s[..., 0] = np.where(b[..., 0] <= IDLE, np.float32(idle_scale), s[..., 0])
    return np.clip(b + s * np.asarray(residual, np.float32), -1.0, 1.0).astype(np.float32)


def augment(obs: np.ndarray, base_action: np.ndarray) -> np.ndarray:
    return np.concatenate([np.asarray(obs, np.float32), np.asarray(base_action, np.float32)], axis=-1)


class _Base:
    """The baseline's action for one env, with its recurrent state and per-episode hook."""

    def __init__(self, name: str, params: dict[str, Any], env: Any) -> None:
        self.policy = make_baseline(name, params, obs_names_of(env))
        self.state: Any = None
        self.start = True

    def reset(self, env: Any) -> None:
        if hasattr(self.policy, "reset"):
            self.policy.reset(env)
        self.state, self.start = None, True

    def act(self, obs: np.ndarray) -> np.ndarray:
        a, self.state = self.policy.predict(obs, state=self.state, episode_start=np.array([self.start]))
        self.start = False
        return np.asarray(a, np.float32)


class ResidualAgentPolicy:
    """Evaluation twin of :class:`agents.training.residual_env.ResidualEnv`: baseline action + scale x the model's, on the plain env."""

    def __init__(self, model_policy: Any, base: str, base_params: dict[str, Any], scale: float,
                 idle_scale: float | None = None, history: int = 1, cap: dict[str, float] | None = None) -> None:
        check_scales(scale, idle_scale)
        check_cap(cap)
        self.model, self.base_name, self.base_params, self.scale = model_policy, base, base_params, float(scale)
        self.idle_scale, self.cap = idle_scale, cap
        self.history = History(history)  # the model sees the last K observations; the base the current one
        self.base: _Base | None = None

    def reset(self, env: Any, index: int | None = None) -> None:
        if index not in (None, 0):
            raise ValueError("ResidualAgentPolicy drives one env")
        self.base = _Base(self.base_name, self.base_params, env)
        self.base.reset(env)
        self.history.reset()
        if hasattr(self.model, "reset"):  # a model that reads the well at reset (agents.policies.described_features)
            self.model.reset(env)

    def predict(self, observation: Any, state: Any = None, episode_start: Any = None,
                deterministic: bool = True) -> tuple[np.ndarray, Any]:
        if self.base is None:
            raise RuntimeError("ResidualAgentPolicy: call reset(env) after env.reset")
        obs = np.asarray(observation, np.float32)
        b = self.base.act(obs)
        r, state = self.model.predict(augment(self.history.push(obs), b), state=state, episode_start=episode_start,
                                      deterministic=deterministic)
        r = bound_correction(np.asarray(r).reshape(b.shape), self.cap)
        return compose(b, r, self.scale, self.idle_scale), state
