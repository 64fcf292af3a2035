"""Compiled time-stepping kernel: Newmark + the step problem solved by certified active-set reuse.

Each step's problem (design §3) is the strictly convex QP
    min_v  1/2 v'K*v - b'v + sum_i j_i(v_i),   j_i(v) = sup{lam v : lam in [lo_i, hi_i]}
over the free nodes (the top node's velocity is prescribed). Its KKT conditions are
    K*v = b - lam,  lam_i = hi_i if v_i > 0,  lam_i = lo_i if v_i < 0,  lam_i in [lo_i, hi_i] if v_i = 0.
Given a pattern (each nonsmooth node sliding down, sliding up or stuck) the KKT system is one tridiagonal
solve (stuck rows replaced by v_i = 0). If the solution satisfies the sign and interval conditions it *is*
the unique QP minimiser: no solver call is needed ("certified"). Otherwise the violating nodes are flipped
(primal-dual active set; K* is a Stieltjes matrix, for which this converges) and the solve is repeated up
to ``max_corrections`` times ("corrected"). If that does not certify, the kernel returns to Python with
the step's data in the work arrays; Python solves the QP with ProxSuite through qpsolvers and resumes.

Nonmonotone laws (j = j1 - j2, j2 smooth convex) are handled by DC iterations: each sub-problem is the same
convex QP with b shifted by j2'(v_k). Everything here is O(n) per step with no allocation.
"""

from __future__ import annotations

import numpy as np
from numba import njit

# return codes of advance()
DONE = 0
NEED_QP = 1
EVENT = 2

# path codes recorded per step
PATH_CERTIFIED = 0
PATH_CORRECTED = 1
PATH_QP = 2

# indices into the float parameter vector `par`
P_DT, P_BETA, P_GAMMA, P_TOLV, P_TOLL, P_DCTOL = 0, 1, 2, 3, 4, 5
P_PUMP_LO, P_PUMP_HI, P_PUMP_DROP, P_PUMP_V0 = 6, 7, 8, 9
P_FRIC_RATIO, P_FRIC_V0 = 10, 11
P_MA, P_MOA, P_CA, P_FA, P_KC, P_MC = 12, 13, 14, 15, 17, 18  # 16: free
P_PB, P_PA, P_VOID_UNTIL = 19, 20, 21
P_EA0 = 22
P_UBMAX, P_UBMIN = 24, 25  # plunger position extremes since the caller last reset them (stroke bookkeeping)
# gas in the pump chamber (pump.GasChamber): the chamber state (reference plunger position, gas volume and
# pressure there, liquid volume), the polytropic exponent, the valve pressures (intake, discharge), the plunger
# area, the pressure above the plunger, the plunger friction and the intake gas fraction
P_GAS_U0, P_GAS_V0, P_GAS_P0, P_GAS_K, P_GAS_PIN, P_GAS_PD, P_GAS_APL, P_GAS_POUT, P_GAS_FRIC = (
    26, 27, 28, 29, 30, 31, 32, 33, 34)
P_GAS_DK, P_GAS_SHIFT = 35, 36  # the current linearisation: c2 * gas stiffness (in K*_BB), force moved into b
P_GAS_PHI, P_GAS_LIQ, P_GAS_UT = 37, 38, 39  # intake gas fraction, chamber liquid, this step's u-tilde_B
P_GAS_VMIN = 40  # A_pl x the smallest valve delay the gas spring resolves (less: rigid valve law)
N_PAR = 41

# indices into the integer state vector `ist`
I_STEP, I_DCIT, I_HAVEQP, I_MAXCORR, I_DCMAX, I_ALWAYSQP, I_NONSMOOTH = 0, 1, 2, 3, 4, 5, 6
I_PLDIR, I_EVENT, I_VOID, I_NCERT, I_NCORR, I_NQP, I_NDC, I_RECORD, I_NREC = 7, 8, 9, 10, 11, 12, 13, 14, 15
I_PUMP_NONMONO, I_FRIC_NONMONO = 16, 17
I_GAS = 18  # 1: free gas in the chamber is followed (kernel.gas_valves); 2: unanchored tubing (a spring)
I_GASON = 19  # 1 this step: the plunger load follows the chamber pressure at its position (gas spring)
N_IST = 20

# rows of the per-step record (one column per step; upward positions and velocities)
R_T, R_UA, R_PRL, R_UB, R_VB, R_PUMP, R_PATH, R_VA = 0, 1, 2, 3, 4, 5, 6, 7
N_REC = 8

