"""Gas in the pump chamber (srenv.pump.GasChamber) or unanchored tubing as a spring on the plunger.

Mode 1 (gas): the plunger reaction is (p_c - p_out) A_pl with the chamber pressure p_c = p0 (V0 / V)^k,
V = V0 - A_pl (u_B - u0), held between the intake and discharge pressures by the valves; while it is on the
valve law keeps only the plunger friction as its interval. Mode 2 (unanchored tubing, a plunger area of 0):
while the plunger is stuck in its barrel the load transfer stretches the tubing (stiffness k_t = E A_t / L,
in the ``k`` field), centre = c0 + k_t (u_B - u0) between the valve law's bounds. The spring is taken
implicitly: linearised at the latest iterate's position inside the DC loop (``linearise``), its stiffness
added to K*_BB and its force moved into b.
"""

from __future__ import annotations

from numba import njit

# fields of the valve law's record (srenv.laws.valve.PARAMS) that belong to the spring: the mode (0 none,
# 1 gas, 2 tubing), whether it carries the plunger this step, the chamber state (reference plunger position,
# gas volume and pressure there - tubing: its centre force -, liquid volume), the exponent (tubing: its
# stiffness), the valve pressures, the plunger area, the pressure above the plunger, the plunger friction,
# the intake gas fraction, A_pl x the smallest valve delay the spring resolves, and the current
# linearisation (c2 x stiffness in K*_BB, force moved into b, this step's u-tilde_B)
GAS_FIELDS = [("gas_mode", "i8"), ("gas_on", "i8"), ("u0_m", "f8"), ("gas_m3", "f8"), ("p0", "f8"),
              ("liquid_m3", "f8"), ("k", "f8"), ("p_in_pa", "f8"), ("p_d_pa", "f8"), ("area_m2", "f8"),
              ("p_out_pa", "f8"), ("gas_friction_n", "f8"), ("phi", "f8"), ("v_min_m3", "f8"),
              ("lin_dk", "f8"), ("lin_shift_n", "f8"), ("u_tilde_m", "f8"),
              # the liquid's compressibility (1/Pa, pump.liquid_compressibility_per_pa; 0: incompressible) and
              # unanchored tubing's compliance seen by the chamber, A_pl^2 / k_t (m^3/Pa; 0: anchored)
              ("liq_c", "f8"), ("tub_c", "f8"),
              # mode 2: the stiffness of the downstroke's transfer at the top when it differs from k, the
              # upstroke's at the bottom (the chamber's liquid: clearance + swept there; 0: k for both)
              ("k_top", "f8"),
              # mode 1: gas at p_d the travelling valve does not pass, kept in the clearance (m^3; 0: the chamber
              # expels its own mixture, gas and liquid alike; pump.clearance_gas_fraction)
              ("gas_keep_m3", "f8")]


@njit(cache=True, inline="always")
def gas_active(params):
    """With enough gas in the chamber (its volume at p_in exceeds its volume at p_d by more than a small
    plunger travel) the chamber pressure is a spring on the plunger; less gas: the rigid valve law.
    Unanchored tubing: its stretch always carries the load transfer."""
    p = params[0]
    if p.gas_mode == 2:
        return True
    if p.gas_mode == 1 and (p.gas_m3 > 0.0 or p.liq_c + p.tub_c > 0.0):
        ik = 1.0 / p.k
        v_in = p.gas_m3 * (p.p0 / p.p_in_pa) ** ik
        squeeze = (p.liquid_m3 * p.liq_c + p.tub_c) * (p.p_d_pa - p.p_in_pa) if p.liq_c + p.tub_c > 0.0 else 0.0
        return v_in - p.gas_m3 * (p.p0 / p.p_d_pa) ** ik + squeeze >= p.v_min_m3
    return False


@njit(cache=True)
def spring(params, ub):
    """(centre, stiffness) of the plunger reaction at plunger position ub: (p_c - p_out) A_pl and
    d(centre)/du_B = A_pl^2 k p_c / V between the valve pressures, 0 outside (module docstring)."""
    p = params[0]
    if p.area_m2 == 0.0:
        return tubing_spring(params, ub)
    if p.liq_c + p.tub_c > 0.0:
        return compressible_spring(params, ub)
    a = p.area_m2
    vg = p.gas_m3 - a * (ub - p.u0_m)
    pc = p.p_d_pa
    k = 0.0
    if vg > 0.0:
        pc = p.p0 * (p.gas_m3 / vg) ** p.k
        if pc <= p.p_in_pa:
            pc = p.p_in_pa
        elif pc >= p.p_d_pa:
            pc = p.p_d_pa
        else:
            k = a * a * p.k * pc / vg
    return (pc - p.p_out_pa) * a, k


