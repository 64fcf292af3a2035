"""The annulus's hot path (srenv/physics/inflow.py, docs/speed.md §2j): the intake pressure, the IPR and the
accumulation with the configs' inputs read once and min/max written as comparisons give the same floats, to the
bit, as the form they replaced (copied below verbatim), on many states of linear and Vogel wells: levels below
0, beyond the pump, NaN; clocks that run backwards; drawdowns of either sign."""

from __future__ import annotations

import copy
import math

import numpy as np
import pytest

from srenv.physics.inflow import SECONDS_PER_DAY, Annulus, level_intake_pressure_pa
from srenv.simulation.simulator import Simulator
from srenv.task import well_family as wf


# ---- the form before docs/speed.md §2j, verbatim (methods of Annulus then) ----
def old_intake_pressure_pa(self, level_m=None):
    h = min(self.level_m if level_m is None else max(level_m, 0.0), self.pump_md_m)
    return level_intake_pressure_pa(self.cfg.casing_pressure_pa, self.fluid.density_kg_m3, self._pump_tvd,
                                    self._tvd(self.pump_md_m - h))


def old_rate_m3_day(self, p_wf):
    p_r = self.cfg.reservoir_pressure_pa
    if self.cfg.model == "linear":
        return self.cfg.productivity_index_m3_day_pa * max(p_r - p_wf, 0.0)
    r = min(max(p_wf / p_r, 0.0), 1.0)
    return self.cfg.max_rate_m3_day * (1 - 0.2 * r - 0.8 * r * r)


def old_inflow_m3_s(self):
    return self.rate_multiplier * old_rate_m3_day(self, old_intake_pressure_pa(self)) / SECONDS_PER_DAY


def old_accumulate(self, time_s):
    dt = max(time_s - self.last_time_s, 0.0)
    self.volume_m3 = min(self.volume_m3 + old_inflow_m3_s(self) * dt, self._full_m3)
    self.last_time_s = time_s


def old_draw(self, displaced_m3, time_s):
    old_accumulate(self, time_s)
    if displaced_m3 <= 0:
        return 0.0
    taken = min(displaced_m3, self.volume_m3)
    self.volume_m3 -= taken
    return taken


def _same(a: float, b: float) -> bool:
    return (math.isnan(a) and math.isnan(b)) or (a == b and math.copysign(1.0, a) == math.copysign(1.0, b))


@pytest.fixture(scope="module")
def annuli() -> list[Annulus]:
    """Annuli of family wells of both inflow models (deviated and vertical), and one of each model forced."""
    out = []
    for index in (0, 1, 2, 3, 5, 8):
        sim = Simulator(wf.build_spec("train", index).cfg)
        out.append(sim.annulus)
    models = {a.cfg.model for a in out}
    assert models == {"linear", "vogel"}, models
    return out


def test_the_annulus_gives_the_old_forms_floats(annuli: list[Annulus]) -> None:
    rng = np.random.default_rng(0)
    checked = 0
    for ann in annuli:
        full = ann._full_m3
        levels = [None, -5.0, 0.0, -0.0, ann.pump_md_m, ann.pump_md_m + 1.0, float("nan"), 1e9]
        levels += list(rng.uniform(-0.1, 1.1, 40) * ann.pump_md_m)
        volumes = [0.0, full, 1.5 * full, 1e-12] + list(rng.uniform(0.0, 1.05, 30) * full)
        for volume in volumes:
            for mult in (1.0, 0.0, 0.37, 1.3):
                ann.volume_m3, ann.rate_multiplier = volume, mult
                for level in levels:
                    assert _same(ann.intake_pressure_pa(level), old_intake_pressure_pa(ann, level))
                    checked += 1
                assert _same(ann.inflow_m3_s(), old_inflow_m3_s(ann))
                for p_wf in (-1e5, 0.0, 0.5 * ann.cfg.reservoir_pressure_pa, ann.cfg.reservoir_pressure_pa,
                             2.0 * ann.cfg.reservoir_pressure_pa, float("nan")):
                    assert _same(ann._rate_m3_day(p_wf), old_rate_m3_day(ann, p_wf))
                # a run of accumulations (clock forward, backward, repeated) on two copies, volume by volume
                new, old = copy.copy(ann), copy.copy(ann)
                new.last_time_s = old.last_time_s = 100.0
                for t in (105.0, 105.0, 90.0, 400.0, 400.5, 1e4, 3e5, 2e5, 3e6):
                    new.accumulate(t)
                    old_accumulate(old, t)
                    assert _same(new.volume_m3, old.volume_m3) and new.last_time_s == old.last_time_s
                    checked += 1
                # draws of the pump (more than the annulus holds, none, a little) after each accumulation
                for t, want in ((4e6, 0.5 * full), (4e6 + 5.0, 2.0 * full), (4e6 + 9.0, 0.0), (4e6 + 12.0, 1e-6),
                                (4e6 + 12.0, -1.0), (4e6 + 30.0, 0.01 * full)):
                    assert _same(new.draw(want, t), old_draw(old, want, t))
                    assert _same(new.volume_m3, old.volume_m3)
                    checked += 1
    assert checked > 20_000
