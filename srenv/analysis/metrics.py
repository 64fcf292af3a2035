"""Per-stroke metrics computed from simulated traces (pure numpy, no dependency on the rest of srenv).

Conventions (shared with the simulator, see design.md §2)
---------------------------------------------------------
* Traces are 1-D arrays sampled at uniformly spaced times ``t_s`` (s). Functions that need a time
  step check the sampling is uniform and raise ``ValueError`` otherwise.
* SI units throughout; every argument and result key names its unit.
* Polished-rod position is measured UPWARD from the bottom of the stroke (m); loads are true axial
  tension, positive in tension (N).
* Displacements ``u_a_m`` (polished rod, point A) and ``u_b_m`` (pump plunger, point B) and the pump
  velocity are positive DOWNWARD.
* A stuck node/plunger has velocity exactly 0.0 (the step problem is solved exactly), so "at rest" means
  ``abs(v) <= tol`` with ``tol = 1e-12`` m/s by default.

Definitions (cite these)
------------------------
Rest (stick) episode
    A maximal run of consecutive samples with ``abs(v) <= tol`` that is at least ``min_steps`` samples
    long (default 2, so a single sample passing through zero velocity is a reversal, not a stick).
    Runs touching either end of the trace count like any other run.
Expected reversals, partial strokes
    A plunger (and every rod node) comes to rest at each of the two valve reversals of a stroke. For a
    trace holding ``n_strokes`` strokes (may be fractional) the allowance is
    ``ceil(2 * n_strokes - 1e-9)``: rounding UP is the largest number of reversals a half-open window of
    that length can contain, so a legitimate reversal in a partial stroke is never charged as extra
    stick; the 1e-9 absorbs round-off in ``n_strokes = duration * spm / 60``. Pass ``n_strokes = 0`` for
    a pull-out run (no reversals: every stick episode is extra). A rest cut in two by the window
    boundary counts in both pieces, so per-stroke windows should start at a stroke boundary of the
    harmonic drive (``t = k * 60 / spm``, where the plunger is still moving before its bottom rest).
Plunger extra stick episodes
    ``max(0, episodes(pump_velocity) - allowance)``.
Rod extra stick episodes
    ``sum_i max(0, episodes_i - allowance)`` over the rod's nonsmooth nodes ``i`` (per-node counts are
    supplied, e.g. counted on the fly by the simulator or by :func:`count_stick_episodes_per_node`).
Slip amplitude (paper Fig. 7-9)
    With ``Δu = u_B - u_A``: remove a least-squares line, subtract the centered moving average over
    ``window_s`` (an odd number of samples ``2*round(window_s / (2*dt)) + 1``), drop the half-window at
    each edge where the average is incomplete; the amplitude is half the peak-to-peak of that residual.
    A centered moving average reproduces a straight line exactly, so a linear (steady sliding) Δu gives
    0; amplitudes at or below ``tol_m = 1e-9`` m are round-off and are returned as exactly 0.0. Choose
    ``window_s`` = one natural period so one slip cycle is averaged out. Smooth, slow curvature leaks
    through: a stroke-frequency stretch of amplitude A leaves about ``A * (pi * f_stroke * window_s)**2
    / 6`` (``slip_floor_m`` in :func:`stick_slip_index` can discount that).
Stick-slip index
    ``plunger_extra + rod_extra / n_rod_nodes + max(0, slip_amplitude_m - slip_floor_m) /
    slip_reference_m`` (the rod term is 0 when no rod nodes are given). Each term is 0 in a smooth
    regime (two rests per stroke, no rod node sticking beyond its reversals, no Δu oscillation), so the
    index is exactly 0 there, and each grows with stick-slip. With the default ``slip_reference_m =
    0.01``, 1 cm of slip oscillation weighs as much as one extra plunger stick.
Load oscillation (paper Fig. 6)
    Peak-to-peak of ``load - centered moving average`` over ``window_s`` (one natural period), edges
    excluded as above, optionally restricted to samples where ``mask`` is True (e.g. the upstroke).
Card metrics
    PPRL / MPRL = max / min polished-rod load; stroke = max - min position; card area (polished-rod work
    per stroke, J) = closed-curve integral ``∮ load d(position)`` by the trapezoid rule over the samples
    in time order, closed by the segment from the last sample back to the first. A normal card is
    traversed clockwise (the upstroke carries more load), giving a positive area = work done on the rods.
Stresses and Goodman loading (API RP 11BR)
    Stresses are the loads at the top of each taper over that taper's rod area. Allowable stress
    ``S_A = (T/4 + 0.5625 * S_min) * SF``. RP 11BR loading is the range-of-stress form
    ``100 * (S_max - S_min) / (S_A - S_min)`` (actual over allowable stress range); the simpler
    ``100 * S_max / S_A`` is :func:`goodman_smax_ratio_pct`. Both reach 100 % together (at S_max = S_A).
    ``T`` is the minimum tensile strength of the API grade (API Spec 11B: C 90 ksi, K 85 ksi,
    D 115 ksi; converted with 1 ksi = 6.894757 MPa), tabulated in :data:`ROD_GRADE_TENSILE_PA`.
Production
    ``Q = 1440 * spm * plunger_area_m2 * net_stroke_m * fillage * volumetric_efficiency`` (m³/day):
    ``net_stroke_m`` is the plunger (pump) stroke, ``fillage`` the liquid fraction of the displaced
    barrel volume, ``volumetric_efficiency`` the remaining losses (slippage, shrinkage).
Dominant frequency
    Remove a least-squares line, apply a Hann window, zero-pad the FFT to at least 16x the trace length,
    take the largest magnitude at a positive frequency >= ``fmin_hz`` and refine it by a parabola through
    the log-magnitudes of the peak bin and its two neighbours (exact for a Gaussian peak, close to a
    Hann main lobe).
Card resampling
    Positions are normalised to [0, 1] over the card's range. Samples of segments with increasing
    (decreasing) position form the up (down) branch; each branch is sorted by position and linearly
    interpolated on ``linspace(0, 1, n_points)`` (constant beyond its ends). The result is
    ``[up loads, down loads]``. A degenerate card (position range <= 1e-9 m) or an empty branch gives the
    mean load instead, so the result is never NaN.
"""

