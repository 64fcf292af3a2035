"""The simulator: assembles the FE model of a well, runs strokes through the compiled kernel, calls the
step QP (ProxSuite through qpsolvers) where the kernel cannot certify a step, and records traces.

Typical use::

    sim = Simulator(load_config("paper_fig4_deviated"))
    stroke = sim.run_stroke()              # one stroke at the config's SPM and stroke length
    stroke.trace["polished_rod_load_n"]    # per-step arrays (if record=True)
"""

from __future__ import annotations

import math

import numpy as np

from ..config import ConfigError, WellConfig, check_dense_size
from ..numerics import convexity
from ..numerics import kernel as K
from ..numerics import kernel_layout as L
from ..numerics.step_qp import StepQP
from ..physics.fluid import tubing_pressure_pa
from ..physics.inflow import Annulus
from ..physics.laws import rod_friction
from ..physics.laws import valve as valve_law_record
from ..physics.pump import GasChamber, ValveLaw, chamber_spring_n_m, valve_law
from ..physics.pump_inputs import intake_at_pump_pa, pump_at_rod_end
from ..physics.rod import (
    GRAVITY_M_S2,
    build_mesh,
    coupling_buoyancy_n_m,
    damping,
    first_natural_frequency_hz,
    mass,
    solve_tridiagonal,
    stiffness,
)
from ..physics.survey import Survey
from ..surface_unit.surface import SurfaceMotion
from .kernel_args import KernelArgs
from .pump_cycle import GAS_MIN_DELAY_FRACTION, PumpCycle  # noqa: F401 - GAS_MIN_DELAY_FRACTION: public
from .run_result import TRACE_COLUMNS, RunResult, concat_traces, trace_from_record  # noqa: F401 - public


