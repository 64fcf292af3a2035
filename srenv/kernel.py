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
"""

from __future__ import annotations

from numba import njit

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
from .laws import gas_spring, rod_friction, valve


def run(stepper: Stepper, va_t, t0: float, k_end: int) -> int:
    """advance() with the stepper's groups (the one call site of both callers)."""
    return advance(*stepper, va_t, t0, k_end)


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
def top_motion(c, top, va_new):
    """The prescribed top's displacement and acceleration at the step's end (same Newmark relations)."""
    dt, beta, gamma = c.dt_s, c.beta, c.gamma
    c1 = 1.0 / (gamma * dt)
    c2 = beta * dt / gamma
    vpa = top[TOP_V] + dt * (1.0 - gamma) * top[TOP_A]
    ua_new = top[TOP_U] + dt * top[TOP_V] + dt * dt * (0.5 - beta) * top[TOP_A] - c2 * vpa + c2 * va_new
    aa_new = (va_new - vpa) * c1
    return ua_new, aa_new


@njit(cache=True)
def predict(c, model, state, work, ua_new, aa_new):
    """Predictor and right-hand side: b0 = b* with the prescribed top column moved over; u-tilde in
    work.rhs. v_n is read from prev_v, not v: within a step `v` holds the latest DC iterate or a failed
    pattern solve, and b0 is rebuilt from scratch when the kernel resumes after a NEED_QP return."""
    dt, beta, gamma = c.dt_s, c.beta, c.gamma
    c1 = 1.0 / (gamma * dt)
    c2 = beta * dt / gamma
    u, a, prev_v = state.u, state.a, state.prev_v
    kd, ko, md, mo, f = model.kd, model.ko, model.md, model.mo, model.f
    b, b0, rhs = work.b, work.b0, work.rhs  # b: predicted velocity until the DC loop fills it
    n = u.shape[0]
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
    b0[0] -= c.top_coupling_stiffness_n_m * ua_new + c.top_coupling_mass_kg * aa_new


@njit(cache=True)
def set_bounds(valve_p, model, side, state, work):
    """The laws' intervals: rod friction from the side force with the previous step's axial force
    (quasi-variational), the valve law on the pump node."""
    u = state.u
    node_axial_force(u, state.top[TOP_U], model.ea_len, work.nforce)
    rod_friction.bounds(side, work.nforce, work.lo, work.hi, work.ns, work.fric_s)
    valve.bounds(valve_p, u[u.shape[0] - 1], work.lo, work.hi, work.ns)


@njit(cache=True)
def concave_shift(fric_p, valve_p, v, work):
    """j2'(v) of every law into work.shift (zero where a law is monotone)."""
    shift = work.shift
    for i in range(shift.shape[0]):
        shift[i] = 0.0
    rod_friction.concave_shift(fric_p, v, work.fric_s, shift)
    valve.concave_shift(valve_p, v, shift)


@njit(cache=True)
def dc_solve(c, fric_p, valve_p, prog, model, state, work, nonmono, gas):
    """DC iterations of certified pattern solves (one pass when every law is monotone). Returns -1 when a
    sub-problem needs the QP (its data in work.wb/wlo/whi), else 1 if a correction was used, 0 if not."""
    c2 = c.beta * c.dt_s / c.gamma
    ksd, kso = model.ksd, model.kso
    v, vk, b, b0, shift = state.v, work.vk, work.b, work.b0, work.shift
    n = v.shape[0]
    p = prog[0]
    vp = valve_p[0]
    corrected = 0
    while True:
        if nonmono:
            concave_shift(fric_p, valve_p, vk, work)
            for i in range(n):
                b[i] = b0[i] + shift[i]
        else:
            for i in range(n):
                b[i] = b0[i]
        if p.have_qp != 0:
            for i in range(n):
                v[i] = work.wv[i]
            p.have_qp = 0
        else:
            nc = -1
            if c.always_qp == 0:
                nc = solve_pattern(ksd, kso, b, work.lo, work.hi, work.ns, state.status, v, work.lam, work.rhs,
                                   work.stuck, work.cp, work.dp, c.max_corrections, c.tol_v_m_s, c.tol_lambda)
            if nc < 0:
                for i in range(n):
                    work.wb[i] = b[i]
                    work.wlo[i] = work.lo[i]
                    work.whi[i] = work.hi[i]
                return -1
            if nc > 0:
                corrected = 1
        p.dc_iterations += 1
        if not nonmono:
            return corrected
        dv = 0.0
        for i in range(n):
            dv = max(dv, abs(v[i] - vk[i]))
            vk[i] = v[i]
        if dv <= c.dc_tol_m_s or p.dc_iterations >= c.dc_max_iterations:
            return corrected
        if gas:
            gas_spring.linearise(valve_p, ksd, b0, c2, vp.u_tilde_m + c2 * v[n - 1])


