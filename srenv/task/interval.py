"""One control interval of well time: exact strokes, a quasi-steady fast-forward, and idle time.

The v1 env's step is ``task.interval_s`` of well time at an *average* stroke rate. At or above the VSD's
minimum speed the unit runs continuously at that rate; below it, it runs at the minimum speed for the fraction
``avg / spm_min`` of the interval and stands still for the rest (intermittent pumping), so the interval's
production is continuous in the action down to 0 SPM (idle).

Strokes are simulated **exactly** (the full nonsmooth FE model) until two consecutive strokes agree
(fillage within 0.01, PPRL within 0.5 %, stick-slip energy within 10 % + 1 J) or ``task.exact_strokes_max`` were run. The remaining strokes of
the interval are **fast-forwarded**: the last exact stroke repeats (its loads, card work, Goodman loading,
stick-slip energy and impact speed), while the annulus mass balance is integrated stroke by stroke (inflow
at the current level; the pump draws ``min(displacement, liquid available)``), so the fillage follows the
level. When the fast-forwarded fillage drifts from the exact stroke's by more than
``task.fast_forward_fillage_tol`` and the exact budget is not spent, the next stroke is simulated exactly
again. A fractional last stroke is counted by its fraction (of its liquid, work and costs), so every figure
is continuous in the stroke rate. The error of the fast-forward against simulating every stroke is measured
by ``tests/test_interval.py`` (production and PPRL within 1 %).

Options (off in v1; v2's default, docs/speed.md): ``reuse_periodic`` starts an interval from the stroke an
earlier interval at the same setpoint converged to, while the intake pressure has barely moved and the physics
is the same; ``carry`` also carries a kept stroke to a farther intake pressure along the slopes of two kept
strokes (:mod:`srenv.task.reuse`). Opt-in, off everywhere: ``exact_min`` and ``follow_drift``
(:mod:`srenv.task.stepping`), ``boundary_strokes`` (:mod:`srenv.task.boundary`), ``draw_follows_pump``
(:mod:`srenv.task.pump_draw`).
"""

from __future__ import annotations

import contextlib
from dataclasses import dataclass, field

import numpy as np

from ..analysis import card_features as cf
from ..analysis.stroke_summary import summarize
from ..physics.pump import plunger_area_m2
from ..simulation.simulator import RunResult, Simulator
from . import boundary, pump_draw, reuse, stepping
from .fillage_reading import controller_fillage

# the fast option (IntervalRunner(reuse_periodic=True)): how far the intake pressure may move the plunger's
# fluid load, as a fraction of the reused stroke's PPRL, and how many setpoints' strokes are kept
REUSE_LOAD_FRACTION = 0.002
REUSE_CACHE_SIZE = 8


@dataclass
class StrokeFigures:
    """What the costs need from one stroke (per stroke)."""

    summary: dict
    trace: dict
    lifted_m3: float
    displacement_m3: float
    fillage: float
    fillage_est: float
    work_j: float
    damage: float
    stick_slip_j: float
    impact_m_s: float
    power_mean_w: float
    power_peak_w: float
    gearbox: object = None  # its gearbox report while the summary's optimal counterbalance and powers wait (completed)


@dataclass
class IntervalResult:
    duration_s: float
    pumping_s: float = 0.0
    spm: float = 0.0
    stroke_length_m: float = 0.0
    strokes: float = 0.0
    exact_strokes: int = 0
    fast_forward_strokes: float = 0.0
    lifted_m3: float = 0.0
    displaced_m3: float = 0.0
    annulus_start_m3: float = 0.0
    annulus_end_m3: float = 0.0
    inflow_m3: float = 0.0
    work_j: float = 0.0
    damage: float = 0.0
    stick_slip_j: float = 0.0
    impact_sq_sum: float = 0.0
    impact_sum: float = 0.0
    pprl_n: float = float("nan")
    mprl_n: float = float("nan")
    goodman_max_pct: float = 0.0
    gearbox_loading_pct: float = 0.0
    last: StrokeFigures | None = None
    solver: dict = field(default_factory=lambda: {"certified_steps": 0, "corrected_steps": 0, "qp_steps": 0,
                                                  "solver_calls": 0})

    @property
    def pumping_fraction(self) -> float:
        return self.pumping_s / self.duration_s if self.duration_s > 0 else 0.0

    @property
    def fillage(self) -> float:
        return self.lifted_m3 / self.displaced_m3 if self.displaced_m3 > 0 else float("nan")


