"""Opt-in: exact strokes placed where a fast-forward crosses a regime boundary (docs/speed.md §2h).

``IntervalRunner(boundary_strokes=N)`` (0, the default, is off: v1's and v2's results do not move). A fast-forward
repeats one stroke; the error left at full speed (§2g) is where the interval's strokes stop being that stroke: the
pump starting to pump off as the annulus drains, a loading crossing its rating, or the interval's largest loading
set at its far end by the drift. Before a fast-forward the annulus' trend a stroke is read (its inflow less the
repeated stroke's lift, and the intake pressure that gives), and the repeated stroke's figures are extrapolated
along the carry's intake-pressure slopes (:mod:`srenv.task.reuse`) to the stroke where

- the pump's fill goes partial (the liquid the annulus holds at the draw falls below the stroke's lift; aimed
  ``FILL_LEAD`` strokes early),
- the PPRL, Goodman or gearbox loading crosses its rating (the peak-load term's relu switches on or off), or
- the interval's last whole stroke, when the loading the drift predicts there moves the peak-load term or the PPRL
  by more than ``PEAK_TOLERANCE`` (a repeated stroke books the run's first loading as its peak);

the fast-forward stops there and that stroke is simulated exactly, and more while the strokes after a boundary
found mid-interval (by this or by the fast-forward's fillage drift) disagree (re-settling in the new regime), after
which the fast-forward repeats the new stroke. At most N strokes an
interval beyond ``task.exact_strokes_max`` are spent so. Valve-event changes other than the pump's fill are not
predicted (no figure of a stroke carries them smoothly).
"""

from __future__ import annotations

import copy
import math

from .runner_options import BOUNDARY_STROKES_MAX, check_option  # noqa: F401 (re-exported)

FULL = 0.99  # a stroke at or above this fillage fills the pump
PEAK_TOLERANCE = 0.005  # the error goal: a predicted change below it is not worth an exact stroke
# the fill's boundary is aimed this many strokes early: the fast-forward's annulus is its own balance, a stroke or
# so off the pump's by then, and the strokes of the crossing (the pound's worst is in them) are then all exact
FILL_LEAD = 1.0
SETTLE = 2  # exact strokes granted at a boundary: the stroke there and one to re-settle if it differs
LOADINGS = (("pprl_n", None), ("goodman_max_pct", 100.0), ("gearbox_loading_pct", 100.0))


def check(boundary_strokes) -> int:
    """The option, validated (runner_options.check_option: ValueError naming it, its value and what was expected)."""
    return check_option("boundary_strokes", boundary_strokes)


def strokes_to_boundary(f, s, p_f, p_now: float, dp: float, avail_m3: float, dv_m3: float, to_end: int,
                        pprl_rating_n: float) -> int | None:
    """Whole fast-forwarded strokes from now to the first predicted boundary (None: none before the run's end).
    ``f``: the repeated stroke's figures, held at intake pressure ``p_f``; ``s``: the carry's slopes (or None);
    ``dp``/``dv_m3``: the intake pressure's and the annulus liquid's change per stroke; ``avail_m3``: the liquid
    the next draw finds; ``to_end``: whole strokes before the interval's last whole stroke."""
    ks = []
    if f.fillage >= FULL and dv_m3 < 0.0 and f.lifted_m3 > 0.0:  # pumping down: the fill goes partial
        ks.append((avail_m3 - f.lifted_m3) / -dv_m3 - FILL_LEAD)
    if s is not None and p_f is not None and dp != 0.0:
        end = False
        for key, rating in LOADINGS:
            thr = pprl_rating_n if rating is None else rating
            v0 = f.summary.get(key, 0.0) + s.of[key] * (p_now - p_f)
            rate = s.of[key] * dp
            if rate != 0.0 and (thr - v0) / rate > 0.0:  # heading for its rating
                ks.append((thr - v0) / rate)
            v_end = v0 + rate * to_end
            if v_end > max(v0, 0.0) and thr > 0.0:  # the run's largest loading is at its end
                moved = (v_end - v0) / v_end if key == "pprl_n" else 0.0
                if v_end > thr:  # relu(v/thr - 1)^2: its relative change is 2 dv / (v - thr)
                    moved = max(moved, 2.0 * (v_end - max(v0, thr)) / (v_end - thr))
                end = end or moved > PEAK_TOLERANCE
        if end:
            ks.append(float(to_end))
    ks = [k for k in ks if k < to_end + 0.5]
    return max(0, math.ceil(min(ks) - 1e-9)) if ks else None


def _liquid_m3(ann, t_s: float) -> float:
    """The liquid the annulus holds at ``t_s`` (it books its inflow lazily, at valve events): read, not booked."""
    if ann is None:
        return 0.0
    return ann.volume_m3 + ann.inflow_m3_s() * max(t_s - ann.last_time_s, 0.0)


def _pressure_at(ann, volume_m3: float) -> float:
    """The intake pressure the annulus would give holding ``volume_m3`` (a copy's: the annulus is not touched)."""
    probe = copy.copy(ann)
    probe.volume_m3 = max(volume_m3, 0.0)
    return probe.intake_pressure_pa()


def fast_forward(runner, res, f, p_f, s, period: float, n_total: float, done: float, t_end: float, n_exact: int,
                 exact_max: int, need_exact: bool) -> tuple[float, bool]:
    """``runner._repeat_stroke`` run up to the next predicted boundary, where an exact stroke is made due (and
    granted beyond ``exact_max`` through ``runner._exact_cap``); the same call as the plain fast-forward when no
    boundary is predicted or the option's strokes are spent."""
    budget, ann = exact_max + runner.boundary_strokes, runner.sim.annulus
    rest = n_total - done
    tail = rest - math.floor(rest + 1e-9)  # the fractional stroke that ends the interval
    last_full = n_total - tail - 1.0  # where the interval's last whole stroke starts
    if n_exact >= budget or ann is None or last_full - done < 1.0 - 1e-9:
        return runner._repeat_stroke(res, f, period, n_total, done, t_end, n_exact, exact_max, need_exact)
    due = need_exact  # an unsettled stroke with exact_max spent
    if due and res.fast_forward_strokes > 0:  # unsettled after a boundary found mid-interval: re-settle first
        runner._exact_cap = n_exact + 1
        return done, True
    # the trend a stroke: the annulus gains its inflow and gives the repeated stroke's lift; the pressure follows
    v0, q = _liquid_m3(ann, runner.sim.time_s), ann.inflow_m3_s()
    dv = q * period - f.lifted_m3
    p0 = _pressure_at(ann, v0)
    avail = v0 + q * (runner.sim.upstroke_s(period) if runner.draw_at_top else period)
    k = strokes_to_boundary(f, s, p_f, p0, _pressure_at(ann, v0 + dv) - p0, avail, dv, round(last_full - done),
                            runner.econ.pprl_rating_n)
    if k is None:
        return runner._repeat_stroke(res, f, period, n_total, done, t_end, n_exact, exact_max, need_exact)
    if k > 0:
        done, need_exact = runner._repeat_stroke(res, f, period, min(done + k, last_full), done, t_end, n_exact,
                                                 exact_max, need_exact)
        if need_exact and not due:  # the fillage drift asked for one within exact_max
            return done, need_exact
    runner._exact_cap = min(n_exact + SETTLE, budget)  # the boundary: an exact stroke is due there, and granted
    return done, True