# energy accumulators
E_TOP, E_GRAV, E_REACT, E_VISC = 0, 1, 2, 3
N_ENERGY = 4


@njit(cache=True)
def thomas_pattern(kd, ko, rhs, stuck, v, cp, dp):
    """Solve K* v = rhs with rows of stuck nodes replaced by v_i = 0 (Thomas algorithm)."""
    n = kd.shape[0]
    # forward sweep
    if stuck[0]:
        cp[0] = 0.0
        dp[0] = 0.0
    else:
        cp[0] = ko[0] / kd[0] if n > 1 else 0.0
        dp[0] = rhs[0] / kd[0]
    for i in range(1, n):
        if stuck[i]:
            cp[i] = 0.0
            dp[i] = 0.0
            continue
        a = ko[i - 1]
        den = kd[i] - a * cp[i - 1]
        cp[i] = (ko[i] / den) if i < n - 1 else 0.0
        dp[i] = (rhs[i] - a * dp[i - 1]) / den
    v[n - 1] = dp[n - 1]
    for i in range(n - 2, -1, -1):
        v[i] = dp[i] - cp[i] * v[i + 1]


@njit(cache=True)
def solve_pattern(ksd, kso, b, lo, hi, ns, status, v, lam, rhs, stuck, cp, dp, maxcorr, tolv, toll):
    """Certified active-set solve with up to `maxcorr` corrections.

    Returns the number of corrections used (0 = certified as is) or -1 when not certified.
    `status`: +1 sliding down (lam = hi), -1 sliding up (lam = lo), 0 stuck (v = 0).
    """
    n = ksd.shape[0]
    for it in range(maxcorr + 1):
        for i in range(n):
            if ns[i] and status[i] == 0:
                stuck[i] = True
                rhs[i] = 0.0
            else:
                stuck[i] = False
                if ns[i]:
                    lam[i] = hi[i] if status[i] > 0 else lo[i]
                else:
                    lam[i] = lo[i]
                rhs[i] = b[i] - lam[i]
        thomas_pattern(ksd, kso, rhs, stuck, v, cp, dp)
        ok = True
        for i in range(n):
            if not ns[i]:
                continue
            if status[i] == 0:
                kv = ksd[i] * v[i]
                if i > 0:
                    kv += kso[i - 1] * v[i - 1]
                if i < n - 1:
                    kv += kso[i] * v[i + 1]
                lam[i] = b[i] - kv
                scale = toll * (abs(lo[i]) + abs(hi[i]) + 1.0)
                if lam[i] > hi[i] + scale:
                    status[i] = 1
                    ok = False
                elif lam[i] < lo[i] - scale:
                    status[i] = -1
                    ok = False
            elif status[i] > 0:
                if v[i] < -tolv:
                    status[i] = 0
                    ok = False
            else:
                if v[i] > tolv:
                    status[i] = 0
                    ok = False
        if ok:
            for i in range(n):
                if ns[i] and status[i] == 0:
                    v[i] = 0.0  # exact rest
            return it
    return -1


@njit(cache=True)
def node_axial_force(u, ua, ea_len, nforce):
    """Equivalent axial force at each free node: mean of the adjacent element forces."""
    n = u.shape[0]
    prev = ea_len[0] * (u[0] - ua)
    for i in range(n):
        if i < n - 1:
            nxt = ea_len[i + 1] * (u[i + 1] - u[i])
            nforce[i] = 0.5 * (prev + nxt)
            prev = nxt
        else:
            nforce[i] = prev