def string_stiffness_n_m(sim: Simulator) -> float:
    """Static axial stiffness of the string at the pump with the top held: 1 / sum(L / EA)."""
    return float(1.0 / np.sum(sim.mesh.length_m / sim.mesh.ea_n))


def stroke_figures(sim: Simulator, r: RunResult, fatigue_life: float, fatigue_exponent: float,
                   stiffness_n_m: float, defer: bool = False) -> StrokeFigures:
    """``defer``: the summary's gearbox figures no cost reads (the optimal counterbalance, the powers) are None
    until :func:`completed` (an exact stroke of an interval is summarised before it is known to be the last)."""
    made: list = []
    with sim.surface.deferring() if defer else contextlib.nullcontext(made) as made:
        m = summarize(sim, [r])
    tr = r.trace
    a_pl = plunger_area_m2(sim.cfg.pump)
    disp = a_pl * max(m["pump_stroke_m"], 0.0)
    p_mean, p_peak = cf.polished_rod_power_w(tr["polished_rod_position_m"], tr["polished_rod_velocity_m_s"],
                                             tr["polished_rod_load_n"], tr["t_s"])
    return StrokeFigures(
        summary=m, trace=tr, lifted_m3=r.pumped_m3, displacement_m3=disp, fillage=r.fillage,
        fillage_est=controller_fillage(sim, m, tr),
        work_j=m["card_work_j_per_stroke"], damage=reuse.fatigue_damage(m["goodman_max_pct"], fatigue_exponent,
                                                                   fatigue_life),
        stick_slip_j=cf.stick_slip_energy_j(tr["pump_position_m"], tr["pump_velocity_m_s"], tr["pump_load_n"],
                                            stiffness_n_m),
        impact_m_s=cf.impact_speed_m_s(tr["pump_position_m"], tr["pump_velocity_m_s"], tr["pump_load_n"]),
        power_mean_w=p_mean, power_peak_w=p_peak, gearbox=made[-1] if made else None)


def completed(f: StrokeFigures) -> StrokeFigures:
    """``f`` with the figures its summary deferred, in their places: the summary ``stroke_figures`` gives without
    ``defer``."""
    if f.gearbox is not None:
        f.summary.update(f.gearbox.completed().summary())
        f.gearbox = None
    return f


