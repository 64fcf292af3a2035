"""The step problem's certified active-set solve (design §3; the kernel's inner solve).

Given a pattern (each nonsmooth node sliding down, sliding up or stuck) the KKT system of
    min_v  1/2 v'K*v - b'v + sum_i j_i(v_i),   j_i(v) = sup{lam v : lam in [lo_i, hi_i]}
is one tridiagonal solve (stuck rows replaced by v_i = 0). If its solution satisfies the sign and
interval conditions it *is* the unique minimiser ("certified"); otherwise the violating nodes are flipped
(primal-dual active set; K* is a Stieltjes matrix, for which this converges) and the solve is repeated.
"""

from __future__ import annotations

from numba import njit


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
    Each pass is two sweeps: the pattern's right-hand side inside the forward elimination, the certificate
    inside the back substitution (node i+1's conditions once v_i is known). The arithmetic is
    :func:`thomas_pattern`'s after a separate right-hand-side pass and followed by a separate check pass,
    operation for operation (tests/srenv/numerics/test_active_set_fused.py).
    """
    n = ksd.shape[0]
    for it in range(maxcorr + 1):
        # forward sweep: the pattern's rhs and the elimination (stuck rows: v_i = 0)
        cprev = 0.0
        dprev = 0.0
        nstuck = 0
        for i in range(n):
            nsi = ns[i]
            st = status[i]
            if nsi and st == 0:
                stuck[i] = True
                rhs[i] = 0.0
                cp[i] = 0.0
                dp[i] = 0.0
                cprev = 0.0
                dprev = 0.0
                nstuck += 1
                continue
            stuck[i] = False
            if nsi:
                li = hi[i] if st > 0 else lo[i]
            else:
                li = lo[i]
            lam[i] = li
            r = b[i] - li
            rhs[i] = r
            if i == 0:
                cprev = kso[0] / ksd[0] if n > 1 else 0.0
                dprev = r / ksd[0]
            else:
                a = kso[i - 1]
                den = ksd[i] - a * cprev
                cprev = (kso[i] / den) if i < n - 1 else 0.0
                dprev = (r - a * dprev) / den
            cp[i] = cprev
            dp[i] = dprev
        # back substitution; the certificate of node j = i + 1 once v_i is known
        ok = True
        vn = 0.0  # v[j]
        vnn = 0.0  # v[j + 1]
        for i in range(n - 1, -2, -1):
            vi = 0.0
            if i >= 0:
                vi = dp[i] - cp[i] * vn if i < n - 1 else dp[i]
                v[i] = vi
            j = i + 1
            if j < n and ns[j]:
                sj = status[j]
                if sj == 0:
                    kv = ksd[j] * vn
                    if j > 0:
                        kv += kso[j - 1] * vi
                    if j < n - 1:
                        kv += kso[j] * vnn
                    lj = b[j] - kv
                    lam[j] = lj
                    scale = toll * (abs(lo[j]) + abs(hi[j]) + 1.0)
                    if lj > hi[j] + scale:
                        status[j] = 1
                        ok = False
                    elif lj < lo[j] - scale:
                        status[j] = -1
                        ok = False
                elif sj > 0:
                    if vn < -tolv:
                        status[j] = 0
                        ok = False
                else:
                    if vn > tolv:
                        status[j] = 0
                        ok = False
            vnn = vn
            vn = vi
        if ok:
            if nstuck > 0:
                for i in range(n):
                    if ns[i] and status[i] == 0:
                        v[i] = 0.0  # exact rest
            return it
    return -1
