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


class Annulus:
    def __init__(self, cfg: InflowConfig, fluid: FluidConfig, pump_md_m: float, tvd) -> None:
        self.cfg = cfg
        self.fluid = fluid
        self.pump_md_m = pump_md_m
        self._tvd = tvd
        self._pump_tvd = tvd(pump_md_m)  # asked for at every stroke the env fast-forwards: computed once
        d_c, d_t = cfg.casing_inner_diameter_mm * 1e-3, cfg.tubing_outer_diameter_mm * 1e-3
        self.area_m2 = math.pi / 4 * (d_c * d_c - d_t * d_t)
        self.rate_multiplier = 1.0  # the reservoir's deliverability over time (v1's inflow schedule)
        self.reset(cfg.initial_fluid_level_m)

    def reset(self, level_m: float) -> None:
        self.volume_m3 = self.area_m2 * min(level_m, self.pump_md_m)
        self.last_time_s = 0.0

    @property
    def level_m(self) -> float:
        """Liquid column above the pump, along measured depth."""
        return self.volume_m3 / self.area_m2

    def intake_pressure_pa(self) -> float:
        h = min(self.level_m, self.pump_md_m)
        column_tvd = float(self._pump_tvd - self._tvd(self.pump_md_m - h))
        return self.cfg.casing_pressure_pa + self.fluid.density_kg_m3 * GRAVITY_M_S2 * column_tvd

    def inflow_m3_s(self) -> float:
        p_wf = self.intake_pressure_pa()
        p_r = self.cfg.reservoir_pressure_pa
        if self.cfg.model == "linear":
            q_day = self.cfg.productivity_index_m3_day_pa * max(p_r - p_wf, 0.0)
        else:
            r = min(max(p_wf / p_r, 0.0), 1.0)
            q_day = self.cfg.max_rate_m3_day * (1 - 0.2 * r - 0.8 * r * r)
        return self.rate_multiplier * q_day / SECONDS_PER_DAY

    def accumulate(self, time_s: float) -> None:
        dt = max(time_s - self.last_time_s, 0.0)
        self.volume_m3 = min(self.volume_m3 + self.inflow_m3_s() * dt, self.area_m2 * self.pump_md_m)
        self.last_time_s = time_s

    def take(self, displaced_m3: float, time_s: float) -> float:
        """End of an upstroke: the pump draws up to `displaced_m3`; returns the fillage."""
        self.accumulate(time_s)
        if displaced_m3 <= 0:
            return 1.0
        taken = min(displaced_m3, self.volume_m3)
        self.volume_m3 -= taken
        return taken / displaced_m3
