"""Domain randomisation of simulated cards, towards what a field dynamometer records (training only).

Each clean card (one stroke, equally spaced in time) is re-sampled as a field card would be: 150-300
points, starting anywhere in the stroke, with sampling jitter and a smooth warp of the time axis (other
surface-unit kinematics reach the same positions at other times); the load passes a first-order low-pass
(a load cell and its electronics, time constant up to 3 % of the stroke), gets white noise (up to 1.5 %
of the load range) and an offset of the zero (up to 3 % of the peak), the position white noise (up to
0.3 % of the stroke).

Opt-in instrument effects (``instrument=InstrumentAugment(...)``; run 5, docs/conditions.md): a position channel
synthesised by a load-only controller (a pure cosine of time at the card's stroke and period, phased on its
bottom, the loads kept by time) and a position transducer lagging the load cell. Without it every call draws
and returns exactly what it did for runs 1-4.

Opt-in spectral smoothing (``spectral=SpectralAugment(p)``; run 6): real strings and load cells smooth the card
(srenv's predicted cards carry 1.2-2.6x the measured share of harmonics 4-20 of the stroke and 25-100x above the
20th, docs/realism.md), so with probability p the recorded card, position and load alike, passes a zero-phase
periodic low-pass whose gain on harmonic k is exp(-(k/K)^2), K log-uniform in [6, 30]. Its draws come after every
draw of runs 1-5, so without it the arrays are runs 1-5's.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class InstrumentAugment:
    """Instrument effects on the position channel: probabilities per card and the lag's range (of the period)."""

    synth_position_p: float = 0.0
    position_lag_p: float = 0.0
    max_lag_of_period: float = 0.03

    def __post_init__(self):
        _in_unit_interval(self, ("synth_position_p", "position_lag_p", "max_lag_of_period"))


def _in_unit_interval(obj, names: tuple[str, ...]) -> None:
    for name in names:
        v = getattr(obj, name)
        if not 0.0 <= v <= 1.0:
            raise ValueError(f"{name}={v}: expected a number in [0, 1]")


@dataclass(frozen=True)
class SpectralAugment:
    """The card's spectrum: probability per card of the low-pass and the range of its corner harmonic K."""

    p: float = 0.0
    k_range: tuple[float, float] = (6.0, 30.0)  # K log-uniform in it (run 6: fixed a priori, not tuned)

    def __post_init__(self):
        _in_unit_interval(self, ("p",))
        if not 0.0 < self.k_range[0] <= self.k_range[1]:
            raise ValueError(f"k_range={self.k_range}: expected 0 < low <= high")


def spectral_lowpass(y: np.ndarray, k_corner: float) -> np.ndarray:
    """Zero-phase periodic low-pass of one stroke (n samples equally spaced in time): harmonic k of the stroke
    times exp(-(k / k_corner)^2) (the mean kept, no phase shift: corners smooth without moving in time)."""
    y = np.asarray(y, dtype=float)
    c = np.fft.rfft(y)
    k = np.arange(len(c))
    return np.fft.irfft(c * np.exp(-(k / k_corner) ** 2), n=len(y))


def synthesised_position(position: np.ndarray) -> np.ndarray:
    """The position a load-only controller writes for a card (one stroke, n samples equally spaced in time):
    x_min + (S/2)(1 - cos 2pi (k - k0)/n), S the card's stroke, k0 its bottom sample (docs/realism.md)."""
    x = np.asarray(position, dtype=float)
    n, k0 = len(x), int(np.argmin(x))
    stroke = float(x.max() - x.min())
    return float(x.min()) + 0.5 * stroke * (1.0 - np.cos(2.0 * np.pi * (np.arange(n) - k0) / n))


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


def augment(position: np.ndarray, load: np.ndarray, rng: np.random.Generator,
            instrument: InstrumentAugment | None = None,
            spectral: SpectralAugment | None = None) -> tuple[np.ndarray, np.ndarray]:
    """One field-like version of a clean card (``instrument``: the opt-in position-channel effects, drawn after
    every draw of runs 1-4; ``spectral``: the opt-in low-pass of the recorded card, drawn after those: without
    an option the draws and the arrays are unchanged)."""
    x, y = _field_like(position, load, rng, instrument)
    if spectral is not None:
        apply, k_corner = rng.uniform(), float(np.exp(rng.uniform(*np.log(spectral.k_range))))
        if apply < spectral.p:
            return spectral_lowpass(x, k_corner), spectral_lowpass(y, k_corner)
    return x, y


def _field_like(position: np.ndarray, load: np.ndarray, rng: np.random.Generator,
                instrument: InstrumentAugment | None) -> tuple[np.ndarray, np.ndarray]:
    """Runs 1-5's augmentation (the resampling, the load cell, noise and zero, the instrument effects)."""
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
    x_noise = rng.normal(0.0, rng.uniform(0.0, 0.003) * float(position.max() - position.min()), n)
    if instrument is not None:
        synth, lag, d = rng.uniform(), rng.uniform(), rng.uniform(0.0, instrument.max_lag_of_period)
        if synth < instrument.synth_position_p:
            return synthesised_position(x), y  # the controller writes it: no transducer noise
        if lag < instrument.position_lag_p:
            x = _periodic_interp((t - d) % 1.0, position)  # the transducer reads d of the period late
    return x + x_noise, y
