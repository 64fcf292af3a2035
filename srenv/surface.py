"""Prescribed motion of the polished rod (top boundary, point A), positive downward.

``harmonic`` (paper): u_A = -(S/2)(1 - cos wt), each stroke starting at the bottom (u_A = 0).
``conventional``: API 11E beam-unit four-bar linkage (``beam_unit.py``) at constant crank speed.
``pullout``: constant upward speed V reached through a half-cosine ramp of ``pull_ramp_s``.
The simulator prescribes the *velocity*; displacement follows by Newmark integration, which for the
trapezoidal rule reproduces a periodic motion without drift.
"""

from __future__ import annotations

import math
from functools import lru_cache

import numpy as np

from .config import SurfaceConfig


class SurfaceMotion:
    def __init__(self, cfg: SurfaceConfig) -> None:
        self.cfg = cfg
        self.kind = cfg.motion
        self._unit = None
        if self.kind == "conventional":
            self._unit = _conventional_unit(cfg.unit, cfg.crank_hole)

    @property
    def unit(self):  # noqa: ANN201 - ConventionalUnit, imported lazily
        return self._unit

    def stroke_length_m(self, requested_m: float) -> float:
        """The conventional unit's stroke is set by its crank hole, not by the request."""
        return self._unit.stroke_m if self._unit is not None else requested_m

    def stroke_velocity(self, spm: float, stroke_m: float, n_steps: int) -> np.ndarray:
        """Top velocity (positive down) at the end of each of the n_steps steps of one stroke."""
        period = 60.0 / spm
        t = np.arange(1, n_steps + 1) * (period / n_steps)
        omega = 2 * math.pi / period
        if self.kind == "harmonic":
            return -0.5 * stroke_m * omega * np.sin(omega * t)
        if self.kind == "conventional":
            return -np.asarray(self._unit.torque_factor_m(self._unit.crank_angle_rad(t, spm))) * omega
        raise ValueError("pull-out motion has no strokes: use duration-based runs")

    def pull_velocity(self, t_s: np.ndarray, speed_m_s: float) -> np.ndarray:
        ramp = max(self.cfg.pull_ramp_s, 1e-12)
        s = np.where(t_s >= ramp, 1.0, 0.5 * (1 - np.cos(np.pi * np.clip(t_s, 0, ramp) / ramp)))
        return -speed_m_s * s


@lru_cache(maxsize=16)
def _conventional_unit(designation: str, crank_hole: int):  # noqa: ANN202
    from .beam_unit import ConventionalUnit
    from .unit_catalogue import get_unit

    return ConventionalUnit(get_unit(designation), crank_hole)
