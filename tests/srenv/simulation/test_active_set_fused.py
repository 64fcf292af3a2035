"""The certified pattern solve in two sweeps (srenv/numerics/active_set.py) against the three-pass form it replaced
(pattern right-hand side, `thomas_pattern`, then the certificate), bit for bit: solution, multipliers, statuses,
correction count, on random tridiagonal Stieltjes systems with every kind of pattern and node."""

from __future__ import annotations

import numpy as np
import pytest

from srenv.numerics.active_set import solve_pattern, thomas_pattern


def reference(ksd, kso, b, lo, hi, ns, status, v, lam, rhs, stuck, cp, dp, maxcorr, tolv, toll):
    """The solve as it was before the sweeps were fused (commit f04a69e), in plain Python."""
    n = len(ksd)
    for it in range(maxcorr + 1):
        for i in range(n):
            if ns[i] and status[i] == 0:
                stuck[i] = True
                rhs[i] = 0.0
            else:
                stuck[i] = False
                lam[i] = (hi[i] if status[i] > 0 else lo[i]) if ns[i] else lo[i]
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
                    status[i], ok = 1, False
                elif lam[i] < lo[i] - scale:
                    status[i], ok = -1, False
            elif status[i] > 0:
                if v[i] < -tolv:
                    status[i], ok = 0, False
            elif v[i] > tolv:
                status[i], ok = 0, False
        if ok:
            for i in range(n):
                if ns[i] and status[i] == 0:
                    v[i] = 0.0
            return it
    return -1


@pytest.mark.parametrize("n", [1, 2, 3, 42])
@pytest.mark.parametrize("seed", range(40))
def test_fused_solve_matches_the_three_pass_solve_bit_for_bit(n: int, seed: int) -> None:
    rng = np.random.default_rng(seed)
    kso = -rng.uniform(1e3, 1e7, n)
    kso[-1] = 0.0
    ksd = np.abs(kso) + np.abs(np.r_[0.0, kso[:-1]]) + rng.uniform(1.0, 1e5, n)  # diagonally dominant
    b = rng.normal(0.0, 1e4, n)
    f = rng.uniform(0.0, 3e4, n) * (rng.random(n) < 0.8)
    lo, hi = -f, f
    ns = f > 0.0
    if rng.random() < 0.5:  # a one-sided (valve-like) interval on the last node
        lo[-1], hi[-1], ns[-1] = -2e4, -5e3, True
    status0 = rng.integers(-1, 2, n).astype(np.int64)
    maxcorr = int(rng.integers(0, 6))
    results = []
    for solve in (solve_pattern, reference):
        st = status0.copy()
        arrays = [np.zeros(n) for _ in range(3)]
        v, lam, rhs = arrays
        stuck, cp, dp = np.zeros(n, bool), np.zeros(n), np.zeros(n)
        code = solve(ksd, kso, b, lo, hi, ns, st, v, lam, rhs, stuck, cp, dp, maxcorr, 1e-12, 1e-10)
        results.append((code, st, v, lam, rhs, stuck, cp, dp))
    (c1, *a1), (c2, *a2) = results
    assert c1 == c2
    for x, y in zip(a1, a2):
        assert np.array_equal(x, y) and np.array_equal(np.signbit(x), np.signbit(y))