from __future__ import annotations

import math
from functools import lru_cache

import numpy as np
import numpy.typing as npt
from numba import njit

from .stick_metrics import (  # noqa: F401  (re-exported: one module of metrics for every caller)
    count_stick_episodes_per_node,
    load_oscillation_pp_n,
    plunger_extra_stick_episodes,
    rest_episodes,
    rod_extra_stick_episodes,
    slip_amplitude_m,
    stick_slip_index,
)
from .trace_arrays import (
    FloatArray,
    _as_float_1d,
    _detrend_linear,
    _scalar_or_array,
    _uniform_step_s,
)

_PA_PER_KSI = 6.894757293168361e6
ROD_GRADE_TENSILE_PA: dict[str, float] = {
    # API Spec 11B minimum tensile strengths (the "T" of RP 11BR), not the maxima of the grade ranges.
    "C": 90.0 * _PA_PER_KSI,
    "K": 85.0 * _PA_PER_KSI,
    "D": 115.0 * _PA_PER_KSI,
}

# Below this a position range is numerically zero: a card cannot be normalised by it.
_DEGENERATE_SPAN_M = 1e-9
# Zero-padding factor of the FFT: makes the parabolic refinement's bias negligible.
_FFT_PAD_FACTOR = 16


def _card_arrays(position_m: npt.ArrayLike, load_n: npt.ArrayLike) -> tuple[FloatArray, FloatArray]:
    x = _as_float_1d("position_m", position_m)
    f = _as_float_1d("load_n", load_n)
    if x.size != f.size or x.size == 0:
        raise ValueError("position_m and load_n must be non-empty and of equal length")
    return x, f



def taper_stress_range(
    max_load_n: npt.ArrayLike, min_load_n: npt.ArrayLike, area_m2: npt.ArrayLike
) -> dict[str, FloatArray | float]:
    """Max / min stress and stress range per taper from the loads at the top of each taper."""
    area = np.asarray(area_m2, dtype=np.float64)
    max_stress = np.asarray(max_load_n, dtype=np.float64) / area
    min_stress = np.asarray(min_load_n, dtype=np.float64) / area
    return {
        "max_stress_pa": _scalar_or_array(max_stress),
        "min_stress_pa": _scalar_or_array(min_stress),
        "stress_range_pa": _scalar_or_array(max_stress - min_stress),
    }


