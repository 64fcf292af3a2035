"""One labelled card: a well put into a pump condition, run to its periodic stroke, the last stroke's cards.

Used by ``srenv cards`` (srenv.tools.cards), the mechanism tests and the gallery (docs/conditions.md).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..config import WellConfig, apply_overrides, config_from_dict, to_dict
from ..physics.conditions import condition_overrides

STROKES = 4  # start-up, two to settle (a pounding pump takes a few), the recorded one


@dataclass(frozen=True)
class Card:
    """The last stroke: surface and pump positions (m, up from the bottom) and loads (N, tension positive)."""

    t_s: np.ndarray
    polished_rod_position_m: np.ndarray
    polished_rod_load_n: np.ndarray
    pump_position_m: np.ndarray
    pump_load_n: np.ndarray
    fillage: float


def condition_config(well: WellConfig, label: str, severity: float, extra: dict | None = None) -> WellConfig:
    """``well`` in condition ``label`` at ``severity`` (plus ``extra`` overrides)."""
    over = condition_overrides(label, severity, well)
    over.update(extra or {})
    return config_from_dict(apply_overrides(to_dict(well), over))


def simulate_card(cfg: WellConfig, strokes: int = STROKES) -> Card:
    """Run ``strokes`` strokes from rest and return the last one's cards."""
    from ..simulation.simulator import Simulator

    sim = Simulator(cfg)
    sim.reset()
    res = sim.run_strokes(strokes)
    tr = res[-1].trace
    return Card(tr["t_s"] - tr["t_s"][0], tr["polished_rod_position_m"], tr["polished_rod_load_n"],
                tr["pump_position_m"], tr["pump_load_n"], float(res[-1].fillage))
