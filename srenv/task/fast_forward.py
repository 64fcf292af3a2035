"""The interval's fast-forward (strokes not simulated, the last exact one repeated) as one compiled loop.

``IntervalRunner._repeat_stroke`` books the annulus stroke by stroke: the pump draws what the annulus holds
(at the upstroke's end in v2, the stroke's end in v1), the reservoir fills it at the inflow of the current
level, and the interval's sums grow one stroke at a time. In Python that was ~44 µs a stroke, ~60 strokes an
env step at 12 SPM (docs/speed.md §2c, §2e). :func:`repeat_strokes` runs the same loop compiled, with the same
floating-point operations in the same order as the Python it replaces (``Annulus.draw``/``accumulate``/
``inflow_m3_s``/``intake_pressure_pa``, ``Survey.tvd_at``'s interpolation, Python's ``min``/``max`` as their
comparisons), so the same bits: tests/srenv/task/test_fast_forward_loop.py pins it against the Python loop and
the acceptance's digests (tests/srenv/envs/test_rl_digest.py) against the code before it.

A well with free gas keeps the Python loop: its pump's liquid share follows the gas chamber's law at each
stroke's intake pressure.
"""

# Python's min(a, b) / max(a, b) are written out as the comparisons CPython makes (which argument wins on a tie,
# a signed zero or a NaN), not numba's min/max:
# ruff: noqa: PLR1730, FURB136
from __future__ import annotations

import math

import numpy as np
from numba import njit

from ..physics.inflow import SECONDS_PER_DAY
from ..physics.rod import GRAVITY_M_S2

# acc: the loop's state, read and written back (sums of the interval, the stroke count, the clock, the annulus)
STROKES, LIFTED, DISPLACED, WORK, DAMAGE, STICK, IMP_SQ, IMP, FF, DONE, TIME, VOLUME, LAST = range(13)
# returns: the interval's strokes are done / exact strokes are due / the fillage drifted (the caller re-plans the
# coming upstroke, as the Python loop does inside it, and calls again with exact strokes due)
FINISHED, EXACT_DUE, DRIFTED = 0, 1, 2


@njit(cache=True)
def _tvd_at(grid, z, x):
    """Survey.tvd_at: np.interp's arithmetic on one depth (bisect_right is searchsorted's 'right')."""
    if math.isnan(x):
        return x
    n = grid.shape[0]
    j = np.searchsorted(grid, x, side="right") - 1
    if j < 0 or j >= n - 1 or grid[j] == x:
        k = j
        if k < 0:
            k = 0
        if k > n - 1:
            k = n - 1
        return z[k]
    slope = (z[j + 1] - z[j]) / (grid[j + 1] - grid[j])
    return slope * (x - grid[j]) + z[j]


@njit(cache=True)
def _inflow_m3_s(volume, a, grid, z):
    """Annulus.inflow_m3_s at ``volume`` (``a``: the annulus's constants, see :func:`annulus_params`)."""
    level = volume / a[0]
    h = a[1] if a[1] < level else level  # min(level, pump_md)
    p_wf = a[2] + a[3] * GRAVITY_M_S2 * (a[4] - _tvd_at(grid, z, a[1] - h))
    p_r = a[7]
    if a[5] == 0.0:  # linear
        d = p_r - p_wf
        if 0.0 > d:
            d = 0.0
        q_day = a[6] * d
    else:  # Vogel
        r = p_wf / p_r
        if 0.0 > r:
            r = 0.0
        if r > 1.0:
            r = 1.0
        q_day = a[8] * (1 - 0.2 * r - 0.8 * r * r)
    return a[9] * q_day / SECONDS_PER_DAY


@njit(cache=True)
def _accumulate(acc, a, grid, z, time_s):
    dt = time_s - acc[LAST]
    if 0.0 > dt:
        dt = 0.0
    v = acc[VOLUME] + _inflow_m3_s(acc[VOLUME], a, grid, z) * dt
    acc[VOLUME] = a[10] if a[10] < v else v
    acc[LAST] = time_s


@njit(cache=True)
def _draw(acc, a, grid, z, displaced_m3, time_s):
    _accumulate(acc, a, grid, z, time_s)
    if displaced_m3 <= 0:
        return 0.0
    taken = acc[VOLUME] if acc[VOLUME] < displaced_m3 else displaced_m3
    acc[VOLUME] -= taken
    return taken


