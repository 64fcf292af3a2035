"""The prime mover of a beam pumping unit (``surface.motor``, opt-in): a NEMA induction motor's torque-slip line
and the crank speed it gives through a stroke. docs/surface_unit.md ("The motor") gives the equations.

Motor law
---------
An induction motor near its operating point delivers a torque proportional to its slip s = 1 - ω/Ω_s (Ω_s the
synchronous speed): T = T_r s / s_r, with s_r the rated slip at the rated torque T_r = P_r / ((1 - s_r) Ω_s).
Referred to the crank shaft through the sheaves and the gearbox (speeds divided, torques multiplied by the
total ratio, losses ignored), the same line holds with Ω_s the synchronous speed at the crank. NEMA MG-1
(Part 1.19.1, "Design letters") sets the designs by their locked-rotor and breakdown torques and slip: Design B
(normal torque, slip at rated load below 5 %, breakdown torque >= 200 % of rated for the sizes of pumping-unit
motors), Design C (high starting torque, slip below 5 %, breakdown >= 190 %), Design D (high slip: 5 % or
more; locked-rotor torque >= 275 %, which is also its largest torque: a D motor has no distinct breakdown
point). Pumping units run Design D motors, sold as 5-8 % ("standard") and 8-13 % slip; the ultra-high-slip
motors beyond (15-45 %) are no NEMA design. The nominal rated slips taken when none is given
(:data:`NEMA_DESIGNS`): B 3 %, C 4 % (typical catalogue figures under MG-1's 5 %), D 6.5 % (the middle of the
5-8 % standard range). A torque above the design's largest one stalls the motor: refused, naming the rated
power.

Crank speed
-----------
The net gearbox torque T_net(θ) of a stroke (``gearbox.py``: torque factor x rod load minus the counterbalance
and the structural unbalance) is what the motor must deliver at the crank. With the unit's rotating inertia J
referred to the crank shaft (motor rotor, sheaves, gearbox, cranks and counterweights), the crank speed follows

    J dω/dt = T_r (1 - ω/Ω_s) / s_r - T_net(θ),        dθ/dt = ω,

periodic over a crank turn; without J (0) the quasi-static slip line, ω = Ω_s (1 - s_r T_net / T_r). The mean
speed is the stroke's: the sheaves are what set the SPM, so Ω_s (the crank's synchronous speed) is solved
for the stroke period ∮ dθ/ω = 60/SPM. ω is resolved on :data:`GRID` crank angles past the bottom of the
stroke; between them the crank angle is linear in time.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from ..errors import ConfigError

if TYPE_CHECKING:
    from ..config_unit import MotorConfig

# NEMA design letter -> (nominal rated slip, largest torque / rated torque): NEMA MG-1 Part 1.19.1 (module doc)
NEMA_DESIGNS: dict[str, tuple[float, float]] = {"B": (0.03, 2.0), "C": (0.04, 1.9), "D": (0.065, 2.75)}
GRID = 720            # crank angles per turn on which the speed is resolved
WHERE = "surface.motor"


@dataclass(frozen=True)
class MotorLaw:
    """A NEMA motor on the crank shaft: design letter, rated power (W), rated slip, inertia at the crank."""

    design: str
    rated_power_w: float
    rated_slip: float
    inertia_kg_m2: float = 0.0

    @classmethod
    def from_config(cls, m: MotorConfig) -> MotorLaw:
        slip = NEMA_DESIGNS[m.nema_design][0] if m.rated_slip is None else float(m.rated_slip)
        return cls(m.nema_design, float(m.rated_power_w), slip, float(m.inertia_kg_m2))

    @property
    def max_torque_ratio(self) -> float:
        return NEMA_DESIGNS[self.design][1]

    def rated_crank_torque_nm(self, sync_rad_s: float) -> float:
        """T_r at the crank for a crank synchronous speed Ω_s (rad/s)."""
        return self.rated_power_w / ((1.0 - self.rated_slip) * sync_rad_s)


def _quasi_static(law: MotorLaw, torque: np.ndarray, sync: float) -> np.ndarray:
    return sync * (1.0 - law.rated_slip * torque / law.rated_crank_torque_nm(sync))


def _with_inertia(law: MotorLaw, torque: np.ndarray, sync: float) -> np.ndarray:
    """The periodic solution of J dω/dt = T_m(ω) - T_net(θ) on the grid: each step relaxes ω exactly towards the
    quasi-static speed of the step's mean torque (time constant τ = J s_r Ω_s / T_r, unconditionally stable);
    the start speed is found by a secant on the turn's end speed (the map is nearly affine)."""
    step = 2.0 * math.pi / torque.size
    eq = _quasi_static(law, 0.5 * (torque + np.roll(torque, -1)), sync)
    tau = law.inertia_kg_m2 * law.rated_slip * sync / law.rated_crank_torque_nm(sync)

    def turn(w0: float) -> tuple[np.ndarray, float]:
        w = np.empty(torque.size)
        cur = w0
        for j in range(torque.size):
            w[j] = cur
            cur = eq[j] + (cur - eq[j]) * math.exp(-step / (max(cur, 1e-9 * sync) * tau))
        return w, cur

    a = float(eq[-1])
    _, ea = turn(a)
    b = float(ea)
    for _ in range(50):
        wb, eb = turn(b)
        fa, fb = ea - a, eb - b
        if abs(fb) <= 1e-13 * sync or fb == fa:
            return wb
        a, ea, b = b, eb, b - fb * (b - a) / (fb - fa)
    return wb


