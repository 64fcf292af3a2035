"""Pump (plunger) valve law, paper eqs. 1-2 and 32, in equivalent-force form.

Sign convention: loads are true axial tension at the rod end, positive in tension. P- acts while the
plunger moves up (travelling valve closed, fluid load on the plunger), P+ while it moves down; at rest the
load is anywhere in [P+, P-]. In equivalent force (N_eq = N + p A, p = tubing pressure at the pump):
P-_eq = (p_out - p_in) A_pl + P_f and P+_eq = -dp_out A_pl - P_f.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from ..config import PumpConfig


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
    """Valve law from the two loads or from pressures and diameters (p_out = tubing pressure at the pump).
    A well flowing through the pump (``flow_through_fraction`` f) lifts that share of the fluid load itself:
    P- - P+ shrinks by the factor 1 - f."""
    law = _valve_law(pump, p_out_pa, rod_area_m2, intake_pressure_pa)
    f = pump.flow_through_fraction
    if f <= 0:
        return law
    return ValveLaw(law.down_eq_n + (1.0 - f) * (law.up_eq_n - law.down_eq_n), law.down_eq_n,
                    (1.0 - f) * law.drop_n, law.v0_m_s)


def _valve_law(pump: PumpConfig, p_out_pa: float, rod_area_m2: float, intake_pressure_pa: float | None
               ) -> ValveLaw:
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


STANDARD_PRESSURE_PA = 101325.0


def liquid_stiffness_n_m(pump: PumpConfig, nominal_stroke_m: float) -> float:
    """The liquid-full chamber at the top of the stroke (clearance + swept volume V) as a spring on the
    plunger: A_pl^2 / (c V); the downstroke's load transfer (p_in -> p_d) takes the travel (fluid load) / k.
    inf when incompressible."""
    c = pump.liquid_compressibility_per_pa
    a = plunger_area_m2(pump)
    if not c > 0:
        return math.inf
    return a / (c * (1.0 + pump.clearance_volume_fraction) * nominal_stroke_m)


def liquid_bottom_stiffness_n_m(pump: PumpConfig, nominal_stroke_m: float) -> float:
    """The liquid-full chamber at the bottom of the stroke, the clearance V_d alone, as a spring on the
    plunger: A_pl^2 / (c V_d); the upstroke's transfer (p_d -> p_in) takes (fluid load) / k, a clearance
    fraction's share of the downstroke's. ``liquid_chamber_volume: top_of_stroke`` keeps the earlier law
    (the top's chamber for both transfers, ~20x too long a travel here; the classifier's card sets)."""
    if pump.liquid_chamber_volume == "top_of_stroke":
        return liquid_stiffness_n_m(pump, nominal_stroke_m)
    c = pump.liquid_compressibility_per_pa
    if not c > 0:
        return math.inf
    return plunger_area_m2(pump) / (c * pump.clearance_volume_fraction * nominal_stroke_m)


def chamber_spring_n_m(pump: PumpConfig, nominal_stroke_m: float, tubing_n_m: float, gas: bool
                       ) -> tuple[float, float]:
    """The spring on the plunger without free gas (the valve law's mode 2, laws/gas_spring.tubing_spring):
    (stiffness of the upstroke's transfer at the bottom, of the downstroke's at the top; 0 = the first for
    both). Unanchored tubing's stretch (``tubing_n_m``, 0 anchored) in series with the chamber's liquid,
    whose volume differs between the two: the clearance at the bottom, clearance + swept at the top. With free
    gas the chamber law (mode 1) keeps its own volumes and only the tubing is returned."""
    if gas or not pump.liquid_compressibility_per_pa > 0:
        return tubing_n_m, 0.0
    bottom = series_stiffness_n_m(tubing_n_m, liquid_bottom_stiffness_n_m(pump, nominal_stroke_m))
    top = series_stiffness_n_m(tubing_n_m, liquid_stiffness_n_m(pump, nominal_stroke_m))
    return bottom, (0.0 if top == bottom else top)


def series_stiffness_n_m(k1: float, k2: float) -> float:
    """Two springs in series (0 or inf: absent); 0 = no spring at all (rigid valve law)."""
    ks = [k for k in (k1, k2) if 0 < k < math.inf]
    return 1.0 / sum(1.0 / k for k in ks) if ks else 0.0


def fluid_column_mass_kg(density_kg_m3: float, length_m: float, plunger_area_m2: float, tubing_area_m2: float,
                         rod_area_m2: float) -> float:
    """The liquid column above a rising plunger as a mass at the plunger: the column in the tubing-rod
    annulus moves at v A_pl / (A_t - A_r), so its kinetic energy is (1/2) rho L A_pl^2 / (A_t - A_r) v^2."""
    return density_kg_m3 * length_m * plunger_area_m2 ** 2 / max(tubing_area_m2 - rod_area_m2, 1e-9)


MAX_FILLAGE_GAS_FRACTION = 0.95


def gas_fraction_for_fillage(fillage: float, p_in_pa: float, p_d_pa: float, k: float = 1.0,
                             clearance_fraction: float = 0.05) -> float:
    """Free-gas fraction of the intake mixture whose compression from p_in to p_d takes (1 - fillage) of the
    plunger's stroke (GasChamber.compression_travel_m over a full upstroke):
    phi = (1 - f) / ((1 + clearance) (1 - (p_in / p_d)^(1/k))), at most MAX_FILLAGE_GAS_FRACTION."""
    if not fillage < 1.0:
        return 0.0
    p_in = max(p_in_pa, STANDARD_PRESSURE_PA)
    squeeze = 1.0 - (p_in / max(p_d_pa, p_in * (1.0 + 1e-9))) ** (1.0 / k)
    phi = (1.0 - fillage) / ((1.0 + clearance_fraction) * max(squeeze, 1e-12))
    return float(min(max(phi, 0.0), MAX_FILLAGE_GAS_FRACTION))


def gas_fraction_keeping(fillage: float, p_in_pa: float, p_d_pa: float, k: float, clearance_fraction: float,
                         kept_fraction: float) -> float:
    """``gas_fraction_for_fillage`` when the clearance keeps the share ``kept_fraction`` of its volume as gas at
    p_d (``pump.clearance_gas_fraction``): the top of the stroke holds that gas re-expanded to p_in, psi c
    (p_d / p_in)^(1/k) of the swept volume, and intake mixture in the rest of the chamber, so that the gas the
    downstroke compresses, (1 - f) / squeeze, stays the fillage's:
    phi = ((1 - f) / squeeze - psi c (p_d/p_in)^(1/k)) / (1 + c - psi c (p_d/p_in)^(1/k)), within [0, max]."""
    p_in = max(p_in_pa, STANDARD_PRESSURE_PA)
    ratio = max(p_d_pa, p_in * (1.0 + 1e-9)) / p_in
    top_gas = (1.0 - fillage) / max(1.0 - ratio ** (-1.0 / k), 1e-12)
    kept = kept_fraction * clearance_fraction * ratio ** (1.0 / k)
    phi = (top_gas - kept) / max(1.0 + clearance_fraction - kept, 1e-12)
    return float(min(max(phi, 0.0), MAX_FILLAGE_GAS_FRACTION))


@dataclass(frozen=True)
class GasChamber:
    """Free gas in the pump chamber (ideal gas, polytropic p V^k = const, liquid incompressible).

    The upstroke fills the chamber (clearance V_d + swept A_pl L) with intake mixture of free-gas volume
    fraction phi at p_in. On the downstroke both valves stay closed until the plunger has compressed the gas
    to the discharge pressure p_d = p_out + dp_out: over the travel
        s_open = phi V_c (1 - (p_in / p_d)^(1/k)) / A_pl,
    the load falls along the compression curve (p_out - p_c) A_pl instead of at once (gas interference).
    The clearance keeps the compressed mixture (gas fraction phi_d); on the upstroke it re-expands to p_in
    before the standing valve opens, over s_up = V_gd ((p_d / p_in)^(1/k) - 1) / A_pl.
    ``intake_glr_m3_m3`` gives phi from the free gas-liquid ratio at standard conditions (isothermal,
    z = 1): G = GLR p_std / p_in, phi = G / (1 + G).
    """

    area_m2: float
    clearance_m3: float
    exponent: float
    gas_fraction: float = 0.0
    glr_m3_m3: float = 0.0
    kept_m3: float = 0.0  # gas at p_d the clearance keeps (pump.clearance_gas_fraction x its volume)

    @classmethod
    def from_config(cls, pump: PumpConfig, nominal_stroke_m: float, p_d_pa: float | None = None
                    ) -> GasChamber | None:
        """The chamber of the config's free gas: its fraction or GLR, or the fraction that gives
        ``pump.fillage`` at the config's intake pressure and the discharge pressure p_d."""
        phi = pump.intake_gas_fraction
        psi = pump.clearance_gas_fraction
        if pump.fillage < 1 and p_d_pa is not None:
            state = (pump.fillage, pump.intake_pressure_pa, p_d_pa, pump.gas_polytropic_exponent,
                     pump.clearance_volume_fraction)
            # two formulas, not one with psi = 0: the keeping one's arithmetic order differs by round-off
            phi = gas_fraction_keeping(*state, psi) if psi > 0 else gas_fraction_for_fillage(*state)
        if phi <= 0 and pump.intake_glr_m3_m3 <= 0 and psi == 0:
            return None
        a = plunger_area_m2(pump)
        clearance = pump.clearance_volume_fraction * a * nominal_stroke_m
        return cls(a, clearance, pump.gas_polytropic_exponent, phi, pump.intake_glr_m3_m3, psi * clearance)

    def fraction(self, p_in_pa: float) -> float:
        """Free-gas volume fraction of the intake mixture at p_in."""
        if self.glr_m3_m3 > 0:
            g = self.glr_m3_m3 * STANDARD_PRESSURE_PA / max(p_in_pa, STANDARD_PRESSURE_PA)
            return g / (1.0 + g)
        return self.gas_fraction

    def top_gas_m3(self, p_in_pa: float, upstroke_m: float) -> float:
        """Gas volume at p_in in the chamber at the top of the stroke."""
        return self.fraction(p_in_pa) * (self.clearance_m3 + self.area_m2 * max(upstroke_m, 0.0))

    def clearance_gas_m3(self, p_in_pa: float, p_d_pa: float) -> float:
        """Gas volume at p_d left in the clearance at the bottom of the stroke."""
        phi = self.fraction(p_in_pa)
        vg = phi * (p_in_pa / p_d_pa) ** (1.0 / self.exponent)
        if self.kept_m3 > 0:  # the kept gas, and intake mixture compressed to p_d in the rest
            return self.kept_m3 + (self.clearance_m3 - self.kept_m3) * vg / (vg + 1.0 - phi)
        return self.clearance_m3 * vg / (vg + 1.0 - phi)

    def compression_travel_m(self, p_in_pa: float, p_d_pa: float, upstroke_m: float,
                             p_to_pa: float | None = None) -> float:
        """Plunger travel from the top until the chamber reaches p_to (default p_d: the valve opens)."""
        p_to = p_d_pa if p_to_pa is None else p_to_pa
        v0 = self.top_gas_m3(p_in_pa, upstroke_m)
        return v0 * (1.0 - (p_in_pa / p_to) ** (1.0 / self.exponent)) / self.area_m2

    def liquid_fraction(self, p_in_pa: float, p_d_pa: float, upstroke_m: float) -> float:
        """Liquid delivered per stroke / swept volume (what the gas leaves of the pump's displacement)."""
        swept = self.area_m2 * max(upstroke_m, 1e-12)
        phi = self.fraction(p_in_pa)
        vg_d = self.clearance_gas_m3(p_in_pa, p_d_pa)
        # the kept gas re-expanded to p_in fills its share of the top's chamber; intake mixture the rest
        kept_in = self.kept_m3 * (p_d_pa / p_in_pa) ** (1.0 / self.exponent) if self.kept_m3 > 0 else 0.0
        liquid_in = (1.0 - phi) * (self.clearance_m3 + swept - kept_in)
        return float(min(max((liquid_in - (self.clearance_m3 - vg_d)) / swept, 0.0), 1.0))
