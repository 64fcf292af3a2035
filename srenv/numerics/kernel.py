"""Compiled time stepper: Newmark + the step's box QP, solved by certified active-set reuse (design §3).

Each step's problem is the strictly convex QP
    min_v  1/2 v'K*v - b'v + sum_i j_i(v_i),   j_i(v) = sup{lam v : lam in [lo_i, hi_i]}
over the free nodes (the top node's velocity is prescribed). The intervals come from the laws
(srenv/laws: rod friction on the rod nodes, the valve law on the pump node); the pattern solve and its
certificate are in srenv/active_set.py. A step that does not certify within ``max_corrections`` returns
NEED_QP with its data in Work.wb/wlo/whi; the caller solves the QP (ProxSuite), puts the answer in Work.wv,
sets Progress.have_qp and calls again. Nonmonotone laws (j = j1 - j2, j2 smooth convex) are handled by DC
iterations: each sub-problem is the same convex QP with b shifted by j2'(v_k). O(n) per step, no
allocation. The calling convention (what each argument holds) is in srenv/kernel_layout.py.

A step is: top motion -> prediction (b0, u-tilde) -> bounds (laws) -> DC loop of certified solves (with the
gas spring linearised inside) -> reactions -> Newmark update, energy, record -> events (valves, reversals).
``advance`` unpacks the named groups once per call and hands the step functions plain arrays and scalars:
numba compiles loops over arrays taken out of a named tuple inside a callee several times slower.
"""

from __future__ import annotations

from numba import njit

from ..physics.laws import gas_spring, rod_friction, valve
from .active_set import solve_pattern, thomas_pattern  # noqa: F401 - re-exported for the callers
from .kernel_layout import (  # noqa: F401 - the layout's constants are part of the kernel's API
    DONE,
    E_GRAV,
    E_REACT,
    E_TOP,
    E_VISC,
    EVENT,
    N_ENERGY,
    N_REC,
    NEED_QP,
    PATH_CERTIFIED,
    PATH_CORRECTED,
    PATH_QP,
    R_PATH,
    R_PRL,
    R_PUMP,
    R_T,
    R_UA,
    R_UB,
    R_VA,
    R_VB,
    TOP_A,
    TOP_PRL,
    TOP_U,
    TOP_V,
    Stepper,
)


def run(stepper: Stepper, va_t, t0: float, k_end: int) -> int:
    """advance() with the stepper's groups (the one call site of both callers)."""
    return advance(*stepper, va_t, t0, k_end)


# The Newmark relations of one free node (every path of the kernel takes them from here; kept in this file so
# that an edit of them invalidates numba's cache of the kernel, which watches this file only). With
# h = dt (1 - gamma), q = dt^2 (1/2 - beta), c1 = 1 / (gamma dt), c2 = beta dt / gamma: v-tilde = v + h a,
# u-tilde = u + dt v + q a - c2 v-tilde; at the step's end u = u-tilde + c2 v_new, a = (v_new - v-tilde) c1.
# The order of the operations is part of the results (tests/test_kernel_regression.py).
@njit(cache=True, inline="always")
def coefficients(dt, beta, gamma):
    """(h, q, c1, c2) of the time step."""
    return dt * (1.0 - gamma), dt * dt * (0.5 - beta), 1.0 / (gamma * dt), beta * dt / gamma


@njit(cache=True, inline="always")
def predict(u, v, a, dt, h, q, c2):
    """(v-tilde, u-tilde) of a node from its state at the step's start."""
    vpr = v + h * a
    return vpr, u + dt * v + q * a - c2 * vpr


@njit(cache=True, inline="always")
def update(u, v, a, v_new, dt, h, q, c1, c2):
    """(u, a) at the step's end from the state at its start and the new velocity."""
    vpr = v + h * a
    return u + dt * v + q * a - c2 * vpr + c2 * v_new, (v_new - vpr) * c1


@njit(cache=True, inline="always")
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


