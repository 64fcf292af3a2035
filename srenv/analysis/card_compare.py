"""Comparing two cards of one stroke: load levels, the card's RMS difference on position (upstroke and
downstroke apart) and the load spectrum's share of energy by harmonic band.

Resampling on position: each card is cut at its lowest and highest position into the upstroke and the
downstroke, each branch is interpolated onto the same positions (the overlap of the two cards' strokes,
trimmed by 1 % at each end where a branch turns), and the RMS of the load differences is taken over both
branches together. Positions are compared as given, or from each card's own bottom (``align_bottom``:
pump cards whose zero differs between the tools).
"""

from __future__ import annotations

import numpy as np

RESAMPLE_POINTS = 200
TRIM_FRACTION = 0.01


def stroke_branches(x: np.ndarray, f: np.ndarray) -> tuple[tuple[np.ndarray, np.ndarray], tuple[np.ndarray, np.ndarray]]:
    """(upstroke, downstroke) of a periodic one-stroke card, each as (position, load)."""
    i0 = int(np.argmin(x))
    x2, f2 = np.roll(x, -i0), np.roll(f, -i0)
    x2, f2 = np.r_[x2, x2[0]], np.r_[f2, f2[0]]
    i1 = int(np.argmax(x2))
    return (x2[:i1 + 1], f2[:i1 + 1]), (x2[i1:], f2[i1:])


def _on_grid(xb: np.ndarray, fb: np.ndarray, grid: np.ndarray) -> np.ndarray:
    o = np.argsort(xb, kind="stable")
    return np.interp(grid, xb[o], fb[o])


def card_difference(x_ref: np.ndarray, f_ref: np.ndarray, x: np.ndarray, f: np.ndarray,
                    align_bottom: bool = False) -> np.ndarray:
    """Load differences f - f_ref on common positions, upstroke then downstroke."""
    if align_bottom:
        x_ref, x = x_ref - x_ref.min(), x - x.min()
    lo, hi = max(x_ref.min(), x.min()), min(x_ref.max(), x.max())
    span = hi - lo
    grid = np.linspace(lo + TRIM_FRACTION * span, hi - TRIM_FRACTION * span, RESAMPLE_POINTS)
    (ru, rd), (su, sd) = stroke_branches(x_ref, f_ref), stroke_branches(x, f)
    return np.r_[_on_grid(*su, grid) - _on_grid(*ru, grid), _on_grid(*sd, grid) - _on_grid(*rd, grid)]


def card_rms(x_ref: np.ndarray, f_ref: np.ndarray, x: np.ndarray, f: np.ndarray, align_bottom: bool = False) -> float:
    d = card_difference(x_ref, f_ref, x, f, align_bottom)
    return float(np.sqrt(np.mean(d * d)))


def harmonic_shares(load: np.ndarray, bands: tuple[tuple[int, int], ...] = ((4, 20), (21, 10**9))) -> list[float]:
    """Share of the load's fluctuation energy (harmonics >= 1 of the stroke) in each band of harmonics
    [lo, hi], for one stroke sampled at equal times."""
    c = np.abs(np.fft.rfft(np.asarray(load, dtype=float))) ** 2
    total = float(c[1:].sum())
    if not total > 0:
        return [0.0 for _ in bands]
    return [float(c[lo:min(hi, len(c) - 1) + 1].sum()) / total for lo, hi in bands]


def resample_stroke(t: np.ndarray, y: np.ndarray, period_s: float, m: int) -> np.ndarray:
    """One periodic stroke resampled at m equal times from t[0]."""
    tt = t[0] + np.arange(m) * (period_s / m)
    return np.interp(tt, np.r_[t, t[0] + period_s], np.r_[y, y[0]])
