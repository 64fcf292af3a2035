"""Baseline controllers for ``srenv/SuckerRod-v1`` on the FIELD observation, with SB3's ``predict``.

Every policy here answers ``predict(obs, state=None, episode_start=None, deterministic=True) ->
(action, state)`` for one flat observation or a batch ``(n_envs, obs_dim)``, and reads the observation by
name (the env's ``obs_names``), never by a hard-coded position. Policies whose action depends on the
well (the installed operating point, the VSD's start speed, the oracle's model) have a per-episode hook
``reset(env, index=None)``: call it after ``env.reset`` (``index`` = the row of a batch). The benchmark's
rollout calls it; SB3 models have no such hook and need none.

Action coordinates. v1's action is ``a = (a0, a1)`` in [-1, 1]^2: ``a0`` maps linearly to the AVERAGE
stroke rate in ``[0, spm_max]`` (``a0 = -1`` idles the whole interval; an average below the VSD minimum
``spm_min`` runs at ``spm_min`` for part of the interval), ``a1`` to the stroke length in
``[stroke_min_m, stroke_max_m]``. The ranges are per well, so the tunable baselines are parametrised in
action coordinates (a fraction of each well's range), which is also how one set-point transfers from
the tuning wells to unseen ones.

- :class:`InstalledPolicy` - the unit as configured: the well's ``surface.spm`` and
  ``surface.stroke_length_m``, constant.
- :class:`ConstantPolicy` - one constant action for every well (``best_constant`` once tuned).
- :class:`PumpOffPolicy` - the field's pump-off controller: pump at a set point while the card's fillage
  estimate stays at or above a threshold; below it, idle for a set time, then restart.
- :class:`FillagePIPolicy` - VSD speed control: PI on the card's fillage estimate, the average-rate
  output free over the whole action range (below ``spm_min`` the unit goes intermittent).
- :class:`agents.policies.oracle.OraclePolicy` - knows the hidden well and inflow schedule: a perfect-model
  planner on deep copies of ``env.unwrapped`` (docs/benchmark.md says why it is a fair top of the
  normalised score).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

IDLE = -1.0  # a0 that idles the whole interval (average rate 0)


# ------------------------------------------------------------------------------------------ helpers
def obs_names_of(env: Any) -> tuple[str, ...]:
    """Names of the env's flat observation, in order (the v1 contract: ``env.unwrapped.obs_names``)."""
    return tuple(env.unwrapped.obs_names)


def name_index(obs_names: Sequence[str], name: str) -> int:
    try:
        return list(obs_names).index(name)
    except ValueError:
        raise ValueError(f"observation has no {name!r} (names: {', '.join(obs_names[:6])}, ...)") from None


def action_from_setpoints(avg_spm: float, stroke_m: float, control: Any) -> np.ndarray:
    """The action commanding an average stroke rate and a stroke length on a well with this ``control``:
    the env's own map (one definition), imported when first used (it loads the simulator)."""
    from srenv.envs.sucker_rod_v1 import action_from_setpoints as env_map

    return np.asarray(env_map(avg_spm, stroke_m, control), dtype=np.float32)


def interval_s_of(env: Any) -> float:
    """Seconds of well time per env step (v1: ``cfg.task.interval_s``)."""
    return float(env.unwrapped.cfg.task.interval_s)


def _batch(obs: Any) -> tuple[np.ndarray, int, bool]:
    """(obs as 2-D, rows, batched?) - SB3's ``predict`` answers in the shape it was asked in."""
    x = np.asarray(obs, dtype=np.float64)
    return (x, x.shape[0], True) if x.ndim > 1 else (x.reshape(1, -1), 1, False)


def _starts(episode_start: Any, n: int, state: Any) -> np.ndarray:
    if state is None:
        return np.ones(n, bool)
    return np.zeros(n, bool) if episode_start is None else np.asarray(episode_start, bool).reshape(n)


def _out(action: np.ndarray, batched: bool) -> np.ndarray:
    a = np.clip(np.asarray(action, dtype=np.float32), -1.0, 1.0)
    return a if batched else a[0]


class _RowActions:
    """Per-row constant actions filled by ``reset(env, index)`` (a batch holds different wells)."""

    def __init__(self) -> None:
        self._rows: dict[int, np.ndarray] = {}

    def set(self, index: int | None, action: np.ndarray) -> None:
        self._rows[0 if index is None else int(index)] = np.asarray(action, np.float32)

    def get(self, n: int, what: str) -> np.ndarray:
        missing = [i for i in range(n) if i not in self._rows]
        if missing:
            raise RuntimeError(f"{what}: call reset(env, index) after env.reset for rows {missing}")
        return np.stack([self._rows[i] for i in range(n)])