@njit(cache=True)
def tubing_spring(params, ub):
    """Unanchored tubing: centre = c0 + k_t (u_B - u0) between the valve law's bounds [lo_n, hi_n]."""
    p = params[0]
    k = tubing_k(params)
    c = p.p0 + k * (ub - p.u0_m)
    lo = fluid_clamp(params)
    if c <= lo:
        return lo, 0.0
    if c >= p.hi_n:
        return p.hi_n, 0.0
    return c, k


@njit(cache=True, inline="always")
def tubing_k(params):
    """Mode 2's stiffness for the transfer under way: the reference p0 is the bound the spring was last held
    at, so below the downstroke bound hi_n it left the top (the fluid load) and the downstroke's transfer
    k_top applies; at hi_n (the bottom, and the start) the upstroke's, k. Fixed within a step (the reference
    moves only between steps, in ``valves``), so each step stays the same convex problem."""
    p = params[0]
    if p.k_top > 0.0 and p.p0 < p.hi_n:
        return p.k_top
    return p.k


@njit(cache=True, inline="always")
def fluid_clamp(params):
    """The tubing spring's fluid-load bound lo_n, less the share of the fluid load a tubing leak has drained
    (laws.pump_conditions.drain_discharge; the rigid law's P-_eff)."""
    p = params[0]
    if p.drain_share > 0.0:
        return p.hi_n - (p.hi_n - p.lo_n) * (1.0 - p.drain_share)
    return p.lo_n


@njit(cache=True)
def valves(params, ub):
    """After a step: a valve that opened changes what the chamber holds; the state is re-referenced at the
    plunger's new position. Below p_in the standing valve is open and the chamber draws intake mixture
    (gas fraction phi at p_in); above p_d the travelling valve is open and the chamber expels its own
    mixture (gas and liquid in the proportion it holds at p_d). Both valves closed: nothing changes."""
    p = params[0]
    if p.area_m2 == 0.0:  # unanchored tubing: the plunger slid in its barrel, the spring re-references
        c = p.p0 + tubing_k(params) * (ub - p.u0_m)
        lo = fluid_clamp(params)
        if c <= lo or c >= p.hi_n:
            p.p0 = min(max(c, lo), p.hi_n)
            p.u0_m = ub
        return
    if p.liq_c + p.tub_c > 0.0:
        compressible_valves(params, ub)
        return
    a = p.area_m2
    k = p.k
    v0 = p.gas_m3
    p0 = p.p0
    vg = v0 - a * (ub - p.u0_m)
    phi = p.phi
    if vg > 0.0 and (v0 <= 0.0 or p0 * (v0 / vg) ** k < p.p_in_pa):
        v_open = v0 * (p0 / p.p_in_pa) ** (1.0 / k) if v0 > 0.0 else 0.0
        p.gas_m3 = v_open + phi * (vg - v_open)
        p.liquid_m3 += (1.0 - phi) * (vg - v_open)
        p.p0 = p.p_in_pa
        p.u0_m = ub
    elif v0 > 0.0 and (vg <= 0.0 or p0 * (v0 / vg) ** k > p.p_d_pa):
        v_open = v0 * (p0 / p.p_d_pa) ** (1.0 / k)
        out = v_open - vg
        if p.gas_keep_m3 > 0.0:
            p.gas_m3, p.liquid_m3 = expel_keeping(p.gas_keep_m3, v_open, p.liquid_m3, out)
        else:
            f = v_open / (v_open + p.liquid_m3)
            p.gas_m3 = max(v_open - f * out, 0.0)
            p.liquid_m3 = max(p.liquid_m3 - (1.0 - f) * out, 0.0)
        p.p0 = p.p_d_pa
        p.u0_m = ub
    elif v0 <= 0.0 and vg <= 0.0:
        p.u0_m = ub  # liquid-full chamber moving down: the travelling valve is open


@njit(cache=True)
def expel_keeping(keep_m3, gas_m3, liquid_m3, out_m3):
    """(gas, liquid) left after the open travelling valve passed out_m3 at p_d, keeping up to keep_m3 of the
    chamber's gas (trapped in the clearance, where the plunger does not sweep it out): the rest of the gas and
    the liquid leave mixed as the chamber holds them; once they are gone the kept gas leaves too."""
    held = min(keep_m3, gas_m3)
    free = gas_m3 - held
    mix = free + liquid_m3
    if out_m3 <= mix and mix > 0.0:
        f = free / mix
        return held + free - f * out_m3, liquid_m3 - (1.0 - f) * out_m3
    return max(gas_m3 + liquid_m3 - out_m3, 0.0), 0.0


