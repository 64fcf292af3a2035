"""Domain randomisation of simulated cards, towards what a field dynamometer records (training only).

Each clean card (one stroke, equally spaced in time) is re-sampled as a field card would be: 150-300
points, starting anywhere in the stroke, with sampling jitter and a smooth warp of the time axis (other
surface-unit kinematics reach the same positions at other times); the load passes a first-order low-pass
(a load cell and its electronics, time constant up to 3 % of the stroke), gets white noise (up to 1.5 %
of the load range) and an offset of the zero (up to 3 % of the peak), the position white noise (up to
0.3 % of the stroke).
"""

from __future__ import annotations

import numpy as np


def _periodic_interp(t: np.ndarray, y: np.ndarray) -> np.ndarray:
    """y sampled at k / n (one period, k = 0..n-1) read at times t in [0, 1)."""
    n = len(y)
    tt = np.r_[np.arange(n) / n, 1.0]
    return np.interp(t, tt, np.r_[y, y[0]])


def _lowpass(y: np.ndarray, alpha: float) -> np.ndarray:
    """First-order low-pass s += alpha (y - s), run twice around the periodic signal so the start has settled."""
    if alpha >= 1.0:
        return y
    from scipy.signal import lfilter

    out = lfilter([alpha], [1.0, alpha - 1.0], np.r_[y, y], zi=[(1.0 - alpha) * y[0]])[0]
    return out[len(y):]


def augment(position: np.ndarray, load: np.ndarray, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """One field-like version of a clean card."""
    n = int(rng.integers(150, 301))
    t = (rng.uniform() + np.arange(n) / n + rng.normal(0.0, 0.15 / n, n)) % 1.0
    a, phi = rng.uniform(0.0, 0.12), rng.uniform(0.0, 2 * np.pi)
    t = np.sort((t + a * np.sin(2 * np.pi * t + phi) / (2 * np.pi)) % 1.0)
    t = np.roll(t, -int(rng.integers(n)))
    x = _periodic_interp(t, position)
    y = _periodic_interp(t, load)
    tau = rng.uniform(0.0, 0.03) * n  # samples
    y = _lowpass(y, 1.0 / (1.0 + tau))
    y_range = float(load.max() - load.min())
    y = y + rng.normal(0.0, rng.uniform(0.0, 0.015) * y_range, n)
    y = y + rng.uniform(-0.03, 0.03) * float(np.abs(load).max())
    x = x + rng.normal(0.0, rng.uniform(0.0, 0.003) * float(position.max() - position.min()), n)
    return x, y