@njit(cache=True)
def set_bounds(par, ist, u, ua, ea_len, fa, fw, fc, lo, hi, ns, nforce, fric_s):
    """Friction bounds from the side force with the previous step's axial force (quasi-variational);
    the plunger interval on the last node (collapsed to P-_eq during a fluid-pound void stroke)."""
    n = u.shape[0]
    node_axial_force(u, ua, ea_len, nforce)
    for i in range(n - 1):
        nn = nforce[i]
        q1 = fw[i] - fa[i] * nn
        q2 = fc[i] * nn
        f = np.sqrt(q1 * q1 + q2 * q2)
        fric_s[i] = f
        lo[i] = -f
        hi[i] = f
        ns[i] = f > 0.0
    fric_s[n - 1] = 0.0
    plo = par[P_PUMP_LO]
    phi = par[P_PUMP_HI]
    # gas interference: with enough gas in the chamber (its volume at p_in exceeds its volume at p_d by more
    # than a small plunger travel) the chamber pressure is a spring on the plunger (gas_spring, taken
    # implicitly in advance) and the pump node keeps only the plunger friction as its interval; less gas:
    # the rigid valve law
    gas_on = ist[I_GAS] == 2  # unanchored tubing: its stretch always carries the load transfer
    if ist[I_GAS] == 1 and par[P_GAS_V0] > 0.0:
        ik = 1.0 / par[P_GAS_K]
        v_in = par[P_GAS_V0] * (par[P_GAS_P0] / par[P_GAS_PIN]) ** ik
        gas_on = v_in - par[P_GAS_V0] * (par[P_GAS_P0] / par[P_GAS_PD]) ** ik >= par[P_GAS_VMIN]
    # fluid pound: above the liquid level in the barrel (u_B < P_VOID_UNTIL, positions positive down) the
    # travelling valve cannot open, so the plunger carries P- whether it moves up, rests or moves down
    if ist[I_VOID] != 0:
        ist[I_VOID] = 2 if u[n - 1] < par[P_VOID_UNTIL] else 1
        if ist[I_VOID] == 2:
            phi = plo
            gas_on = False
    if gas_on:
        plo = -par[P_GAS_FRIC] if ist[I_GAS] == 1 else 0.0
        phi = -plo
    ist[I_GASON] = 1 if gas_on else 0
    lo[n - 1] = plo
    hi[n - 1] = phi
    ns[n - 1] = phi > plo


@njit(cache=True)
def gas_spring(par, ub):
    """(centre, stiffness) of the plunger reaction -(p_out - p_c) A_pl = (p_c - p_out) A_pl with the chamber
    pressure p_c = p0 (V0 / V)^k, V = V0 - A_pl (u_B - u0), held between the intake and discharge pressures
    (the valves); stiffness d(centre)/du_B = A_pl^2 k p_c / V inside that range, 0 outside."""
    if par[P_GAS_APL] == 0.0:
        return tubing_spring(par, ub)
    a = par[P_GAS_APL]
    vg = par[P_GAS_V0] - a * (ub - par[P_GAS_U0])
    pc = par[P_GAS_PD]
    k = 0.0
    if vg > 0.0:
        pc = par[P_GAS_P0] * (par[P_GAS_V0] / vg) ** par[P_GAS_K]
        if pc <= par[P_GAS_PIN]:
            pc = par[P_GAS_PIN]
        elif pc >= par[P_GAS_PD]:
            pc = par[P_GAS_PD]
        else:
            k = a * a * par[P_GAS_K] * pc / vg
    return (pc - par[P_GAS_POUT]) * a, k


@njit(cache=True)
def tubing_spring(par, ub):
    """Unanchored tubing: while the plunger is stuck in its barrel the load transfer stretches or releases
    the tubing (stiffness k_t = E A_t / L, in P_GAS_K), so the reaction moves along
    centre = c0 + k_t (u_B - u0) between the valve law's bounds [-P-_eq, -P+_eq] (sliding in the barrel)."""
    c = par[P_GAS_P0] + par[P_GAS_K] * (ub - par[P_GAS_U0])
    if c <= par[P_PUMP_LO]:
        return par[P_PUMP_LO], 0.0
    if c >= par[P_PUMP_HI]:
        return par[P_PUMP_HI], 0.0
    return c, par[P_GAS_K]