# --------------------------------------------------------------------------------------- baselines
class InstalledPolicy:
    """The unit as configured: ``cfg.surface.spm`` and ``cfg.surface.stroke_length_m`` of the episode's
    well (``env.unwrapped.cfg``, read by :meth:`reset` after every ``env.reset``)."""

    name = "installed"

    def __init__(self) -> None:
        self._actions = _RowActions()

    def reset(self, env: Any, index: int | None = None) -> None:
        cfg = env.unwrapped.cfg
        self._actions.set(index, action_from_setpoints(cfg.surface.spm, cfg.surface.stroke_length_m,
                                                       cfg.control))

    def predict(self, observation: Any, state: Any = None, episode_start: Any = None,
                deterministic: bool = True) -> tuple[np.ndarray, Any]:
        _, n, batched = _batch(observation)
        return _out(self._actions.get(n, "InstalledPolicy"), batched), state

    def params(self) -> dict[str, Any]:
        return {"rule": "cfg.surface.spm and cfg.surface.stroke_length_m of each well"}


class ConstantPolicy:
    """The same action on every well and every interval (action coordinates, see the module doc)."""

    name = "constant"

    def __init__(self, a_spm: float, a_stroke: float) -> None:
        self.action = np.clip(np.array([a_spm, a_stroke], np.float32), -1.0, 1.0)

    def predict(self, observation: Any, state: Any = None, episode_start: Any = None,
                deterministic: bool = True) -> tuple[np.ndarray, Any]:
        _, n, batched = _batch(observation)
        return _out(np.tile(self.action, (n, 1)), batched), state

    def params(self) -> dict[str, Any]:
        return {"a_spm": float(self.action[0]), "a_stroke": float(self.action[1])}


class PumpOffPolicy:
    """Pump-off control as the field runs it (a timer-restart pump-off controller).

    While pumping, at ``a_spm`` / ``a_stroke``: if the last interval pumped and its card's fillage
    estimate (``fillage_est``) fell below ``threshold``, stop for ``idle_time_s`` (rounded to whole control
    intervals, at least one), then restart. During idle the card is stale (the last pumped stroke), so it
    is not read; the restart interval is always pumped and its card decides the next stop.

    ``state`` per row: (intervals of idle left, 1 if the last interval was a pumping one).
    """

    name = "pump_off"

    def __init__(self, obs_names: Sequence[str], threshold: float = 0.8, idle_time_s: float = 1800.0,
                 a_spm: float = 0.5, a_stroke: float = 1.0, interval_s: float = 300.0) -> None:
        if not 0.0 <= threshold <= 1.0:
            raise ValueError(f"pump_off threshold = {threshold!r}: expected a fillage in [0, 1]")
        if idle_time_s < 0:
            raise ValueError(f"pump_off idle_time_s = {idle_time_s!r}: expected >= 0 s")
        self.i_fill = name_index(obs_names, "fillage_est")
        self.threshold, self.idle_time_s = float(threshold), float(idle_time_s)
        self.a_spm, self.a_stroke = float(a_spm), float(a_stroke)
        self.interval_s = float(interval_s)

    @property
    def idle_intervals(self) -> int:
        return max(1, round(self.idle_time_s / self.interval_s))

    def reset(self, env: Any, index: int | None = None) -> None:
        # the env's control interval (the same for all rows of a benchmark)
        self.interval_s = interval_s_of(env)

    def predict(self, observation: Any, state: Any = None, episode_start: Any = None,
                deterministic: bool = True) -> tuple[np.ndarray, Any]:
        obs, n, batched = _batch(observation)
        starts = _starts(episode_start, n, state)
        st = np.zeros((n, 2)) if state is None else np.array(state, np.float64).reshape(n, 2)
        st[starts] = 0.0
        idle_left, pumped_last = st[:, 0], st[:, 1] > 0.5
        pumped_off = pumped_last & (idle_left <= 0) & (obs[:, self.i_fill] < self.threshold)
        idle_left = np.where(pumped_off, self.idle_intervals, idle_left)
        idle_now = idle_left > 0
        st[:, 0] = np.where(idle_now, idle_left - 1, 0.0)
        st[:, 1] = (~idle_now).astype(np.float64)
        action = np.empty((n, 2))
        action[:, 0] = np.where(idle_now, IDLE, self.a_spm)
        action[:, 1] = self.a_stroke
        return _out(action, batched), st

    def params(self) -> dict[str, Any]:
        return {"threshold": self.threshold, "idle_time_s": self.idle_time_s, "a_spm": self.a_spm,
                "a_stroke": self.a_stroke}