@njit(cache=True)
def reactions(valve_p, model, state, work, nonmono):
    """lam = b - K*v (exact for every node, whatever path produced v); the plunger's whole reaction
    includes the gas spring moved into K* and b, which is then taken out of K* again."""
    ksd, kso, v, b, lam, shift = model.ksd, model.kso, state.v, work.b, work.lam, work.shift
    n = v.shape[0]
    for i in range(n):
        kv = ksd[i] * v[i]
        if i > 0:
            kv += kso[i - 1] * v[i - 1]
        if i < n - 1:
            kv += kso[i] * v[i + 1]
        lam[i] = b[i] - kv - shift[i] if nonmono else b[i] - kv
    p = valve_p[0]
    if p.lin_dk != 0.0 or p.lin_shift_n != 0.0:
        lam[n - 1] += p.lin_shift_n + p.lin_dk * v[n - 1]
        ksd[n - 1] -= p.lin_dk
        p.lin_dk = 0.0
        p.lin_shift_n = 0.0


@njit(cache=True)
def update(c, model, state, work, out, ua_new, va_new, aa_new):
    """Newmark update of the free nodes, energy (trapezoidal work of each force over du: closes exactly
    for the trapezoidal rule), the polished-rod load and the element force envelope. Returns PRL_eq."""
    dt, beta, gamma = c.dt_s, c.beta, c.gamma
    c1 = 1.0 / (gamma * dt)
    c2 = beta * dt / gamma
    u, v, a, top, prev_v, prev_lam = state.u, state.v, state.a, state.top, state.prev_v, state.prev_lam
    lam, f, cd, energy = work.lam, model.f, model.cd, out.energy
    n = u.shape[0]
    ua_old = top[TOP_U]
    va_old = top[TOP_V]
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
    energy[E_GRAV] += c.top_load_n * du_a
    # polished-rod load from the top node's equation (includes its half element's weight/inertia)
    n0 = c.top_ea_len_n_m * (u[0] - ua_new)
    prl_eq = (n0 + c.top_load_n - c.top_mass_kg * aa_new - c.top_coupling_mass_kg * a[0]
              - c.top_damping_n_s_m * va_new)
    energy[E_TOP] += -0.5 * (prl_eq + top[TOP_PRL]) * du_a
    energy[E_VISC] += 0.5 * c.top_damping_n_s_m * (va_new + va_old) * du_a
    top[TOP_PRL] = prl_eq
    top[TOP_U] = ua_new
    top[TOP_V] = va_new
    top[TOP_A] = aa_new
    # element force envelope (equivalent force) for stress ranges per taper
    ea_len, emax, emin = model.ea_len, out.emax, out.emin
    ne = n0
    for e in range(n):
        if e > 0:
            ne = ea_len[e] * (u[e] - u[e - 1])
        emax[e] = max(emax[e], ne)
        emin[e] = min(emin[e], ne)
    return prl_eq


@njit(cache=True)
def book(c, valve_p, cnt, state, work, out, path, t_end, prl_eq):
    """Bookkeeping: path counts, stick episodes, statuses of smooth nodes and the per-step record."""
    v, ns, status, prev_stuck, stick = state.v, work.ns, state.status, state.prev_stuck, out.stick
    n = v.shape[0]
    k = cnt[0]
    if path == PATH_QP:
        k.qp += 1
    elif path == PATH_CORRECTED:
        k.corrected += 1
    else:
        k.certified += 1
    for i in range(n):
        s = ns[i] and v[i] == 0.0
        if s and not prev_stuck[i]:
            stick[i] += 1
        prev_stuck[i] = s
        if not ns[i]:
            status[i] = 1 if v[i] > 0 else (-1 if v[i] < 0 else 0)
    rec = out.rec
    if c.record != 0:
        r = k.recorded
        if r < rec.shape[1]:
            # recorded as users read them: positions and velocities upward, true loads
            top, u = state.top, state.u
            rec[R_T, r] = t_end
            rec[R_UA, r] = -top[TOP_U]
            rec[R_PRL, r] = prl_eq - c.top_pressure_force_n
            rec[R_UB, r] = -u[n - 1]
            rec[R_VB, r] = -v[n - 1] + 0.0  # + 0.0: an exact rest is 0.0, never -0.0
            rec[R_PUMP, r] = -work.lam[n - 1] - c.pump_pressure_force_n
            rec[R_PATH, r] = path
            rec[R_VA, r] = -top[TOP_V]
            k.recorded = r + 1


