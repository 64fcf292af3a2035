"""Prescribed motion of the polished rod (top boundary, point A), positive downward.

``harmonic`` (paper): u_A = -(S/2)(1 - cos wt), each stroke starting at the bottom (u_A = 0).
``conventional``: API 11E beam-unit four-bar linkage (``beam_unit.py``) at constant crank speed; the stroke
is the crank hole's, and the unit's gearbox torque and power follow from the simulated loads
(``gearbox.py``, :meth:`SurfaceMotion.gearbox_report`).
``beam_unit``: the same for a unit given by its nameplate, ``surface.beam_unit`` (``inline_unit.py``):
conventional, Mark II or air-balanced.
``pullout``: constant upward speed V reached through a half-cosine ramp of ``pull_ramp_s``.
``measured``: one stroke of a measured polished-rod position (``measured_motion.py``), a periodic spline
starting at the card's bottom; run at another SPM it is re-timed at the same phase, its stroke is the card's.
The simulator prescribes the *velocity*; displacement follows by Newmark integration, which for the
trapezoidal rule reproduces a periodic motion without drift.
"""

from __future__ import annotations

import contextlib
import math
from collections.abc import Iterator
from typing import TYPE_CHECKING

import numpy as np

from ..errors import ConfigError
from .beam_unit import ConventionalUnit
from .inline_unit import counterbalance, inline_unit, unit_for_stroke
from .measured_motion import MeasuredMotion, load_measured_motion
from .motor import motor_drive
from .unit_catalogue import conventional_unit

if TYPE_CHECKING:  # annotations only: the surface unit sits below the config that checks against its catalogue
    from ..config import SurfaceConfig
    from ..simulation.run_result import RunResult
    from .gearbox import GearboxReport


# motions driven by a beam unit's linkage (catalogue or nameplate): they have a gearbox
LINKAGE_MOTIONS = ("conventional", "beam_unit")
STROKE_CACHE_SIZE = 16  # setpoints whose stroke motion a surface keeps (SurfaceMotion.stroke_motion)


