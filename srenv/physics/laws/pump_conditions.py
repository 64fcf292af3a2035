"""Pump conditions as changes of the valve law's interval on the pump node (docs/conditions.md).

Every condition enters the step problem through the plunger's interval [lo, hi] (kernel sign, positive
down: lo = -P-_eq, hi = -P+_eq), so each step stays the same convex box QP:

* **valve leaks**. A closed valve passes q = C dp. While the plunger rises the travelling valve is closed
  and the chamber below it stays at the intake pressure only as long as the plunger's displacement rate
  A_pl v outruns the leak; slower, the leak fills the chamber, the standing valve closes and the chamber
  pressure settles where the two balance, p_c = p_out - A_pl v / C: the plunger carries
  A_pl (p_out - p_c) = dP min(1, v / v_leak) of the fluid load dP = P- - P+, v_leak = C dp / A_pl. The
  standing valve's leak does the same on the downstroke: the chamber drains to the intake while the plunger
  moves slowly and the fluid load comes back on the plunger, P+_eff = P- - dP min(1, v / v_leak). The
  plunger speed in these caps is the stroke's nominal speed at the plunger's position,
  v = v_peak sqrt(4 xi (1 - xi)) (xi the position in the last measured plunger travel, 0 at the bottom),
  which keeps the interval a function of the position (explicit, like the fluid-pound void) rather than of
  the unknown velocity; the config gives v_leak / v_peak (``*_valve_leak_fraction``). With one valve
  leaking the other bound is the tight valve's, so the interval needs no direction; with both the chamber
  pressure balances the two leaks and the plunger's displacement, a single load
  P+ + dP clip((s_sv + v) / (s_tv + s_sv), 0, 1) at signed speed v (up positive, fractions of v_peak): the
  stroke's direction switches near its ends after the plunger has moved back 2 % of its travel.
* **tubing leak**: the column above the pump drains through the hole: the discharge pressure, and with it
  the fluid load, falls over the upstroke, P-_eff = P+ + dP (1 - f (1 + xi) / 2). With a chamber spring
  the same share drains the column the spring pushes on (``drain_discharge``).
* **tagging**: the plunger meets the pump's top (bottom) end: a one-sided contact spring
  f = k max(0, overlap) on the plunger, taken at the step's start position (explicit; k dt^2 well below the
  plunger node's mass), shifts both ends of the interval. The ends are placed ``tag_*_overtravel_m`` inside
  the plunger's free travel of the first stroke (set by the pump cycle at the first top and bottom).

Flow through the pump (a flowing well) lowers the fluid load itself (srenv.physics.pump.valve_law).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

# the conditions' part of the valve law's record (srenv.laws.valve.PARAMS): on (any condition), the two leak
# speed fractions, the tubing-leak share, the last measured plunger travel (top and bottom, positive down),
# the plunger's last position and direction (1 rising, 0 falling), the contact ends (set flags) and stiffness
COND_FIELDS = [("cond_on", "i8"), ("leak_tv", "f8"), ("leak_sv", "f8"), ("drain", "f8"), ("ref_top_m", "f8"),
               ("ref_bottom_m", "f8"), ("last_ub_m", "f8"), ("rising", "i8"), ("tag_top_m", "f8"),
               ("tag_bottom_m", "f8"), ("tag_top_set", "i8"), ("tag_bottom_set", "i8"), ("tag_k", "f8"),
               ("tag_top_over_m", "f8"), ("tag_bottom_over_m", "f8"),
               # a tubing leak with a chamber spring (drain_discharge): the share of the fluid load lost now,
               # and the gas chamber's discharge and above-plunger pressures of the full column
               ("drain_share", "f8"), ("p_d_full_pa", "f8"), ("p_out_full_pa", "f8")]
HYSTERESIS = 0.02  # share of the plunger travel it must move back before the stroke's direction switches
# the fields a run hands to the next (the plunger's travel, direction and the contact ends)
STATE_FIELDS = ("ref_top_m", "ref_bottom_m", "last_ub_m", "rising", "tag_top_m", "tag_bottom_m",
                "tag_top_set", "tag_bottom_set")
CONTACT_FIELDS = ("tag_top_m", "tag_bottom_m", "tag_top_set", "tag_bottom_set")  # the tagging contact's ends


def configure(rec: np.ndarray, pump) -> None:
    """Fill the record's parameters from the pump config (the state comes from the simulator)."""
    on = (pump.travelling_valve_leak_fraction > 0 or pump.standing_valve_leak_fraction > 0
          or pump.tubing_leak_fraction > 0 or pump.tag_top_overtravel_m > 0 or pump.tag_bottom_overtravel_m > 0)
    rec["cond_on"] = int(on)
    rec["leak_tv"], rec["leak_sv"] = pump.travelling_valve_leak_fraction, pump.standing_valve_leak_fraction
    rec["drain"], rec["tag_k"] = pump.tubing_leak_fraction, pump.tag_stiffness_n_m
    rec["tag_top_over_m"], rec["tag_bottom_over_m"] = pump.tag_top_overtravel_m, pump.tag_bottom_overtravel_m


