"""Gearbox (speed reducer) torque and power of a conventional beam unit over simulated strokes.

The simulator gives the polished-rod load PRL(t) of every time step; the unit's kinematics give the crank
angle θ(t) of that step (each stroke starts at the bottom, θ = θ_bottom, and the crank turns at constant
speed ω = 2π·SPM/60). From them, API Spec 11E / RP 11L:

* net gearbox torque  T(θ) = TF(θ)·(PRL − SU) − M·sin(θ + τ)   (N·m, positive = the gearbox drives the
  cranks; sign conventions in :mod:`srenv.beam_unit`),
* gearbox loading     100·max|T| / torque rating   (%),
* polished-rod power  PRL·v, v upward (W); its stroke mean is the card work per unit time,
* crank-shaft power   T·ω (W); over whole strokes its mean equals the polished-rod power, because the
  counterweights and the structural unbalance only store and return energy within a crank turn,
* motor power         mean of max(T·ω, 0) / efficiency: the motor supplies the positive crank power and is
  credited nothing while the well over-runs it (generating torque is braked, not recovered), the usual
  conservative sizing assumption for a conventional unit.

:func:`optimal_counterbalance_nm` picks the counterbalance moment that minimises the peak |T| of a
stroke: the setting a field crew approximates by "balancing" the unit on equal up- and downstroke peaks.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
import numpy.typing as npt
from numba import njit

from .beam_unit import ConventionalUnit

if TYPE_CHECKING:
    from ..simulation.run_result import RunResult

FloatArray = npt.NDArray[np.float64]

# Bisection on the counterbalance moment halves the bracket each pass; 100 passes shrink it by 2^-100,
# far below any torque a gearbox rating resolves, so the loop ends on the tolerance, not the pass limit.
_BISECTION_PASSES = 100
_BISECTION_RTOL = 1e-12
COLUMNS_KEPT = 16  # setpoints whose stroke columns a well keeps (stroke_columns)


@dataclass(frozen=True)
class GearboxReport:
    """Per-sample torque and power of one or more strokes, and the figures a well analyst reads."""

    crank_angle_rad: FloatArray
    net_torque_nm: FloatArray
    polished_rod_power_w: FloatArray
    crank_power_w: FloatArray
    time_step_s: FloatArray
    torque_rating_nm: float
    counterbalance_moment_nm: float
    optimal_counterbalance_nm: float | None  # None while deferred (see completed)
    motor_efficiency: float
    air_balanced: bool = False  # the counterbalance is a cylinder force B at the polished rod (N), not M
    # (w_i, s_i) of optimal_counterbalance_nm while it and the powers are deferred (analyse(defer=True)): the
    # summary then holds None for them until completed() computes them
    deferred: tuple | None = None

    def completed(self) -> GearboxReport:
        """The report with its deferred figures computed (itself when none are): the figures analyse computes
        without ``defer``."""
        if self.deferred is None:
            return self
        return dataclasses.replace(self, optimal_counterbalance_nm=_optimal(*self.deferred), deferred=None)

    @property
    def peak_torque_nm(self) -> float:
        """Largest |T| over the strokes: a reversed (generating) peak loads the gear teeth as much."""
        return float(np.max(np.abs(self.net_torque_nm)))

    @property
    def loading_pct(self) -> float:
        return self._loading_pct(self.peak_torque_nm)

    def _loading_pct(self, peak_nm: float) -> float:
        return 100.0 * peak_nm / self.torque_rating_nm

    def _time_mean(self, values: FloatArray, total_s: float | None = None) -> float:
        # strokes at different SPM have different steps: weight each sample by its own step (``total_s``: the
        # steps' sum when the caller has it)
        total = np.sum(self.time_step_s) if total_s is None else total_s
        return float(np.sum(values * self.time_step_s) / total)

    @property
    def mean_polished_rod_power_w(self) -> float:
        return self._time_mean(self.polished_rod_power_w)

    @property
    def mean_crank_power_w(self) -> float:
        return self._time_mean(self.crank_power_w)

    @property
    def motor_power_w(self) -> float:
        return self._motor_power_w()

    def _motor_power_w(self, total_s: float | None = None) -> float:
        return self._time_mean(np.maximum(self.crank_power_w, 0.0), total_s) / self.motor_efficiency

    def summary(self) -> dict[str, float | None]:
        """The JSON keys :func:`srenv.stroke_summary.summarize` adds for a conventional unit (the properties'
        arithmetic with the peak and the steps' sum taken once: they were taken two and three times). A report
        with deferred figures gives None for the optimal counterbalance and the powers, in their places."""
        peak = self.peak_torque_nm
        later = self.deferred is not None
        total_s = None if later else np.sum(self.time_step_s)
        return {
            "peak_gearbox_torque_nm": peak,
            "max_gearbox_torque_nm": float(np.max(self.net_torque_nm)),
            "min_gearbox_torque_nm": float(np.min(self.net_torque_nm)),
            "gearbox_torque_rating_nm": self.torque_rating_nm,
            "gearbox_loading_pct": self._loading_pct(peak),
            **({"counterbalance_force_n": self.counterbalance_moment_nm,
                "optimal_counterbalance_force_n": self.optimal_counterbalance_nm} if self.air_balanced else
               {"counterbalance_moment_nm": self.counterbalance_moment_nm,
                "optimal_counterbalance_nm": self.optimal_counterbalance_nm}),
            "polished_rod_power_w": None if later else self._time_mean(self.polished_rod_power_w, total_s),
            "motor_power_w": None if later else self._motor_power_w(total_s),
        }


def optimal_counterbalance_nm(
    unit: ConventionalUnit,
    crank_angle_rad: npt.ArrayLike,
    polished_rod_load_n: npt.ArrayLike,
    crank_offset_rad: float = 0.0,
) -> float:
    """The counterbalance moment M ≥ 0 minimising max |T(θ)| over the given samples, N·m (an air-balanced
    unit's: the cylinder force B at the polished rod, N).

    T_i(M) = w_i − M·s_i with w_i = TF(θ_i)(PRL_i − SU) and s_i = sin(θ_i + τ + φ) (or TF(θ_i)), so max_i |T_i| is a
    convex, piecewise-linear function of M. Bisection on the sign of a subgradient (−s_i·sign T_i at the
    worst sample) therefore converges to the exact minimiser without a general-purpose optimiser.
    """
    theta = np.asarray(crank_angle_rad, dtype=float)
    well = unit.net_torque_nm(theta, polished_rod_load_n, 0.0)
    return _optimal(np.asarray(well), unit.counterbalance_arm(theta, crank_offset_rad))


def _optimal(well: FloatArray, arm: FloatArray) -> float:
    """:func:`optimal_counterbalance_nm` from the well's torque w_i and the counterbalance's arm s_i. It reads w
    through |w_i - M s_i| (M > 0) and the sign of w_i - M s_i where s_i != 0 alone, so the sign of a zero w_i
    does not reach the moment."""
    worst_arm = float(np.max(np.abs(arm)))
    if worst_arm == 0.0:
        return 0.0
    # beyond this M the counterweight term alone exceeds twice the M = 0 peak: no better than M = 0
    hi = 2.0 * float(np.max(np.abs(well))) / worst_arm
    return _bisect(np.ascontiguousarray(well, dtype=float), np.ascontiguousarray(arm, dtype=float), hi)


@njit(cache=True)
def _bisect(well: FloatArray, arm: FloatArray, hi: float) -> float:
    """The bisection of :func:`optimal_counterbalance_nm` on [0, hi], compiled: it ran ~40 numpy passes over
    the stroke's samples per env step. The same arithmetic sample by sample (T_i = w_i - M s_i, the first
    sample of largest |T_i|), so the same moment to the bit (tests/srenv/simulation/test_fast_paths.py).

    Once the bracket has narrowed, most samples can no longer be the largest |T_i| anywhere in it: every 4th
    pass from the 6th keeps only those that can (:func:`_prune`, in their order), so the later passes read a
    few samples instead of all: the same worst sample, so the same steps (tests/srenv/simulation/
    test_fast_paths_rl.py)."""
    lo = 0.0
    finite = np.all(np.isfinite(well)) and np.all(np.isfinite(arm)) and math.isfinite(hi) and well.size > 0
    # the rounding of any |T_i| on [0, hi] is below ~1e-15 of this: a margin of 1e-9 of it keeps every sample
    # that could be the computed worst one
    margin = 1e-9 * (np.max(np.abs(well)) + abs(hi) * np.max(np.abs(arm))) if finite else 0.0
    w, s = well, arm
    for it in range(_BISECTION_PASSES):
        if hi - lo <= _BISECTION_RTOL * max(hi, 1.0):
            break
        mid = 0.5 * (lo + hi)
        worst = 0
        peak = -1.0
        for i in range(w.size):
            t = abs(w[i] - mid * s[i])
            if t > peak or math.isnan(t):  # numpy's argmax: the first largest, or the first NaN
                worst, peak = i, t
                if math.isnan(t):
                    break
        slope = -s[worst] * math.copysign(1.0, w[worst] - mid * s[worst])
        if slope > 0.0:
            hi = mid
        elif slope < 0.0:
            lo = mid
        else:
            return mid
        if finite and it >= 5 and (it - 5) % 4 == 0 and w.size > 8:
            w, s = _prune(w, s, lo, hi, margin)
    return 0.5 * (lo + hi)


@njit(cache=True)
def _prune(well: FloatArray, arm: FloatArray, lo: float, hi: float, margin: float) -> tuple:
    """The samples (in their order) whose |T_i| can reach max_j |T_j| for some M in [lo, hi]. |T_i(M)| is convex
    in M, so at most its larger end value on the bracket; max_j |T_j(M)| is at least the largest of the
    samples' smallest |T_j| on it (0 where T_j changes sign)."""
    low = 0.0
    for i in range(well.size):
        a = well[i] - lo * arm[i]
        b = well[i] - hi * arm[i]
        if (a > 0.0 and b > 0.0) or (a < 0.0 and b < 0.0):
            low = max(low, min(abs(a), abs(b)))
    keep = np.empty(well.size, dtype=np.bool_)
    for i in range(well.size):
        keep[i] = max(abs(well[i] - lo * arm[i]), abs(well[i] - hi * arm[i])) >= low - margin
    return well[keep], arm[keep]


def analyse(
    unit: ConventionalUnit,
    crank_angle_rad: npt.ArrayLike,
    polished_rod_load_n: npt.ArrayLike,
    polished_rod_velocity_m_s: npt.ArrayLike,
    crank_speed_rad_s: npt.ArrayLike,
    time_step_s: npt.ArrayLike,
    *,
    counterbalance_moment_nm: float,
    counterbalance_offset_rad: float = 0.0,
    motor_efficiency: float = 1.0,
    factors: tuple[FloatArray, FloatArray] | None = None,
    defer: bool = False,
) -> GearboxReport:
    """Torque and power at each sample (arrays of equal length; velocity upward, ω > 0). On an air-balanced
    unit ``counterbalance_moment_nm`` is the cylinder's force B at the polished rod, in N. ``factors``: the
    unit's (torque factor, counterbalance arm) at these angles with this offset, when the caller keeps them
    (:func:`stroke_columns`). ``defer``: the optimal counterbalance (and the summary's powers) left for
    :meth:`GearboxReport.completed` (a stroke whose figures may never be read: srenv.task.interval)."""
    if not 0.0 < motor_efficiency <= 1.0:
        raise ValueError(f"motor_efficiency = {motor_efficiency!r}: expected a number in (0, 1]")
    theta = np.asarray(crank_angle_rad, dtype=float)
    load = np.asarray(polished_rod_load_n, dtype=float)
    # an air-balanced unit's counterbalance is the cylinder's force at the polished rod, through TF
    moment, force = (0.0, counterbalance_moment_nm) if unit.air_balanced else (counterbalance_moment_nm, 0.0)
    # optimal_counterbalance_nm's w is net_torque_nm(θ, load, 0) = TF·(load - SU - 0) - 0·sin(θ + φ): TF·(load - SU
    # - 0) up to the sign of its zeros, which _optimal does not see; its arm is TF on an air-balanced unit, the
    # torque's crank arm on the others: each taken once here (tests/srenv/simulation/test_fast_paths_rl.py)
    tf = np.asarray(unit.torque_factor_m(theta)) if factors is None else factors[0]
    su = unit.geometry.structural_unbalance_n
    if unit.air_balanced:  # the torque by net_torque_nm: its 0·sin(θ + τ + φ) signs the torque's exact zeros
        torque = np.asarray(unit.net_torque_nm(theta, load, moment, counterbalance_offset_rad, force))
        well, arm = tf * (load - su - 0.0), tf
    else:  # net_torque_nm's arithmetic (force = 0)
        well = tf * (load - su - force)
        arm = unit.counterbalance_arm(theta, counterbalance_offset_rad) if factors is None else factors[1]
        torque = well - moment * arm
    shape = theta.shape
    return GearboxReport(
        crank_angle_rad=theta,
        net_torque_nm=torque,
        polished_rod_power_w=load * np.asarray(polished_rod_velocity_m_s, dtype=float),
        crank_power_w=torque * _of_shape(crank_speed_rad_s, shape),
        time_step_s=np.array(_of_shape(time_step_s, shape)),
        torque_rating_nm=unit.geometry.torque_rating_nm,
        counterbalance_moment_nm=float(counterbalance_moment_nm),
        optimal_counterbalance_nm=None if defer else _optimal(well, arm),
        motor_efficiency=float(motor_efficiency),
        air_balanced=unit.air_balanced,
        deferred=(well, arm) if defer else None,
    )


def _of_shape(values: npt.ArrayLike, shape: tuple) -> FloatArray:
    """``values`` as floats broadcast to ``shape``; np.broadcast_to (~5 µs a call) only when they are not already
    of it (the same elements either way)."""
    arr = np.asarray(values, dtype=float)
    return arr if arr.shape == shape else np.broadcast_to(arr, shape)


def stroke_crank_angle_rad(unit: ConventionalUnit, result: RunResult) -> FloatArray:
    """θ at each recorded step of one stroke: the simulator records the state at the END of step k, i.e.
    k·Δt after the stroke began at the bottom (k = 1..n), the same instants its prescribed velocity uses."""
    step_s = result.duration_s / result.n_steps
    since_bottom_s = np.arange(1, result.n_steps + 1) * step_s
    return np.asarray(unit.crank_angle_rad(since_bottom_s, result.spm), dtype=float)


def _step_column(result: RunResult) -> FloatArray:
    return np.full(result.n_steps, result.duration_s / result.n_steps)


def _constant_speed_columns(unit: ConventionalUnit, result: RunResult) -> tuple[FloatArray, FloatArray, FloatArray]:
    """(θ, ω, step) at each recorded step of one stroke at constant crank speed."""
    return (stroke_crank_angle_rad(unit, result), np.full(result.n_steps, 2.0 * math.pi * result.spm / 60.0),
            _step_column(result))


@dataclass(frozen=True)
class StrokeColumns:
    """The columns of one constant-speed stroke that its setpoint fixes (read-only arrays): θ at each recorded
    step (:func:`stroke_crank_angle_rad`), ω, the step, and the unit's torque factor and counterbalance arm there."""

    unit: ConventionalUnit
    theta: FloatArray
    omega: FloatArray
    dt: FloatArray
    factors: tuple[FloatArray, FloatArray]


def stroke_columns(unit: ConventionalUnit, result: RunResult, offset_rad: float, keep: dict) -> StrokeColumns:
    """:class:`StrokeColumns` of a stroke, kept in ``keep`` (the caller's, per well: its last setpoints). Every
    stroke at one setpoint has the same columns: computing them was ~15 µs of a stroke's gearbox report."""
    key = (id(unit), result.spm, result.n_steps, result.duration_s, offset_rad)
    got = keep.get(key)
    if got is None or got.unit is not unit:
        theta, omega, dt = _constant_speed_columns(unit, result)
        cols = (theta, omega, dt, np.asarray(unit.torque_factor_m(theta), dtype=float),
                unit.counterbalance_arm(theta, offset_rad))
        for c in cols:
            c.setflags(write=False)  # shared by every report of the setpoint
        got = StrokeColumns(unit, *cols[:3], cols[3:])
        if len(keep) >= COLUMNS_KEPT:
            keep.clear()
        keep[key] = got
    return got


def analyse_runs(
    unit: ConventionalUnit,
    results: list[RunResult],
    *,
    counterbalance_moment_nm: float,
    counterbalance_offset_rad: float = 0.0,
    motor_efficiency: float = 1.0,
    crank=None,
    keep: dict | None = None,
    defer: bool = False,
) -> GearboxReport:
    """:func:`analyse` over recorded strokes (``run_stroke(record=True)``), each at its own SPM; ``crank``
    (result -> (θ, ω) at its steps) replaces the constant crank speed (a motor's, ``motor.MotorDrive``). ``keep``
    (a dict the caller holds per well): one stroke at constant speed takes its setpoint's columns from it
    (:func:`stroke_columns`; the same arrays as computed here, so the same report). ``defer``: see :func:`analyse`."""
    if not results or any(r.trace is None or r.spm <= 0 for r in results):
        raise ValueError("gearbox analysis needs recorded strokes (record=True, SPM > 0)")
    r = results[0]
    if keep is not None and crank is None and len(results) == 1 and len(r.trace["t_s"]) == r.n_steps:
        c = stroke_columns(unit, r, counterbalance_offset_rad, keep)
        return analyse(unit, c.theta, r.trace["polished_rod_load_n"], r.trace["polished_rod_velocity_m_s"], c.omega,
                       c.dt, counterbalance_moment_nm=counterbalance_moment_nm,
                       counterbalance_offset_rad=counterbalance_offset_rad, motor_efficiency=motor_efficiency,
                       factors=c.factors, defer=defer)
    columns: dict[str, list[FloatArray]] = {k: [] for k in ("theta", "load", "vel", "omega", "dt")}
    for r in results:
        n = r.n_steps
        if len(r.trace["t_s"]) != n:
            raise ValueError(f"a stroke recorded {len(r.trace['t_s'])} of its {n} steps: cannot place θ")
        if crank is not None:
            (theta, omega), dt = crank(r), _step_column(r)
        else:
            theta, omega, dt = _constant_speed_columns(unit, r)
        columns["theta"].append(theta)
        columns["omega"].append(omega)
        columns["load"].append(r.trace["polished_rod_load_n"])
        columns["vel"].append(r.trace["polished_rod_velocity_m_s"])
        columns["dt"].append(dt)
    joined = {k: np.concatenate(v) for k, v in columns.items()}
    return analyse(
        unit, joined["theta"], joined["load"], joined["vel"], joined["omega"], joined["dt"],
        counterbalance_moment_nm=counterbalance_moment_nm,
        counterbalance_offset_rad=counterbalance_offset_rad,
        motor_efficiency=motor_efficiency,
        defer=defer,
    )