class FillagePIPolicy:
    """VSD speed control: a discrete PI loop on the card's fillage estimate, once per control interval.

    Velocity form on the average-rate coordinate ``u = a0``::

        e_k = fillage_est_k - setpoint          (> 0: liquid left in the annulus -> speed up)
        u_k = clip(u_{k-1} + kp (e_k - e_{k-1}) + ki e_k, u_min, 1)

    The velocity form is its own anti-windup: the clip is the only memory of saturation, so the output
    leaves a limit as soon as the error changes sign. The output spans the whole action range, so below
    the VSD minimum the unit goes intermittent; ``u_min`` (> -1) keeps a little pumping in every interval,
    because a fully idle interval has no new card and the loop would be blind. Gains are in action units
    (2 = the well's whole speed range) per unit fillage (kp) and per unit fillage per interval (ki). The
    loop starts each episode from the installed speed (``reset(env)``) or from ``u0``.

    ``state`` per row: (u, previous error).
    """

    name = "fillage_pi"

    def __init__(self, obs_names: Sequence[str], setpoint: float = 0.85, kp: float = 0.5, ki: float = 0.3,
                 a_stroke: float = 1.0, u0: float = 0.0, u_min: float = -0.95) -> None:
        if not 0.0 < setpoint <= 1.0:
            raise ValueError(f"fillage_pi setpoint = {setpoint!r}: expected a fillage in (0, 1]")
        self.i_fill = name_index(obs_names, "fillage_est")
        self.setpoint, self.kp, self.ki = float(setpoint), float(kp), float(ki)
        self.a_stroke, self.u0, self.u_min = float(a_stroke), float(u0), float(u_min)
        self._u0_rows: dict[int, float] = {}

    def reset(self, env: Any, index: int | None = None) -> None:
        cfg = env.unwrapped.cfg
        a = action_from_setpoints(cfg.surface.spm, cfg.surface.stroke_length_m, cfg.control)
        self._u0_rows[0 if index is None else int(index)] = float(max(a[0], self.u_min))

    def _u0(self, rows: np.ndarray) -> np.ndarray:
        return np.array([self._u0_rows.get(int(i), self.u0) for i in rows])

    def predict(self, observation: Any, state: Any = None, episode_start: Any = None,
                deterministic: bool = True) -> tuple[np.ndarray, Any]:
        obs, n, batched = _batch(observation)
        starts = _starts(episode_start, n, state)
        st = np.zeros((n, 2)) if state is None else np.array(state, np.float64).reshape(n, 2)
        err = obs[:, self.i_fill] - self.setpoint
        # first interval of an episode: no card of ours yet - hold the start speed, remember the error
        rows = np.flatnonzero(starts)
        u = st[:, 0].copy()
        u_new = np.clip(u + self.kp * (err - st[:, 1]) + self.ki * err, self.u_min, 1.0)
        u = np.where(starts, 0.0, u_new)
        u[rows] = self._u0(rows)
        st[:, 0], st[:, 1] = u, err
        action = np.stack([u, np.full(n, self.a_stroke)], axis=1)
        return _out(action, batched), st

    def params(self) -> dict[str, Any]:
        return {"setpoint": self.setpoint, "kp": self.kp, "ki": self.ki, "a_stroke": self.a_stroke,
                "u_min": self.u_min}


# ------------------------------------------------------------------------------------------ factory
FIELD_BASELINES = ("installed", "best_constant", "pump_off", "fillage_pi")


def make_field_baseline(name: str, params: dict[str, Any], obs_names: Sequence[str]) -> Any:
    """A closed-loop field baseline by benchmark name from its (tuned) parameters (the oracle aside:
    :func:`agents.policies.factory.make_baseline` knows every name)."""
    p = dict(params)
    if name == "installed":
        return InstalledPolicy()
    if name in ("best_constant", "constant"):
        return ConstantPolicy(p["a_spm"], p["a_stroke"])
    if name == "pump_off":
        return PumpOffPolicy(obs_names, **p)
    if name == "fillage_pi":
        return FillagePIPolicy(obs_names, **p)
    raise ValueError(f"baseline {name!r}: expected one of {', '.join(FIELD_BASELINES)}")
