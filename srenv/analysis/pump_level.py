"""The pump card's load level against the described well's fluid load (run P2, docs/conditions.md).

On a pump card a full pump, a parted string (its free end's drag), a flowing well (part of the fluid load lifted by
the well) and heavy oil (plunger friction) share one normalised rectangle; their load *levels* differ. Given a well
config, ``level = (P90 - P10) / F_desc``: the spread between the card's two load plateaus (percentiles of the load
samples over the stroke, so impact spikes do not count) over the fluid load a full pump of the described well lifts,
``F_desc = P-_eq - P+_eq`` of the simulator's own valve law at the config's start state. A load difference is the
same in true and effective loads (they differ by a constant p A at the rod end), so the level is free of the load
convention; the card must be in newtons (diagnosed cards are).
"""

from __future__ import annotations

import math

import numpy as np

FEATURE_SETS = ("shape", "shape+level")  # a model file's features: P1's (no entry: shape) or with the level
LEVEL_QUANTILES = (0.10, 0.90)
LEVEL_MAX = 4.0  # clip: a level beyond 4 fluid loads is a wrong description, not a condition
DESCRIPTION_ERROR = 0.15  # training: F_desc times U[1 - e, 1 + e] per augmented copy (a config's own error)


class BadLevel(ValueError):
    """A description or a card whose level cannot be formed (fluid load not positive, level not finite)."""


def described_fluid_load_n(cfg) -> float:
    """F_desc (N) of a well config: P-_eq - P+_eq of the valve law the simulator starts with."""
    from ..simulation.simulator import Simulator

    law = Simulator(cfg)._valve()
    return float(law.up_eq_n - law.down_eq_n)


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

