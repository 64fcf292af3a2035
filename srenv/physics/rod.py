"""Tapered rod string: finite-element mesh, stiffness, mass and damping.

Linear two-node elements, nodes numbered top-down (node 0 = polished rod A, node n = pump B). Matrices
are tridiagonal and kept as (diagonal, off-diagonal) vectors; the integrator never builds a dense matrix.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..config import DampingConfig, RodConfig

GRAVITY_M_S2 = 9.80665


@dataclass(frozen=True)
class Mesh:
    x_m: np.ndarray            # node measured depths, shape (n+1,)
    length_m: np.ndarray       # element lengths, shape (n,)
    area_m2: np.ndarray        # element cross-section
    ea_n: np.ndarray           # element axial stiffness E*A
    rho_a_kg_m: np.ndarray     # element mass per length (rod + couplings)
    taper: np.ndarray          # element -> taper index
    damping_scale: np.ndarray | None = None  # per taper (rod.tapers[i].damping_scale); None = all 1
    coupling_area_m2: np.ndarray | None = None  # steel beyond the body per length (couplings); None = none

    @property
    def n_nodes(self) -> int:
        return len(self.x_m)

    def node_area_m2(self) -> np.ndarray:
        """Area at each node (the lower element's, the last node takes the last element's)."""
        return np.r_[self.area_m2, self.area_m2[-1]]

    def tributary_m(self) -> np.ndarray:
        half = 0.5 * self.length_m
        return np.r_[half, 0.0] + np.r_[0.0, half]


def build_mesh(rod: RodConfig, element_length_m: float) -> Mesh:
    xs, lens, areas, ea, rhoa, taper, extra = [0.0], [], [], [], [], [], []
    for k, t in enumerate(rod.tapers):
        n = max(1, math.ceil(t.length_m / element_length_m - 1e-9))
        h = t.length_m / n
        area = math.pi / 4 * (t.diameter_mm * 1e-3) ** 2
        for _ in range(n):
            xs.append(xs[-1] + h)
            lens.append(h)
            areas.append(area)
            ea.append(t.youngs_modulus_pa * area)
            rhoa.append(t.density_kg_m3 * area + t.coupling_mass_kg_per_m)
            extra.append(t.coupling_mass_kg_per_m / t.density_kg_m3)  # the couplings' steel volume per length
            taper.append(k)
    scale = np.array([t.damping_scale for t in rod.tapers], dtype=float)
    return Mesh(np.array(xs), np.array(lens), np.array(areas), np.array(ea), np.array(rhoa), np.array(taper),
                scale if np.any(scale != 1.0) else None, np.array(extra) if any(extra) else None)


def coupling_buoyancy_n_m(mesh: Mesh, fluid_density_kg_m3: float) -> np.ndarray:
    """The buoyancy of the couplings per length of each element, rho_f g V_c (V_c = coupling mass / steel
    density), before the survey's cos. The FE's pressure-area terms give the rod body's buoyancy, rho_f g A;
    the fluid pushing on a coupling's two shoulders, a coupling length apart, adds its own volume's (all the
    steel displaces liquid: buoyed weight = air weight (1 - rho_f / rho_s)). Zeros without couplings, so the
    callers' arithmetic is unchanged there (docs/realism.md, "The static load budget")."""
    if mesh.coupling_area_m2 is None:
        return np.zeros_like(mesh.area_m2)
    return fluid_density_kg_m3 * GRAVITY_M_S2 * mesh.coupling_area_m2


def tridiag_assemble(elem: np.ndarray, diag_w: float, off_w: float) -> tuple[np.ndarray, np.ndarray]:
    """Assemble per-element 2x2 blocks elem*[[diag_w, off_w], [off_w, diag_w]] into (diag, off)."""
    d = np.zeros(len(elem) + 1)
    d[:-1] += diag_w * elem
    d[1:] += diag_w * elem
    return d, off_w * elem.copy()


