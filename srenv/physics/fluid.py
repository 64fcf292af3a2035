"""Produced fluid in the tubing: hydrostatic pressure and buoyancy along the string."""

from __future__ import annotations

import numpy as np

from ..config import FluidConfig
from .rod import GRAVITY_M_S2


def tubing_pressure_pa(fluid: FluidConfig, tvd_m: np.ndarray | float) -> np.ndarray | float:
    """p = p_wh + rho_f g TVD: the pressure that turns N into N_eq = N + p A."""
    return fluid.wellhead_pressure_pa + fluid.density_kg_m3 * GRAVITY_M_S2 * tvd_m