@njit(cache=True)
def gas_valves(par, ub):
    """After a step: a valve that opened changes what the chamber holds; the state is re-referenced at the
    plunger's new position. Below p_in the standing valve is open and the chamber draws intake mixture
    (gas fraction phi at p_in); above p_d the travelling valve is open and the chamber expels its own
    mixture (gas and liquid in the proportion it holds at p_d). Both valves closed: nothing changes."""
    if par[P_GAS_APL] == 0.0:  # unanchored tubing: the plunger slid in its barrel, the spring re-references
        c = par[P_GAS_P0] + par[P_GAS_K] * (ub - par[P_GAS_U0])
        if c <= par[P_PUMP_LO] or c >= par[P_PUMP_HI]:
            par[P_GAS_P0] = min(max(c, par[P_PUMP_LO]), par[P_PUMP_HI])
            par[P_GAS_U0] = ub
        return
    a = par[P_GAS_APL]
    k = par[P_GAS_K]
    v0 = par[P_GAS_V0]
    p0 = par[P_GAS_P0]
    vg = v0 - a * (ub - par[P_GAS_U0])
    phi = par[P_GAS_PHI]
    if vg > 0.0 and (v0 <= 0.0 or p0 * (v0 / vg) ** k < par[P_GAS_PIN]):
        v_open = v0 * (p0 / par[P_GAS_PIN]) ** (1.0 / k) if v0 > 0.0 else 0.0
        par[P_GAS_V0] = v_open + phi * (vg - v_open)
        par[P_GAS_LIQ] += (1.0 - phi) * (vg - v_open)
        par[P_GAS_P0] = par[P_GAS_PIN]
        par[P_GAS_U0] = ub
    elif v0 > 0.0 and (vg <= 0.0 or p0 * (v0 / vg) ** k > par[P_GAS_PD]):
        v_open = v0 * (p0 / par[P_GAS_PD]) ** (1.0 / k)
        out = v_open - vg
        f = v_open / (v_open + par[P_GAS_LIQ])
        par[P_GAS_V0] = max(v_open - f * out, 0.0)
        par[P_GAS_LIQ] = max(par[P_GAS_LIQ] - (1.0 - f) * out, 0.0)
        par[P_GAS_P0] = par[P_GAS_PD]
        par[P_GAS_U0] = ub
    elif v0 <= 0.0 and vg <= 0.0:
        par[P_GAS_U0] = ub  # liquid-full chamber moving down: the travelling valve is open


@njit(cache=True)
def gas_linearise(par, ksd, b0, n, c2, u_lin):
    """Linearise the gas spring at plunger position u_lin and move it into the step problem: K*_BB gains
    c2 k_g, b_B loses centre + k_g (u-tilde_B - u_lin) (undoing the previous linearisation first)."""
    ksd[n - 1] -= par[P_GAS_DK]
    b0[n - 1] += par[P_GAS_SHIFT]
    centre, kg = gas_spring(par, u_lin)
    par[P_GAS_DK] = c2 * kg
    par[P_GAS_SHIFT] = centre + kg * (par[P_GAS_UT] - u_lin)
    ksd[n - 1] += par[P_GAS_DK]
    b0[n - 1] -= par[P_GAS_SHIFT]


@njit(cache=True)
def concave_shift(par, ist, v, fric_s, shift):
    """j2'(v): the smooth concave part of the nonmonotone laws, added to b in a DC iteration."""
    n = v.shape[0]
    for i in range(n):
        shift[i] = 0.0
    if ist[I_FRIC_NONMONO] != 0:
        d = 1.0 - par[P_FRIC_RATIO]
        v0 = par[P_FRIC_V0]
        for i in range(n - 1):
            vi = v[i]
            if vi > 0:
                shift[i] = d * fric_s[i] * (1.0 - np.exp(-vi / v0))
            elif vi < 0:
                shift[i] = -d * fric_s[i] * (1.0 - np.exp(vi / v0))
    if ist[I_PUMP_NONMONO] != 0 and ist[I_VOID] != 2:
        vb = v[n - 1]
        if vb < 0:
            shift[n - 1] = -par[P_PUMP_DROP] * (1.0 - np.exp(vb / par[P_PUMP_V0]))