@njit(cache=True, inline="always")
def top_motion(dt, beta, gamma, top, va_new):
    """The prescribed top's displacement and acceleration at the step's end (same Newmark relations)."""
    c1 = 1.0 / (gamma * dt)
    c2 = beta * dt / gamma
    vpa = top[TOP_V] + dt * (1.0 - gamma) * top[TOP_A]
    ua_new = top[TOP_U] + dt * top[TOP_V] + dt * dt * (0.5 - beta) * top[TOP_A] - c2 * vpa + c2 * va_new
    aa_new = (va_new - vpa) * c1
    return ua_new, aa_new


@njit(cache=True, inline="always")
def set_bounds(valve_p, axial, weight, turn, u, ua, ea_len, lo, hi, ns, nforce, fric_s):
    """The laws' intervals: rod friction from the side force with the previous step's axial force
    (quasi-variational), the valve law on the pump node."""
    node_axial_force(u, ua, ea_len, nforce)
    rod_friction.bounds(axial, weight, turn, nforce, lo, hi, ns, fric_s)
    valve.bounds(valve_p, u[u.shape[0] - 1], lo, hi, ns)


@njit(cache=True, inline="always")
def concave_shift(fric_p, valve_p, v, fric_s, shift):
    """j2'(v) of every law into shift (zero where a law is monotone)."""
    for i in range(shift.shape[0]):
        shift[i] = 0.0
    rod_friction.concave_shift(fric_p, v, fric_s, shift)
    valve.concave_shift(valve_p, v, shift)


@njit(cache=True)
def kv_work(energy, kv, ea_len, u, v, prev_v, a, dt, beta, gamma, ua_old, ua_new, va_old, va_new):
    """Work of the Kelvin-Voigt element forces tau EA/L dv over the step (trapezoidal in the element's
    velocity difference, over its strain increment), added to the viscous energy."""
    h, q, c1, c2 = coefficients(dt, beta, gamma)
    uj_old, uj_new, vj_old, vj_new = ua_old, ua_new, va_old, va_new
    for e in range(u.shape[0]):
        ui_new = update(u[e], prev_v[e], a[e], v[e], dt, h, q, c1, c2)[0]  # the step's own Newmark update
        d_strain = (ui_new - uj_new) - (u[e] - uj_old)
        energy[E_VISC] += 0.5 * kv * ea_len[e] * ((v[e] - vj_new) + (prev_v[e] - vj_old)) * d_strain
        uj_old, uj_new, vj_old, vj_new = u[e], ui_new, prev_v[e], v[e]


@njit(cache=True, inline="always")
def events(valve_p, prog, ub, vb):
    """After the step: gas chamber valves, plunger extremes, and a plunger reversal (True: return EVENT;
    Progress.event = +1 the plunger turned down, top of stroke, -1 it turned up, bottom)."""
    if valve_p[0].gas_mode != 0:
        gas_spring.valves(valve_p, ub)
    p = prog[0]
    p.ub_max_m = max(p.ub_max_m, ub)
    p.ub_min_m = min(p.ub_min_m, ub)
    d = 1 if vb > 0 else (-1 if vb < 0 else 0)
    if d != 0 and d != p.plunger_dir:
        old = p.plunger_dir
        p.plunger_dir = d
        if old != 0:
            p.event = d
            return True
    return False


@njit(cache=True, nogil=True)  # nogil: the vector env steps wells on threads (srenv/envs/vector.py)
def advance(const, fric_p, valve_p, prog, cnt, model, side, state, work, out, va_t, t0, k_end):
    """Advance from step Progress.step to k_end; va_t[k] is the prescribed top velocity at the end of step
    k. Returns DONE, NEED_QP (work.wb/wlo/whi hold the sub-problem; the caller puts the solution in work.wv,
    sets Progress.have_qp and calls again) or EVENT (a plunger reversal, Progress.event)."""
    ksd, kso, kd, ko, md, mo, cd, f, ea_len = model
    axial, weight, turn = side
    u, v, a, top, status, prev_lam, prev_v, prev_stuck = state
    lo, hi, ns, lam, b, b0, shift, vk, rhs, stuck, cp, dp, nforce, fric_s, wv, wb, wlo, whi = work
    rec, energy, emax, emin, stick = out
    return steps(const, fric_p, valve_p, prog, cnt, ksd, kso, kd, ko, md, mo, cd, f, ea_len, axial, weight, turn,
                 u, v, a, top, status, prev_lam, prev_v, prev_stuck, lo, hi, ns, lam, b, b0, shift, vk, rhs, stuck,
                 cp, dp, nforce, fric_s, wv, wb, wlo, whi, rec, energy, emax, emin, stick, va_t, t0, k_end)


