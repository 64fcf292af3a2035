"""Checks and small transforms shared by the trace metrics (``metrics``, ``stick_metrics``): 1-D float arrays,
uniform sampling, linear detrending. Conventions in :mod:`srenv.analysis.metrics`."""

from __future__ import annotations

import numpy as np
import numpy.typing as npt
from numba import njit

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.int64]


def _as_float_1d(name: str, x: npt.ArrayLike) -> FloatArray:
    arr = np.asarray(x, dtype=np.float64)
    if arr.ndim != 1:
        raise ValueError(f"{name} must be a 1-D trace, got shape {arr.shape}")
    return arr


def _scalar_or_array(x: FloatArray) -> FloatArray | float:
    # Scalar in, scalar out: keeps single-taper calls readable without losing vectorisation.
    return float(x) if x.ndim == 0 else x


# The trace metrics run on every env step, so their loops are compiled (numba): one implementation,
# called by the CLI summary, the env and the tests alike.
@njit(cache=True)
def _max_step_jitter(t: FloatArray, dt: float) -> float:
    worst = 0.0
    for i in range(1, t.size):
        worst = max(worst, abs(t[i] - t[i - 1] - dt))
    return worst


def _uniform_step_s(t_s: npt.ArrayLike, n_expected: int) -> float:
    t = _as_float_1d("t_s", t_s)
    if t.size != n_expected:
        raise ValueError(f"t_s has {t.size} samples, the trace {n_expected}")
    if t.size < 2:
        raise ValueError("need at least two time samples")
    dt = (t[-1] - t[0]) / (t.size - 1)
    # Moving averages and FFT bins assume one fixed step; silently accepting a jittered grid would bias them.
    if not dt > 0.0 or _max_step_jitter(t, dt) > 1e-6 * dt:
        raise ValueError("t_s must be strictly increasing and uniformly sampled")
    return float(dt)


def _detrend_linear(t_s: FloatArray, x: FloatArray) -> FloatArray:
    """x minus its least-squares straight line in t (centred, so the normal equations are diagonal)."""
    tc = t_s - t_s.mean()
    xc = x - x.mean()
    return xc - (np.dot(tc, xc) / np.dot(tc, tc)) * tc


