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
        # the inputs of the intake pressure and the IPR, read from cfg / fluid once (the env fast-forwards
        # ~60 strokes a step, each asking for them twice; the configs are frozen and never replaced here)
        self._casing_pa, self._rho_f = cfg.casing_pressure_pa, fluid.density_kg_m3
        self._p_r, self._linear = cfg.reservoir_pressure_pa, cfg.model == "linear"
        self._pi, self._q_max = cfg.productivity_index_m3_day_pa, cfg.max_rate_m3_day
        self.reset(cfg.initial_fluid_level_m)

    def reset(self, level_m: float) -> None:
        self.volume_m3 = self.area_m2 * min(level_m, self.pump_md_m)
        self.last_time_s = 0.0

    @property
    def level_m(self) -> float:
        """Liquid column above the pump, along measured depth."""
        return self.volume_m3 / self.area_m2

    def intake_pressure_pa(self, level_m: float | None = None) -> float:
        # min(level, pump depth) as a comparison (the same float; builtin min/max calls were a third of an
        # accumulation's time, so the hot path here and below spells them out: hence the noqa)
        h = self.volume_m3 / self.area_m2 if level_m is None else max(level_m, 0.0)  # level_m, without its call
        pump_md = self.pump_md_m
        if pump_md < h:  # noqa: PLR1730
            h = pump_md
        return level_intake_pressure_pa(self._casing_pa, self._rho_f, self._pump_tvd, self._tvd(pump_md - h))

    def _rate_m3_day(self, p_wf: float) -> float:
        """The IPR at the reservoir's nominal deliverability (multiplier 1)."""
        p_r = self._p_r
        if self._linear:
            drawdown = p_r - p_wf
            return self._pi * (0.0 if 0.0 > drawdown else drawdown)  # noqa: FURB136 (max(p_r - p_wf, 0.0))
        r = p_wf / p_r
        r = 0.0 if 0.0 > r else r  # noqa: FURB136 (min(max(r, 0), 1))
        r = 1.0 if 1.0 < r else r  # noqa: FURB136
        return self._q_max * (1 - 0.2 * r - 0.8 * r * r)

    def inflow_m3_s(self) -> float:
        return self.rate_multiplier * self._rate_m3_day(self.intake_pressure_pa()) / SECONDS_PER_DAY

    def nominal_inflow_m3_s(self, level_m: float) -> float:
        """The inflow at a given level and deliverability 1, the state untouched (a level observer's model)."""
        return self._rate_m3_day(self.intake_pressure_pa(level_m)) / SECONDS_PER_DAY

    def accumulate(self, time_s: float) -> None:
        dt = time_s - self.last_time_s
        volume = self.volume_m3 + self.inflow_m3_s() * (0.0 if 0.0 > dt else dt)  # noqa: FURB136 (max(dt, 0))
        full = self._full_m3
        self.volume_m3 = full if full < volume else volume  # noqa: FURB136 (min(volume, full))
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
        volume = self.volume_m3
        taken = volume if volume < displaced_m3 else displaced_m3  # noqa: FURB136 (min(displaced_m3, volume))
        self.volume_m3 = volume - taken
        return taken

    def give_back(self, volume_m3: float) -> None:
        """Liquid lifted but not produced falls back into the annulus (no cap: it came from there)."""
        self.volume_m3 += volume_m3
