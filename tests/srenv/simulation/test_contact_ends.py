"""Simulator.fix_contact_ends (srenv/SuckerRod-v3): a tagging contact's end, once placed, stays through a stop at
the bottom; by default (v2, the cards) the stop clears it and the next stroke places it again."""

from __future__ import annotations

from srenv.config import load_config
from srenv.simulation.simulator import Simulator


def _ends_after_a_stop(fixed: bool) -> tuple[dict, dict]:
    cfg = load_config("default", {"pump.tag_bottom_overtravel_m": 0.1})
    sim = Simulator(cfg)
    if fixed:
        sim.fix_contact_ends()
    spm, stroke = cfg.surface.spm, cfg.surface.stroke_length_m
    for _ in range(2):
        sim.run_stroke(spm, stroke)
    placed = sim.contact_ends()
    sim.stop_at_bottom()
    return placed, sim.contact_ends()


def test_a_stop_keeps_the_end_only_when_fixed() -> None:
    placed, after = _ends_after_a_stop(fixed=True)
    assert placed["tag_bottom_set"] == 1 and after == placed
    placed, after = _ends_after_a_stop(fixed=False)
    assert placed["tag_bottom_set"] == 1 and after["tag_bottom_set"] == 0
