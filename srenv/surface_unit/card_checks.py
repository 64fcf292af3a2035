"""The checks every measured card passes before any work (``srenv diagnose``, ``srenv fit``, measured motion,
``srenv validate``): enough samples, finite and physically sized values, a stroke > 0, a closed single
stroke, and time running forward (the upstroke's load above the downstroke's). Each failure is one
ConfigError naming the file, the defect and what is expected.

Time direction: a dynamometer card is traversed clockwise in (position, load): the rod string takes work
from the unit over a stroke, so the loop integral W = closed-integral of F dx is positive. A record stored in
reverse time has W < 0 (three of five public vendor exports do); it is refused unless the caller says
``reverse`` (then the samples are reversed in time, keeping the time stamps).
"""

from __future__ import annotations

import numpy as np

from ..errors import ConfigError

MIN_SAMPLES = 16
MAX_STROKE_M = 20.0           # the config's bound on a stroke (surface.stroke_length_m)
MAX_ABS_LOAD_N = 1e7          # the config's bound on pump loads
# A stroke's period: 0.1 to 60 strokes/min covers every beam, long-stroke and hydraulic unit (1-20 SPM in
# practice); outside it a card's time column is in the wrong unit or broken (1e5 s a stroke, 1e298 s a sample)
MIN_PERIOD_S, MAX_PERIOD_S = 1.0, 600.0
MAX_CARD_BYTES = 64 * 1024 * 1024  # a card file read whole (CSV rows in memory): far above any measured card
MAX_ABS_CARD_VALUE = 1e12     # any cell of a card, in any unit: beyond it arithmetic on the card overflows
CLOSURE_FRACTION = 0.05       # a one-stroke card ends within 5 % of its stroke from where it began


def _upward_crossings(x: np.ndarray) -> int:
    c = x - 0.5 * (x.max() + x.min())
    return int(np.count_nonzero((c[:-1] < 0) & (c[1:] >= 0)))


def loop_work(x: np.ndarray, f: np.ndarray) -> float:
    """Closed-loop integral of F dx over the samples in order (trapezoids, closed back to the first)."""
    xc, fc = np.r_[x, x[0]], np.r_[f, f[0]]
    return float(np.sum(0.5 * (fc[1:] + fc[:-1]) * np.diff(xc)))


def check_magnitude(values: np.ndarray, field: str, source: str, what: str, row: str = "sample",
                    bound: float = MAX_ABS_CARD_VALUE) -> None:
    """Every value finite and of magnitude at most `bound`, checked as read (before any unit conversion or
    arithmetic, which would overflow): one ConfigError naming the first bad `row`. (A time column is checked
    finite only, ``bound=inf``: its size is judged as the stroke period it gives, ``check_period``.)"""
    bad = ~(np.isfinite(values) & (np.abs(values) <= bound))
    if bad.any():
        i = int(np.argmax(bad))
        size = f" of magnitude at most {bound:g}" if np.isfinite(bound) else ""
        raise ConfigError(field, source, f"finite {what}{size} ({row} {i + 1} is {values[i]})")


def check_card(position_m: np.ndarray, load_n: np.ndarray | None, field: str, source: str,
               reverse: bool = False) -> tuple[np.ndarray, np.ndarray | None]:
    """Checked (position, load), reversed in time when `reverse`; load may be None (position-only card)."""
    x = np.asarray(position_m, dtype=float)
    f = None if load_n is None else np.asarray(load_n, dtype=float)
    if len(x) < MIN_SAMPLES:
        raise ConfigError(field, source, f"a card of at least {MIN_SAMPLES} samples (found {len(x)})")
    for name, col in (("position", x), ("load", f)):
        if col is not None and not np.all(np.isfinite(col)):
            i = int(np.argmax(~np.isfinite(col)))
            raise ConfigError(field, source, f"finite {name} values (sample {i + 1} is {col[i]})")
    stroke = float(np.ptp(x))
    if not stroke > 0:
        raise ConfigError(field, source, "a card whose polished-rod position moves (the card has zero stroke)")
    if stroke > MAX_STROKE_M:
        raise ConfigError(field, source, f"a stroke of at most {MAX_STROKE_M:g} m (found {stroke:.4g} m; "
                          "positions in inches need a unit row or units: block)")
    if f is not None and float(np.max(np.abs(f))) > MAX_ABS_LOAD_N:
        raise ConfigError(field, source, f"loads within +-{MAX_ABS_LOAD_N:g} N (found {np.max(np.abs(f)):.4g} N; "
                          "loads in lbf need a unit row or units: block)")
    if _upward_crossings(x) < 2 and abs(x[-1] - x[0]) > CLOSURE_FRACTION * stroke:
        raise ConfigError(field, source, f"a closed stroke (the card ends {abs(x[-1] - x[0]):.4g} m from where it "
                          f"began, more than {CLOSURE_FRACTION:.0%} of its {stroke:.4g} m stroke)")
    if f is None:
        return x[::-1].copy() if reverse else x, None
    work = loop_work(x, f)
    if reverse:
        if work > 0:
            raise ConfigError("--reverse", source, "a card stored in reverse time (this one already runs "
                              "forward: its upstroke load is above its downstroke load); drop --reverse")
        return x[::-1].copy(), f[::-1].copy()
    if work < 0:
        raise ConfigError(field, source, "a card in forward time (upstroke load above downstroke load); this one "
                          "runs in reverse time (the loop is anticlockwise): pass --reverse or reverse its rows")
    return x, f


def check_period(period_s: float, field: str, source: str) -> float:
    """A card's own stroke period (s), within [MIN_PERIOD_S, MAX_PERIOD_S]."""
    if not MIN_PERIOD_S <= period_s <= MAX_PERIOD_S:
        raise ConfigError(field, source, f"a stroke period of {MIN_PERIOD_S:g} to {MAX_PERIOD_S:g} s (0.1 to 60 "
                          f"strokes/min; this card's t_s gives {period_s:.4g} s: check the time column's unit)")
    return period_s