@njit(cache=True)
def events(valve_p, prog, state):
    """After the step: gas chamber valves, plunger extremes, and a plunger reversal (True: return EVENT;
    Progress.event = +1 the plunger turned down, top of stroke, -1 it turned up, bottom)."""
    u, v = state.u, state.v
    n = u.shape[0]
    if valve_p[0].gas_mode != 0:
        gas_spring.valves(valve_p, u[n - 1])
    p = prog[0]
    p.ub_max_m = max(p.ub_max_m, u[n - 1])
    p.ub_min_m = min(p.ub_min_m, u[n - 1])
    vb = v[n - 1]
    d = 1 if vb > 0 else (-1 if vb < 0 else 0)
    if d != 0 and d != p.plunger_dir:
        old = p.plunger_dir
        p.plunger_dir = d
        if old != 0:
            p.event = d
            return True
    return False


@njit(cache=True)
def advance(const, fric_p, valve_p, prog, cnt, model, side, state, work, out, va_t, t0, k_end):
    """Advance from step Progress.step to k_end; va_t[k] is the prescribed top velocity at the end of step
    k. Returns DONE, NEED_QP (work.wb/wlo/whi hold the sub-problem; the caller puts the solution in work.wv,
    sets Progress.have_qp and calls again) or EVENT (a plunger reversal, Progress.event)."""
    c = const[0]
    p = prog[0]
    vp = valve_p[0]
    dt = c.dt_s
    c2 = c.beta * dt / c.gamma
    n = state.u.shape[0]
    while p.step < k_end:
        k = p.step
        va_new = va_t[k]
        ua_new, aa_new = top_motion(c, state.top, va_new)
        predict(c, model, state, work, ua_new, aa_new)
        if p.have_qp == 0:
            if c.nonsmooth != 0:
                set_bounds(valve_p, model, side, state, work)
            p.dc_iterations = 0
            for i in range(n):
                work.vk[i] = state.prev_v[i]  # linearise j2 at v_n first
        # the chamber's gas: a stiff nonlinear spring on the plunger, taken implicitly by Newton passes (each
        # pass linearises it at the latest iterate's position u_B = u-tilde_B + c2 v_B, inside the DC loop)
        gas = vp.gas_on != 0 and c.nonsmooth != 0
        if gas:
            if p.have_qp == 0:
                vp.u_tilde_m = work.rhs[n - 1]
                model.ksd[n - 1] -= vp.lin_dk  # nothing is left from a previous step; kept for safety
                vp.lin_dk = 0.0
                vp.lin_shift_n = 0.0
                gas_spring.linearise(valve_p, model.ksd, work.b0, c2, state.u[n - 1])
            else:  # resumed after NEED_QP: b0 was rebuilt, K* still holds this pass's linearisation
                work.b0[n - 1] -= vp.lin_shift_n
        used_qp = p.have_qp != 0
        nonmono = fric_p[0].nonmonotone != 0 or vp.nonmonotone != 0 or gas
        corrected = dc_solve(c, fric_p, valve_p, prog, model, state, work, nonmono, gas)
        if corrected < 0:
            return NEED_QP
        cnt[0].dc_iterations += p.dc_iterations
        reactions(valve_p, model, state, work, nonmono)
        prl_eq = update(c, model, state, work, out, ua_new, va_new, aa_new)
        path = PATH_QP if used_qp else (PATH_CORRECTED if corrected > 0 else PATH_CERTIFIED)
        book(c, valve_p, cnt, state, work, out, path, t0 + (k + 1) * dt, prl_eq)
        p.step = k + 1
        if events(valve_p, prog, state):
            return EVENT
    return DONE