@njit(cache=True)
def repeat_strokes(acc, p, a, grid, z):
    """The loop of ``IntervalRunner._repeat_stroke`` (no gas). ``p``: n_total, period, t_end, the stroke's
    displacement, upstroke (NaN: draw at the stroke's end), fillage, drift tolerance, work, damage, stick-slip,
    impact², impact, exact due, room for exact strokes, drift may call them, an annulus. Returns (why it
    stopped, whether a stroke was repeated)."""
    n_total, period, t_end, disp, up_s = p[0], p[1], p[2], p[3], p[4]
    fillage, tol, need_exact, room, can_drift, has_ann = p[5], p[6], p[12] != 0.0, p[13] != 0.0, p[14] != 0.0, \
        p[15] != 0.0
    ran = False
    while acc[DONE] < n_total - 1e-9:
        remaining = n_total - acc[DONE]
        if need_exact and room and remaining >= 1.0 - 1e-9:
            return EXACT_DUE, ran
        ran = True
        w = remaining if remaining < 1.0 else 1.0
        if w < 1.0:
            t_next = acc[TIME] + w * period
            if t_end < t_next:
                t_next = t_end
        else:
            t_next = acc[TIME] + period
        cap = w * disp
        if not has_ann:
            take = cap
        elif not math.isnan(up_s) and acc[TIME] + up_s < t_next:
            take = _draw(acc, a, grid, z, cap, acc[TIME] + up_s)
            _accumulate(acc, a, grid, z, t_next)
        else:
            take = _draw(acc, a, grid, z, cap, t_next)
        acc[TIME] = t_next
        fill = take / (w * disp) if disp > 0 else 1.0
        acc[STROKES] += w
        acc[LIFTED] += take
        acc[DISPLACED] += w * disp
        acc[WORK] += w * p[7]
        acc[DAMAGE] += w * p[8]
        acc[STICK] += w * p[9]
        acc[IMP_SQ] += w * p[10]
        acc[IMP] += w * p[11]
        acc[FF] += w
        acc[DONE] += w
        if abs(fill - fillage) > tol and can_drift:
            return DRIFTED, ran
    return FINISHED, ran


def annulus_params(ann) -> np.ndarray:
    """The annulus's constants for the loop: area, pump MD, casing pressure, density, pump TVD, model (0 linear,
    1 Vogel), PI, reservoir pressure, max rate, rate multiplier, full volume."""
    c, fl = ann.cfg, ann.fluid
    return np.array([ann.area_m2, ann.pump_md_m, c.casing_pressure_pa, fl.density_kg_m3, ann._pump_tvd,
                     0.0 if c.model == "linear" else 1.0, c.productivity_index_m3_day_pa, c.reservoir_pressure_pa,
                     c.max_rate_m3_day, ann.rate_multiplier, ann._full_m3])


def compiled_applies(sim) -> bool:
    """The compiled loop books this simulator's fast-forward: no free gas, and the annulus (if any) reads the
    simulator's own survey (the only annulus a Simulator builds)."""
    ann = sim.annulus
    return sim.gas is None and (ann is None or ann._tvd == sim.survey.tvd_at)


def run_compiled(sim, res, f, period: float, n_total: float, done: float, t_end: float, up_s: float | None,
                 tol: float, room: bool, can_drift: bool, need_exact: bool) -> tuple[float, bool, bool]:
    """``IntervalRunner._repeat_stroke``'s loop compiled (:func:`repeat_strokes`); the interval's sums, the clock
    and the annulus written back. Returns (strokes done, exact strokes due, a stroke was repeated)."""
    ann = sim.annulus
    acc = np.array([res.strokes, res.lifted_m3, res.displaced_m3, res.work_j, res.damage, res.stick_slip_j,
                    res.impact_sq_sum, res.impact_sum, res.fast_forward_strokes, done, sim.time_s,
                    ann.volume_m3 if ann is not None else 0.0, ann.last_time_s if ann is not None else 0.0])
    a = annulus_params(ann) if ann is not None else np.zeros(11)
    grid, z = sim.survey._tvd_table
    p = np.array([n_total, period, t_end, f.displacement_m3, math.nan if up_s is None else up_s, f.fillage, tol,
                  f.work_j, f.damage, f.stick_slip_j, f.impact_m_s ** 2, f.impact_m_s, float(need_exact),
                  float(room), float(can_drift), float(ann is not None)])
    ran = False
    while True:
        why, ran_now = repeat_strokes(acc, p, a, grid, z)
        ran = ran or ran_now
        sim.fast_forwarded(float(acc[TIME]), float(acc[VOLUME]), float(acc[LAST]))
        if why != DRIFTED:
            break
        sim.replan_upstroke(period)  # as the Python loop: the coming upstroke's liquid, exact strokes due
        need_exact = True
        p[12] = 1.0
    (res.strokes, res.lifted_m3, res.displaced_m3, res.work_j, res.damage, res.stick_slip_j, res.impact_sq_sum,
     res.impact_sum, res.fast_forward_strokes) = (float(x) for x in acc[:DONE])
    return float(acc[DONE]), need_exact, ran
