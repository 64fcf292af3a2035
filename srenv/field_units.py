"""Field (oilfield) units at the edges: the one place srenv converts in, ft, lbf, psi, lb/ft, bbl/d, API
gravity and water cut to SI and back. Everything inside srenv is SI.

A card or a well description in field units names its units in a ``units:`` block (YAML) or a unit row
(CSV, the row under the header): each quantity's unit from ``UNITS``. ``to_si(value, unit)`` and
``from_si(value, unit)`` are the only conversions; an unknown unit is a ConfigError naming the field.
"""

from __future__ import annotations

import numpy as np

from .errors import ConfigError

# factor to SI of each unit: value_si = value * factor (exact where the definition is exact)
UNITS: dict[str, tuple[str, float]] = {
    "m": ("m", 1.0), "mm": ("m", 1e-3), "in": ("m", 0.0254), "ft": ("m", 0.3048),
    "N": ("N", 1.0), "kN": ("N", 1e3), "lbf": ("N", 4.4482216152605),
    "Pa": ("Pa", 1.0), "kPa": ("Pa", 1e3), "MPa": ("Pa", 1e6), "psi": ("Pa", 6894.757293168361),
    "kg/m": ("kg/m", 1.0), "lb/ft": ("kg/m", 0.45359237 / 0.3048),
    "m^3/day": ("m^3/day", 1.0), "bbl/d": ("m^3/day", 0.158987294928),
    "s": ("s", 1.0), "min": ("s", 60.0),
    "kg/m^3": ("kg/m^3", 1.0), "g/cm^3": ("kg/m^3", 1000.0),
    "-": ("-", 1.0), "%": ("-", 0.01),
}
WATER_DENSITY_KG_M3 = 999.0  # fresh water at 15.6 C (60 F): the reference of specific gravities


def factor(unit: str, field: str = "units") -> float:
    if unit not in UNITS:
        raise ConfigError(field, unit, "a unit among " + ", ".join(UNITS))
    return UNITS[unit][1]


def to_si(value, unit: str, field: str = "units"):
    """Value(s) in `unit` -> SI (arrays stay arrays)."""
    f = factor(unit, field)
    return np.asarray(value, dtype=float) * f if isinstance(value, (list, tuple, np.ndarray)) else float(value) * f


def from_si(value, unit: str, field: str = "units"):
    f = factor(unit, field)
    return np.asarray(value, dtype=float) / f if isinstance(value, (list, tuple, np.ndarray)) else float(value) / f


def convert(value: float, unit: str, to: str, field: str = "units") -> float:
    """One number in `unit` -> `to` (a unit of the same quantity), rounded once from the decimal product of the
    value as written and the factors: 1.75 in is 44.45 mm to the last bit, as if 44.45 had been written."""
    from decimal import Decimal, localcontext

    with localcontext() as ctx:
        ctx.prec = 40
        exact = Decimal(repr(float(value))) * Decimal(repr(factor(unit, field))) / Decimal(repr(factor(to, field)))
    return float(exact)


def same_dimension(unit: str, si_unit: str, field: str) -> float:
    """Factor of `unit`, checked to measure the quantity whose SI unit is `si_unit`."""
    f = factor(unit, field)
    if UNITS[unit][0] != si_unit:
        same = [u for u, (s, _) in UNITS.items() if s == si_unit]
        raise ConfigError(field, unit, f"a unit of {si_unit}: one of {', '.join(same)}")
    return f


def oil_specific_gravity(api_deg: float) -> float:
    """API gravity -> specific gravity at 60 F (API definition)."""
    return 141.5 / (131.5 + api_deg)


def liquid_density_kg_m3(water_cut: float, water_sg: float, oil_api_deg: float) -> float:
    """Produced liquid density from the water cut (fraction), the water's specific gravity and the oil's API
    gravity: volume-weighted (no free gas, no slip)."""
    sg = water_cut * water_sg + (1.0 - water_cut) * oil_specific_gravity(oil_api_deg)
    return sg * WATER_DENSITY_KG_M3
