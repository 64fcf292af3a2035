"""The plunger's valve law on the pump node (paper eqs. 1-2 and 32; srenv.pump builds it from the config).

Interval: lam_B in [-P-_eq, -P+_eq] (kernel sign: positive down), i.e. the plunger carries the fluid load
P- while it rises, P+ while it falls, anything between at rest. Two modifications:
  * fluid pound: above the liquid level in the barrel (u_B < void_until_m, positions positive down) the
    travelling valve cannot open, so the interval collapses to the point -P-_eq ("void");
  * velocity weakening (nonmonotone upstroke law P-(v) = P_inf + (P0 - P_inf) exp(-|v|/v0)): j = j1 - j2
    with j2'(v) = -(P0 - P_inf)(1 - exp(v/v0)) for v < 0 (rising), 0 otherwise; sup j2'' = (P0 - P_inf)/v0.
With enough free gas in the chamber (or unanchored tubing) the gas spring (``gas_spring``) carries the
load transfer and the interval shrinks to the plunger friction (shifted by tagging's contact force, which
does not depend on the chamber). Valve leaks, a tubing leak and tagging move
the interval with the plunger's position (``pump_conditions``).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ..pump import ValveLaw
from .gas_spring import GAS_FIELDS, gas_active
from .pump_conditions import COND_FIELDS, adjust, contact_force, drain_discharge

# void: 0 no fluid-pound plan, 1 planned (liquid level at void_until_m), 2 the plunger is in the void now
PARAMS = np.dtype([("lo_n", np.float64), ("hi_n", np.float64), ("drop_n", np.float64),
                   ("v0_m_s", np.float64), ("nonmonotone", np.int64), ("void", np.int64),
                   ("void_until_m", np.float64), *GAS_FIELDS,
                   # the liquid column that moves with the plunger while it rises (pump.fluid_column_mass_kg)
                   # and its term in K*_BB this step (c1 x the mass, 0 while the plunger does not rise)
                   ("fluid_kg", np.float64), ("fluid_dk", np.float64), *COND_FIELDS])


def make(law: ValveLaw, void: int = 0, void_until_m: float = 0.0) -> np.ndarray:
    """The parameter record from a valve law (equivalent forces, true tension positive)."""
    p = np.zeros(1, PARAMS)
    set_interval(p, law)
    p["drop_n"], p["v0_m_s"], p["nonmonotone"] = law.drop_n, law.v0_m_s, int(law.drop_n > 0)
    p["void"], p["void_until_m"] = void, void_until_m
    return p


def set_interval(params: np.ndarray, law: ValveLaw) -> None:
    """[-P-_eq, -P+_eq] in the kernel's sign (a new intake pressure between strokes changes P-)."""
    params["lo_n"], params["hi_n"] = -law.up_eq_n, -law.down_eq_n


def slope(law: ValveLaw) -> float:
    """sup j2'' of the pump node (N*s/m): (P0 - P_inf) / v0 for the nonmonotone law, else 0."""
    return law.drop_n / law.v0_m_s if law.drop_n > 0 else 0.0


@njit(cache=True, inline="always")
def bounds(params, ub, lo, hi, ns):
    """The pump node's interval at plunger position ub (the last of lo, hi, ns): the valve law, collapsed
    to -P-_eq in a fluid-pound void, or the plunger friction alone while the gas spring is on."""
    p = params[0]
    n = lo.shape[0]
    plo = p.lo_n
    phi = p.hi_n
    if p.drain > 0.0 and p.gas_mode != 0:  # a tubing leak drains the column the chamber's spring pushes on
        drain_discharge(params, ub)
    gas_on = gas_active(params)
    if p.void != 0:
        p.void = 2 if ub < p.void_until_m else 1
        if p.void == 2:
            phi = plo
            gas_on = False
    if gas_on:
        plo = -p.gas_friction_n if p.gas_mode == 1 else 0.0
        phi = -plo
        if p.cond_on != 0:  # tagging: the pump's end pushes on the plunger whatever the chamber holds
            force = contact_force(params, ub)
            plo -= force
            phi -= force
    elif p.cond_on != 0 and p.void != 2:  # leaks, tubing leak, tagging (laws.pump_conditions)
        plo, phi = adjust(params, ub, plo, phi)
    p.gas_on = 1 if gas_on else 0
    lo[n - 1] = plo
    hi[n - 1] = phi
    ns[n - 1] = phi > plo


@njit(cache=True, inline="always")
def concave_shift(params, v, shift):
    """j2'(v_B) of the velocity-weakening upstroke law (not in a void, where the plunger meets no liquid)."""
    p = params[0]
    if p.nonmonotone != 0 and p.void != 2:
        n = v.shape[0]
        vb = v[n - 1]
        if vb < 0:
            shift[n - 1] = -p.drop_n * (1.0 - np.exp(vb / p.v0_m_s))