class SurfaceMotion:
    """The top boundary of one well. ``unit`` overrides the catalogue unit named in the config (a custom or
    modified linkage, e.g. :meth:`~srenv.beam_unit.BeamUnitGeometry.scaled_linkage`); conventional only."""

    def __init__(self, cfg: SurfaceConfig, unit: ConventionalUnit | None = None) -> None:
        self.cfg = cfg
        self.kind = cfg.motion
        # SurfaceConfig(...) built in code skips load_config's range checks on this field
        if not 0.0 < cfg.motor_efficiency <= 1.0:
            raise ConfigError("surface.motor_efficiency", cfg.motor_efficiency, "a number in (0, 1]")
        if unit is not None and self.kind not in LINKAGE_MOTIONS:
            raise ConfigError("surface.motion", self.kind, "'conventional' or 'beam_unit' when a beam unit is given")
        self._unit: ConventionalUnit | None = None
        if self.kind == "conventional":
            self._unit = unit if unit is not None else conventional_unit(cfg.unit, cfg.crank_hole)
        elif self.kind == "beam_unit":
            if cfg.beam_unit is None:  # SurfaceConfig(...) built in code skips load_config's checks
                raise ConfigError("surface.beam_unit", None, "the unit's nameplate with surface.motion 'beam_unit'")
            self._unit = unit if unit is not None else inline_unit(cfg.beam_unit)
        self._measured: MeasuredMotion | None = None
        # a stroke's top velocity and start state recur stroke after stroke at one setpoint: kept per
        # (SPM, stroke, steps) (the same arrays, computed once; the unit's linkage costs ~0.2 ms a stroke)
        self._strokes: dict[tuple, tuple[np.ndarray, tuple[float, float]]] = {}
        self._columns: dict = {}  # and a stroke's gearbox columns (gearbox.stroke_columns)
        self._deferring: list | None = None  # see deferring()
        if self.kind == "measured":
            self._measured = load_measured_motion(cfg.measured_card_csv, cfg.measured_spm)
        # surface.motor (opt-in): the crank speed follows the gearbox torque (motor.py); None = constant speed
        self.motor = motor_drive(cfg) if self._unit is not None else None

    @property
    def measured(self) -> MeasuredMotion | None:
        return self._measured

    @property
    def unit(self) -> ConventionalUnit | None:
        return self._unit

    def default_spm(self, configured_spm: float) -> float:
        """Stroke rate of a run that names none: the config's ``surface.spm``, or a measured card's own."""
        return self._measured.spm if self._measured is not None else configured_spm

    def stroke_length_m(self, requested_m: float) -> float:
        """The conventional unit's stroke is set by its crank hole, a measured card's by the card, not by the
        request; an inline unit with ``crank_follows_stroke`` takes the request up to its crank's stroke."""
        if self._measured is not None:
            return self._measured.stroke_m
        if self._follows:
            return min(float(requested_m), self._unit.stroke_m)
        return self._unit.stroke_m if self._unit is not None else requested_m

    @property
    def _follows(self) -> bool:
        return self.kind == "beam_unit" and self.cfg.beam_unit is not None and self.cfg.beam_unit.crank_follows_stroke

    def unit_for(self, stroke_m: float) -> ConventionalUnit | None:
        """The linkage that runs a stroke of ``stroke_m``: the configured one, or with ``crank_follows_stroke``
        the same unit on the crank radius of that stroke."""
        if self._follows:
            return unit_for_stroke(self.cfg.beam_unit, self.stroke_length_m(stroke_m))
        return self._unit

    def stroke_motion(self, spm: float, stroke_m: float, n_steps: int) -> tuple[np.ndarray, tuple[float, float]]:
        """(:meth:`stroke_velocity`, :meth:`stroke_start_state`) of one stroke, kept for the last setpoints (a
        fresh copy of the velocity each call: the caller owns it)."""
        key = (float(spm), float(stroke_m), int(n_steps), self.motor.version if self.motor is not None else 0)
        got = self._strokes.get(key)
        if got is None:
            got = (self.stroke_velocity(spm, stroke_m, n_steps), self.stroke_start_state(spm, stroke_m))
            if len(self._strokes) >= STROKE_CACHE_SIZE:
                self._strokes.clear()
            self._strokes[key] = got
        return got[0].copy(), got[1]

    def stroke_velocity(self, spm: float, stroke_m: float, n_steps: int) -> np.ndarray:
        """Top velocity (positive down) at the end of each of the n_steps steps of one stroke."""
        period = 60.0 / spm
        t = np.arange(1, n_steps + 1) * (period / n_steps)
        return self.velocity_at(t, spm, stroke_m)

    def velocity_at(self, t_s: np.ndarray, spm: float, stroke_m: float) -> np.ndarray:
        """Top velocity (positive down) at times t_s since the start (bottom) of a stroke."""
        t = np.asarray(t_s, dtype=float)
        omega = 2 * math.pi * spm / 60.0
        if self.kind == "harmonic":
            return -0.5 * stroke_m * omega * np.sin(omega * t)
        if self.kind in LINKAGE_MOTIONS:
            unit = self.unit_for(stroke_m)
            if self.motor is not None:  # the motor's crank angle and speed (constant until a stroke has run)
                theta, omega = self.motor.angle_and_speed(unit, t, spm)
                return -np.asarray(unit.torque_factor_m(theta)) * omega
            return -np.asarray(unit.torque_factor_m(unit.crank_angle_rad(t, spm))) * omega
        if self.kind == "measured":
            return self._measured.velocity_down_m_s(t, spm)
        raise ValueError("pull-out motion has no strokes: use duration-based runs")

    def stroke_start_state(self, spm: float, stroke_m: float) -> tuple[float, float]:
        """(velocity, acceleration) of the top (positive down) at the start of a stroke.

        The Newmark recursion of the prescribed top, a_{n+1} = (v_{n+1} - v_n)/(gamma dt) - a_n (1-gamma)/gamma,
        never forgets a wrong a_0: started at rest (a = 0) while the harmonic motion starts at -(S/2)w^2, the
        error alternates sign every step and reaches the polished-rod load through the top node's mass as a
        sawtooth at the Nyquist frequency. The simulator starts each stroke from this state instead.
        """
        omega = 2 * math.pi * spm / 60.0
        if self.kind == "harmonic":
            return 0.0, -0.5 * stroke_m * omega * omega
        if self.kind == "measured":
            return float(self._measured.velocity_down_m_s(np.array([0.0]), spm)[0]), \
                self._measured.acceleration_down_m_s2(0.0, spm)
        # periodic motions: a central difference of the velocity (t < 0 is the end of the previous stroke)
        h = 1e-5 * 60.0 / spm
        v = self.velocity_at(np.array([-h, 0.0, h]), spm, stroke_m)
        return float(v[1]), float((v[2] - v[0]) / (2 * h))

    def stroke_done(self, result: RunResult) -> RunResult:
        """A stroke has run (Simulator.run_stroke): with a motor, its torque sets the next strokes' crank speed.
        Returns the result."""
        if self.motor is not None:
            self.motor.observe(self.unit_for(result.stroke_length_m), result)
        return result

    def pull_velocity(self, t_s: np.ndarray, speed_m_s: float) -> np.ndarray:
        ramp = max(self.cfg.pull_ramp_s, 1e-12)
        s = np.where(t_s >= ramp, 1.0, 0.5 * (1 - np.cos(np.pi * np.clip(t_s, 0, ramp) / ramp)))
        return -speed_m_s * s

    @contextlib.contextmanager
    def deferring(self) -> Iterator[list]:
        """Within it, :meth:`gearbox_report` defers its optimal counterbalance and powers
        (``GearboxReport.completed`` computes them) and appends each report it makes to the list yielded: a
        caller whose summaries may never be read (srenv.task.interval: an exact stroke that is not an
        interval's last) completes only the one it keeps."""
        made: list = []
        self._deferring = made
        try:
            yield made
        finally:
            self._deferring = None

    def gearbox_report(
        self, results: list[RunResult], counterbalance_moment_nm: float | None = None
    ) -> GearboxReport | None:
        """Gearbox torque and power of recorded strokes with the configured counterbalance (or the given
        moment); None unless the motion is conventional (no linkage, no gearbox)."""
        if self._unit is None:
            return None
        from .gearbox import analyse_runs

        if self.kind == "beam_unit" and self.cfg.beam_unit is not None:
            configured, offset_rad = counterbalance(self.cfg.beam_unit)
        else:
            configured, offset_rad = self.cfg.counterbalance_moment_nm, math.radians(self.cfg.counterbalance_offset_deg)
        moment = configured if counterbalance_moment_nm is None else counterbalance_moment_nm
        # the crank radius of the recorded strokes (one setpoint per call: an interval's or a run's)
        unit = self.unit_for(results[0].stroke_length_m) if results else self._unit
        if self._follows and not unit.air_balanced and counterbalance_moment_nm is None:
            # a crew that changes the crank hole rebalances: the counterbalance effect at the rod stays (M ~ R)
            moment *= unit.stroke_m / self._unit.stroke_m
        report = analyse_runs(
            unit, results,
            counterbalance_moment_nm=moment,
            counterbalance_offset_rad=offset_rad,
            motor_efficiency=self.cfg.motor_efficiency,
            crank=None if self.motor is None else (lambda r: self.motor.crank_of(unit, r)), keep=self._columns,
            defer=self._deferring is not None,
        )
        if self._deferring is not None:
            self._deferring.append(report)
        return report
