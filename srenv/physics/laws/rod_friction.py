"""Rod-on-tubing friction: Coulomb or velocity-weakening mu(v) times the side force from the survey.

The side force at rod node i with tributary length l_i, buoyed weight per length w_b, inclination a,
build rate da/ds, turn rate dphi/ds and the node's axial force N (equivalent force, quasi-variational:
the previous step's) is
    F_i = mu l_i sqrt((w_b sin a - N da/ds)^2 + (N sin a dphi/ds)^2) = sqrt((weight - axial N)^2 + (turn N)^2)
with the three coefficients per node of :class:`SideForce`. The law's interval is [-F_i, F_i] (Coulomb,
static coefficient mu_s); the velocity-weakening law mu(v) = mu_k + (mu_s - mu_k) exp(-|v|/v0) is
j = j1 - j2 with j1 the static Coulomb law and j2'(v) = (1 - mu_k/mu_s) F_i (1 - exp(-|v|/v0)) sign v.
The pump node (the last one) carries no rod friction.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba import njit

# the law's constants: kinetic/static ratio mu_k/mu_s, reference velocity v0 (m/s), 1 if velocity-weakening
PARAMS = np.dtype([("ratio", np.float64), ("v0_m_s", np.float64), ("nonmonotone", np.int64)])


class SideForce(NamedTuple):
    """Per free node: F = sqrt((weight_n - axial * N)^2 + (turn * N)^2) with N the node's axial force (N)."""

    axial: np.ndarray    # mu l_i da/ds (1): the axial force pressing the rod into the build's curvature
    weight_n: np.ndarray  # mu l_i w_b sin(a) (N): the buoyed weight's normal component
    turn: np.ndarray     # mu l_i sin(a) dphi/ds (1): the axial force in the turn's curvature


def side_force(mu: float, tributary_m, build_rad_m, weight_n_m, incl_rad, turn_rad_m) -> SideForce:
    """The coefficients at every mesh node but the top (free nodes); the pump node gets none."""
    axial = (mu * tributary_m * build_rad_m)[1:].copy()
    weight = (mu * tributary_m * weight_n_m * np.sin(incl_rad))[1:].copy()
    turn = (mu * tributary_m * np.sin(incl_rad) * turn_rad_m)[1:].copy()
    axial[-1] = weight[-1] = turn[-1] = 0.0  # the pump node carries the valve law only
    return SideForce(axial, weight, turn)


def make(static_coefficient: float, kinetic_coefficient: float, reference_velocity_m_s: float,
         weakening: bool) -> np.ndarray:
    """The parameter record of the law (``weakening``: the velocity-weakening law is asked for)."""
    p = np.zeros(1, PARAMS)
    p["ratio"] = kinetic_coefficient / static_coefficient if static_coefficient > 0 else 1.0
    p["v0_m_s"] = reference_velocity_m_s
    p["nonmonotone"] = int(weakening and static_coefficient > kinetic_coefficient)
    return p


def slope(side: SideForce, node_force_n: np.ndarray, params: np.ndarray) -> np.ndarray:
    """sup j2'' per free node, (1 - mu_k/mu_s) F_i / v0, for a given axial force per node (N)."""
    p = params[0]
    if not p["nonmonotone"]:
        return np.zeros(len(side.axial))
    f = np.hypot(side.weight_n - side.axial * node_force_n, side.turn * node_force_n)
    f[-1] = 0.0
    return (1.0 - p["ratio"]) * f / p["v0_m_s"]


@njit(cache=True, inline="always")
def bounds(axial, weight, turn, nforce, lo, hi, ns, fric_s):
    """The interval [-F_i, F_i] on the rod nodes (all but the last) from the axial forces `nforce` and the
    SideForce coefficients; F_i is kept in fric_s for the concave part."""
    n = lo.shape[0]
    for i in range(n - 1):
        nn = nforce[i]
        q1 = weight[i] - axial[i] * nn
        q2 = turn[i] * nn
        f = np.sqrt(q1 * q1 + q2 * q2)
        fric_s[i] = f
        lo[i] = -f
        hi[i] = f
        ns[i] = f > 0.0
    fric_s[n - 1] = 0.0


@njit(cache=True, inline="always")
def concave_shift(params, v, fric_s, shift):
    """j2'(v) on the rod nodes (velocity-weakening law only; the kernel zeroed `shift`)."""
    p = params[0]
    if p.nonmonotone == 0:
        return
    d = 1.0 - p.ratio
    v0 = p.v0_m_s
    for i in range(v.shape[0] - 1):
        vi = v[i]
        if vi > 0:
            shift[i] = d * fric_s[i] * (1.0 - np.exp(-vi / v0))
        elif vi < 0:
            shift[i] = -d * fric_s[i] * (1.0 - np.exp(vi / v0))
