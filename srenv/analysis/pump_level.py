"""The pump card's load level against the described well's fluid load (run P2, docs/conditions.md).

On a pump card a full pump, a parted string (its free end's drag), a flowing well (part of the fluid load lifted by
the well) and heavy oil (plunger friction) share one normalised rectangle; their load *levels* differ. Given a well
config, ``level = (P90 - P10) / F_desc``: the spread between the card's two load plateaus (percentiles of the load
samples over the stroke, so impact spikes do not count) over the fluid load a full pump of the described well lifts,
``F_desc = P-_eq - P+_eq`` of the simulator's own valve law at the config's start state. A load difference is the
same in true and effective loads (they differ by a constant p A at the rod end), so the level is free of the load
convention; the card must be in newtons (diagnosed cards are).

Run P3 adds ``offset = (P10 - P+_desc) / F_desc``: the lower plateau against the described plunger's downstroke load
as a *true* load at the string's bottom (srenv.simulation.described; the card sets' pump cards and ``srenv diagnose``
give true loads). It is convention-bound on purpose: a string parted above the pump, diagnosed through the described
intact string, has its lower plateau about the missing rods' weight below P+ (docs/conditions.md, run P3).
"""

from __future__ import annotations

import math

import numpy as np

# a model file's features: P1's (no entry: shape), P2's with the level, P3's with the level and the offset
FEATURE_SETS = ("shape", "shape+level", "shape+level+offset")
LEVEL_QUANTILES = (0.10, 0.90)
LEVEL_MAX = 4.0  # clip: a level beyond 4 fluid loads is a wrong description, not a condition
DESCRIPTION_ERROR = 0.15  # training: F_desc times U[1 - e, 1 + e] per augmented copy (a config's own error)
OFFSET_MAX = 4.0  # clip to [-4, 4]: beyond four fluid loads from P+ is a wrong description, not a condition
OFFSET_ERROR = 0.15  # training (P3): P+_desc plus F_desc times U[-e, e] per augmented copy


class BadLevel(ValueError):
    """A description or a card whose level cannot be formed (fluid load not positive, level not finite)."""


def described_fluid_load_n(cfg) -> float:
    """F_desc (N) of a well config: P-_eq - P+_eq of the valve law the simulator starts with."""
    from ..simulation.described import described_pump

    return described_pump(cfg).fluid_load_n


def check_fluid_load(fluid_load_n: float, where: str) -> float:
    f = float(fluid_load_n)
    if not (math.isfinite(f) and f > 0.0):
        raise BadLevel(f"{where}: described fluid load {f!r} N, expected a finite load above 0 "
                       "(the pump's upstroke load must exceed its downstroke load)")
    return f


def level(load_n, fluid_load_n: float) -> float:
    """(P90 - P10) / F_desc of one pump card's loads (N), clipped to [0, LEVEL_MAX]; raises BadLevel."""
    y = np.asarray(load_n, dtype=np.float64)
    f = check_fluid_load(fluid_load_n, "the well")
    lo, hi = np.quantile(y, LEVEL_QUANTILES) if y.size else (math.nan, math.nan)
    with np.errstate(over="ignore", invalid="ignore"):  # judged below, in one line
        v = float((hi - lo) / f)
    if not math.isfinite(v):
        raise BadLevel(f"the card's load level {v!r} is not finite (expected finite loads in N)")
    return float(min(max(v, 0.0), LEVEL_MAX))


def with_level(shape_features: np.ndarray, load_n, fluid_load_n: float) -> np.ndarray:
    """The pump representation (card_shape.features(..., "pump")) with its 65th entry (0) set to the level."""
    out = np.array(shape_features, dtype=np.float64)
    out[-1] = level(load_n, fluid_load_n)
    return out



def offset(load_n, downstroke_load_n: float, fluid_load_n: float) -> float:
    """(P10 - P+_desc) / F_desc of one pump card's true loads (N), clipped to [-OFFSET_MAX, OFFSET_MAX]; raises
    BadLevel."""
    y = np.asarray(load_n, dtype=np.float64)
    f = check_fluid_load(fluid_load_n, "the well")
    p_plus = float(downstroke_load_n)
    lo = np.quantile(y, LEVEL_QUANTILES[0]) if y.size else math.nan
    with np.errstate(over="ignore", invalid="ignore"):
        v = float((lo - p_plus) / f)
    if not math.isfinite(v):
        raise BadLevel(f"the card's offset from the described P+ {v!r} is not finite (expected finite loads in N)")
    return float(min(max(v, -OFFSET_MAX), OFFSET_MAX))


def with_offset(level_features: np.ndarray, load_n, downstroke_load_n: float, fluid_load_n: float) -> np.ndarray:
    """Run P3's representation: P2's 65 entries (with_level) and the offset as a 66th."""
    return np.r_[np.asarray(level_features, dtype=np.float64), offset(load_n, downstroke_load_n, fluid_load_n)]
