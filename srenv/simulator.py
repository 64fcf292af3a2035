"""The simulator: assembles the FE model of a well, runs strokes through the compiled kernel, calls the
step QP (ProxSuite through qpsolvers) where the kernel cannot certify a step, and records traces.

Typical use::

    sim = Simulator(load_config("paper_fig4_deviated"))
    stroke = sim.run_stroke()              # one stroke at the config's SPM and stroke length
    stroke.trace["polished_rod_load_n"]    # per-step arrays (if record=True)
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from . import kernel as K
from .config import ConfigError, WellConfig
from .fluid import tubing_pressure_pa
from .inflow import Annulus
from .pump import ValveLaw, plunger_area_m2, valve_law
from .rod import (
    GRAVITY_M_S2,
    build_mesh,
    damping,
    first_natural_frequency_hz,
    mass,
    solve_tridiagonal,
    stiffness,
)
from .step_qp import StepQP
from .surface import SurfaceMotion
from .survey import Survey

TRACE_COLUMNS = ("t_s", "polished_rod_position_m", "polished_rod_velocity_m_s", "polished_rod_load_n",
                 "pump_position_m", "pump_velocity_m_s", "pump_load_n", "step_path")


@dataclass
class RunResult:
    """One stroke (or a duration run): counters, events and, if recorded, the per-step trace."""

    n_steps: int
    duration_s: float
    spm: float
    stroke_length_m: float
    certified_steps: int
    corrected_steps: int
    qp_steps: int
    qp_calls: int
    dc_iterations: int
    fillage: float
    pumped_m3: float  # liquid lifted by the plunger in this run (fillage x upstroke x plunger area, summed)
    intake_pressure_pa: float
    rod_stick_episodes: np.ndarray
    element_force_max_eq_n: np.ndarray
    element_force_min_eq_n: np.ndarray
    energy_j: dict
    trace: dict | None = None
    events: list = field(default_factory=list)

    @property
    def solver_calls(self) -> int:
        return self.qp_calls


class Simulator:
    """Exact nonsmooth FE sucker-rod string (design §2-§3)."""

    def __init__(self, cfg: WellConfig, *, always_qp: bool | None = None, qp_solver: str | None = None,
                 persistent_qp: bool = False) -> None:
        self.cfg = cfg
        sim = cfg.simulation
        self.always_qp = sim.always_qp if always_qp is None else always_qp
        self.qp = StepQP(qp_solver or sim.qp_solver, sim.qp_eps_abs, persistent=persistent_qp)
        self.polish = True  # exact active-set polish of QP answers (off: keep the solver's raw velocity)
        self.linear_reference = False  # bench only: skip friction and valve law (a plain linear Newmark step)
        self.mesh = build_mesh(cfg.rod, sim.element_length_m)
        self.survey = Survey.from_config(cfg.survey, cfg.rod_length_m)
        self.surface = SurfaceMotion(cfg.surface)
        self._assemble()
        self.reset()

    # ------------------------------------------------------------------------------------------ model
    def _assemble(self) -> None:
        cfg, mesh = self.cfg, self.mesh
        x = mesh.x_m
        n = mesh.n_nodes - 1
        self.n_free = n
        kd, ko = stiffness(mesh)
        md, mo = mass(mesh, cfg.rod.mass_matrix)
        cd, _ = damping(mesh, cfg.damping)
        self._k = (kd, ko)
        self._m = (md, mo)
        self._c = cd
        # distributed load: buoyed weight along MD, (rho - rho_f) g cos(alpha) A, lumped per element half
        x_mid = 0.5 * (x[1:] + x[:-1])
        cos_mid = np.cos(self.survey.inclination(x_mid))
        rho_rod = mesh.rho_a_kg_m / mesh.area_m2
        w_elem = (rho_rod - cfg.fluid.density_kg_m3) * GRAVITY_M_S2 * cos_mid * mesh.area_m2 * mesh.length_m
        f_all = np.zeros(n + 1)
        f_all[:-1] += 0.5 * w_elem
        f_all[1:] += 0.5 * w_elem
        self._f_all = f_all
        # side force coefficients per node: F = mu * l_i * sqrt((w_b sin a - N da/ds)^2 + (N sin a dphi/ds)^2)
        trib = mesh.tributary_m()
        area_node = mesh.node_area_m2()
        rho_node = np.r_[rho_rod, rho_rod[-1]]
        incl = self.survey.inclination(x)
        w_b = (rho_node - cfg.fluid.density_kg_m3) * GRAVITY_M_S2 * area_node
        mu = cfg.friction.coefficient
        self._fa = (mu * trib * self.survey.build_rate(x))[1:].copy()
        self._fw = (mu * trib * w_b * np.sin(incl))[1:].copy()
        turn = self.survey.turn_rate(x) if cfg.survey.three_d else np.zeros_like(x)
        self._fc = (mu * trib * np.sin(incl) * turn)[1:].copy()
        self._fa[-1] = self._fw[-1] = self._fc[-1] = 0.0  # the pump node carries the valve law only
        self._ea_len = mesh.ea_n / mesh.length_m
        # pressures and the valve law
        tvd = self.survey.tvd(x)
        self.p_pump_pa = float(tubing_pressure_pa(cfg.fluid, tvd[-1]))
        self.p_top_pa = float(cfg.fluid.wellhead_pressure_pa)
        self.area_bottom_m2 = float(mesh.area_m2[-1])
        self.area_top_m2 = float(mesh.area_m2[0])
        self.annulus = None
        if cfg.inflow.model != "none":
            self.annulus = Annulus(cfg.inflow, cfg.fluid, float(x[-1]), self.survey.tvd)
        self.f1_hz = first_natural_frequency_hz(mesh, cfg.rod.mass_matrix)
        self._check_convexity()

    def _valve(self) -> ValveLaw:
        p_in = self.annulus.intake_pressure_pa() if self.annulus is not None else None
        law = valve_law(self.cfg.pump, self.p_pump_pa, self.area_bottom_m2, p_in)
        if not law.up_eq_n > law.down_eq_n:
            raise ConfigError("pump.intake_pressure_pa", p_in if p_in is not None else
                              self.cfg.pump.intake_pressure_pa,
                              f"an intake pressure in Pa below the discharge pressure {self.p_pump_pa:.4g} Pa "
                              "(the upstroke load must exceed the downstroke load)")
        return law

    def _kstar(self, dt: float) -> tuple[np.ndarray, np.ndarray]:
        s = self.cfg.simulation
        (kd, ko), (md, mo), cd = self._k, self._m, self._c
        c1, c2 = 1.0 / (s.newmark_gamma * dt), s.newmark_beta * dt / s.newmark_gamma
        return (c1 * md + cd + c2 * kd)[1:].copy(), (c1 * mo + c2 * ko)[1:].copy()

    def _check_convexity(self, dt: float | None = None) -> None:
        """Warn when a nonmonotone law makes the step problem nonconvex (design §2).

        With j = j1 - j2 the step objective 1/2 v'K*v - b'v + j1(v) - j2(v) is convex iff K* - diag(s) is
        positive definite, s_i = sup j2_i'' the steepest negative slope of node i's law: (P0 - P_inf)/v0 at
        the pump, (mu_s - mu_k) q_n l_i / v0 on the rod. K* is tridiagonal, so its LDL' pivots decide it;
        for the pump alone the last pivot is the condensed stiffness 1/(K*^-1)_BB. The rod's q_n depends on
        the axial force, estimated here from the static string with the plunger at P+ and at P0 (dynamic
        loads can raise it, so this is an estimate).

        Violation is an error by default (``simulation.nonconvex_step: error``) and a warning with
        ``nonconvex_step: warn``, which runs anyway: each DC sub-problem (K* plus the convex j1) stays strictly
        convex, and the iterations lower the step objective monotonically to a stationary point, i.e. a
        solution of the step's hemivariational inequality. What is lost is uniqueness, so the result may
        depend on the iteration start (v_n) and on dt. The message names the time step that restores
        convexity (K* grows like M/(gamma dt)).
        """
        import warnings

        dt = dt or self.cfg.simulation.time_step_s
        cfg = self.cfg
        slope = np.zeros(self.n_free)
        law = valve_law(cfg.pump, self.p_pump_pa, self.area_bottom_m2)
        if law.drop_n > 0:
            slope[-1] = law.drop_n / law.v0_m_s
        fr = cfg.friction
        if fr.law == "nonmonotone" and fr.coefficient > fr.kinetic_coefficient:
            weight = self._f_all[1:]
            side = np.zeros(self.n_free)
            for plunger_eq_n in (law.down_eq_n, law.up_eq_n):
                # static hanging string: element force = plunger load + weight of the nodes below it
                elem = plunger_eq_n + np.cumsum(weight[::-1])[::-1]
                node = np.r_[0.5 * (elem[:-1] + elem[1:]), elem[-1]]
                side = np.maximum(side, np.hypot(self._fw - self._fa * node, self._fc * node))
            weakening = 1.0 - fr.kinetic_coefficient / fr.coefficient
            slope[:-1] += weakening * side[:-1] / fr.reference_velocity_m_s
        if not np.any(slope > 0):
            return

        def convex(step_s: float) -> bool:
            diag, off = self._kstar(step_s)
            pivot = diag[0] - slope[0]
            for i in range(1, len(diag)):
                if pivot <= 0:
                    return False
                pivot = diag[i] - slope[i] - off[i - 1] ** 2 / pivot
            return pivot > 0

        if convex(dt):
            return
        lo_dt, hi_dt = 0.0, dt  # K*(dt) - diag(s) is positive definite for a small enough dt: bisect
        for _ in range(60):
            mid = 0.5 * (lo_dt + hi_dt)
            lo_dt, hi_dt = (mid, hi_dt) if convex(mid) else (lo_dt, mid)
        node_i = int(np.argmax(slope))
        where = "the pump" if node_i == self.n_free - 1 else f"rod node {node_i + 1}"
        why = (f"K* - diag(law slopes) is not positive definite; steepest slope {slope[node_i]:.4g} N*s/m at "
               f"{where}")
        if cfg.simulation.nonconvex_step == "error":
            raise ConfigError("simulation.time_step_s", dt,
                              f"a time step in s below {lo_dt:.3g} (the step problem is not convex: {why}; "
                              "set simulation.nonconvex_step: warn to run the DC iterations anyway)")
        warnings.warn(
            f"simulation.time_step_s = {dt:g} s: the step problem is not convex ({why}). DC iterations "
            f"still converge to a stationary point of each step, but it may not be unique. A time step "
            f"below {lo_dt:.3g} s restores convexity.", UserWarning, stacklevel=4)

    # ------------------------------------------------------------------------------------------ state
    def reset(self, fluid_level_m: float | None = None) -> None:
        """Static equilibrium at the bottom of the stroke, plunger at rest holding P+ (end of a downstroke)."""
        n = self.n_free
        if self.annulus is not None:
            self.annulus.reset(self.cfg.inflow.initial_fluid_level_m if fluid_level_m is None else fluid_level_m)
        self.law = self._valve()
        kd, ko = self._k
        rhs = self._f_all[1:].copy()
        rhs[-1] += self.law.down_eq_n  # the plunger pulls down with P+_eq
        self.u = solve_tridiagonal(kd[1:], ko[1:], rhs)
        self.v = np.zeros(n)
        self.a = np.zeros(n)
        ea0 = self._ea_len[0]
        prl_eq0 = ea0 * self.u[0] + self._f_all[0]
        self.uav = np.array([0.0, 0.0, 0.0, prl_eq0])
        self.time_s = 0.0
        self.status = np.zeros(n, dtype=np.int64)
        self.prev_lam = np.zeros(n)
        self.prev_lam[-1] = -self.law.down_eq_n
        self.prev_v = np.zeros(n)
        self.prev_stuck = np.zeros(n, dtype=np.bool_)
        self.pl_dir = 0
        self.void = 0
        self.void_until = 0.0
        # plunger stroke bookkeeping: extremes since the last accepted reversal (see _on_event)
        self._ub_max = self._ub_min = self._top_ub = float(self.u[-1])
        self._pump_phase = "up"  # the initial state is the bottom of the stroke
        self._liquid_stroke_m = np.inf
        if self.annulus is not None:
            plan_par = np.zeros(K.N_PAR)
            plan_ist = np.zeros(K.N_IST, dtype=np.int64)
            self._plan_upstroke(float(self.u[-1]), 0.0, 60.0 / self.cfg.surface.spm, plan_ist, plan_par)
            self.void, self.void_until = int(plan_ist[K.I_VOID]), float(plan_par[K.P_VOID_UNTIL])
        self.fillage = 1.0
        self.energy = np.zeros(K.N_ENERGY)
        self.e0 = self.mechanical_energy_j()
        self._work = _Work(n)

    def mechanical_energy_j(self) -> float:
        """Kinetic + strain energy of the whole string (top node included)."""
        u = np.r_[self.uav[0], self.u]
        v = np.r_[self.uav[1], self.v]
        (kd, ko), (md, mo) = self._k, self._m
        ku = kd * u
        ku[:-1] += ko * u[1:]
        ku[1:] += ko * u[:-1]
        mv = md * v
        mv[:-1] += mo * v[1:]
        mv[1:] += mo * v[:-1]
        return 0.5 * float(u @ ku) + 0.5 * float(v @ mv)

    def energy_balance(self) -> dict:
        """Energy terms accumulated since reset (J); `residual_j` closes to round-off for beta=1/4, gamma=1/2."""
        e = self.energy
        stored = self.mechanical_energy_j() - self.e0
        supplied = e[K.E_TOP] + e[K.E_GRAV] + e[K.E_REACT] - e[K.E_VISC]
        return {"polished_rod_work_j": float(e[K.E_TOP]), "gravity_work_j": float(e[K.E_GRAV]),
                "friction_and_pump_work_j": float(e[K.E_REACT]), "viscous_dissipation_j": float(e[K.E_VISC]),
                "stored_energy_change_j": stored, "residual_j": float(stored - supplied)}

    # ------------------------------------------------------------------------------------------ running
    def _params(self, dt: float) -> tuple[np.ndarray, np.ndarray]:
        cfg, s = self.cfg, self.cfg.simulation
        par = np.zeros(K.N_PAR)
        par[K.P_DT], par[K.P_BETA], par[K.P_GAMMA] = dt, s.newmark_beta, s.newmark_gamma
        par[K.P_TOLV], par[K.P_TOLL], par[K.P_DCTOL] = 1e-13, 1e-12, s.dc_tolerance_m_s
        law = self.law
        par[K.P_PUMP_LO], par[K.P_PUMP_HI] = -law.up_eq_n, -law.down_eq_n
        par[K.P_PUMP_DROP], par[K.P_PUMP_V0] = law.drop_n, law.v0_m_s
        fr = cfg.friction
        par[K.P_FRIC_RATIO] = fr.kinetic_coefficient / fr.coefficient if fr.coefficient > 0 else 1.0
        par[K.P_FRIC_V0] = fr.reference_velocity_m_s
        (_, ko), (md, mo), cd = self._k, self._m, self._c
        par[K.P_MA], par[K.P_MOA], par[K.P_CA], par[K.P_FA] = md[0], mo[0], cd[0], self._f_all[0]
        par[K.P_KC], par[K.P_MC] = ko[0], mo[0]
        par[K.P_PB] = self.p_pump_pa * self.area_bottom_m2
        par[K.P_PA] = self.p_top_pa * self.area_top_m2
        par[K.P_VOID_UNTIL] = self.void_until
        par[K.P_EA0] = self._ea_len[0]
        par[K.P_UBMAX], par[K.P_UBMIN] = self._ub_max, self._ub_min
        ist = np.zeros(K.N_IST, dtype=np.int64)
        ist[K.I_MAXCORR], ist[K.I_DCMAX] = s.max_corrections, s.dc_max_iterations
        ist[K.I_ALWAYSQP] = int(self.always_qp)
        ist[K.I_NONSMOOTH] = 0 if self.linear_reference else 1
        ist[K.I_PLDIR], ist[K.I_VOID] = self.pl_dir, self.void
        ist[K.I_PUMP_NONMONO] = int(law.drop_n > 0)
        ist[K.I_FRIC_NONMONO] = int(fr.law == "nonmonotone" and fr.coefficient > fr.kinetic_coefficient)
        return par, ist

    def run_stroke(self, spm: float | None = None, stroke_length_m: float | None = None,
                   record: bool = True) -> RunResult:
        """One full stroke starting at the bottom, at the given (or configured) SPM and stroke length."""
        sc = self.cfg.surface
        spm = sc.spm if spm is None else float(spm)
        stroke = self.surface.stroke_length_m(sc.stroke_length_m if stroke_length_m is None
                                              else float(stroke_length_m))
        period = 60.0 / spm
        n_steps = max(1, math.ceil(period / self.cfg.simulation.time_step_s - 1e-9))
        va = self.surface.stroke_velocity(spm, stroke, n_steps)
        return self._run(va, period / n_steps, record, spm, stroke)

    def run_duration(self, duration_s: float, pull_velocity_m_s: float | None = None,
                     record: bool = True) -> RunResult:
        """Pull-out: the top rises at constant speed (after a short ramp) for `duration_s`."""
        dt = self.cfg.simulation.time_step_s
        n_steps = max(1, math.ceil(duration_s / dt - 1e-9))
        speed = self.cfg.surface.pull_velocity_m_s if pull_velocity_m_s is None else pull_velocity_m_s
        t = self.time_s + np.arange(1, n_steps + 1) * dt
        va = self.surface.pull_velocity(t, speed)
        return self._run(va, dt, record, 0.0, 0.0)

    def run_velocity(self, top_velocity_m_s: np.ndarray, dt: float, record: bool = True) -> RunResult:
        """Advance with an arbitrary prescribed top velocity series (positive down), one value per step."""
        return self._run(np.ascontiguousarray(top_velocity_m_s, dtype=float), float(dt), record, 0.0, 0.0)

    def _run(self, va: np.ndarray, dt: float, record: bool, spm: float, stroke: float) -> RunResult:
        w = self._work
        n = self.n_free
        n_steps = len(va)
        ksd, kso = self._kstar(dt)
        (kd, ko), (md, mo) = self._k, self._m
        kd_f, ko_f, md_f, mo_f, cd_f = kd[1:], ko[1:], md[1:], mo[1:], self._c[1:]
        f_f = self._f_all[1:]
        par, ist = self._params(dt)
        ist[K.I_RECORD] = int(record)
        rec = np.empty((K.N_REC, n_steps if record else 0))
        stick = np.zeros(n, dtype=np.int64)
        emax = np.full(n, -np.inf)
        emin = np.full(n, np.inf)
        qp_calls0 = self.qp.stats.calls
        events = []
        t0 = self.time_s
        fillage = self.fillage
        self._pumped_m3 = 0.0
        while True:
            code = K.advance(par, ist, self.u, self.v, self.a, self.uav, va, t0,
                             ksd, kso, kd_f, ko_f, md_f, mo_f, cd_f, f_f, self._ea_len, self._fa, self._fw,
                             self._fc, self.status, w.lo, w.hi, w.ns, w.lam, w.b, w.b0, w.shift, w.vk, w.rhs,
                             w.stuck, w.cp, w.dp, w.nforce, w.fric_s, w.wv, w.wb, w.wlo, w.whi,
                             self.prev_lam, self.prev_v, self.prev_stuck, stick, rec, self.energy,
                             emax, emin, n_steps)
            if code == K.DONE:
                break
            step = int(ist[K.I_STEP])
            if code == K.NEED_QP:
                self._solve_qp(ksd, kso, dt, par, ist, step, t0 + (step + 1) * dt)
            else:
                fillage = self._on_event(int(ist[K.I_EVENT]), par, ist, t0 + step * dt, events, fillage, stroke,
                                         60.0 / spm if spm > 0 else 0.0)
        self.pl_dir, self.void = int(ist[K.I_PLDIR]), int(ist[K.I_VOID])
        self._ub_max, self._ub_min = float(par[K.P_UBMAX]), float(par[K.P_UBMIN])
        self.void_until = float(par[K.P_VOID_UNTIL])
        self.time_s = t0 + n_steps * dt
        trace = self._trace(rec[:, : ist[K.I_NREC]]) if record else None
        self.fillage = fillage
        return RunResult(
            n_steps=n_steps, duration_s=n_steps * dt, spm=spm, stroke_length_m=stroke,
            certified_steps=int(ist[K.I_NCERT]), corrected_steps=int(ist[K.I_NCORR]),
            qp_steps=int(ist[K.I_NQP]), qp_calls=self.qp.stats.calls - qp_calls0,
            dc_iterations=int(ist[K.I_NDC]), fillage=fillage, pumped_m3=self._pumped_m3,
            intake_pressure_pa=(self.annulus.intake_pressure_pa() if self.annulus else
                                self.cfg.pump.intake_pressure_pa),
            rod_stick_episodes=stick[:-1].copy(), element_force_max_eq_n=emax, element_force_min_eq_n=emin,
            energy_j=self.energy_balance(), trace=trace, events=events)

    def _solve_qp(self, ksd, kso, dt, par, ist, step, time_s) -> None:
        w = self._work
        inv = self.qp.inverse(ksd, kso, dt)
        v_raw, status = self.qp.solve(inv, w.wb, w.wlo, w.whi, w.ns.copy(), step, time_s)
        # polish: exact active-set solve from the QP's pattern, kept only if it is KKT-certified
        v = np.empty(self.n_free)
        ok = -1
        if self.polish:
            ok = K.solve_pattern(ksd, kso, w.wb, w.wlo, w.whi, w.ns, status, v, w.lam, w.rhs, w.stuck,
                                 w.cp, w.dp, int(ist[K.I_MAXCORR]), par[K.P_TOLV], par[K.P_TOLL])
        if ok >= 0:
            self.qp.stats.polished += 1
            w.wv[:] = v
        else:
            w.wv[:] = v_raw
        self.status[:] = status
        ist[K.I_HAVEQP] = 1

    def _plan_upstroke(self, u_bottom_m: float, time_s: float, period_s: float, ist, par) -> None:
        """At the bottom: the liquid the coming upstroke can draw (annulus + inflow during the upstroke)
        fixes the liquid level in the barrel; above it the plunger meets no liquid (fluid pound)."""
        if self.annulus is None:
            return
        self.annulus.accumulate(time_s)
        available_m3 = self.annulus.volume_m3 + self.annulus.inflow_m3_s() * 0.5 * period_s
        self._liquid_stroke_m = available_m3 / plunger_area_m2(self.cfg.pump)
        par[K.P_VOID_UNTIL] = u_bottom_m - self._liquid_stroke_m
        ist[K.I_VOID] = 1

    def _on_event(self, direction: int, par, ist, time_s: float, events: list, fillage: float,
                  stroke_m: float, period_s: float) -> float:
        """A plunger reversal. Short reversals inside a stroke (stick-slip chatter, the bounce when a pounding
        plunger meets liquid) are not valve cycles: a reversal counts only after a travel of a quarter of the
        surface stroke, and the stroke is measured between position extremes, not reversal points."""
        ub = float(self.u[-1])
        min_travel = 0.25 * stroke_m
        if direction > 0 and self._pump_phase == "up":  # top: the barrel holds what the upstroke drew
            upstroke = float(par[K.P_UBMAX]) - float(par[K.P_UBMIN])  # since the last accepted top
            if upstroke <= min_travel:
                return fillage
            self._top_ub = float(par[K.P_UBMIN])
            liquid_m = upstroke
            if self.annulus is not None:
                liquid_m = min(self._liquid_stroke_m, upstroke)
                self.annulus.take(plunger_area_m2(self.cfg.pump) * liquid_m, time_s)
                fillage = liquid_m / upstroke
            self._pumped_m3 += plunger_area_m2(self.cfg.pump) * liquid_m
            self._pump_phase = "down"
            par[K.P_UBMAX] = ub
            events.append(("top", time_s, ub, fillage))
        elif direction < 0 and self._pump_phase == "down":  # bottom: intake pressure sets the next P-
            if float(par[K.P_UBMAX]) - self._top_ub <= min_travel:
                return fillage
            if self.annulus is not None:
                self.law = self._valve()
                par[K.P_PUMP_LO] = -self.law.up_eq_n
                self._plan_upstroke(float(par[K.P_UBMAX]), time_s, period_s, ist, par)
            self._pump_phase = "up"
            par[K.P_UBMIN] = ub
            events.append(("bottom", time_s, ub, fillage))
        return fillage

    def _trace(self, rec: np.ndarray) -> dict:
        return {
            "t_s": rec[K.R_T],  # views into the record: no copies per stroke
            "polished_rod_position_m": rec[K.R_UA],
            "polished_rod_velocity_m_s": rec[K.R_VA],
            "polished_rod_load_n": rec[K.R_PRL],
            "pump_position_m": rec[K.R_UB],
            "pump_velocity_m_s": rec[K.R_VB],
            "pump_load_n": rec[K.R_PUMP],
            "step_path": rec[K.R_PATH],
        }

    def run_strokes(self, n: int, record: bool = True, **kw) -> list[RunResult]:
        return [self.run_stroke(record=record, **kw) for _ in range(n)]

    # ------------------------------------------------------------------------------------------ idle time
    # The v1 env stops the unit between strokes (intermittent pumping) and fast-forwards quasi-steady
    # strokes; these keep the annulus, the clock and the fluid-pound plan consistent when it does.
    def stop_at_bottom(self) -> None:
        """The unit stops at the bottom of a stroke: the string settles to its static state (plunger at rest
        holding P+); the annulus contents and the clock are kept."""
        t = self.time_s
        vol = self.annulus.volume_m3 if self.annulus is not None else 0.0
        self.reset(self.annulus.level_m if self.annulus is not None else None)
        self.time_s = t
        if self.annulus is not None:
            self.annulus.volume_m3 = vol
            self.annulus.last_time_s = t

    def idle(self, duration_s: float) -> None:
        """Let `duration_s` pass with the unit stopped: the annulus refills, no rod dynamics."""
        self.time_s += max(float(duration_s), 0.0)
        if self.annulus is not None:
            self.annulus.accumulate(self.time_s)

    def replan_upstroke(self, period_s: float) -> None:
        """Re-plan the coming upstroke's liquid (fluid pound) after the annulus changed outside a stroke."""
        if self.annulus is None or self._pump_phase != "up":
            return
        plan_par = np.zeros(K.N_PAR)
        plan_ist = np.zeros(K.N_IST, dtype=np.int64)
        self._plan_upstroke(self._ub_max, self.time_s, period_s, plan_ist, plan_par)
        self.void, self.void_until = int(plan_ist[K.I_VOID]), float(plan_par[K.P_VOID_UNTIL])


class _Work:
    """Scratch arrays of the kernel, allocated once per simulator (no per-step allocation)."""

    def __init__(self, n: int) -> None:
        for name in ("lo", "hi", "lam", "b", "b0", "shift", "vk", "rhs", "cp", "dp", "nforce", "fric_s",
                     "wv", "wb", "wlo", "whi"):
            setattr(self, name, np.zeros(n))
        self.ns = np.zeros(n, dtype=np.bool_)
        self.stuck = np.zeros(n, dtype=np.bool_)


def concat_traces(results: list[RunResult]) -> dict:
    traces = [r.trace for r in results if r.trace is not None]
    return {k: np.concatenate([t[k] for t in traces]) for k in TRACE_COLUMNS} if traces else {}
