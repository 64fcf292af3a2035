"""Hopf (flutter) threshold of velocity-weakening friction: the 1-DOF spring-block and the rod string.

Spring-block (docs/stick_slip.md)
---------------------------------
A block of mass m is pulled through a spring k whose far end moves at constant speed V; a dashpot b to
ground and a friction force F(v) = C + (C0 - C) exp(-v/v0) (c_v = 1/v0) oppose its motion x(t):

    m x'' + b x' + F(x') = k (V t - x).

Steady sliding x' = V is a solution. Linearised, a perturbation xi obeys m xi'' + (b + F'(V)) xi' + k xi = 0
with F'(V) = -(C0 - C) c_v exp(-c_v V) < 0: the friction slope is a negative damper. Sliding is unstable
(a growing oscillation that ends in stick-slip) when |F'(V)| > b, i.e. below the Hopf velocity

    v_H = ln(c_v (C0 - C) / b) / c_v       (none if c_v (C0 - C) <= b: stable at every V).

:class:`SpringBlock` integrates this system with the SAME compiled step machinery as the rod
(:func:`srenv.numerics.kernel.advance`, built by :func:`srenv.numerics.kernel_layout.build`, on a one-node model: the block is the "pump" node carrying the nonmonotone
law of paper eq. 32, the spring is the single element to the prescribed top). The trapezoidal Newmark
rule (beta = 1/4, gamma = 1/2) maps the continuous stability boundary Re(lambda) = 0 onto |z| = 1
exactly, so with converged DC iterations the simulated threshold equals v_H up to the resolution of the
growth test, which :func:`find_hopf_velocity` exploits.

Rod string
----------
A semi-infinite rod presents its impedance Z = sqrt(EA rho A) to its end: the lumped estimate replaces b by
Z (:func:`rod_impedance_n_s_m`). A finite rod driven in displacement at the top reflects the waves back,
so only its distributed damping removes energy; :func:`rod_critical_slope_n_s_m` finds the end slope at
which the linearised FE string (top fixed, plunger slope as a negative end damper) loses stability, and
:func:`rod_hopf_velocity_m_s` turns it into a pulling velocity.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
from scipy.linalg import eigvals

from ..numerics import kernel as K
from ..numerics import kernel_layout as L
from ..physics.laws import rod_friction
from ..physics.laws import valve as valve_law_record
from ..physics.pump import ValveLaw

if TYPE_CHECKING:
    from .simulator import Simulator

# Kernel tolerances as the simulator sets them: exact rest below 1e-13 m/s, multiplier slack 1e-12 relative.
_TOL_V_M_S = 1e-13
_TOL_LAMBDA = 1e-12


def hopf_velocity_m_s(weakening_n: float, reference_velocity_m_s: float, damping_n_s_m: float) -> float:
    """v_H = v0 ln((C0 - C) / (v0 b)) for F(v) = C + (C0 - C) e^(-v/v0); 0.0 when sliding is always stable."""
    if weakening_n <= 0 or damping_n_s_m <= 0:
        return math.inf if weakening_n > 0 else 0.0  # no damper: every V is unstable; no weakening: none
    ratio = weakening_n / (reference_velocity_m_s * damping_n_s_m)
    return reference_velocity_m_s * math.log(ratio) if ratio > 1.0 else 0.0


@dataclass(frozen=True)
class SpringBlock:
    """Block on velocity-weakening friction, pulled through a spring (module docstring)."""

    mass_kg: float
    stiffness_n_m: float
    damping_n_s_m: float
    static_force_n: float           # C0 = F(0)
    kinetic_force_n: float          # C  = F(infinity)
    reference_velocity_m_s: float   # v0 = 1/c_v

    @property
    def hopf_velocity_m_s(self) -> float:
        return hopf_velocity_m_s(self.static_force_n - self.kinetic_force_n, self.reference_velocity_m_s,
                                 self.damping_n_s_m)

    def friction_n(self, speed_m_s: float) -> float:
        drop = self.static_force_n - self.kinetic_force_n
        return self.kinetic_force_n + drop * math.exp(-abs(speed_m_s) / self.reference_velocity_m_s)

    def simulate(self, pull_velocity_m_s: float, duration_s: float, time_step_s: float,
                 perturbation_m_s: float, dc_tolerance_m_s: float = 1e-13,
                 dc_max_iterations: int = 200) -> tuple[np.ndarray, np.ndarray]:
        """Start in steady sliding at V with the block's velocity kicked by ``perturbation_m_s``; return
        (t_s, upward block velocity in m/s) at the end of each step, computed by :func:`kernel.advance`."""
        n_steps = max(1, math.ceil(duration_s / time_step_s - 1e-9))
        m, k, b = self.mass_kg, self.stiffness_n_m, self.damping_n_s_m
        v_up = pull_velocity_m_s
        # kernel convention: positive DOWN; the top (point A) moves up at V, the block follows
        force = self.friction_n(v_up) + b * v_up  # steady spring force: friction plus dashpot
        v = np.array([-v_up - perturbation_m_s])
        state = L.State(u=np.array([force / k]),  # spring stretched by its steady force (top at u_A = 0)
                        v=v, a=np.zeros(1), top=np.array([0.0, -v_up, 0.0, 0.0]),
                        status=np.array([-1], dtype=np.int64), prev_lam=np.array([-self.friction_n(v_up)]),
                        prev_v=v.copy(), prev_stuck=np.zeros(1, dtype=np.bool_))
        # the block is the "pump" node with the nonmonotone law: friction interval [-C0, C0] (lam = lo while
        # moving up); weakening only on the upward branch, which is the only one visited near steady sliding
        valve = valve_law_record.make(ValveLaw(self.static_force_n, -self.static_force_n,
                                               self.static_force_n - self.kinetic_force_n,
                                               self.reference_velocity_m_s))
        valve["nonmonotone"] = 1  # DC iterations even without weakening (as the rod's kernel runs them)
        # the whole "string": a massless top joined to the block by one element of stiffness k
        st = L.build(dt_s=time_step_s, beta=0.25, gamma=0.5, stiffness=(np.array([k, k]), np.array([-k])),
                     mass=(np.array([0.0, m]), np.zeros(1)), damping=np.array([0.0, b]), load_n=np.zeros(2),
                     ea_len_n_m=np.array([k]), side=rod_friction.side_force(0.0, *np.zeros((5, 2))),
                     rod_friction=rod_friction.make(1.0, 1.0, 1.0, False), valve=valve, state=state,
                     scratch=L.work(1), energy=np.zeros(L.N_ENERGY), n_steps=n_steps, record=True,
                     max_corrections=8, dc_max_iterations=dc_max_iterations, dc_tolerance_m_s=dc_tolerance_m_s,
                     tol_v_m_s=_TOL_V_M_S, tol_lambda=_TOL_LAMBDA, plunger_dir=-1)  # moving up: no start event
        ksd, w, va_t = st.model.ksd, st.work, np.full(n_steps, -v_up)
        while True:
            code = K.run(st, va_t, 0.0, n_steps)
            if code == L.DONE:
                break
            if code == L.NEED_QP:
                # the one-node box QP min 1/2 k* v^2 - b v + max(lo v, hi v) has a closed form
                # (soft threshold), so no solver is needed; the kernel resumes with it
                wb, wlo, whi = w.wb[0], w.wlo[0], w.whi[0]
                w.wv[0] = (wb - whi) / ksd[0] if wb > whi else ((wb - wlo) / ksd[0] if wb < wlo else 0.0)
                state.status[0] = 1 if w.wv[0] > 0 else (-1 if w.wv[0] < 0 else 0)
                st.progress["have_qp"] = 1
            # EVENT (the block reversed): nothing to update, keep stepping
        rec = st.out.rec
        return rec[L.R_T].copy(), rec[L.R_VB].copy()  # recorded upward positive


def oscillation_growth(velocity_m_s: np.ndarray, pull_velocity_m_s: float, window_steps: int) -> float:
    """ln(peak deviation from V over the last window / over the first window): > 0 growing, < 0 decaying.

    A window of one period makes each peak an envelope sample. The first window is anchored at the kick,
    so a run that has saturated on the stick-slip cycle still counts as growing."""
    dev = np.abs(np.asarray(velocity_m_s) - pull_velocity_m_s)
    w = max(1, min(window_steps, len(dev) // 2))
    return float(math.log(dev[-w:].max() / dev[:w].max()))


def find_hopf_velocity(block: SpringBlock, v_low_m_s: float, v_high_m_s: float, *, periods: float = 40.0,
                       steps_per_period: int = 80, relative_kick: float = 1e-4,
                       relative_tolerance: float = 1e-3) -> float:
    """Bisect V between a growing (v_low) and a decaying (v_high) case of :meth:`SpringBlock.simulate`.

    The kick is small (``relative_kick`` * V) so the run stays in the linear regime (the Hopf point of
    exponential weakening is subcritical: a large kick could jump onto the stick-slip cycle above v_H)."""
    period_s = 2 * math.pi * math.sqrt(block.mass_kg / block.stiffness_n_m)
    dt = period_s / steps_per_period

    def grows(speed: float) -> bool:
        _, vel = block.simulate(speed, periods * period_s, dt, relative_kick * speed)
        return oscillation_growth(vel, speed, steps_per_period) > 0

    if not grows(v_low_m_s) or grows(v_high_m_s):
        raise ValueError(f"[{v_low_m_s}, {v_high_m_s}] m/s does not bracket the Hopf velocity")
    lo, hi = v_low_m_s, v_high_m_s
    while hi - lo > relative_tolerance * hi:
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if grows(mid) else (lo, mid)
    return 0.5 * (lo + hi)


# ---------------------------------------------------------------------------------------------- the rod
def rod_impedance_n_s_m(sim: Simulator) -> float:
    """Z = sqrt(EA rho A) of the bottom element: the damper a long rod presents to its end."""
    return float(math.sqrt(sim.mesh.ea_n[-1] * sim.mesh.rho_a_kg_m[-1]))


def _max_growth_rate(sim: Simulator, end_slope_n_s_m: float, max_frequency_hz: float = math.inf) -> float:
    """Largest real part (1/s) of the linearised FE string with the plunger slope as a negative end damper,
    over the modes up to ``max_frequency_hz``."""
    (kd, ko), (md, mo), cd = sim._k, sim._m, sim._c
    n = sim.n_free

    def dense(d: np.ndarray, o: np.ndarray) -> np.ndarray:
        return np.diag(d[1:]) + np.diag(o[1:], 1) + np.diag(o[1:], -1)

    stiff, mass, damp = dense(kd, ko), dense(md, mo), np.diag(cd[1:])
    damp[-1, -1] -= end_slope_n_s_m
    inv_m = np.linalg.inv(mass)
    system = np.block([[np.zeros((n, n)), np.eye(n)], [-inv_m @ stiff, -inv_m @ damp]])
    lam = eigvals(system)
    return float(lam.real[np.abs(lam.imag) <= 2 * math.pi * max_frequency_hz].max())


def rod_critical_slope_n_s_m(sim: Simulator, relative_tolerance: float = 1e-6,
                             max_frequency_hz: float = math.inf) -> float:
    """Smallest plunger friction slope |dP/dv| (N*s/m) that destabilises steady sliding of the FE string.

    Rod friction is Coulomb (constant while sliding), so it adds no slope; the top is held by the prescribed
    velocity. Bisection on the sign of the largest real part; bracket [0, Z] since a slope beyond the
    impedance is unstable even for a semi-infinite rod. With every mode (default) this is the threshold of
    the simulated model, which is set by its highest, plunger-localised mesh mode; ``max_frequency_hz``
    keeps only the modes the mesh resolves (the continuum's threshold, docs/stick_slip.md)."""
    lo, hi = 0.0, rod_impedance_n_s_m(sim)
    if _max_growth_rate(sim, hi, max_frequency_hz) <= 0:
        raise ValueError("the FE string is stable even with an end slope equal to its impedance")
    while hi - lo > relative_tolerance * hi:
        mid = 0.5 * (lo + hi)
        lo, hi = (lo, mid) if _max_growth_rate(sim, mid, max_frequency_hz) > 0 else (mid, hi)
    return 0.5 * (lo + hi)


def rod_hopf_velocity_m_s(sim: Simulator, damping_n_s_m: float | None = None,
                          max_frequency_hz: float = math.inf) -> float:
    """Hopf velocity of the plunger law on the rod: b = the FE string's critical slope (default, over the
    modes up to ``max_frequency_hz``), or a given damper (e.g. :func:`rod_impedance_n_s_m`: the lumped
    estimate)."""
    law = sim.law
    b = rod_critical_slope_n_s_m(sim, max_frequency_hz=max_frequency_hz) if damping_n_s_m is None \
        else damping_n_s_m
    return hopf_velocity_m_s(law.drop_n, law.v0_m_s, b)
