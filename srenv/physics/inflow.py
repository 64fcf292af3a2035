"""Reservoir inflow, annulus fluid level and pump fillage.

Liquid flows from the reservoir into the casing-tubing annulus at q(p_wf) (linear PI or Vogel IPR, with
the pump set at the perforations so p_wf = p_intake). The pump takes liquid from the annulus on each
upstroke: fillage = min(1, available / displaced). The annulus level sets the intake pressure
p_in = p_casing + rho_f g (TVD of the liquid column), which sets the upstroke load P- of the next stroke.
Bookkeeping happens at the plunger's reversals (events from the kernel), a few times per stroke.
"""

from __future__ import annotations

import math

from ..config import FluidConfig, InflowConfig
from .rod import GRAVITY_M_S2

SECONDS_PER_DAY = 86400.0


def level_intake_pressure_pa(casing_pressure_pa: float, density_kg_m3: float, pump_tvd_m: float,
                             level_tvd_m: float) -> float:
    """The pump's intake pressure under an annulus fluid level: casing pressure + rho_f g (TVD of the pump -
    TVD of the level). The gas column above the level is taken as weightless: its weight adds
    p_c M g h / (R T) - for methane at 300 K 0.6 % of the casing pressure per 100 m (12 kPa over 1000 m at
    200 kPa, the weight of 1.3 m of water), within an acoustic shot's resolution of the level."""
    return casing_pressure_pa + density_kg_m3 * GRAVITY_M_S2 * float(pump_tvd_m - level_tvd_m)


class Annulus:
    def __init__(self, cfg: InflowConfig, fluid: FluidConfig, pump_md_m: float, tvd) -> None:
        self.cfg = cfg
        self.fluid = fluid
        self.pump_md_m = pump_md_m
        self._tvd = tvd
        self._pump_tvd = tvd(pump_md_m)  # asked for at every stroke the env fast-forwards: computed once
        d_c, d_t = cfg.casing_inner_diameter_mm * 1e-3, cfg.tubing_outer_diameter_mm * 1e-3
        self.area_m2 = math.pi / 4 * (d_c * d_c - d_t * d_t)
        self._full_m3 = self.area_m2 * pump_md_m  # the annulus filled to the pump
        self.rate_multiplier = 1.0  # the reservoir's deliverability over time (v1's inflow schedule)
        self.reset(cfg.initial_fluid_level_m)

    def reset(self, level_m: float) -> None:
        self.volume_m3 = self.area_m2 * min(level_m, self.pump_md_m)
        self.last_time_s = 0.0

    @property
    def level_m(self) -> float:
        """Liquid column above the pump, along measured depth."""
        return self.volume_m3 / self.area_m2

    def intake_pressure_pa(self, level_m: float | None = None) -> float:
        h = min(self.level_m if level_m is None else max(level_m, 0.0), self.pump_md_m)
        return level_intake_pressure_pa(self.cfg.casing_pressure_pa, self.fluid.density_kg_m3, self._pump_tvd,
                                        self._tvd(self.pump_md_m - h))

    def _rate_m3_day(self, p_wf: float) -> float:
        """The IPR at the reservoir's nominal deliverability (multiplier 1)."""
        p_r = self.cfg.reservoir_pressure_pa
        if self.cfg.model == "linear":
            return self.cfg.productivity_index_m3_day_pa * max(p_r - p_wf, 0.0)
        r = min(max(p_wf / p_r, 0.0), 1.0)
        return self.cfg.max_rate_m3_day * (1 - 0.2 * r - 0.8 * r * r)

    def inflow_m3_s(self) -> float:
        return self.rate_multiplier * self._rate_m3_day(self.intake_pressure_pa()) / SECONDS_PER_DAY

    def nominal_inflow_m3_s(self, level_m: float) -> float:
        """The inflow at a given level and deliverability 1, the state untouched (a level observer's model)."""
        return self._rate_m3_day(self.intake_pressure_pa(level_m)) / SECONDS_PER_DAY

    def accumulate(self, time_s: float) -> None:
        dt = max(time_s - self.last_time_s, 0.0)
        self.volume_m3 = min(self.volume_m3 + self.inflow_m3_s() * dt, self._full_m3)
        self.last_time_s = time_s

    def take(self, displaced_m3: float, time_s: float) -> float:
        """End of an upstroke: the pump draws up to `displaced_m3`; returns the fillage."""
        taken = self.draw(displaced_m3, time_s)
        return taken / displaced_m3 if displaced_m3 > 0 else 1.0

    def draw(self, displaced_m3: float, time_s: float) -> float:
        """The annulus filled to `time_s`, then the pump draws up to `displaced_m3`; returns the volume drawn."""
        self.accumulate(time_s)
        if displaced_m3 <= 0:
            return 0.0
        taken = min(displaced_m3, self.volume_m3)
        self.volume_m3 -= taken
        return taken

    def give_back(self, volume_m3: float) -> None:
        """Liquid lifted but not produced falls back into the annulus (no cap: it came from there)."""
        self.volume_m3 += volume_m3