def crank_speed_rad_s(law: MotorLaw, torque_nm: np.ndarray, spm: float) -> np.ndarray:
    """The crank speed (rad/s) at the :data:`GRID` (or ``torque_nm.size``) crank angles 2πj/n past the bottom of
    the stroke, for the net gearbox torque ``torque_nm`` at those angles, with the stroke period 60/SPM."""
    torque = np.asarray(torque_nm, dtype=float)
    period = 60.0 / spm
    step = 2.0 * math.pi / torque.size
    speed = _quasi_static if law.inertia_kg_m2 == 0.0 else _with_inertia

    def excess(sync: float) -> tuple[np.ndarray, float]:
        w = speed(law, torque, sync)
        if np.min(w) <= 0.0:
            return w, math.inf
        return w, step * float(np.sum(1.0 / w)) - period

    mean = 2.0 * math.pi / period
    a, b = mean, mean * (1.0 + law.rated_slip)
    _, fa = excess(a)
    wb, fb = excess(b)
    for _ in range(60):
        if not math.isfinite(fb):  # a stalled guess: step back towards the last finite one
            b = 0.5 * (a + b) if math.isfinite(fa) else 1.5 * b
            wb, fb = excess(b)
            continue
        if abs(fb) <= 1e-12 * period or fb == fa:
            break
        a, fa, b = b, fb, b - fb * (b - a) / (fb - fa)
        wb, fb = excess(b)
    ratio = float(np.max(torque)) / law.rated_crank_torque_nm(b)
    if not math.isfinite(fb) or ratio > law.max_torque_ratio:
        raise ConfigError(f"{WHERE}.rated_power_w", law.rated_power_w,
                          f"W of a motor that carries the stroke's peak crank torque ({float(np.max(torque)):.6g} "
                          f"N*m = {ratio:.3g} x rated; a NEMA {law.design} motor stalls above "
                          f"{law.max_torque_ratio:g} x)")
    return wb


