"""Baseline controllers with the Stable-Baselines3 ``predict`` interface.

Both map physical set-points (SPM, stroke length in m) into the env's action box [-1, 1]^2 with the env's own
linear map (:func:`srenv.envs.sucker_rod_v0.action_from_setpoints`: ``control.spm_min..spm_max``,
``control.stroke_min_m..stroke_max_m``), so they can
be dropped in wherever an SB3 model is evaluated (``evaluate_policy`` included: they accept and return the
recurrent ``state`` and honour ``episode_start``).

- :class:`RockingMachinePolicy`: the unit as installed, constant SPM and stroke (the config's
  ``surface.spm`` and ``surface.stroke_length_m``). This is the baseline users compare against.
- :class:`FillagePolicy`: a VSD pump-off controller. A discrete PI loop on the pump fillage of the last
  stroke moves the SPM towards a fillage set-point (stroke fixed): below the set-point the pump is
  outrunning the inflow (fluid pound), so it slows down; above it, liquid is left in the annulus, so it
  speeds up. It reads the fillage from the observation at ``fillage_index`` (the env documents its
  layout), or, when driven step by step, from ``info["fillage"]`` fed through :meth:`FillagePolicy.observe`.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from srenv.config import WellConfig
from srenv.envs.sucker_rod_v0 import action_from_setpoints, setpoints_from_action  # noqa: F401 - the env's map, public here


def _batch(obs: np.ndarray) -> tuple[int, bool]:
    """Number of observations and whether they came batched: the env's observation is flat (1-D), a
    VecEnv's is (n_envs, obs_dim); SB3's ``predict`` accepts both and answers in the same shape."""
    obs = np.asarray(obs)
    return (obs.shape[0], True) if obs.ndim > 1 else (1, False)


class RockingMachinePolicy:
    """Constant SPM and stroke length: the beam unit running as installed."""

    def __init__(self, cfg: WellConfig, spm: float | None = None, stroke_length_m: float | None = None) -> None:
        self.spm = cfg.surface.spm if spm is None else float(spm)
        self.stroke_length_m = cfg.surface.stroke_length_m if stroke_length_m is None else float(stroke_length_m)
        self._action = action_from_setpoints(self.spm, self.stroke_length_m, cfg.control)

    def predict(self, observation: np.ndarray, state: Any = None, episode_start: np.ndarray | None = None,
                deterministic: bool = True) -> tuple[np.ndarray, Any]:
        n, batched = _batch(observation)
        return (np.tile(self._action, (n, 1)) if batched else self._action.copy()), state

    def __repr__(self) -> str:
        return f"RockingMachinePolicy(spm={self.spm:g}, stroke_length_m={self.stroke_length_m:g})"


class FillagePolicy:
    """VSD pump-off control: PI on pump fillage acting on SPM, stroke length fixed.

    Velocity-form PI, once per control interval (one env step)::

        e_k   = fillage_k - setpoint                      (> 0: liquid left in the annulus)
        spm_k = clip(spm_{k-1} + kp (e_k - e_{k-1}) + ki e_k, spm_min, spm_max)

    The velocity form needs no separate anti-windup: the clip is the only memory of saturation, so the
    controller leaves a limit as soon as the error changes sign. Gains are in SPM per unit fillage
    (``kp``) and SPM per unit fillage per step (``ki``). The recurrent ``state`` is an array of shape
    (n_envs, 2) holding (commanded SPM, previous error) per env; ``episode_start`` resets a row to the
    config's SPM.
    """

    def __init__(self, cfg: WellConfig, fillage_index: int | None = None, setpoint: float = 0.88,
                 kp: float = 4.0, ki: float = 2.0, initial_spm: float | None = None,
                 stroke_length_m: float | None = None) -> None:
        if not 0.0 < setpoint <= 1.0:
            raise ValueError(f"fillage setpoint = {setpoint!r}: expected a number in (0, 1]")
        self.control = cfg.control
        self.fillage_index = fillage_index
        self.setpoint = float(setpoint)
        self.kp, self.ki = float(kp), float(ki)
        self.initial_spm = float(np.clip(cfg.surface.spm if initial_spm is None else initial_spm,
                                         cfg.control.spm_min, cfg.control.spm_max))
        self.stroke_length_m = cfg.surface.stroke_length_m if stroke_length_m is None else float(stroke_length_m)
        self._fed_fillage: np.ndarray | None = None

    def initial_state(self, n: int) -> np.ndarray:
        state = np.empty((n, 2))
        state[:, 0], state[:, 1] = self.initial_spm, 0.0
        return state

    @property
    def needs_info(self) -> bool:
        """True when the observation has no fillage to read: the episode loop feeds each step's info."""
        return self.fillage_index is None

    def observe(self, info: dict | list[dict]) -> None:
        """Feed the fillage from the env's ``info`` (one dict, or a VecEnv's list) for the next ``predict``."""
        infos = [info] if isinstance(info, dict) else list(info)
        self._fed_fillage = np.array([float(i["fillage"]) for i in infos])

    def _fillage(self, obs: np.ndarray, n: int) -> np.ndarray | None:
        if self._fed_fillage is not None:
            fill, self._fed_fillage = self._fed_fillage, None
            return np.broadcast_to(fill, (n,))
        if self.fillage_index is None:
            return None  # nothing measured yet (first step of an info-fed episode): hold the SPM
        return obs.reshape(n, -1)[:, self.fillage_index].astype(np.float64)

    def predict(self, observation: np.ndarray, state: np.ndarray | None = None,
                episode_start: np.ndarray | None = None, deterministic: bool = True) -> tuple[np.ndarray, Any]:
        obs = np.asarray(observation)
        n, batched = _batch(obs)
        state = self.initial_state(n) if state is None else np.array(state, dtype=np.float64).reshape(n, 2)
        starts = np.zeros(n, bool) if episode_start is None else np.asarray(episode_start, bool).reshape(n)
        state[starts] = self.initial_state(int(starts.sum()))
        fill = self._fillage(obs, n)
        if fill is not None:
            # the first interval of an episode has no previous error: start the P term from rest
            err = fill - self.setpoint
            prev = np.where(starts, err, state[:, 1])
            spm = state[:, 0] + self.kp * (err - prev) + self.ki * err
            state[:, 0] = np.clip(spm, self.control.spm_min, self.control.spm_max)
            state[:, 1] = err
        action = action_from_setpoints(state[:, 0], self.stroke_length_m, self.control)
        return (action if batched else action[0]), state

    def __repr__(self) -> str:
        return (f"FillagePolicy(setpoint={self.setpoint:g}, kp={self.kp:g}, ki={self.ki:g}, "
                f"stroke_length_m={self.stroke_length_m:g})")
