"""The floor of an exact implicit step on a mesh: what any Newmark step of the string must at least do.

:func:`floor_steps` is a numba loop doing only the Newmark predictor (the right-hand side b* = f + M/(gamma dt)
v-tilde - K u-tilde with the prescribed top's column moved over), one forward/back substitution of the
pre-factored tridiagonal K* and the Newmark update: the plain linear step, no laws, no certificate, no energy,
no record, no events. ``srenv bench`` times it next to the kernel on the same mesh and time step (one run) and
reports the kernel's cost over it, ``kernel.floor_ratio`` (docs/speed.md). It computes the linear string's
trajectory, the same as the kernel's ``nonsmooth=0`` path (tests/test_speed.py checks that to round-off).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from .kernel_layout import TOP_A, TOP_U, TOP_V


def factor(ksd: np.ndarray, kso: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """LU of the tridiagonal K* (no pivoting: K* is SPD): the super-diagonal multipliers cp and the pivots'
    reciprocals, so the substitution needs no division."""
    n = len(ksd)
    cp, inv = np.zeros(n), np.zeros(n)
    den = ksd[0]
    for i in range(n):
        if i > 0:
            den = ksd[i] - kso[i - 1] * cp[i - 1]
        inv[i] = 1.0 / den
        cp[i] = kso[i] * inv[i] if i < n - 1 else 0.0
    return cp, inv


@njit(cache=True)
def floor_steps(kd, ko, md, mo, f, kso, cp, inv, u, v, a, top, va_t, dt, beta, gamma, kc, mc, d):
    """Advance the linear string len(va_t) steps (u, v, a, top updated in place); d: scratch of n."""
    n = u.shape[0]
    c1 = 1.0 / (gamma * dt)
    c2 = beta * dt / gamma
    h = dt * (1.0 - gamma)
    q = dt * dt * (0.5 - beta)
    for k in range(va_t.shape[0]):
        va_new = va_t[k]
        vpa = top[TOP_V] + h * top[TOP_A]
        ua_new = top[TOP_U] + dt * top[TOP_V] + q * top[TOP_A] - c2 * vpa + c2 * va_new
        aa_new = (va_new - vpa) * c1
        # predictor and forward substitution in one sweep: row i of b* needs u-tilde and v-tilde at i+1
        vp_next = v[0] + h * a[0]
        ut_next = u[0] + dt * v[0] + q * a[0] - c2 * vp_next
        vp_prev = 0.0
        ut_prev = 0.0
        prev = 0.0
        for i in range(n):
            vp_i, ut_i = vp_next, ut_next
            b = f[i] + c1 * md[i] * vp_i - kd[i] * ut_i
            if i > 0:
                b += c1 * mo[i - 1] * vp_prev - ko[i - 1] * ut_prev
            else:
                b -= kc * ua_new + mc * aa_new
            if i < n - 1:
                vp_next = v[i + 1] + h * a[i + 1]
                ut_next = u[i + 1] + dt * v[i + 1] + q * a[i + 1] - c2 * vp_next
                b += c1 * mo[i] * vp_next - ko[i] * ut_next
            if i > 0:
                b -= kso[i - 1] * prev
            prev = b * inv[i]
            d[i] = prev
            vp_prev, ut_prev = vp_i, ut_i
        # back substitution and the Newmark update
        vn = 0.0
        for i in range(n - 1, -1, -1):
            vn = d[i] - cp[i] * vn if i < n - 1 else d[i]
            vpr = v[i] + h * a[i]
            u[i] = u[i] + dt * v[i] + q * a[i] - c2 * vpr + c2 * vn
            a[i] = (vn - vpr) * c1
            v[i] = vn
        top[TOP_U] = ua_new
        top[TOP_V] = va_new
        top[TOP_A] = aa_new