class IntervalRunner:
    """Runs control intervals on one simulator (see the module docstring)."""

    def __init__(self, sim: Simulator, reuse_periodic: bool = False, carry: bool = False,
                 draw_at_top: bool = False, exact_min: int = 0, follow_drift: bool = False,
                 boundary_strokes: int = 0, draw_follows_pump: bool = False) -> None:
        self.sim = sim
        self.draw_follows_pump = pump_draw.check(draw_follows_pump)  # opt-in: the fast-forward draws as the pump
        self.boundary_strokes = boundary.check(boundary_strokes)  # opt-in: exact strokes at regime boundaries
        # opt-in (srenv/task/stepping.py): K exact strokes an interval, their mean repeated; figures along the drift
        self.exact_min, self.follow_drift = stepping.check(exact_min, follow_drift, carry)
        # draw_at_top (v2): a fast-forwarded stroke draws its liquid at the upstroke's end as an exact stroke does
        # (v1 draws at the stroke's end: the annulus is then empty at the bottom where an exact stroke finds the
        # downstroke's inflow, and the exact strokes after a fast-forward pound on that; docs/speed.md)
        self.draw_at_top = draw_at_top
        # reuse_periodic (off in v1): an interval at the previous interval's setpoint starts from that
        # interval's converged stroke instead of simulating it again (docs/speed.md)
        self.reuse_periodic = reuse_periodic
        # carry (v2): a kept stroke is carried to a farther intake pressure along two kept strokes' slopes
        self.carry = carry
        self._periodic: dict[tuple, tuple[StrokeFigures, float, object]] = {}
        self._slopes: dict[tuple, reuse.Slopes] = {}
        cfg = sim.cfg
        self.task = cfg.task
        self.econ = cfg.economics
        self.spm_min = cfg.control.spm_min
        self.stiffness = string_stiffness_n_m(sim)
        self.running = True  # the unit is turning (False after an idle stretch: the next run restarts from rest)
        self._setpoint: tuple[float, float] | None = None
        self._restart = False

    def _figures(self, r: RunResult, defer: bool = False) -> StrokeFigures:
        return stroke_figures(self.sim, r, self.econ.fatigue_life_cycles, self.econ.fatigue_exponent,
                              self.stiffness, defer)

    def warm_up(self, spm: float, stroke_m: float) -> StrokeFigures:
        """One exact stroke outside any interval (the env's reset), for the first observation."""
        return self._figures(self.sim.run_stroke(spm, stroke_m, record=True))

    def run(self, avg_spm: float, stroke_m: float, duration_s: float,
            exact_strokes_max: int | None = None, fast_forward: bool = True) -> IntervalResult:
        """One interval; ``fast_forward=False`` simulates every stroke exactly (the reference the quasi-steady
        fast-forward is measured against)."""
        sim = self.sim
        ann = sim.annulus
        exact_max = self.task.exact_strokes_max if exact_strokes_max is None else exact_strokes_max
        self._fast_forward = fast_forward
        if not fast_forward:
            exact_max = 10**9
        exact_max = max(exact_max, self.exact_min)
        res = IntervalResult(duration_s=duration_s)
        t0 = sim.time_s
        res.annulus_start_m3 = ann.volume_m3 if ann is not None else 0.0
        stroke_m = sim.surface.stroke_length_m(stroke_m)
        res.stroke_length_m = stroke_m
        if avg_spm > 1e-9:
            spm = max(avg_spm, self.spm_min)
            res.spm = spm
            res.pumping_s = duration_s * min(1.0, avg_spm / self.spm_min)
            period = 60.0 / spm
            n_total = res.pumping_s / period
            self._restart = not self.running
            if self._restart:
                sim.replan_upstroke(period)
            self.running = True
            self._pump(res, spm, stroke_m, period, n_total, exact_max)
        if sim.time_s < t0 + duration_s - 1e-9 or res.pumping_s < duration_s:
            if self.running:
                sim.stop_at_bottom()
                self.running = False
            sim.idle(t0 + duration_s - sim.time_s)
        if ann is not None:
            ann.accumulate(sim.time_s)  # the annulus is otherwise booked at valve events only
        res.annulus_end_m3 = ann.volume_m3 if ann is not None else 0.0
        res.inflow_m3 = res.annulus_end_m3 - res.annulus_start_m3 + res.lifted_m3
        return res

    def _add(self, res: IntervalResult, f: StrokeFigures, w: float, lifted_m3: float, displaced_m3: float,
             costs: bool = True) -> None:
        res.strokes += w
        res.lifted_m3 += lifted_m3
        res.displaced_m3 += displaced_m3
        res.work_j += w * f.work_j
        if costs:
            self._add_costs(res, f, w)

    def _add_costs(self, res: IntervalResult, f: StrokeFigures, w: float) -> None:
        res.damage += w * f.damage
        res.stick_slip_j += w * f.stick_slip_j
        res.impact_sq_sum += w * f.impact_m_s ** 2
        res.impact_sum += w * f.impact_m_s
        self._add_peaks(res, f.summary)

    @staticmethod
    def _add_peaks(res: IntervalResult, m: dict) -> None:
        res.pprl_n = m["pprl_n"] if not np.isfinite(res.pprl_n) else max(res.pprl_n, m["pprl_n"])
        res.mprl_n = m["mprl_n"] if not np.isfinite(res.mprl_n) else min(res.mprl_n, m["mprl_n"])
        res.goodman_max_pct = max(res.goodman_max_pct, m["goodman_max_pct"])
        res.gearbox_loading_pct = max(res.gearbox_loading_pct, m.get("gearbox_loading_pct", 0.0))

    def _intake_pa(self) -> float:
        return self.sim.annulus.intake_pressure_pa() if self.sim.annulus is not None else 0.0

    def _reusable(self, key: tuple, allowed: bool) -> StrokeFigures | None:
        """The converged stroke of an earlier interval at this setpoint (``key``: SPM, stroke, from rest), if
        the pump's state allows it: the string runs on at the same setpoint or restarts from rest, and the
        intake pressure moved the plunger's fluid load by at most ``REUSE_LOAD_FRACTION`` of that stroke's
        PPRL (the load is what the stroke depends on; the liquid follows the annulus in the fast-forward)."""
        got = self._periodic.get(key) if self.reuse_periodic and allowed else None
        if got is None:
            return None
        f, p_in, cfg = got
        if cfg is not self.sim.cfg:  # a condition changed the physics since (v2's events): the stroke is stale
            return None
        area = plunger_area_m2(self.sim.cfg.pump)
        p_now = self._intake_pa()
        if abs(p_now - p_in) * area <= REUSE_LOAD_FRACTION * abs(f.summary["pprl_n"]):
            self._held_pa = p_in  # the pressure the reused figures hold at (follow_drift moves them from there)
            return f
        s = self._slopes.get(key) if self.carry else None
        if s is not None and s.reaches(p_now):  # v2: carried along two kept strokes' slopes (srenv/task/reuse.py)
            self._held_pa = p_now
            return reuse.carried(f, s, p_now - p_in)
        return None

    def _quasi_steady(self, exact: list[StrokeFigures]) -> bool:
        """A pumped-off well's strokes differ stroke to stroke (the pound) while the interval is steady: its last
        two strokes' fillages within the fast-forward's drift tolerance."""
        return len(exact) >= 2 and abs(exact[-1].fillage - exact[-2].fillage) < self.task.fast_forward_fillage_tol

    def _remember(self, key: tuple, f: StrokeFigures, p_in: float) -> None:
        old = self._periodic.pop(key, None)
        if self.carry:  # v2: two strokes kept at one physics and different intake pressures give slopes
            self._slopes.pop(key, None)
            if old is not None and old[2] is self.sim.cfg:
                span = abs(p_in - old[1]) * plunger_area_m2(self.sim.cfg.pump)
                if span > reuse.MIN_SPAN_LOAD_FRACTION * abs(f.summary["pprl_n"]):
                    self._slopes[key] = reuse.slopes(old[0], old[1], f, p_in)
        self._periodic[key] = (f, p_in, self.sim.cfg)
        while len(self._periodic) > REUSE_CACHE_SIZE:
            self._slopes.pop(next(iter(self._periodic)), None)
            self._periodic.pop(next(iter(self._periodic)))

    def _repeat_stroke(self, res: IntervalResult, f: StrokeFigures, period: float, n_total: float, done: float,
                      t_end: float, n_exact: int, exact_max: int, need_exact: bool) -> tuple[float, bool]:
        """Strokes not simulated, repeating the last exact one ``f``, until the interval ends or exact strokes
        are due; returns (strokes done, exact strokes due). Stroke by stroke: the annulus is drawn and filled
        and the interval's sums grow one stroke at a time, in the order ``_add`` / ``_add_costs`` add them (the
        same sums to the bit), kept in locals for the loop (it ran ~60 times an env step at 12 SPM)."""
        sim, tol = self.sim, self.task.fast_forward_fillage_tol
        disp, m = f.displacement_m3, f.summary
        in_barrel = max(m["pump_stroke_m"], 0.0)
        gas = sim.gas is not None
        up_s = sim.upstroke_s(period) if self.draw_at_top else None
        room = n_exact < max(exact_max, 1)
        strokes, lifted, displaced, work = res.strokes, res.lifted_m3, res.displaced_m3, res.work_j
        damage, stick, imp_sq, imp = res.damage, res.stick_slip_j, res.impact_sq_sum, res.impact_sum
        ff = res.fast_forward_strokes
        # the repeated stroke's figures and the simulator's method in locals (the same floats, fewer lookups)
        f_work, f_damage, f_stick, f_imp, f_fill = f.work_j, f.damage, f.stick_slip_j, f.impact_m_s, f.fillage
        imp2 = f_imp ** 2
        forward = sim.fast_forward
        unit_of = pump_draw.displacement_rule(self, disp) if self.draw_follows_pump else None
        ran = False
        while done < n_total - 1e-9:
            remaining = n_total - done
            if need_exact and room and remaining >= 1.0 - 1e-9:
                break
            ran = True
            w = remaining if remaining < 1.0 else 1.0  # noqa: FURB136 (min(1.0, remaining): a builtin call less)
            t_next = min(sim.time_s + w * period, t_end) if w < 1.0 else sim.time_s + period
            # what the pump can draw: its displacement less the free gas's share (1 without gas)
            unit = disp if unit_of is None else unit_of(self._intake_pa())
            cap = w * unit * (sim.gas_liquid_fraction(in_barrel) if gas else 1.0)
            take = forward(t_next, cap, sim.time_s + up_s if up_s is not None else None)
            fill = take / (w * unit) if unit > 0 else 1.0
            strokes += w
            lifted += take
            displaced += w * unit
            work += w * f_work
            damage += w * f_damage
            stick += w * f_stick
            imp_sq += w * imp2
            imp += w * f_imp
            ff += w
            done += w
            if abs(fill - f_fill) > tol and n_exact < exact_max:
                sim.replan_upstroke(period)
                need_exact = True
        res.strokes, res.lifted_m3, res.displaced_m3, res.work_j = strokes, lifted, displaced, work
        res.damage, res.stick_slip_j, res.impact_sq_sum, res.impact_sum = damage, stick, imp_sq, imp
        res.fast_forward_strokes = ff
        if ran:  # the peaks of a repeated stroke: taking them once is taking them at every stroke
            self._add_peaks(res, m)
        return done, need_exact

    def _pump(self, res: IntervalResult, spm: float, stroke_m: float, period: float, n_total: float,
              exact_max: int) -> None:
        sim, ann = self.sim, self.sim.annulus
        t_end = sim.time_s + res.pumping_s
        done = 0.0
        exact: list[StrokeFigures] = []
        need_exact, self._exact_cap = True, 0  # the cap: exact strokes boundary.py grants beyond exact_max
        # The simulator switches the setpoint at a stroke boundary, a VSD ramps it over seconds: the first stroke
        # after a change rings with the step change. Its liquid and work count as simulated; its costs (peaks,
        # stick-slip, pound, fatigue) are those of the next, settled stroke when there is one.
        setpoint = (spm, stroke_m)
        transient_w = 0.0 if setpoint == self._setpoint and not self._restart else None
        self._setpoint = setpoint
        key = (spm, stroke_m, self._restart)
        reused = self._reusable(key, (transient_w is not None or self._restart) and not self.exact_min)
        pressures, settled = [], 0  # the pressure each of `exact` holds at; the first settled one (exact_min)
        if reused is not None:
            exact.append(reused)
            pressures.append(self._held_pa)
            need_exact, transient_w = False, 0.0
        p_exact = None  # the intake pressure of the last stroke simulated here
        while done < n_total - 1e-9:
            remaining = n_total - done
            room = len(exact) < max(exact_max, 1, self._exact_cap)
            if need_exact and room and (remaining >= 1.0 - 1e-9 or not exact):
                r = sim.run_stroke(spm, stroke_m, record=True)
                f = self._figures(r, defer=True)  # the last one kept is completed below
                p_exact = self._intake_pa() if self.reuse_periodic else None
                w = min(1.0, remaining)
                lifted = f.lifted_m3
                if w < 1.0 and ann is not None:  # only part of this stroke belongs to the interval
                    sim.return_liquid((1.0 - w) * lifted)
                    lifted *= w
                if transient_w is None:  # the first stroke after a change: its costs wait for the next one
                    self._add(res, f, w, lifted, w * f.displacement_m3, costs=False)
                    transient_w, settled = w, 1
                else:
                    self._add(res, f, w, lifted, w * f.displacement_m3)
                    if transient_w > 0:
                        self._add_costs(res, f, transient_w)
                        transient_w = 0.0
                for k in res.solver:
                    res.solver[k] += int(f.summary[k])
                res.exact_strokes += 1
                done += w
                exact.append(f)
                pressures.append(p_exact)
                if len(exact) >= 2:
                    a, b = exact[-2].summary, exact[-1].summary
                    e1, e2 = exact[-2].stick_slip_j, exact[-1].stick_slip_j
                    need_exact = not self._fast_forward or not (abs(exact[-1].fillage - exact[-2].fillage) < 0.01
                                      and abs(b["pprl_n"] / a["pprl_n"] - 1.0) < 0.005
                                      and abs(e2 - e1) <= 0.1 * max(e1, e2) + 1.0)
                need_exact = need_exact or res.exact_strokes < self.exact_min
                continue
            # fast-forward from the last exact stroke (or the options' stroke: srenv/task/stepping.py)
            done, need_exact = stepping.fast_forward(self, res, exact, pressures, settled, key, period, n_total,
                                                     done, t_end, exact_max, need_exact)
        if transient_w and exact:  # no settled stroke followed: the transient stroke prices itself
            self._add_costs(res, exact[0], transient_w)
        res.last = completed(exact[-1]) if exact else None
        if p_exact is not None and (not need_exact or self._quasi_steady(exact)):
            self._remember(key, exact[-1], p_exact)
        sim.replan_upstroke(period)