class Simulator(PumpCycle):
    """Exact nonsmooth FE sucker-rod string (design §2-§3)."""

    def __init__(self, cfg: WellConfig, *, always_qp: bool | None = None, qp_solver: str | None = None,
                 persistent_qp: bool = False, linear_reference: bool = False,
                 fluid_level_m: float | None = None) -> None:
        self.cfg = cfg
        sim = cfg.simulation
        self.always_qp = sim.always_qp if always_qp is None else always_qp
        check_dense_size(cfg, self.always_qp)  # the config alone was checked at load; --always-qp was not
        self.qp = StepQP(qp_solver or sim.qp_solver, sim.qp_eps_abs, persistent=persistent_qp)
        self.polish = True  # exact active-set polish of QP answers (off: keep the solver's raw velocity)
        self.linear_reference = linear_reference  # bench only: skip friction and valve law (a plain linear Newmark step)
        self.mesh = build_mesh(cfg.rod, sim.element_length_m)
        self.survey = Survey.from_config(cfg.survey, cfg.rod_length_m)
        self.surface = SurfaceMotion(cfg.surface)
        self._kernel_args = KernelArgs()
        self._assemble()
        self.reset(fluid_level_m)  # the state reset(fluid_level_m) gives: an env starts its episode here

    # ------------------------------------------------------------------------------------------ model
    def _assemble(self) -> None:
        # a pump below the rods or a fluid level: the laws see the pump at the rod end (physics.pump_inputs);
        # the intake pressure at the pump is what a run reports
        # (every caller sets a config as given before it assembles: __init__, task.events.apply_condition)
        self.intake_at_pump_pa = intake_at_pump_pa(self.cfg, self.survey)
        self.cfg = pump_at_rod_end(self.cfg, self.survey)
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
        # distributed load: buoyed weight along MD, ((rho - rho_f) A - rho_f V_c) g cos(alpha) (V_c: couplings),
        # lumped per element half
        x_mid = 0.5 * (x[1:] + x[:-1])
        cos_mid = np.cos(self.survey.inclination(x_mid))
        rho_rod = mesh.rho_a_kg_m / mesh.area_m2
        w_c = coupling_buoyancy_n_m(mesh, cfg.fluid.density_kg_m3)  # zeros without couplings
        w_elem = ((rho_rod - cfg.fluid.density_kg_m3) * GRAVITY_M_S2 * cos_mid * mesh.area_m2
                  - w_c * cos_mid) * mesh.length_m
        f_all = np.zeros(n + 1)
        f_all[:-1] += 0.5 * w_elem
        f_all[1:] += 0.5 * w_elem
        self._f_all = f_all
        # side force coefficients per node: F = mu * l_i * sqrt((w_b sin a - N da/ds)^2 + (N sin a dphi/ds)^2)
        trib = mesh.tributary_m()
        area_node = mesh.node_area_m2()
        rho_node = np.r_[rho_rod, rho_rod[-1]]
        incl = self.survey.inclination(x)
        w_b = (rho_node - cfg.fluid.density_kg_m3) * GRAVITY_M_S2 * area_node - np.r_[w_c, w_c[-1]]
        turn = self.survey.turn_rate(x) if cfg.survey.three_d else np.zeros_like(x)
        self.side_force = rod_friction.side_force(cfg.friction.coefficient, trib, self.survey.build_rate(x), w_b,
                                                  incl, turn)
        self._ea_len = mesh.ea_n / mesh.length_m
        # pressures and the valve law
        tvd = self.survey.tvd(x)
        self.p_pump_pa = float(tubing_pressure_pa(cfg.fluid, tvd[-1]))
        self.p_top_pa = float(cfg.fluid.wellhead_pressure_pa)
        self.area_bottom_m2 = float(mesh.area_m2[-1])
        self.area_top_m2 = float(mesh.area_m2[0])
        self.annulus = None
        if cfg.inflow.model != "none":
            self.annulus = Annulus(cfg.inflow, cfg.fluid, float(x[-1]), self.survey.tvd_at)
        self.gas = GasChamber.from_config(cfg.pump, self.surface.stroke_length_m(cfg.surface.stroke_length_m),
                                          self.p_pump_pa + cfg.pump.discharge_overpressure_pa)
        tb = cfg.tubing
        self.tubing_stiffness_n_m = 0.0  # anchored: the barrel does not move
        if not tb.anchored:  # the free tubing between the anchor (or the surface) and the pump, as a spring
            area = math.pi / 4 * ((tb.outer_diameter_mm * 1e-3) ** 2 - (tb.inner_diameter_mm * 1e-3) ** 2)
            free_m = cfg.rod_length_m - tb.anchor_depth_m  # its stiffness given (docs/realism.md) or from its size
            self.tubing_stiffness_n_m = tb.stiffness_n_m or tb.youngs_modulus_pa * area / free_m
        self.tubing_stiffness_n_m, self.tubing_top_stiffness_n_m = chamber_spring_n_m(  # the liquid in series
            cfg.pump, self.surface.stroke_length_m(cfg.surface.stroke_length_m), self.tubing_stiffness_n_m,
            self.gas is not None)
        self.f1_hz = first_natural_frequency_hz(mesh, cfg.rod.mass_matrix)
        self._check_convexity()

    def valve_law_now(self) -> ValveLaw:
        """The valve law (equivalent rod-end loads) at the intake pressure now (srenv.simulation.described)."""
        p_in = self.annulus.intake_pressure_pa() if self.annulus is not None else None
        law = valve_law(self.cfg.pump, self.p_pump_pa, self.area_bottom_m2, p_in)
        if not law.up_eq_n > law.down_eq_n:
            raise ConfigError("pump.intake_pressure_pa", self.cfg.pump.intake_pressure_pa if p_in is None else p_in,
                              f"an intake pressure in Pa below the discharge pressure {self.p_pump_pa:.4g} Pa "
                              "(the upstroke load must exceed the downstroke load)")
        return law

    def _kstar(self, dt: float) -> tuple[np.ndarray, np.ndarray]:
        s, d = self.cfg.simulation, self.cfg.damping
        c = self._c
        if (d.upstroke_factor, d.downstroke_factor) != (1.0, 1.0):  # the convexity check's least K*
            c = c * min(d.upstroke_factor, d.downstroke_factor, 1.0)
        return L.kstar(self._k, self._m, c, dt, s.newmark_beta, s.newmark_gamma, d.stiffness_proportional_s)

    def _friction_record(self) -> np.ndarray:
        fr = self.cfg.friction
        return rod_friction.make(fr.coefficient, fr.kinetic_coefficient, fr.reference_velocity_m_s,
                                 fr.law == "nonmonotone")

    def _check_convexity(self, dt: float | None = None) -> None:
        """Warn or fail when a nonmonotone law makes the step problem nonconvex (srenv.numerics.convexity).

        The slopes are the laws' own (laws.valve.slope, laws.rod_friction.slope); the rod's side force
        depends on the axial force, estimated here from the static string with the plunger at P+ and at P0
        (dynamic loads can raise it, so this is an estimate)."""
        dt = dt or self.cfg.simulation.time_step_s
        law = valve_law(self.cfg.pump, self.p_pump_pa, self.area_bottom_m2)
        slope = np.zeros(self.n_free)
        slope[-1] = valve_law_record.slope(law)
        fric = self._friction_record()
        if fric["nonmonotone"][0]:
            weight = self._f_all[1:]
            rod = np.zeros(self.n_free)
            for plunger_eq_n in (law.down_eq_n, law.up_eq_n):
                # static hanging string: element force = plunger load + weight of the nodes below it
                elem = plunger_eq_n + np.cumsum(weight[::-1])[::-1]
                node = np.r_[0.5 * (elem[:-1] + elem[1:]), elem[-1]]
                rod = np.maximum(rod, rod_friction.slope(self.side_force, node, fric))
            slope[:-1] += rod[:-1]
        convexity.check(slope, self._kstar, dt, self.cfg.simulation.nonconvex_step)

    # ------------------------------------------------------------------------------------------ state
    def reset(self, fluid_level_m: float | None = None) -> None:
        """Static equilibrium at the bottom of the stroke, plunger at rest holding P+ (end of a downstroke)."""
        n = self.n_free
        if self.annulus is not None:
            self.annulus.reset(self.cfg.inflow.initial_fluid_level_m if fluid_level_m is None else fluid_level_m)
        self.law = self.valve_law_now()
        kd, ko = self._k
        rhs = self._f_all[1:].copy()
        rhs[-1] += self.law.down_eq_n  # the plunger pulls down with P+_eq
        self.u = solve_tridiagonal(kd[1:], ko[1:], rhs)
        self.v = np.zeros(n)
        self.a = np.zeros(n)
        self.uav = np.zeros(4)
        self._at_rest = True  # until the first run: the string is static (see _start_top)
        self._start_top(0.0, 0.0)  # each run_stroke starts from its motion's state; run_velocity may name one
        self.time_s = 0.0
        self.status = np.zeros(n, dtype=np.int64)
        self.prev_lam = np.zeros(n)
        self.prev_lam[-1] = -self.law.down_eq_n
        self.prev_v = np.zeros(n)
        self.prev_stuck = np.zeros(n, dtype=np.bool_)
        self.pl_dir = 0
        self._damp_s = 1.0
        self.void = 0
        self.void_until = 0.0
        # plunger stroke bookkeeping: extremes since the last accepted reversal (see _on_event)
        self._ub_max = self._ub_min = self._top_ub = float(self.u[-1])
        self._pump_phase = "up"  # the initial state is the bottom of the stroke
        self._t_bottom = self.time_s
        self._rising_s = None
        self._liquid_stroke_m = np.inf
        if self.annulus is not None:
            self.void = 1
            self.void_until = self._plan_upstroke(
                float(self.u[-1]), 0.0, 60.0 / self.surface.default_spm(self.cfg.surface.spm))
        # gas in the chamber: the first upstroke re-expands what the clearance holds at the bottom
        # (on, reference plunger position, gas volume and pressure there, liquid volume) of the chamber; the
        # kernel re-references it when a valve opens (kernel.gas_valves)
        self._gas_init()
        self._cond_reset()
        self.fillage = 1.0
        self.energy = np.zeros(L.N_ENERGY)
        self.e0 = self.mechanical_energy_j()
        self._work = L.work(n)

    def _gas_init(self) -> None:
        """The chamber's spring state at the bottom of the stroke with the plunger holding P+."""
        self._gas = np.zeros(5)
        if self.gas is not None:
            self._gas_start()
        elif self.tubing_stiffness_n_m > 0:  # the plunger holds P+ at rest: the tubing carries the fluid load
            self._gas[:] = (1.0, float(self.u[-1]), 0.0, -self.law.down_eq_n, 0.0)

    def switch_config(self, cfg: WellConfig, keep_annulus: bool = True) -> None:
        """Run on with another config of the same string (a condition comes or goes, at a stroke boundary: the
        plunger at the bottom): matrices, loads, valve law and chamber from ``cfg``; the rod's state, the clock
        and (``keep_annulus``) the annulus's liquid carry on. The chamber's spring state is started afresh when
        free gas (or the tubing spring) appears or goes: the kernel reads its law from that state, so a chamber
        switched on without it would leave the transfer rigid while the bookkeeping counts the gas."""
        if cfg.rod != self.cfg.rod:
            raise ValueError("switch_config: the rod string cannot change on a running well (build a new Simulator)")
        had = (self.gas is not None, self.tubing_stiffness_n_m > 0)
        ann = self.annulus
        self.cfg = cfg
        self._assemble()
        if keep_annulus and ann is not None and self.annulus is not None:
            self.annulus = ann
        self.law = self.valve_law_now()
        if (self.gas is not None, self.tubing_stiffness_n_m > 0) != had:
            self._gas_init()

    def _start_top(self, v_m_s: float, a_m_s2: float) -> None:
        """Set the prescribed top's velocity and acceleration (start of a stroke, see
        SurfaceMotion.stroke_start_state) and the polished-rod load that goes with them. While the string is
        still static (after reset) and the mass matrix is consistent, the free nodes' accelerations follow
        from M_ff a_f = -M_fA a_A."""
        (md, mo), cd = self._m, self._c
        if self._at_rest and mo[0] != 0.0:
            rhs = np.zeros(self.n_free)
            rhs[0] = -mo[0] * a_m_s2
            self.a = solve_tridiagonal(md[1:], mo[1:], rhs)
        self.uav[1], self.uav[2] = v_m_s, a_m_s2
        n0 = self._ea_len[0] * (self.u[0] - self.uav[0])
        self.uav[3] = n0 + self._f_all[0] - md[0] * a_m_s2 - mo[0] * self.a[0] - cd[0] * v_m_s

    def mechanical_energy_j(self) -> float:
        """Kinetic + strain energy of the whole string (top node included)."""
        u = np.concatenate((self.uav[:1], self.u))  # np.r_ costs ~40 µs a call (twice a stroke)
        v = np.concatenate((self.uav[1:2], self.v))
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
        supplied = e[L.E_TOP] + e[L.E_GRAV] + e[L.E_REACT] - e[L.E_VISC]
        return {"polished_rod_work_j": float(e[L.E_TOP]), "gravity_work_j": float(e[L.E_GRAV]),
                "friction_and_pump_work_j": float(e[L.E_REACT]), "viscous_dissipation_j": float(e[L.E_VISC]),
                "stored_energy_change_j": stored, "residual_j": float(stored - supplied)}

    # ------------------------------------------------------------------------------------------ running
    def run_stroke(self, spm: float | None = None, stroke_length_m: float | None = None,
                   record: bool = True) -> RunResult:
        """One full stroke starting at the bottom, at the given (or configured) SPM and stroke length."""
        sc = self.cfg.surface
        spm = self.surface.default_spm(sc.spm) if spm is None else float(spm)
        stroke = self.surface.stroke_length_m(sc.stroke_length_m if stroke_length_m is None
                                              else float(stroke_length_m))
        period = 60.0 / spm
        n_steps = max(1, math.ceil(period / self.cfg.simulation.time_step_s - 1e-9))
        # the stroke's own start state: the top's acceleration jumps when the SPM (or stroke) changes
        va, start = self.surface.stroke_motion(spm, stroke, n_steps)
        self._start_top(*start)
        return self.surface.stroke_done(self._run(va, period / n_steps, record, spm, stroke))  # surface.motor

    def run_duration(self, duration_s: float, pull_velocity_m_s: float | None = None,
                     record: bool = True) -> RunResult:
        """Pull-out: the top rises at constant speed (after a short ramp) for `duration_s`."""
        dt = self.cfg.simulation.time_step_s
        n_steps = max(1, math.ceil(duration_s / dt - 1e-9))
        speed = self.cfg.surface.pull_velocity_m_s if pull_velocity_m_s is None else pull_velocity_m_s
        t = self.time_s + np.arange(1, n_steps + 1) * dt
        va = self.surface.pull_velocity(t, speed)
        return self._run(va, dt, record, 0.0, 0.0)

    def run_velocity(self, top_velocity_m_s: np.ndarray, dt: float, record: bool = True,
                     start_velocity_m_s: float | None = None, start_acceleration_m_s2: float | None = None
                     ) -> RunResult:
        """Advance with an arbitrary prescribed top velocity series (positive down), one value per step.
        `start_velocity_m_s` / `start_acceleration_m_s2` (positive down) set the top's state before the first
        step (default: keep the current one); give the series' own values, or the polished-rod load carries a
        Nyquist sawtooth of (top node mass) x (acceleration mismatch) for the whole run."""
        if start_velocity_m_s is not None or start_acceleration_m_s2 is not None:
            self._start_top(self.uav[1] if start_velocity_m_s is None else float(start_velocity_m_s),
                            self.uav[2] if start_acceleration_m_s2 is None else float(start_acceleration_m_s2))
        return self._run(np.ascontiguousarray(top_velocity_m_s, dtype=float), float(dt), record, 0.0, 0.0)

    def _stepper(self, dt: float, n_steps: int, record: bool) -> L.Stepper:
        """The kernel's arguments for a run (kernel_layout.build's, their shared part kept: .kernel_args)."""
        return self._kernel_args.stepper(self, dt, n_steps, record)

    def _run(self, va: np.ndarray, dt: float, record: bool, spm: float, stroke: float) -> RunResult:
        n_steps = len(va)
        st = self._stepper(dt, n_steps, record)
        valve, progress, counters = st.valve, st.progress, st.counters
        qp_calls0 = self.qp.stats.calls
        events = []
        t0 = self.time_s
        fillage = self.fillage
        self._pumped_m3 = 0.0
        while True:
            code = K.run(st, va, t0, n_steps)
            if code == L.DONE:
                break
            step = int(progress["step"][0])
            if code == L.NEED_QP:
                self._solve_qp(st, dt, step, t0 + (step + 1) * dt)
            else:
                fillage = self._on_event(int(progress["event"][0]), valve, progress, t0 + step * dt, events,
                                         fillage, stroke, 60.0 / spm if spm > 0 else 0.0)
        self._at_rest = False
        p, v, cnt = progress[0], valve[0], counters[0]
        self.pl_dir, self.void = int(p["plunger_dir"]), int(v["void"])
        self._damp_s = float(p["damp_s"])  # damping per direction: the factor K* ends the run with
        self._ub_max, self._ub_min = float(p["ub_max_m"]), float(p["ub_min_m"])
        self.void_until = float(v["void_until_m"])
        self._cond_keep(valve)
        if self.gas is not None or self.tubing_stiffness_n_m > 0:  # the kernel moved the reference on
            self._gas[1:5] = v["u0_m"], v["gas_m3"], v["p0"], v["liquid_m3"]
        self.time_s = t0 + n_steps * dt
        out = st.out
        trace = trace_from_record(out.rec[:, : cnt["recorded"]], self.cfg.surface.stuffing_box_friction_n) \
            if record else None
        self.fillage = fillage
        return RunResult(
            n_steps=n_steps, duration_s=n_steps * dt, spm=spm, stroke_length_m=stroke,
            certified_steps=int(cnt["certified"]), corrected_steps=int(cnt["corrected"]),
            qp_steps=int(cnt["qp"]), qp_calls=self.qp.stats.calls - qp_calls0,
            dc_iterations=int(cnt["dc_iterations"]), fillage=fillage, pumped_m3=self._pumped_m3,
            intake_pressure_pa=(self.annulus.intake_pressure_pa() if self.annulus else self.intake_at_pump_pa),
            rod_stick_episodes=out.stick[:-1].copy(), element_force_max_eq_n=out.emax,
            element_force_min_eq_n=out.emin, energy_j=self.energy_balance(), trace=trace, events=events)

    def _solve_qp(self, st: L.Stepper, dt: float, step: int, time_s: float) -> None:
        w, c = st.work, st.const[0]
        ksd, kso = st.model.ksd, st.model.kso
        dk = float(st.valve["lin_dk"][0])
        ds = float(st.progress["damp_s"][0])
        key = dt if ds == 1.0 else (dt, ds)  # damping per direction: one cached K*^-1 per direction
        if dk == 0.0:
            inv = self.qp.inverse(ksd, kso, key)
        else:  # the kernel added the gas spring dk to K*_BB (ksd holds it): Sherman-Morrison on the cached K*^-1
            ksd0 = ksd.copy()
            ksd0[-1] -= dk
            inv = self.qp.inverse(ksd0, kso, key)
            col = inv[:, -1] / (1.0 + dk * inv[-1, -1])
            inv = inv - dk * np.outer(col, inv[-1, :])
        v_raw, status = self.qp.solve(inv, w.wb, w.wlo, w.whi, w.ns.copy(), step, time_s)
        # polish: exact active-set solve from the QP's pattern, kept only if it is KKT-certified
        v = np.empty(self.n_free)
        ok = -1
        if self.polish:
            ok = K.solve_pattern(ksd, kso, w.wb, w.wlo, w.whi, w.ns, status, v, w.lam, w.rhs, w.stuck,
                                 w.cp, w.dp, int(c["max_corrections"]), float(c["tol_v_m_s"]),
                                 float(c["tol_lambda"]))
        if ok >= 0:
            self.qp.stats.polished += 1
            w.wv[:] = v
        else:
            w.wv[:] = v_raw
        self.status[:] = status
        st.progress["have_qp"] = 1

    def run_strokes(self, n: int, record: bool = True, **kw) -> list[RunResult]:
        return [self.run_stroke(record=record, **kw) for _ in range(n)]
