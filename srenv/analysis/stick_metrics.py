"""Rest (stick) episodes, slip amplitude, load oscillation and the stick-slip index of traces; definitions in the
docstring of :mod:`srenv.analysis.metrics` (which re-exports these)."""

from __future__ import annotations

import math

import numpy as np
import numpy.typing as npt
from numba import njit

from .trace_arrays import FloatArray, IntArray, _as_float_1d, _uniform_step_s

# Two reversals (bottom and top) per stroke, each with the plunger at rest while the valves switch.
_RESTS_PER_STROKE = 2
# Absorbs round-off in a stroke count computed as duration * spm / 60 before rounding up.
_STROKE_COUNT_SLACK = 1e-9


@njit(cache=True)
def _moving_average_residual(t: FloatArray, x: FloatArray, half: int) -> FloatArray:
    """y[j + half] minus the mean of y[j : j + 2 half + 1] for every complete window (running sum), where
    y = x minus its least-squares line in t. A moving average maps a line onto itself, so removing it first
    changes nothing but keeps the running sum small (less round-off, which would show as oscillation)."""
    tm = t.mean()
    xm = x.mean()
    num = 0.0
    den = 0.0
    for i in range(t.size):
        num += (t[i] - tm) * (x[i] - xm)
        den += (t[i] - tm) * (t[i] - tm)
    slope = num / den
    y = np.empty(x.size)
    for i in range(x.size):
        y[i] = (x[i] - xm) - slope * (t[i] - tm)
    width = 2 * half + 1
    out = np.empty(y.size - 2 * half)
    acc = 0.0
    for i in range(width):
        acc += y[i]
    for j in range(out.size):
        out[j] = y[j + half] - acc / width
        if j + width < y.size:
            acc += y[j + width] - y[j]
    return out


@njit(cache=True)
def _true_runs(mask: npt.NDArray[np.bool_]) -> tuple[IntArray, IntArray]:
    """First and last index of every maximal run of True."""
    first = np.empty(mask.size, dtype=np.int64)
    last = np.empty(mask.size, dtype=np.int64)
    k = 0
    i = 0
    while i < mask.size:
        if mask[i]:
            j = i
            while j + 1 < mask.size and mask[j + 1]:
                j += 1
            first[k] = i
            last[k] = j
            k += 1
            i = j + 1
        else:
            i += 1
    return first[:k], last[:k]


def _centered_residual(t_s: npt.ArrayLike, x: npt.ArrayLike, window_s: float) -> tuple[FloatArray, int]:
    """Interior residual x - (centered moving average over window_s) and the half-width in samples.

    Element j of the residual belongs to sample j + half; the half-window at each edge is dropped.
    """
    xs = _as_float_1d("trace", x)
    dt = _uniform_step_s(t_s, xs.size)
    half = round(0.5 * window_s / dt)
    if half < 1:
        raise ValueError(f"window_s={window_s} is shorter than two time steps ({dt} s)")
    width = 2 * half + 1
    if xs.size < width:
        raise ValueError(f"trace of {xs.size} samples is shorter than the {width}-sample window")
    return _moving_average_residual(np.asarray(t_s, dtype=np.float64), xs, half), half



def _reversal_allowance(n_strokes: float) -> int:
    if n_strokes < 0:
        raise ValueError(f"n_strokes must be >= 0, got {n_strokes}")
    return max(0, math.ceil(_RESTS_PER_STROKE * n_strokes - _STROKE_COUNT_SLACK))


def _run_bounds(mask: npt.NDArray[np.bool_]) -> tuple[IntArray, IntArray, IntArray]:
    """(column, first row, last row) of every maximal True run along axis 0 of a 2-D mask.

    Runs come out sorted by column, then by time, because np.nonzero scans the transposed edges row-major.
    """
    cols = mask.shape[1]
    pad = np.zeros((1, cols), dtype=np.int8)
    # Padding with False makes every run have both a rising and a falling edge, also at the trace ends.
    edges = np.diff(np.concatenate((pad, mask.astype(np.int8), pad)), axis=0).T
    col, first = np.nonzero(edges == 1)
    _, after_last = np.nonzero(edges == -1)
    return col.astype(np.int64), first.astype(np.int64), after_last.astype(np.int64) - 1


def _check_min_steps(min_steps: int) -> None:
    if min_steps < 1:
        raise ValueError(f"min_steps must be >= 1, got {min_steps}")


