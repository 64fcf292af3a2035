"""Prescribed motion of the polished rod (top boundary, point A), positive downward.

``harmonic`` (paper): u_A = -(S/2)(1 - cos wt), each stroke starting at the bottom (u_A = 0).
``conventional``: API 11E beam-unit four-bar linkage (``beam_unit.py``) at constant crank speed; the stroke
is the crank hole's, and the unit's gearbox torque and power follow from the simulated loads
(``gearbox.py``, :meth:`SurfaceMotion.gearbox_report`).
``pullout``: constant upward speed V reached through a half-cosine ramp of ``pull_ramp_s``.
The simulator prescribes the *velocity*; displacement follows by Newmark integration, which for the
trapezoidal rule reproduces a periodic motion without drift.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np

from .beam_unit import ConventionalUnit
from .config import SurfaceConfig
from .errors import ConfigError
from .unit_catalogue import conventional_unit

if TYPE_CHECKING:
    from .gearbox import GearboxReport
    from .simulator import RunResult


class SurfaceMotion:
    """The top boundary of one well. ``unit`` overrides the catalogue unit named in the config (a custom or
    modified linkage, e.g. :meth:`~srenv.beam_unit.BeamUnitGeometry.scaled_linkage`); conventional only."""

    def __init__(self, cfg: SurfaceConfig, unit: ConventionalUnit | None = None) -> None:
        self.cfg = cfg
        self.kind = cfg.motion
        # SurfaceConfig(...) built in code skips load_config's range checks on this field
        if not 0.0 < cfg.motor_efficiency <= 1.0:
            raise ConfigError("surface.motor_efficiency", cfg.motor_efficiency, "a number in (0, 1]")
        if unit is not None and self.kind != "conventional":
            raise ConfigError("surface.motion", self.kind, "'conventional' when a beam unit is given")
        self._unit: ConventionalUnit | None = None
        if self.kind == "conventional":
            self._unit = unit if unit is not None else conventional_unit(cfg.unit, cfg.crank_hole)

    @property
    def unit(self) -> ConventionalUnit | None:
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

    def gearbox_report(
        self, results: list[RunResult], counterbalance_moment_nm: float | None = None
    ) -> GearboxReport | None:
        """Gearbox torque and power of recorded strokes with the configured counterbalance (or the given
        moment); None unless the motion is conventional (no linkage, no gearbox)."""
        if self._unit is None:
            return None
        from .gearbox import analyse_runs

        moment = self.cfg.counterbalance_moment_nm if counterbalance_moment_nm is None else counterbalance_moment_nm
        return analyse_runs(
            self._unit, results,
            counterbalance_moment_nm=moment,
            counterbalance_offset_rad=math.radians(self.cfg.counterbalance_offset_deg),
            motor_efficiency=self.cfg.motor_efficiency,
        )