@njit(cache=True, nogil=True)
def steps(const, fric_p, valve_p, prog, cnt, ksd, kso, kd, ko, md, mo, cd, f, ea_len, axial, weight, turn,
          u, v, a, top, status, prev_lam, prev_v, prev_stuck, lo, hi, ns, lam, b, b0, shift, vk, rhs, stuck,
          cp, dp, nforce, fric_s, wv, wb, wlo, whi, rec, energy, emax, emin, stick, va_t, t0, k_end):
    """advance() on the unpacked groups (numba compiles the loops over arguments, not over arrays taken
    out of named tuples, to fast code)."""
    c = const[0]
    p = prog[0]
    vp = valve_p[0]
    dt, beta, gamma = c.dt_s, c.beta, c.gamma
    h, q, c1, c2 = coefficients(dt, beta, gamma)
    nonsmooth, rec_on = c.nonsmooth != 0, c.record != 0
    kc, mc = c.top_coupling_stiffness_n_m, c.top_coupling_mass_kg
    fric_nonmono = fric_p[0].nonmonotone != 0
    maxcorr, tolv, toll, always_qp = c.max_corrections, c.tol_v_m_s, c.tol_lambda, c.always_qp
    dc_tol, dc_max = c.dc_tol_m_s, c.dc_max_iterations
    kv_tau = c.kv_tau_s
    n = u.shape[0]
    while p.step < k_end:
        k = p.step
        va_new = va_t[k]
        ua_new, aa_new = top_motion(dt, beta, gamma, top, va_new)
        # -- prediction (kept in this loop, like the update below: numba pays per array passed to a call)
        # b0 = b* with the prescribed top column moved over; u-tilde in rhs; b: the predicted velocity
        # v_n + dt(1-gamma)a_n until the DC loop fills it. v_n is read from prev_v, not v: within a step `v`
        # holds the latest DC iterate or a failed pattern solve, and b0 is rebuilt from scratch when the
        # kernel resumes after a NEED_QP return.
        for i in range(n):
            vpr, ut = predict(u[i], prev_v[i], a[i], dt, h, q, c2)
            b[i] = vpr
            rhs[i] = ut
            b0[i] = f[i] + c1 * md[i] * vpr
        for i in range(n):
            ku = kd[i] * rhs[i]
            if i > 0:
                ku += ko[i - 1] * rhs[i - 1]
                b0[i] += c1 * mo[i - 1] * b[i - 1]
            if i < n - 1:
                ku += ko[i] * rhs[i + 1]
                b0[i] += c1 * mo[i] * b[i + 1]
            b0[i] -= ku
        b0[0] -= kc * ua_new + mc * aa_new
        if kv_tau != 0.0:  # the top column of C_K = tau K, moved over like K's
            b0[0] -= kv_tau * kc * va_new
        if c.damp_split != 0 and p.have_qp == 0:  # damping per direction of the prescribed polished rod
            p.damp_prev = p.damp_s
            ds = c.damp_up if va_new < 0.0 else (c.damp_down if va_new > 0.0 else p.damp_s)
            if ds != p.damp_s:  # a turn: K* takes the other direction's C
                for i in range(n):
                    ksd[i] += (ds - p.damp_s) * cd[i]
                p.damp_s = ds
        if vp.fluid_kg != 0.0:  # the liquid column rides on the rising plunger: extra mass at the pump node
            if p.have_qp == 0:
                vp.fluid_dk = c1 * vp.fluid_kg if p.plunger_dir < 0 else 0.0
                ksd[n - 1] += vp.fluid_dk
            b0[n - 1] += vp.fluid_dk * b[n - 1]  # b holds the predicted velocities here
        # -- bounds: the laws' intervals
        if p.have_qp == 0:
            if nonsmooth:
                set_bounds(valve_p, axial, weight, turn, u, top[TOP_U], ea_len, lo, hi, ns, nforce, fric_s)
            p.dc_iterations = 0
            for i in range(n):
                vk[i] = prev_v[i]  # linearise j2 at v_n first
        # the chamber's gas: a stiff nonlinear spring on the plunger, taken implicitly by Newton passes (each
        # pass linearises it at the latest iterate's position u_B = u-tilde_B + c2 v_B, inside the DC loop)
        gas = vp.gas_on != 0 and nonsmooth
        if gas:
            if p.have_qp == 0:
                vp.u_tilde_m = rhs[n - 1]
                ksd[n - 1] -= vp.lin_dk  # nothing is left from a previous step; kept for safety
                vp.lin_dk = 0.0
                vp.lin_shift_n = 0.0
                gas_spring.linearise(valve_p, ksd, b0, c2, u[n - 1])
            else:  # resumed after NEED_QP: b0 was rebuilt, K* still holds this pass's linearisation
                b0[n - 1] -= vp.lin_shift_n
        used_qp = p.have_qp != 0
        # -- DC iterations of certified solves / corrections
        nonmono = fric_nonmono or vp.nonmonotone != 0 or gas
        corrected = 0
        while True:  # (one pass when every law is monotone)
            if nonmono:
                concave_shift(fric_p, valve_p, vk, fric_s, shift)
                for i in range(n):
                    b[i] = b0[i] + shift[i]
            else:
                for i in range(n):
                    b[i] = b0[i]
            if p.have_qp != 0:
                for i in range(n):
                    v[i] = wv[i]
                p.have_qp = 0
            else:
                nc = -1
                if always_qp == 0:
                    nc = solve_pattern(ksd, kso, b, lo, hi, ns, status, v, lam, rhs, stuck, cp, dp, maxcorr, tolv,
                                       toll)
                if nc < 0:
                    for i in range(n):
                        wb[i] = b[i]
                        wlo[i] = lo[i]
                        whi[i] = hi[i]
                    return NEED_QP
                if nc > 0:
                    corrected = 1
            p.dc_iterations += 1
            if not nonmono:
                break
            dv = 0.0
            for i in range(n):
                dv = max(dv, abs(v[i] - vk[i]))
                vk[i] = v[i]
            if dv <= dc_tol or p.dc_iterations >= dc_max:
                break
            if gas:
                gas_spring.linearise(valve_p, ksd, b0, c2, vp.u_tilde_m + c2 * v[n - 1])
        cnt[0].dc_iterations += p.dc_iterations
        # -- reactions lam = b - K*v (exact for every node, whatever path produced v)
        for i in range(n):
            kv = ksd[i] * v[i]
            if i > 0:
                kv += kso[i - 1] * v[i - 1]
            if i < n - 1:
                kv += kso[i] * v[i + 1]
            lam[i] = b[i] - kv - shift[i] if nonmono else b[i] - kv
        if vp.fluid_dk != 0.0:  # the column's inertia m a is part of the pump's force on the rod
            lam[n - 1] += vp.fluid_dk * (v[n - 1] - (prev_v[n - 1] + h * a[n - 1]))  # v_new - v-tilde
            ksd[n - 1] -= vp.fluid_dk
            vp.fluid_dk = 0.0
        if vp.lin_dk != 0.0 or vp.lin_shift_n != 0.0:
            # the plunger's whole reaction: friction part + the gas spring moved into K* and b
            lam[n - 1] += vp.lin_shift_n + vp.lin_dk * v[n - 1]
            ksd[n - 1] -= vp.lin_dk
            vp.lin_dk = 0.0
            vp.lin_shift_n = 0.0
        # -- Newmark update and the work of each force (trapezoidal work over du: closes exactly for the
        # trapezoidal rule)
        ua_old = top[TOP_U]
        va_old = top[TOP_V]
        du_a = ua_new - ua_old
        split = c.damp_split != 0
        ds_new, ds_old = p.damp_s, p.damp_prev
        if kv_tau != 0.0:  # Kelvin-Voigt work, before u and prev_v move on (kv = 0: nothing changes)
            kv_work(energy, kv_tau, ea_len, u, v, prev_v, a, dt, beta, gamma, ua_old, ua_new, va_old, va_new)
        # the sums in locals (the same additions in the same order: an array element written in the loop is
        # reloaded and stored at every node, since numba cannot tell it apart from the other arrays)
        e_grav, e_react, e_visc = energy[E_GRAV], energy[E_REACT], energy[E_VISC]
        for i in range(n):
            vo = prev_v[i]  # v_n: `v` already holds v_{n+1}
            vi = v[i]
            u_new, a_new = update(u[i], vo, a[i], vi, dt, h, q, c1, c2)
            du = u_new - u[i]
            e_grav += f[i] * du
            li = lam[i]
            e_react -= 0.5 * (li + prev_lam[i]) * du
            e_visc += 0.5 * cd[i] * (vi + vo) * du
            if split:  # the trapezoid of each end's own damping force: the factors' share beyond C's
                e_visc += 0.5 * cd[i] * ((ds_new - 1.0) * vi + (ds_old - 1.0) * vo) * du
            prev_lam[i] = li
            prev_v[i] = vi
            u[i] = u_new
            a[i] = a_new
        energy[E_GRAV] = e_grav + c.top_load_n * du_a
        energy[E_REACT] = e_react
        energy[E_VISC] = e_visc
        # polished-rod load from the top node's equation (includes its half element's weight/inertia)
        n0 = c.top_ea_len_n_m * (u[0] - ua_new)
        if kv_tau != 0.0:
            n0 += kv_tau * c.top_ea_len_n_m * (v[0] - va_new)
        prl_eq = (n0 + c.top_load_n - c.top_mass_kg * aa_new - c.top_coupling_mass_kg * a[0]
                  - c.top_damping_n_s_m * va_new)
        if split:  # the top element's damping at the step's factor
            prl_eq -= (ds_new - 1.0) * c.top_damping_n_s_m * va_new
            energy[E_VISC] += 0.5 * c.top_damping_n_s_m * ((ds_new - 1.0) * va_new + (ds_old - 1.0) * va_old) * du_a
        energy[E_TOP] += -0.5 * (prl_eq + top[TOP_PRL]) * du_a
        energy[E_VISC] += 0.5 * c.top_damping_n_s_m * (va_new + va_old) * du_a
        top[TOP_PRL] = prl_eq
        top[TOP_U] = ua_new
        top[TOP_V] = va_new
        top[TOP_A] = aa_new
        # element force envelope (equivalent force) for stress ranges per taper
        ne = n0
        for e in range(n):
            if e > 0:
                ne = ea_len[e] * (u[e] - u[e - 1])
                if kv_tau != 0.0:
                    ne += kv_tau * ea_len[e] * (v[e] - v[e - 1])
            emax[e] = max(emax[e], ne)
            emin[e] = min(emin[e], ne)
        # -- recording: paths, stick episodes, statuses of the smooth nodes, the per-step record
        path = PATH_QP if used_qp else (PATH_CORRECTED if corrected > 0 else PATH_CERTIFIED)
        cn = cnt[0]
        if path == PATH_QP:
            cn.qp += 1
        elif path == PATH_CORRECTED:
            cn.corrected += 1
        else:
            cn.certified += 1
        for i in range(n):
            s = ns[i] and v[i] == 0.0
            if s and not prev_stuck[i]:
                stick[i] += 1
            prev_stuck[i] = s
            if not ns[i]:
                status[i] = 1 if v[i] > 0 else (-1 if v[i] < 0 else 0)
        if rec_on:
            r = cn.recorded
            if r < rec.shape[1]:
                # recorded as users read them: positions and velocities upward, true loads
                rec[R_T, r] = t0 + (k + 1) * dt
                rec[R_UA, r] = -ua_new
                rec[R_PRL, r] = prl_eq - c.top_pressure_force_n
                rec[R_UB, r] = -u[n - 1]
                rec[R_VB, r] = -v[n - 1] + 0.0  # + 0.0: an exact rest is 0.0, never -0.0
                rec[R_PUMP, r] = -lam[n - 1] - c.pump_pressure_force_n
                rec[R_PATH, r] = path
                rec[R_VA, r] = -va_new
                cn.recorded = r + 1
        p.step = k + 1
        # -- events: gas chamber valves, plunger extremes and reversals
        if events(valve_p, prog, u[n - 1], v[n - 1]):
            return EVENT
    return DONE
