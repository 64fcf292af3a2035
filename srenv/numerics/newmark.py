"""The Newmark relations of one free node, shared by every path of the kernel (kernel.py).

With h = dt (1 - gamma), q = dt^2 (1/2 - beta), c1 = 1 / (gamma dt), c2 = beta dt / gamma (kernel.newmark_coefficients):
the predicted velocity v-tilde = v + h a, the predicted displacement u-tilde = u + dt v + q a - c2 v-tilde, and
at the step's end u = u-tilde + c2 v_new, a = (v_new - v-tilde) c1. The order of the operations is part of
the kernel's results (tests/test_kernel_regression.py compares trajectories bit for bit).
"""

from __future__ import annotations

from numba import njit


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