@dataclass(frozen=True)
class CrankProfile:
    """The crank's motion through one stroke: speed ω_j at the crank angles 2πj/n past the bottom, and the time
    each angle is reached (trapezoid of dθ/ω; the last is the period)."""

    omega_rad_s: np.ndarray
    period_s: float

    @property
    def angles_rad(self) -> np.ndarray:
        n = self.omega_rad_s.size
        return 2.0 * math.pi * np.arange(n + 1) / n

    @property
    def times_s(self) -> np.ndarray:
        w = np.append(self.omega_rad_s, self.omega_rad_s[0])
        step = 2.0 * math.pi / self.omega_rad_s.size
        t = np.concatenate(([0.0], np.cumsum(0.5 * step * (1.0 / w[:-1] + 1.0 / w[1:]))))
        return t * (self.period_s / t[-1])  # the round-off of the period constraint, not a correction

    def angle_and_speed(self, t_s: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(crank angle past the bottom, not wrapped; crank speed) at times t_s since the start of a stroke."""
        t = np.asarray(t_s, dtype=float)
        turns = np.floor(t / self.period_s)
        tau = t - turns * self.period_s
        times = self.times_s
        theta = np.interp(tau, times, self.angles_rad) + 2.0 * math.pi * turns
        return theta, np.interp(tau, times, np.append(self.omega_rad_s, self.omega_rad_s[0]))

    def speed_range_pct(self) -> dict[str, float]:
        """The crank speed's extremes and its time mean, in % of the mean (the time mean is 2π/period)."""
        mean = 2.0 * math.pi / self.period_s
        return {"min_pct_of_mean": 100.0 * float(self.omega_rad_s.min()) / mean,
                "max_pct_of_mean": 100.0 * float(self.omega_rad_s.max()) / mean}


def torque_on_grid(theta_past_bottom_rad: np.ndarray, torque_nm: np.ndarray, n: int = GRID) -> np.ndarray:
    """A stroke's net torque at its samples' crank angles (past the bottom) resampled on n equal angles."""
    th = np.mod(np.asarray(theta_past_bottom_rad, dtype=float), 2.0 * math.pi)
    order = np.argsort(th, kind="stable")
    return np.interp(2.0 * math.pi * np.arange(n) / n, th[order], np.asarray(torque_nm, dtype=float)[order],
                     period=2.0 * math.pi)


def net_torque_nm(unit, theta_rad: np.ndarray, load_n: np.ndarray, counterbalance: float | None,
                  offset_rad: float = 0.0, tf_scale: float = 1.0) -> tuple[np.ndarray, float]:
    """(net gearbox torque at the samples, counterbalance used): the given moment (an air-balanced unit's force),
    or with None the stroke's optimal one (``gearbox.optimal_counterbalance_nm``: a unit balanced on equal
    torque peaks, as a crew balances it). ``tf_scale`` scales the torque factor (a motion scaled to another
    stroke: validate's record unit); T = s TF (PRL - SU) - M arm is passed as TF (s PRL - (s - 1) SU - SU)."""
    from .gearbox import optimal_counterbalance_nm

    su = unit.geometry.structural_unbalance_n
    load = tf_scale * np.asarray(load_n, dtype=float) - (tf_scale - 1.0) * su
    if counterbalance is None:
        counterbalance = optimal_counterbalance_nm(unit, theta_rad, load, offset_rad)
    moment, force = (0.0, counterbalance) if unit.air_balanced else (counterbalance, 0.0)
    return np.asarray(unit.net_torque_nm(theta_rad, load, moment, offset_rad, force), dtype=float), counterbalance


def position_change_pct(old: CrankProfile | None, new: CrankProfile, unit, samples: int = 400) -> float:
    """max |x_new(t) - x_old(t)| over a stroke, in % of the stroke (old None: constant crank speed)."""
    t = np.arange(samples) * new.period_s / samples
    th_new, _ = new.angle_and_speed(t)
    th_old = 2.0 * math.pi * t / new.period_s if old is None else old.angle_and_speed(t)[0]
    b = unit.theta_bottom
    dx = np.asarray(unit.position_m(b + th_new)) - np.asarray(unit.position_m(b + th_old))
    return 100.0 * float(np.max(np.abs(dx))) / unit.stroke_m


USED_KEPT = 64  # recorded strokes whose crank angles a drive keeps for the gearbox report


class MotorDrive:
    """The motor on a linkage motion's unit. The first stroke runs at constant crank speed; each recorded stroke's
    net torque then sets the crank speed of the strokes after it (a Picard iteration on the periodic stroke:
    simulate, torque, speed, simulate; ``last_change_pct`` is how far the last update moved the polished rod, in
    % of the stroke, converged below 0.1). Counterbalance: the configured one, or with None the stroke's optimum."""

    def __init__(self, law: MotorLaw, counterbalance: float | None, offset_rad: float) -> None:
        self.law, self.counterbalance, self.offset_rad = law, counterbalance, offset_rad
        self.torque: np.ndarray | None = None  # the last recorded stroke's net torque on the GRID angles
        self.version = 0
        self.last_change_pct: float | None = None
        self.last_counterbalance: float | None = None
        self._profiles: dict[float, CrankProfile] = {}
        self._used: dict[int, tuple[object, np.ndarray, np.ndarray]] = {}

    def profile(self, spm: float) -> CrankProfile | None:
        """The crank profile at this SPM from the last recorded torque (None before the first)."""
        if self.torque is None:
            return None
        got = self._profiles.get(float(spm))
        if got is None:
            got = CrankProfile(crank_speed_rad_s(self.law, self.torque, spm), 60.0 / spm)
            self._profiles[float(spm)] = got
        return got

    def angle_and_speed(self, unit, t_s: np.ndarray, spm: float) -> tuple[np.ndarray, np.ndarray]:
        """(crank angle θ as the unit measures it, crank speed) at times since the bottom of a stroke."""
        p = self.profile(spm)
        if p is None:
            return np.asarray(unit.crank_angle_rad(t_s, spm)), np.full(np.shape(t_s), 2.0 * math.pi * spm / 60.0)
        theta, omega = p.angle_and_speed(t_s)
        return unit.theta_bottom + theta, omega

    def observe(self, unit, result) -> None:
        """A stroke has run: its net torque sets the crank speed of the next (recorded strokes only)."""
        if result.trace is None or result.spm <= 0:
            return
        n = result.n_steps
        t = np.arange(1, n + 1) * (result.duration_s / n)
        theta, omega = self.angle_and_speed(unit, t, result.spm)
        if len(self._used) >= USED_KEPT:
            self._used.clear()
        self._used[id(result)] = (result, theta, omega)
        torque, self.last_counterbalance = net_torque_nm(unit, theta, result.trace["polished_rod_load_n"],
                                                         self.counterbalance, self.offset_rad)
        old = self.profile(result.spm)
        self.torque = torque_on_grid(theta - unit.theta_bottom, torque)
        self._profiles.clear()
        self.version += 1
        self.last_change_pct = position_change_pct(old, self.profile(result.spm), unit)

    def crank_of(self, unit, result) -> tuple[np.ndarray, np.ndarray]:
        """(θ, ω) at the recorded steps of a stroke, as it ran (the gearbox report's crank angles)."""
        got = self._used.get(id(result))
        if got is not None and got[0] is result:
            return got[1], got[2]
        n = result.n_steps
        return self.angle_and_speed(unit, np.arange(1, n + 1) * (result.duration_s / n), result.spm)

    def summary(self) -> dict:
        """The JSON keys of a run with a motor (srenv simulate)."""
        p = self.profile(self._last_spm()) if self.torque is not None else None
        return {"motor_rated_slip": self.law.rated_slip, "motor_nema_design": self.law.design,
                "motor_inertia_kg_m2": self.law.inertia_kg_m2,
                "motor_counterbalance_nm": self.last_counterbalance,
                "motor_counterbalance_source": "configured" if self.counterbalance is not None else "optimal",
                "crank_speed_pct_of_mean": None if p is None else p.speed_range_pct(),
                "motor_last_change_pct_of_stroke": self.last_change_pct}

    def _last_spm(self) -> float:
        return next(reversed(self._used.values()))[0].spm if self._used else 0.0


def motor_drive(cfg) -> MotorDrive | None:
    """The drive of ``surface.motor`` (None without one): the configured counterbalance when given (> 0), else
    the optimal one of each stroke."""
    if getattr(cfg, "motor", None) is None:
        return None
    if cfg.beam_unit is not None:
        from .inline_unit import counterbalance

        moment, offset = counterbalance(cfg.beam_unit)
    else:
        moment, offset = cfg.counterbalance_moment_nm, math.radians(cfg.counterbalance_offset_deg)
    return MotorDrive(MotorLaw.from_config(cfg.motor), moment if moment > 0 else None, offset)