# ----------------------------------------------------------------------------------------------------
# stick-slip
# ----------------------------------------------------------------------------------------------------
def rest_episodes(v: npt.ArrayLike, min_steps: int = 2, tol: float = 1e-12) -> list[tuple[int, int]]:
    """Maximal runs of ``abs(v) <= tol`` at least ``min_steps`` samples long, as inclusive index pairs."""
    _check_min_steps(min_steps)
    vel = _as_float_1d("v", v)
    first, last = _true_runs(np.abs(vel) <= tol)
    keep = last - first + 1 >= min_steps
    return [(int(a), int(b)) for a, b in zip(first[keep], last[keep], strict=True)]


def count_stick_episodes_per_node(stuck: npt.ArrayLike, min_steps: int = 2) -> IntArray:
    """Stick episodes (True runs of >= ``min_steps`` samples) in each column of ``stuck[steps, nodes]``."""
    _check_min_steps(min_steps)
    mask = np.asarray(stuck, dtype=bool)
    if mask.ndim != 2:
        raise ValueError(f"stuck must be 2-D [steps, nodes], got shape {mask.shape}")
    col, first, last = _run_bounds(mask)
    keep = last - first + 1 >= min_steps
    return np.bincount(col[keep], minlength=mask.shape[1]).astype(np.int64)


def plunger_extra_stick_episodes(
    pump_velocity_m_s: npt.ArrayLike, n_strokes: float, min_steps: int = 2, tol_m_s: float = 1e-12
) -> int:
    """Plunger stick episodes beyond the ``ceil(2 * n_strokes)`` valve-reversal rests (module docstring)."""
    episodes = len(rest_episodes(pump_velocity_m_s, min_steps=min_steps, tol=tol_m_s))
    return max(0, episodes - _reversal_allowance(n_strokes))


def rod_extra_stick_episodes(rod_stick_episodes: npt.ArrayLike, n_strokes: float) -> int:
    """Sum over rod nodes of each node's stick episodes beyond its ``ceil(2 * n_strokes)`` reversal rests."""
    counts = np.asarray(rod_stick_episodes, dtype=np.int64)
    return int(np.maximum(counts - _reversal_allowance(n_strokes), 0).sum())


def slip_amplitude_m(t_s: npt.ArrayLike, du_m: npt.ArrayLike, window_s: float, tol_m: float = 1e-9) -> float:
    """Half peak-to-peak of Δu = u_B - u_A about its centered moving average (paper Fig. 7-9)."""
    residual, _ = _centered_residual(t_s, du_m, window_s)
    amplitude = 0.5 * float(residual.max() - residual.min())
    return amplitude if amplitude > tol_m else 0.0


def load_oscillation_pp_n(
    t_s: npt.ArrayLike, load_n: npt.ArrayLike, window_s: float, mask: npt.ArrayLike | None = None
) -> float:
    """Peak-to-peak of load minus its centered moving average, over the masked interior samples (Fig. 6)."""
    residual, half = _centered_residual(t_s, load_n, window_s)
    if mask is not None:
        selected = np.asarray(mask, dtype=bool)
        if selected.shape != (residual.size + 2 * half,):
            raise ValueError("mask must have the shape of load_n")
        residual = residual[selected[half : selected.size - half]]
        if residual.size == 0:
            raise ValueError("mask selects no sample outside the half-window edges")
    return float(residual.max() - residual.min())


def stick_slip_index(
    t_s: npt.ArrayLike,
    pump_velocity_m_s: npt.ArrayLike,
    du_m: npt.ArrayLike,
    rod_stick_episodes: npt.ArrayLike,
    n_strokes: float,
    window_s: float,
    slip_reference_m: float = 0.01,
    slip_floor_m: float = 0.0,
    min_steps: int = 2,
    tol_m_s: float = 1e-12,
) -> dict[str, float | int]:
    """Stick-slip components and their scalar combination (definition in the module docstring)."""
    if slip_reference_m <= 0:
        raise ValueError(f"slip_reference_m must be > 0, got {slip_reference_m}")
    episodes = len(rest_episodes(pump_velocity_m_s, min_steps=min_steps, tol=tol_m_s))
    plunger_extra = max(0, episodes - _reversal_allowance(n_strokes))
    counts = np.asarray(rod_stick_episodes, dtype=np.int64)
    rod_extra = rod_extra_stick_episodes(counts, n_strokes)
    amplitude_m = slip_amplitude_m(t_s, du_m, window_s)
    rod_term = rod_extra / counts.size if counts.size else 0.0
    index = plunger_extra + rod_term + max(0.0, amplitude_m - slip_floor_m) / slip_reference_m
    return {
        "plunger_stick_episodes": episodes,
        "plunger_extra_stick_episodes": plunger_extra,
        "rod_extra_stick_episodes": rod_extra,
        "slip_amplitude_m": amplitude_m,
        "stick_slip_index": float(index),
    }


# ----------------------------------------------------------------------------------------------------
# stresses
# ----------------------------------------------------------------------------------------------------
