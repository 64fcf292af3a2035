"""Predictive inputs of the pump (docs/realism.md, "Predictive inputs"): a pump set below the rod string's end
(``pump.depth_m``) and an annulus fluid level with its casing pressure (``pump.fluid_level_m``,
``pump.casing_pressure_pa``) instead of an intake pressure.

Both are turned into the one pump the simulator's laws know - at the rod end, with an intake pressure - by
:func:`pump_at_rod_end`:
- the fluid level gives the intake pressure at the pump (:func:`srenv.physics.inflow.level_intake_pressure_pa`,
  the annulus model's own formula);
- between the rod end and a deeper pump stands a liquid column of weight rho_f g dz per area. The discharge
  pressure at the plunger is the rod end's plus that weight, so the upstroke load (p_d - p_in) A_pl + P_f
  is the rod end's discharge pressure against an intake pressure lower by the column: the valve law takes
  p_in - rho_f g dz, and the rod end keeps its own pressure (its true load and p A). The free gas of an
  incomplete fill is compressed between these same two pressures. The intake so referred is held at one
  atmosphere at least (the gas law needs a positive pressure; below it the pump is pumped off).
"""

from __future__ import annotations

import dataclasses

from ..config import WellConfig
from .inflow import level_intake_pressure_pa
from .pump import STANDARD_PRESSURE_PA
from .rod import GRAVITY_M_S2


def pump_md_m(cfg: WellConfig) -> float:
    """Measured depth of the pump: ``pump.depth_m``, or the rod string's end."""
    return cfg.rod_length_m if cfg.pump.depth_m is None else float(cfg.pump.depth_m)


def column_below_rods_pa(cfg: WellConfig, survey) -> float:
    """rho_f g dz of the liquid between the rod string's end and the pump (0 at the rod end); dz along the
    survey, its last station's inclination held below it."""
    if cfg.pump.depth_m is None:
        return 0.0
    dz = survey.tvd_beyond(pump_md_m(cfg)) - survey.tvd_beyond(cfg.rod_length_m)
    return cfg.fluid.density_kg_m3 * GRAVITY_M_S2 * dz


def intake_at_pump_pa(cfg: WellConfig, survey) -> float:
    """The intake pressure at the pump: from the fluid level where one is given, else pump.intake_pressure_pa."""
    p = cfg.pump
    if p.fluid_level_m is None:
        return p.intake_pressure_pa
    return level_intake_pressure_pa(p.casing_pressure_pa, cfg.fluid.density_kg_m3, survey.tvd_beyond(pump_md_m(cfg)),
                                    survey.tvd_beyond(p.fluid_level_m))


def pump_at_rod_end(cfg: WellConfig, survey) -> WellConfig:
    """The config whose pump the laws see: at the rod end with the intake pressure referred to it (module doc).
    A config without predictive inputs is returned as it is (the previous numbers bit for bit)."""
    p = cfg.pump
    if p.depth_m is None and p.fluid_level_m is None:
        return cfg
    p_in = intake_at_pump_pa(cfg, survey)
    if p.depth_m is not None:
        p_in = max(p_in - column_below_rods_pa(cfg, survey), STANDARD_PRESSURE_PA)
    pump = dataclasses.replace(p, intake_pressure_pa=p_in, depth_m=None, fluid_level_m=None,
                               casing_pressure_pa=None)
    return dataclasses.replace(cfg, pump=pump)