def goodman_allowable_stress_pa(
    s_min_pa: npt.ArrayLike, tensile_strength_pa: npt.ArrayLike, service_factor: float = 1.0
) -> FloatArray | float:
    """API RP 11BR modified-Goodman allowable stress S_A = (T/4 + 0.5625 S_min) SF."""
    s_min = np.asarray(s_min_pa, dtype=np.float64)
    tensile = np.asarray(tensile_strength_pa, dtype=np.float64)
    return _scalar_or_array((tensile / 4 + 0.5625 * s_min) * service_factor)


def goodman_loading_pct(
    s_max_pa: npt.ArrayLike,
    s_min_pa: npt.ArrayLike,
    tensile_strength_pa: npt.ArrayLike,
    service_factor: float = 1.0,
) -> FloatArray | float:
    """RP 11BR range-of-stress loading 100 (S_max - S_min) / (S_A - S_min); inf when S_A <= S_min."""
    s_max = np.asarray(s_max_pa, dtype=np.float64)
    s_min = np.asarray(s_min_pa, dtype=np.float64)
    allowable = np.asarray(goodman_allowable_stress_pa(s_min, tensile_strength_pa, service_factor))
    allowable_range = allowable - s_min
    # No allowable range left means any stress range overloads the rod; report that as inf, not a sign flip.
    with np.errstate(divide="ignore", invalid="ignore"):
        pct = np.where(allowable_range > 0, 100.0 * (s_max - s_min) / allowable_range, np.inf)
    return _scalar_or_array(np.asarray(pct, dtype=np.float64))


def goodman_smax_ratio_pct(
    s_max_pa: npt.ArrayLike,
    s_min_pa: npt.ArrayLike,
    tensile_strength_pa: npt.ArrayLike,
    service_factor: float = 1.0,
) -> FloatArray | float:
    """Simpler Goodman ratio 100 S_max / S_A."""
    allowable = np.asarray(goodman_allowable_stress_pa(s_min_pa, tensile_strength_pa, service_factor))
    return _scalar_or_array(100.0 * np.asarray(s_max_pa, dtype=np.float64) / allowable)


# ----------------------------------------------------------------------------------------------------
# cards, production, frequency
# ----------------------------------------------------------------------------------------------------
def card_metrics(position_m: npt.ArrayLike, load_n: npt.ArrayLike) -> dict[str, float]:
    """PPRL, MPRL, stroke and card area (closed-loop trapezoid ∮ load d(position)) of one stroke's card."""
    x, f = _card_arrays(position_m, load_n)
    # Trapezoids along the trace plus the closing segment back to the first sample: the area does not
    # depend on where in the stroke the trace starts.
    area_j = 0.5 * float(np.dot(f[1:] + f[:-1], x[1:] - x[:-1]) + (f[0] + f[-1]) * (x[0] - x[-1]))
    return {
        "pprl_n": float(f.max()),
        "mprl_n": float(f.min()),
        "stroke_m": float(x.max() - x.min()),
        "card_area_j": area_j,
    }


def pump_stroke_m(u_b_m: npt.ArrayLike) -> float:
    """Plunger stroke over the trace: max - min of the pump displacement."""
    u = _as_float_1d("u_b_m", u_b_m)
    return float(u.max() - u.min())


def production_m3_day(
    net_stroke_m: float,
    plunger_area_m2: float,
    spm: float,
    fillage: float,
    volumetric_efficiency: float = 1.0,
) -> float:
    """Liquid rate 1440 * spm * area * net stroke * fillage * efficiency (m³/day; 1440 min per day)."""
    return 1440.0 * spm * plunger_area_m2 * net_stroke_m * fillage * volumetric_efficiency


