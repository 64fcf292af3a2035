"""The fillage a pump-off controller reads off one stroke's card (``task.fillage_estimator``)."""

from __future__ import annotations

from ..analysis import card_features as cf
from ..simulation.simulator import Simulator


def controller_fillage(sim: Simulator, summary: dict, tr: dict) -> float:
    """The fillage a pump-off controller reads (``task.fillage_estimator``): off the downhole card as modern
    controllers compute it, or off the surface card."""
    how = sim.cfg.task.fillage_estimator
    if how == "pump_card":
        return float(summary["card_fillage"])
    if how == "diagnose":
        from ..analysis.diagnose import diagnose_card
        from ..analysis.pump_card import analyse_pump_card

        pc = diagnose_card(sim.cfg, tr["t_s"], tr["polished_rod_position_m"], tr["polished_rod_load_n"],
                           period_s=float(tr["t_s"][-1] - tr["t_s"][0] + (tr["t_s"][1] - tr["t_s"][0])))
        return float(analyse_pump_card(pc.pump_position_m, pc.pump_load_n)["fillage"])
    return cf.fillage_estimate(tr["polished_rod_position_m"], tr["polished_rod_load_n"])