def initial_state(ub_m: float, stroke_m: float) -> dict:
    """The state fields before the first run: the plunger at the bottom, its travel that of the surface."""
    return {"ref_top_m": ub_m - stroke_m, "ref_bottom_m": ub_m, "last_ub_m": ub_m, "rising": 1,
            "tag_top_m": 0.0, "tag_bottom_m": 0.0, "tag_top_set": 0, "tag_bottom_set": 0}


def on_reversal(rec: np.ndarray, top: bool, ub_extreme_m: float) -> None:
    """A valve cycle's reversal: the plunger's measured travel, and the contact end placed the first time."""
    if top:
        rec["ref_top_m"] = ub_extreme_m
        if rec["tag_top_over_m"][0] > 0 and rec["tag_top_set"][0] == 0:
            rec["tag_top_m"], rec["tag_top_set"] = ub_extreme_m + rec["tag_top_over_m"][0], 1
    else:
        rec["ref_bottom_m"] = ub_extreme_m
        if rec["tag_bottom_over_m"][0] > 0 and rec["tag_bottom_set"][0] == 0:
            rec["tag_bottom_m"], rec["tag_bottom_set"] = ub_extreme_m - rec["tag_bottom_over_m"][0], 1


def leak_share(speed_fraction: float, leak_fraction: float) -> float:
    """Share of the fluid load a leaking valve lets the plunger carry at a speed (fraction of its peak)."""
    if leak_fraction <= 0.0:
        return 1.0
    return min(1.0, speed_fraction / leak_fraction)


@njit(cache=True, inline="always")
def track(params, ub):
    """The plunger's position xi in its last measured travel (0 at the bottom) and the stroke's direction,
    switched only near its ends after a small travel back (ringing inside the stroke does not flip it); the
    last position kept is the extreme since the switch. The same ub twice changes nothing."""
    p = params[0]
    travel = p.ref_bottom_m - p.ref_top_m
    xi = 0.0
    if travel > 1e-9:
        xi = min(max((p.ref_bottom_m - ub) / travel, 0.0), 1.0)
    if p.rising != 0:
        if ub < p.last_ub_m:
            p.last_ub_m = ub
        elif xi > 0.5 and ub - p.last_ub_m > HYSTERESIS * travel:
            p.rising, p.last_ub_m = 0, ub
    else:
        if ub > p.last_ub_m:
            p.last_ub_m = ub
        elif xi < 0.5 and p.last_ub_m - ub > HYSTERESIS * travel:
            p.rising, p.last_ub_m = 1, ub
    return xi


@njit(cache=True, inline="always")
def drain_discharge(params, ub):
    """A tubing leak with a chamber spring: the share of the fluid load the drained column has lost, f (1 + xi)
    / 2 over the upstroke (the interval's formula) and f, the top's, while the plunger falls (the column
    lifts nothing then; the rigid law need not say, its downstroke bound is P+). The gas chamber (mode 1)
    meets it as the pressure above the plunger and the discharge pressure lowered by that share of
    p_d - p_in; the liquid / tubing spring (mode 2) as its fluid-load clamp (gas_spring.fluid_clamp)."""
    p = params[0]
    xi = track(params, ub)
    p.drain_share = p.drain * (0.5 * (1.0 + xi) if p.rising != 0 else 1.0)
    if p.gas_mode == 1:
        d = p.drain_share * (p.p_d_full_pa - p.p_in_pa)
        p.p_d_pa = p.p_d_full_pa - d
        p.p_out_pa = p.p_out_full_pa - d


@njit(cache=True, inline="always")
def adjust(params, ub, plo, phi):
    """The interval (plo, phi) at plunger position ub with the conditions (module docstring)."""
    p = params[0]
    xi = track(params, ub)
    speed = math.sqrt(4.0 * xi * (1.0 - xi))
    dp = phi - plo  # P- - P+
    if dp > 0.0:
        tv, sv = p.leak_tv, p.leak_sv
        if tv > 0.0 and sv > 0.0:  # both: one load at each speed, (sv + v) / (tv + sv) of dP, on the bound
            signed = speed if p.rising != 0 else -speed  # the moving plunger reaches (the other stays put)
            share = min(max((sv + signed) / (tv + sv), 0.0), 1.0)
            if p.rising != 0:
                plo = phi - dp * share
            else:
                phi = phi - dp * share
        elif tv > 0.0:  # the rising plunger carries dP min(1, v / v_leak); falling it holds P+ as before
            plo = phi - dp * min(1.0, speed / tv)
        elif sv > 0.0:  # the falling plunger keeps dP (1 - min(1, v / v_leak))
            phi = plo + dp * min(1.0, speed / sv)
        if p.drain > 0.0:
            plo = phi - (phi - plo) * (1.0 - p.drain * 0.5 * (1.0 + xi))
    force = contact_force(params, ub)
    return plo - force, phi - force


@njit(cache=True, inline="always")
def contact_force(params, ub):
    """Tagging's push on the plunger at position ub (positive down): k x the overlap with the pump's top or
    bottom end, 0 inside its free travel. It does not depend on what the chamber holds, so the gas spring's
    interval takes it too (srenv.physics.laws.valve.bounds)."""
    p = params[0]
    force = 0.0
    if p.tag_top_set != 0 and ub < p.tag_top_m:
        force = p.tag_k * (p.tag_top_m - ub)
    if p.tag_bottom_set != 0 and ub > p.tag_bottom_m:
        force = -p.tag_k * (ub - p.tag_bottom_m)
    return force
