"""The surface card's load midline against the described well (issue 23, run 9; docs/conditions.md).

A flowing well's surface card is a full pump's card with a smaller fluid load (physics/pump.py: valve_law keeps P+
and shrinks P- - P+), so the card alone cannot tell the two apart; a well config can. Given one,

    midline = ((P10 + P90) / 2 - D_desc) / F_desc,

where P10 and P90 are percentiles of the card's polished-rod loads (N; samples equally spaced in time, so the
plateaus count, not the impact spikes), F_desc the described well's fluid load (P- - P+ of the valve law at the
simulator's start state) and D_desc its static polished-rod load on the downstroke without rod-tubing friction: the
string's buoyed weight along the survey, less the wellhead pressure on the top area, plus the pump's downstroke
load (analysis/load_budget.py's effective bookkeeping). A full pump sits near 1/2, a flowing well near (1 - f) / 2.
Why the midline and not the spread P90 - P10 (the pump card's level, run P2): loads that act alike on both strokes
with opposite signs - heavy oil's plunger friction and viscous drag, the string's inertia - move the spread but not
the midline, so a condition read by its shape (heavy oil) cannot be read off the spread instead; run 9's validation
study measured it (docs/conditions.md). The midline needs loads in newtons and the description's convention (the
polished-rod load, true = effective at the surface).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .pump_level import LEVEL_QUANTILES, BadLevel, check_fluid_load

FEATURE_SET = "shape+midline"  # a surface model file's entry: the 66th feature is the midline
MIDLINE_MAX = 4.0  # clip to [-4, 4]: beyond four fluid loads from the description is a wrong description


@dataclass(frozen=True)
class DescribedSurface:
    fluid_load_n: float  # F_desc: P- - P+ of the described pump
    downstroke_n: float  # D_desc: static polished-rod load on the downstroke, rod-tubing friction left out


def described_surface(cfg) -> DescribedSurface:
    """F_desc and D_desc (N) of a well config (raises ConfigError as the simulator does)."""
    from ..simulation.simulator import Simulator
    from .load_budget import static_budget

    b = static_budget(Simulator(cfg))
    down = b["buoyed_weight_n"] + b["wellhead_pressure_force_n"] + b["pump"]["downstroke_effective_n"]
    return DescribedSurface(float(b["pump"]["fluid_load_n"]), float(down))


def midline(load_n, downstroke_n: float, fluid_load_n: float) -> float:
    """((P10 + P90) / 2 - D_desc) / F_desc of one surface card's loads (N), clipped; raises BadLevel."""
    y = np.asarray(load_n, dtype=np.float64)
    f = check_fluid_load(fluid_load_n, "the well")
    lo, hi = np.quantile(y, LEVEL_QUANTILES) if y.size else (math.nan, math.nan)
    with np.errstate(over="ignore", invalid="ignore"):  # judged below, in one line
        v = float((0.5 * (lo + hi) - float(downstroke_n)) / f)
    if not math.isfinite(v):
        raise BadLevel(f"the card's load midline {v!r} is not finite (expected finite loads in N)")
    return float(min(max(v, -MIDLINE_MAX), MIDLINE_MAX))


def with_midline(shape_features: np.ndarray, load_n, downstroke_n: float, fluid_load_n: float) -> np.ndarray:
    """Run 9's representation: the surface card's 65 entries (card_shape.features) and the midline as a 66th."""
    return np.r_[np.asarray(shape_features, dtype=np.float64), midline(load_n, downstroke_n, fluid_load_n)]