def dominant_frequency_hz(t_s: npt.ArrayLike, signal: npt.ArrayLike, fmin_hz: float = 0.0) -> float:
    """Largest spectral peak at or above fmin_hz (detrend, Hann, padded FFT, log-parabola refinement)."""
    x = _as_float_1d("signal", signal)
    dt = _uniform_step_s(t_s, x.size)
    if x.size < 3:
        raise ValueError("need at least three samples")
    y = _detrend_linear(np.asarray(t_s, dtype=np.float64), x) * np.hanning(x.size)
    n_fft = 1 << math.ceil(math.log2(_FFT_PAD_FACTOR * x.size))
    magnitude = np.abs(np.fft.rfft(y, n_fft))
    df_hz = 1.0 / (n_fft * dt)
    # Bin 0 is excluded: after detrending it only holds leakage, and it has no left neighbour to refine with.
    first_bin = max(1, math.ceil(fmin_hz / df_hz))
    if first_bin >= magnitude.size:
        raise ValueError(f"fmin_hz={fmin_hz} is above the Nyquist frequency")
    k = first_bin + int(np.argmax(magnitude[first_bin:]))
    if k == first_bin or k == magnitude.size - 1:
        return k * df_hz
    # A Hann main lobe is close to Gaussian, whose log is exactly a parabola.
    left, centre, right = np.log(np.maximum(magnitude[k - 1 : k + 2], np.finfo(np.float64).tiny))
    curvature = left - 2.0 * centre + right
    offset = 0.5 * (left - right) / curvature if curvature < 0 else 0.0
    return (k + offset) * df_hz


def resample_card(position_m: npt.ArrayLike, load_n: npt.ArrayLike, n_points: int) -> FloatArray:
    """Up- and down-branch loads on ``linspace(0, 1, n_points)`` of normalised position, concatenated."""
    if n_points < 2:
        raise ValueError(f"n_points must be >= 2, got {n_points}")
    x, f = _card_arrays(position_m, load_n)
    mean_load = float(f.mean())
    span_m = float(x.max() - x.min())
    if span_m <= _DEGENERATE_SPAN_M:
        return np.full(2 * n_points, mean_load)
    p = (x - x.min()) / span_m
    grid = np.linspace(0.0, 1.0, n_points)
    dp = np.diff(p)

    def branch(segments: npt.NDArray[np.bool_]) -> FloatArray:
        if not segments.any():
            return np.full(n_points, mean_load)
        # Both end samples of every segment of this direction; stationary segments belong to no branch.
        starts = np.nonzero(segments)[0]
        idx = np.unique(np.concatenate((starts, starts + 1)))
        # Sorting tolerates back-and-forth wiggles inside a branch (np.interp needs ascending abscissae).
        order = np.argsort(p[idx], kind="stable")
        return np.interp(grid, p[idx][order], f[idx][order])

    return np.concatenate((branch(dp > 0), branch(dp < 0)))


@lru_cache(maxsize=8)
def _unit_grid(n_points: int) -> FloatArray:
    return np.linspace(0.0, 1.0, n_points)


def resample_prescribed_card(position_m: npt.ArrayLike, load_n: npt.ArrayLike, n_points: int) -> FloatArray:
    """:func:`resample_card` for one stroke of a *prescribed* surface motion starting at the bottom.

    The polished-rod position is then monotone on each branch (bottom -> top -> bottom), so each branch is
    one ``np.interp`` without sorting, compiled: ~20x faster, which matters in the env's step. Same output
    layout.
    """
    return _prescribed_card(np.asarray(position_m, dtype=np.float64), np.asarray(load_n, dtype=np.float64),
                            _unit_grid(n_points))


@njit(cache=True)
def _prescribed_card(x: FloatArray, f: FloatArray, grid: FloatArray) -> FloatArray:
    n = grid.size
    x_min = x.min()
    span_m = x.max() - x_min
    if span_m <= _DEGENERATE_SPAN_M:
        return np.full(2 * n, f.mean())
    p = (x - x_min) / span_m
    top = np.argmax(p)
    out = np.empty(2 * n)
    out[:n] = np.interp(grid, p[: top + 1], f[: top + 1])
    out[n:] = np.interp(grid, p[top:][::-1], f[top:][::-1])
    return out