@njit(cache=True)
def squeeze_m3(params, pc):
    """Plunger travel x A_pl from the chamber's reference state (p0, gas_m3, liquid_m3) to pressure pc: the
    gas's polytropic change, the liquid's compression V_l c (pc - p0) and, unanchored, the barrel's own
    travel as the tubing takes the load (pc - p0) A_pl on the standing valve, A_pl^2 (pc - p0) / k_t."""
    p = params[0]
    vg = p.gas_m3 * (p.p0 / pc) ** (1.0 / p.k) if p.gas_m3 > 0.0 else 0.0
    return p.gas_m3 - vg + (p.liquid_m3 * p.liq_c + p.tub_c) * (pc - p.p0)


@njit(cache=True)
def compressible_spring(params, ub):
    """The chamber of gas and compressible liquid (and unanchored tubing): its pressure pc solves
    A (u_B - u0) = squeeze(pc) (monotone in pc; Newton from the secant, bracketed by the valve pressures);
    the stiffness is the three in series, A^2 / (V_g / (k pc) + V_l c + A^2 / k_t)."""
    p = params[0]
    a = p.area_m2
    swept = a * (ub - p.u0_m)
    lo = p.p_in_pa
    hi = p.p_d_pa
    s_lo = squeeze_m3(params, lo)
    s_hi = squeeze_m3(params, hi)
    if swept <= s_lo:
        return (lo - p.p_out_pa) * a, 0.0
    if swept >= s_hi:
        return (hi - p.p_out_pa) * a, 0.0
    pc = lo + (hi - lo) * (swept - s_lo) / (s_hi - s_lo)
    comp = 1.0
    for _ in range(60):
        vg = p.gas_m3 * (p.p0 / pc) ** (1.0 / p.k) if p.gas_m3 > 0.0 else 0.0
        comp = vg / (p.k * pc) + p.liquid_m3 * p.liq_c + p.tub_c  # d(squeeze)/dp at pc
        r = squeeze_m3(params, pc) - swept
        if abs(r) <= 1e-12 * a or hi - lo <= 1e-9 * p.p_d_pa:
            break
        if r > 0.0:
            hi = pc
        else:
            lo = pc
        step = pc - r / comp
        pc = step if lo < step < hi else 0.5 * (lo + hi)
    return (pc - p.p_out_pa) * a, a * a / comp


@njit(cache=True)
def compressible_valves(params, ub):
    """``valves`` with a compressible liquid: the chamber's liquid changes volume with its pressure, so a
    valve that opens meets gas and liquid at that valve's pressure (incompressible: the same as ``valves``)."""
    p = params[0]
    a = p.area_m2
    swept = a * (ub - p.u0_m)
    total = p.gas_m3 + p.liquid_m3 - swept  # the chamber's volume now
    for side in range(2):
        pv = p.p_in_pa if side == 0 else p.p_d_pa
        s = squeeze_m3(params, pv)
        if (side == 0 and swept < s) or (side == 1 and swept > s and p.gas_m3 + p.liquid_m3 > 0.0):
            vg = p.gas_m3 * (p.p0 / pv) ** (1.0 / p.k) if p.gas_m3 > 0.0 else 0.0
            vl = p.liquid_m3 * (1.0 - p.liq_c * (pv - p.p0))
            # > 0: drawn at the intake, < 0: expelled at the discharge (the barrel rests at the valve's load)
            flow = total + p.tub_c * (pv - p.p0) - vg - vl
            if side == 0:
                p.gas_m3 = vg + p.phi * flow
                p.liquid_m3 = vl + (1.0 - p.phi) * flow
            elif p.gas_keep_m3 > 0.0 and flow < 0.0:
                p.gas_m3, p.liquid_m3 = expel_keeping(p.gas_keep_m3, vg, vl, -flow)
            else:
                f = vg / (vg + vl) if vg + vl > 0.0 else 0.0
                p.gas_m3 = max(vg + f * flow, 0.0)
                p.liquid_m3 = max(vl + (1.0 - f) * flow, 0.0)
            p.p0 = pv
            p.u0_m = ub
            return


@njit(cache=True)
def linearise(params, ksd, b0, c2, u_lin):
    """Linearise the spring at plunger position u_lin and move it into the step problem: K*_BB gains
    c2 k_g, b_B loses centre + k_g (u-tilde_B - u_lin) (undoing the previous linearisation first)."""
    p = params[0]
    n = ksd.shape[0]
    ksd[n - 1] -= p.lin_dk
    b0[n - 1] += p.lin_shift_n
    centre, kg = spring(params, u_lin)
    p.lin_dk = c2 * kg
    p.lin_shift_n = centre + kg * (p.u_tilde_m - u_lin)
    ksd[n - 1] += p.lin_dk
    b0[n - 1] -= p.lin_shift_n
