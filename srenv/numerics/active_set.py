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
