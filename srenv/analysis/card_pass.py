"""Compiled loops of :mod:`srenv.analysis.card_features` run on every exact stroke of the env (issue 25: a
changing-action step simulates ~2 strokes, each summarised). Comparisons, maxima and minima only, and the stick-slip
sum in the numpy form's order: the same numbers to the bit (tests/srenv/simulation/test_fast_paths_rl.py pins
them against the numpy forms they replaced)."""

from __future__ import annotations

import math

import numpy as np
from numba import njit


@njit(cache=True)
def stick_slip_sum(x: np.ndarray, v: np.ndarray, f: np.ndarray, tol: float, end_fraction: float,
                   ramp_fraction: float) -> tuple:
    """(sum over the plunger's rest runs of weight * dF^2, whether there is a run, whether every value is finite)
    of :func:`srenv.analysis.card_features.stick_slip_energy_j`: runs of at least two samples with |v| <= tol,
    dF the load's swing over the run and one sample either side, weighted by the distance from the nearer end of
    the travel. A trace with a value that is not finite is left to the numpy form (its NaN rules)."""
    n = x.size
    for i in range(n):
        if not (math.isfinite(x[i]) and math.isfinite(v[i]) and math.isfinite(f[i])):
            return 0.0, False, False
    lo, hi = x.min(), x.max()
    travel = max(hi - lo, 1e-6)
    d0, ramp = end_fraction * travel, ramp_fraction * travel
    total = 0.0
    any_run = False
    i = 0
    while i < n:
        if abs(v[i]) > tol:
            i += 1
            continue
        s = i
        while i < n and abs(v[i]) <= tol:
            i += 1
        if i - s < 2:
            continue
        any_run = True
        a, b = max(s - 1, 0), min(i + 1, n)
        f_max = f[a]
        f_min = f[a]
        for j in range(a + 1, b):
            f_max = max(f_max, f[j])
            f_min = min(f_min, f[j])
        df = f_max - f_min
        d = min(x[s] - lo, hi - x[s])
        total += min(1.0, max(0.0, d - d0) / ramp) * df * df
    return total, any_run, True


@njit(cache=True)
def first_below(f: np.ndarray, start: int, level: float) -> int:
    """The first index k >= start with f[k] < level, or -1."""
    for k in range(start, f.size):
        if f[k] < level:
            return k
    return -1