@njit(cache=True)
def advance(par, ist, u, v, a, uav, va_t, t0,
            ksd, kso, kd, ko, md, mo, cd, f, ea_len, fa, fw, fc,
            status, lo, hi, ns, lam, b, b0, shift, vk, rhs, stuck, cp, dp, nforce, fric_s,
            wv, wb, wlo, whi, prev_lam, prev_v, prev_stuck, stick_count, rec, energy, emax, emin, k_end):
    """Advance from step ist[I_STEP] to k_end; va_t[k] is the prescribed top velocity at the end of step k.
    uav = (u_A, v_A, a_A, PRL_eq) of the current state. Returns DONE, NEED_QP (wb/wlo/whi hold the
    sub-problem; the caller puts the solution in wv, sets ist[I_HAVEQP] and calls again) or EVENT."""
    n = u.shape[0]
    dt = par[P_DT]
    beta = par[P_BETA]
    gamma = par[P_GAMMA]
    c1 = 1.0 / (gamma * dt)
    c2 = beta * dt / gamma
    maxcorr = ist[I_MAXCORR]
    tolv = par[P_TOLV]
    toll = par[P_TOLL]
    while ist[I_STEP] < k_end:
        k = ist[I_STEP]
        # prescribed top velocity; its displacement and acceleration follow the same Newmark relations
        ua_old = uav[0]
        va_old = uav[1]
        aa_old = uav[2]
        va_new = va_t[k]
        vpa = va_old + dt * (1.0 - gamma) * aa_old
        ua_new = ua_old + dt * va_old + dt * dt * (0.5 - beta) * aa_old - c2 * vpa + c2 * va_new
        aa_new = (va_new - vpa) * c1
        # predictor and right-hand side (b0 = b* with the prescribed top column moved over).
        # v_n is read from prev_v, not v: within a step `v` holds the latest DC iterate or a failed
        # pattern solve, and b0 is rebuilt from scratch when the kernel resumes after a NEED_QP return.
        # scratch until the DC loop fills them: rhs = u-tilde, b = predicted velocity v_n + dt(1-gamma)a_n
        for i in range(n):
            vp = prev_v[i] + dt * (1.0 - gamma) * a[i]
            b[i] = vp
            rhs[i] = u[i] + dt * prev_v[i] + dt * dt * (0.5 - beta) * a[i] - c2 * vp
            b0[i] = f[i] + c1 * md[i] * vp
        for i in range(n):
            ku = kd[i] * rhs[i]
            if i > 0:
                ku += ko[i - 1] * rhs[i - 1]
                b0[i] += c1 * mo[i - 1] * b[i - 1]
            if i < n - 1:
                ku += ko[i] * rhs[i + 1]
                b0[i] += c1 * mo[i] * b[i + 1]
            b0[i] -= ku
        b0[0] -= par[P_KC] * ua_new + par[P_MC] * aa_new
        if ist[I_HAVEQP] == 0:
            if ist[I_NONSMOOTH] != 0:
                set_bounds(par, ist, u, ua_old, ea_len, fa, fw, fc, lo, hi, ns, nforce, fric_s)
            ist[I_DCIT] = 0
            for i in range(n):
                vk[i] = prev_v[i]  # linearise j2 at v_n first
        # the chamber's gas: a stiff nonlinear spring on the plunger, taken implicitly by Newton passes (each
        # pass linearises it at the latest iterate's position u_B = u-tilde_B + c2 v_B, inside the DC loop)
        gas = ist[I_GASON] != 0 and ist[I_NONSMOOTH] != 0
        if gas:
            if ist[I_HAVEQP] == 0:
                par[P_GAS_UT] = rhs[n - 1]
                ksd[n - 1] -= par[P_GAS_DK]  # nothing is left from a previous step; kept for safety
                par[P_GAS_DK] = 0.0
                par[P_GAS_SHIFT] = 0.0
                gas_linearise(par, ksd, b0, n, c2, u[n - 1])
            else:  # resumed after NEED_QP: b0 was rebuilt, K* still holds this pass's linearisation
                b0[n - 1] -= par[P_GAS_SHIFT]
        used_qp = ist[I_HAVEQP] != 0
        corrected = False
        # DC iterations (a single pass when both laws are monotone)
        nonmono = ist[I_PUMP_NONMONO] != 0 or ist[I_FRIC_NONMONO] != 0 or gas
        while True:
            if nonmono:
                concave_shift(par, ist, vk, fric_s, shift)
                for i in range(n):
                    b[i] = b0[i] + shift[i]
            else:
                for i in range(n):
                    b[i] = b0[i]
            if ist[I_HAVEQP] != 0:
                for i in range(n):
                    v[i] = wv[i]
                ist[I_HAVEQP] = 0
            else:
                nc = -1
                if ist[I_ALWAYSQP] == 0:
                    nc = solve_pattern(ksd, kso, b, lo, hi, ns, status, v, lam, rhs, stuck, cp, dp,
                                       maxcorr, tolv, toll)
                if nc < 0:
                    for i in range(n):
                        wb[i] = b[i]
                        wlo[i] = lo[i]
                        whi[i] = hi[i]
                    return NEED_QP
                if nc > 0:
                    corrected = True
            ist[I_DCIT] += 1
            if not nonmono:
                break
            dv = 0.0
            for i in range(n):
                dv = max(dv, abs(v[i] - vk[i]))
                vk[i] = v[i]
            if dv <= par[P_DCTOL] or ist[I_DCIT] >= ist[I_DCMAX]:
                break
            if gas:
                gas_linearise(par, ksd, b0, n, c2, par[P_GAS_UT] + c2 * v[n - 1])
        ist[I_NDC] += ist[I_DCIT]
        # reactions lam = b - K*v (exact for every node, whatever path produced v)
        for i in range(n):
            kv = ksd[i] * v[i]
            if i > 0:
                kv += kso[i - 1] * v[i - 1]
            if i < n - 1:
                kv += kso[i] * v[i + 1]
            lam[i] = b[i] - kv - shift[i] if nonmono else b[i] - kv
        if par[P_GAS_DK] != 0.0 or par[P_GAS_SHIFT] != 0.0:
            # the plunger's whole reaction: friction part + the gas spring moved into K* and b
            lam[n - 1] += par[P_GAS_SHIFT] + par[P_GAS_DK] * v[n - 1]
            ksd[n - 1] -= par[P_GAS_DK]
            par[P_GAS_DK] = 0.0
            par[P_GAS_SHIFT] = 0.0
        # energy: trapezoidal work of each force over du (closes exactly for the trapezoidal rule)
        du_a = ua_new - ua_old
        for i in range(n):
            vo = prev_v[i]  # v_n: `v` already holds v_{n+1}
            vp = vo + dt * (1.0 - gamma) * a[i]
            a_new = (v[i] - vp) * c1
            u_new = u[i] + dt * vo + dt * dt * (0.5 - beta) * a[i] - c2 * vp + c2 * v[i]
            du = u_new - u[i]
            energy[E_GRAV] += f[i] * du
            energy[E_REACT] -= 0.5 * (lam[i] + prev_lam[i]) * du
            energy[E_VISC] += 0.5 * cd[i] * (v[i] + prev_v[i]) * du
            prev_lam[i] = lam[i]
            prev_v[i] = v[i]
            u[i] = u_new
            a[i] = a_new
        energy[E_GRAV] += par[P_FA] * du_a
        # polished-rod load from the top node's equation (includes its half element's weight/inertia)
        n0 = par[P_EA0] * (u[0] - ua_new)
        prl_eq = n0 + par[P_FA] - par[P_MA] * aa_new - par[P_MOA] * a[0] - par[P_CA] * va_new
        energy[E_TOP] += -0.5 * (prl_eq + uav[3]) * du_a
        energy[E_VISC] += 0.5 * par[P_CA] * (va_new + va_old) * du_a
        uav[3] = prl_eq
        uav[0] = ua_new
        uav[1] = va_new
        uav[2] = aa_new
        # element force envelope (equivalent force) for stress ranges per taper
        ne = n0
        for e in range(n):
            if e > 0:
                ne = ea_len[e] * (u[e] - u[e - 1])
            emax[e] = max(emax[e], ne)
            emin[e] = min(emin[e], ne)
        # bookkeeping: paths, stick episodes, plunger direction events
        if used_qp:
            ist[I_NQP] += 1
            path = PATH_QP
        elif corrected:
            ist[I_NCORR] += 1
            path = PATH_CORRECTED
        else:
            ist[I_NCERT] += 1
            path = PATH_CERTIFIED
        for i in range(n):
            s = ns[i] and v[i] == 0.0
            if s and not prev_stuck[i]:
                stick_count[i] += 1
            prev_stuck[i] = s
            if not ns[i]:
                status[i] = 1 if v[i] > 0 else (-1 if v[i] < 0 else 0)
        if ist[I_RECORD] != 0:
            r = ist[I_NREC]
            if r < rec.shape[1]:
                # recorded as users read them: positions and velocities upward, true loads
                rec[R_T, r] = t0 + (k + 1) * dt
                rec[R_UA, r] = -ua_new
                rec[R_PRL, r] = prl_eq - par[P_PA]
                rec[R_UB, r] = -u[n - 1]
                rec[R_VB, r] = -v[n - 1] + 0.0  # + 0.0: an exact rest is 0.0, never -0.0
                rec[R_PUMP, r] = -lam[n - 1] - par[P_PB]
                rec[R_PATH, r] = path
                rec[R_VA, r] = -va_new
                ist[I_NREC] = r + 1
        ist[I_STEP] = k + 1
        if ist[I_GAS] != 0:
            gas_valves(par, u[n - 1])
        par[P_UBMAX] = max(par[P_UBMAX], u[n - 1])
        par[P_UBMIN] = min(par[P_UBMIN], u[n - 1])
        vb = v[n - 1]
        d = 1 if vb > 0 else (-1 if vb < 0 else 0)
        if d != 0 and d != ist[I_PLDIR]:
            old = ist[I_PLDIR]
            ist[I_PLDIR] = d
            if old != 0:
                ist[I_EVENT] = d  # +1: plunger turned down (top of stroke), -1: turned up (bottom)
                return EVENT
    return DONE