def solve_tridiagonal(diag: np.ndarray, off: np.ndarray, rhs: np.ndarray) -> np.ndarray:
    """Solve the symmetric tridiagonal system (diag, off) x = rhs (rhs may have several columns)."""
    from scipy.linalg import solve_banded

    ab = np.zeros((3, len(diag)))
    ab[0, 1:], ab[1], ab[2, :-1] = off, diag, off
    return solve_banded((1, 1), ab, rhs)


def stiffness(mesh: Mesh) -> tuple[np.ndarray, np.ndarray]:
    return tridiag_assemble(mesh.ea_n / mesh.length_m, 1.0, -1.0)


def mass(mesh: Mesh, kind: str) -> tuple[np.ndarray, np.ndarray]:
    m = mesh.rho_a_kg_m * mesh.length_m
    if kind == "lumped":
        return tridiag_assemble(m, 0.5, 0.0)
    return tridiag_assemble(m, 1.0 / 3.0, 1.0 / 6.0)


def wave_speed_m_s(mesh: Mesh) -> np.ndarray:
    return np.sqrt(mesh.ea_n / mesh.rho_a_kg_m)


def damping_per_length(mesh: Mesh, cfg: DampingConfig) -> np.ndarray:
    """Viscous coefficient c per unit length of each element, in N*s/m^2.

    ``dimensionless`` (Gibbs): c = rho*A * pi*a*nu/(2L), a = travel-time-averaged wave speed, so that nu is
    the fraction of critical damping of the first mode of a uniform rod.
    ``annulus_shear``: laminar Couette flow between rod (radius r) and tubing (radius R):
    c = 2*pi*mu / ln(R/r).
    """
    c = _damping_per_length(mesh, cfg)
    if mesh.damping_scale is not None:  # per-taper factors (1 everywhere leaves c untouched)
        c = c * mesh.damping_scale[mesh.taper]
    return c


def _damping_per_length(mesh: Mesh, cfg: DampingConfig) -> np.ndarray:
    if cfg.model == "none":
        return np.zeros(len(mesh.length_m))
    if cfg.model == "dimensionless":
        total = mesh.length_m.sum()
        a_eff = total / np.sum(mesh.length_m / wave_speed_m_s(mesh))
        return mesh.rho_a_kg_m * math.pi * a_eff * cfg.damping_factor / (2 * total)
    r_rod = np.sqrt(mesh.area_m2 / math.pi)
    r_tub = 0.5e-3 * cfg.tubing_inner_diameter_mm
    return 2 * math.pi * cfg.fluid_viscosity_pa_s / np.log(r_tub / r_rod)


def damping(mesh: Mesh, cfg: DampingConfig) -> tuple[np.ndarray, np.ndarray]:
    """Lumped damping (diagonal) from the per-length coefficient."""
    return tridiag_assemble(damping_per_length(mesh, cfg) * mesh.length_m, 0.5, 0.0)


def first_natural_frequency_hz(mesh: Mesh, mass_kind: str = "lumped") -> float:
    """Top fixed, bottom free: lowest eigenvalue of K u = w^2 M u (free nodes only)."""
    from scipy.linalg import eigh_tridiagonal

    kd, ko = stiffness(mesh)
    md, mo = mass(mesh, mass_kind)
    kd, ko, md, mo = kd[1:], ko[1:], md[1:], mo[1:]
    if np.any(mo):
        from scipy.linalg import eigh

        k = np.diag(kd) + np.diag(ko, 1) + np.diag(ko, -1)
        m = np.diag(md) + np.diag(mo, 1) + np.diag(mo, -1)
        w2 = eigh(k, m, eigvals_only=True, subset_by_index=[0, 0])[0]
    else:
        s = 1 / np.sqrt(md)  # symmetric scaling M^-1/2 K M^-1/2 stays tridiagonal
        w2 = eigh_tridiagonal(kd * s * s, ko * s[:-1] * s[1:], eigvals_only=True,
                              select="i", select_range=(0, 0))[0]
    return float(np.sqrt(w2) / (2 * math.pi))
