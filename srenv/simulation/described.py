"""What a well config says its pump lifts: the valve law's loads at the simulator's start state.

The classifier's level and offset features (srenv.analysis.pump_level, runs P2 and P3) compare a pump card with the
*described* well: the fluid load a full pump of that well lifts and the plunger's downstroke load P+. They come from
the simulator's own valve law (srenv.physics.pump.valve_law; the intake pressure from the config's inflow model or
pump block) at the start state, the same numbers every simulation of the config starts from. The valve law holds
*equivalent* rod-end loads (true + p_pump A_rod_bottom); pump cards of the card sets and of ``srenv diagnose`` are
*true* loads, so the true loads are given too (a load difference is the same in both).
"""

from __future__ import annotations

from dataclasses import dataclass

from ..physics.pump import true_loads_n


@dataclass(frozen=True)
class DescribedPump:
    fluid_load_n: float  # P- - P+ (the same in true and equivalent loads)
    upstroke_true_n: float  # P- as a true load at the rod string's bottom
    downstroke_true_n: float  # P+ as a true load at the rod string's bottom


def described_pump(cfg) -> DescribedPump:
    """The described pump of a well config (raises ConfigError as the simulator does for a pump lifting nothing)."""
    from .simulator import Simulator

    sim = Simulator(cfg)
    law = sim.valve_law_now()
    up, down = true_loads_n(law, sim.p_pump_pa, sim.area_bottom_m2)
    return DescribedPump(float(law.up_eq_n - law.down_eq_n), float(up), float(down))
