"""Pump (plunger) valve law, paper eqs. 1-2 and 32, in equivalent-force form.

Sign convention: loads are true axial tension at the rod end, positive in tension. P- acts while the
plunger moves up (travelling valve closed, fluid load on the plunger), P+ while it moves down; at rest the
load is anywhere in [P+, P-]. In equivalent force (N_eq = N + p A, p = tubing pressure at the pump):
P-_eq = (p_out - p_in) A_pl + P_f and P+_eq = -dp_out A_pl - P_f.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from .config import PumpConfig


@dataclass(frozen=True)
class ValveLaw:
    """The plunger's admissible loads in equivalent force (N)."""

    up_eq_n: float          # P-_eq (static value P0 for the nonmonotone law)
    down_eq_n: float        # P+_eq
    drop_n: float = 0.0     # P0 - P_inf of the nonmonotone upstroke law
    v0_m_s: float = 1.0

    def up_eq_at(self, speed_m_s: float) -> float:
        """P-_eq(v) = P_inf + (P0 - P_inf) exp(-|v|/v0)."""
        return self.up_eq_n - self.drop_n * (1.0 - math.exp(-abs(speed_m_s) / self.v0_m_s))


def plunger_area_m2(pump: PumpConfig) -> float:
    return math.pi / 4 * (pump.plunger_diameter_mm * 1e-3) ** 2


def valve_law(pump: PumpConfig, p_out_pa: float, rod_area_m2: float, intake_pressure_pa: float | None = None
              ) -> ValveLaw:
    """Valve law from the two loads or from pressures and diameters (p_out = tubing pressure at the pump)."""
    if pump.load_source == "loads":
        shift = p_out_pa * rod_area_m2  # true -> equivalent force at the rod end
        drop = pump.upstroke_load_n - pump.dynamic_load_n if pump.law == "nonmonotone" else 0.0
        return ValveLaw(pump.upstroke_load_n + shift, pump.downstroke_load_n + shift, drop,
                        pump.reference_velocity_m_s)
    p_in = pump.intake_pressure_pa if intake_pressure_pa is None else intake_pressure_pa
    a_pl = plunger_area_m2(pump)
    up = (p_out_pa - p_in) * a_pl + pump.plunger_friction_n
    down = -pump.discharge_overpressure_pa * a_pl - pump.plunger_friction_n
    return ValveLaw(up, down)


def true_loads_n(law: ValveLaw, p_out_pa: float, rod_area_m2: float) -> tuple[float, float]:
    """(P-, P+) as true loads, for reporting."""
    shift = p_out_pa * rod_area_m2
    return law.up_eq_n - shift, law.down_eq_n - shift
