"""One compiled pass over a recorded stroke for :mod:`srenv.analysis.stroke_summary` (the env's per-step summary).

The summary used to call ten numpy-level metrics, each a few Python calls and array temporaries; on every env
step, right after the compiled kernel, those calls cost as much as ~10 % of the stroke. Here the same
definitions (:mod:`srenv.analysis.metrics`, :mod:`srenv.analysis.stick_metrics`, :mod:`srenv.analysis.pump_card`) are evaluated by one
compiled call that reads each trace column once. Same values: exact for maxima, minima, counts, order
statistics and crossings; the card area and the slip residual differ from the numpy forms at most by the
order of summation (``tests/srenv/simulation/test_stroke_pass.py`` pins them against the metrics functions).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from .stick_metrics import _moving_average_residual

# percentiles of the pump-card levels (pump_card.py: 10th = downstroke plateau, 85th = upstroke plateau)
_Q_DOWN, _Q_UP = 0.10, 0.85


@njit(cache=True)
def _trace_figures(t: np.ndarray, ua: np.ndarray, prl: np.ndarray, ub: np.ndarray, vb: np.ndarray, half: int,
                   rest_tol: float, min_rest_steps: int) -> tuple:
    """(max step jitter of t, PPRL, MPRL, polished-rod stroke, card area, pump stroke, plunger rest episodes,
    peak-to-peak of the slip residual) of one trace; definitions in :mod:`srenv.analysis.metrics`.

    ``half`` is the half-width in samples of the slip moving average (``stick_metrics._centered_residual``)."""
    n = t.size
    dt = (t[-1] - t[0]) / (n - 1)
    jitter = 0.0
    f_max = prl[0]
    f_min = prl[0]
    x_max = ua[0]
    x_min = ua[0]
    b_max = ub[0]
    b_min = ub[0]
    area = 0.0
    episodes = 0
    run = 0
    du = np.empty(n)
    for i in range(n):
        f = prl[i]
        x = ua[i]
        b = ub[i]
        f_max = max(f_max, f)
        f_min = min(f_min, f)
        x_max = max(x_max, x)
        x_min = min(x_min, x)
        b_max = max(b_max, b)
        b_min = min(b_min, b)
        du[i] = x - b
        if i > 0:
            jitter = max(jitter, abs(t[i] - t[i - 1] - dt))
            area += (f + prl[i - 1]) * (x - ua[i - 1])
        # a rest episode: a maximal run of |v| <= tol at least min_rest_steps samples long
        if abs(vb[i]) <= rest_tol:
            run += 1
        else:
            if run >= min_rest_steps:
                episodes += 1
            run = 0
    if run >= min_rest_steps:
        episodes += 1
    area = 0.5 * (area + (prl[0] + prl[-1]) * (ua[0] - ua[-1]))
    residual = _moving_average_residual(t, du, half)
    return (jitter, f_max, f_min, x_max - x_min, area, b_max - b_min, episodes,
            residual.max() - residual.min())


@njit(cache=True)
def _select(a: np.ndarray, k: int, lo: int, hi: int) -> float:
    """The k-th smallest of a[lo:hi + 1], in place (Hoare quickselect; a[lo:k] <= a[k] <= a[k + 1:hi + 1])."""
    while lo < hi:
        mid = (lo + hi) // 2
        x, y, z = a[lo], a[mid], a[hi]  # median of three: no quadratic case on a sorted or plateau card
        pivot = max(min(x, y), min(max(x, y), z))
        i, j = lo, hi
        while i <= j:
            while a[i] < pivot:
                i += 1
            while a[j] > pivot:
                j -= 1
            if i <= j:
                a[i], a[j] = a[j], a[i]
                i += 1
                j -= 1
        if k <= j:
            hi = j
        elif k >= i:
            lo = i
        else:
            break  # a[j + 1:i] == pivot
    return a[k]


@njit(cache=True)
def _percentile(a: np.ndarray, q: float, lo: int) -> tuple:
    """(q-th percentile by np.percentile's 'linear' rule, index of its lower order statistic) of a, whose
    order statistics below `lo` are already in place (a partially selected copy)."""
    m = a.size - 1
    pos = q * m
    i = int(np.floor(pos))
    s_i = _select(a, i, lo, m)
    s_next = a[i + 1:].min() if i < m else s_i  # everything right of i is >= a[i] after the selection
    return s_i + (pos - i) * (s_next - s_i), i


@njit(cache=True)
def _first_fall(x: np.ndarray, f: np.ndarray, start: int, length: int, level: float) -> float:
    """``pump_card._crossing`` on the ``length`` samples from ``start`` on, wrapping round the end of the record."""
    n = x.size
    for k in range(length):
        i = (start + k) % n
        if f[i] <= level:
            if k == 0:
                return x[i]
            j = (start + k - 1) % n
            a = (f[j] - level) / (f[j] - f[i])
            return x[j] + a * (x[i] - x[j])
    return x[(start + length - 1) % n]


@njit(cache=True)
def pump_card_figures(x: np.ndarray, f: np.ndarray) -> tuple:
    """(stroke, downstroke level, upstroke level, x_min, crossings at 50 %, 90 % and 10 % of the transfer on the
    downstroke) of one pump card, as :func:`srenv.analysis.pump_card.analyse_pump_card` reads it."""
    a = f.copy()
    down, i_down = _percentile(a, _Q_DOWN, 0)
    up, _ = _percentile(a, _Q_UP, i_down + 1)
    i_top = np.argmax(x)
    i_min = np.argmin(x)
    x_min = x[i_min]
    fluid = up - down
    # the downstroke: from the top of the plunger travel to the following bottom (the card is periodic)
    length = i_min - i_top + 1 if i_min >= i_top else x.size - i_top + i_min + 1
    x_mid = _first_fall(x, f, i_top, length, down + 0.5 * fluid)
    x90 = _first_fall(x, f, i_top, length, down + 0.9 * fluid)
    x10 = _first_fall(x, f, i_top, length, down + 0.1 * fluid)
    return x[i_top] - x_min, down, up, x_min, x_mid, x90, x10


@njit(cache=True)
def stroke_pass(t: np.ndarray, ua: np.ndarray, prl: np.ndarray, ub: np.ndarray, vb: np.ndarray,
                pump_x: np.ndarray, pump_f: np.ndarray, half: int, rest_tol: float, min_rest_steps: int,
                rod_eps: np.ndarray, allowance: int) -> tuple:
    """:func:`_trace_figures` of the trace, the rod nodes' extra stick episodes (episodes beyond `allowance`,
    summed) and :func:`pump_card_figures` of the pump card (`pump_x`, `pump_f`), in one call: each compiled
    call from Python costs microseconds of argument handling."""
    rod_extra = 0
    for c in rod_eps:
        rod_extra += max(c - allowance, 0)
    return (_trace_figures(t, ua, prl, ub, vb, half, rest_tol, min_rest_steps), rod_extra,
            pump_card_figures(pump_x, pump_f))


@njit(cache=True)
def goodman_pct(fmax_eq: np.ndarray, fmin_eq: np.ndarray, e: np.ndarray, shift: np.ndarray, area: np.ndarray,
                quarter_tensile: np.ndarray) -> np.ndarray:
    """:func:`srenv.analysis.metrics.goodman_loading_pct` (SF = 1) of the true loads ``N_eq - shift`` at elements `e`
    (``quarter_tensile`` = T / 4): inf where no allowable range is left."""
    out = np.empty(e.size)
    for k in range(e.size):
        s_max = (fmax_eq[e[k]] - shift[k]) / area[k]
        s_min = (fmin_eq[e[k]] - shift[k]) / area[k]
        allowable_range = (quarter_tensile[k] + 0.5625 * s_min) - s_min
        out[k] = 100.0 * (s_max - s_min) / allowable_range if allowable_range > 0 else np.inf
    return out
