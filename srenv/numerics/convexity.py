"""Convexity of the step problem with nonmonotone laws (design §2): each law gives its slope.

With j = j1 - j2 the step objective 1/2 v'K*v - b'v + j1(v) - j2(v) is convex iff K* - diag(s) is positive
definite, s_i = sup j2_i'' the steepest negative slope of node i's law (srenv.physics.laws: ``valve.slope`` at the
pump, ``rod_friction.slope`` on the rod). K* is tridiagonal, so its LDL' pivots decide it.

Violation is an error by default (``simulation.nonconvex_step: error``) and a warning with
``nonconvex_step: warn``, which runs anyway: each DC sub-problem (K* plus the convex j1) stays strictly
convex, and the iterations lower the step objective monotonically to a stationary point, i.e. a solution
of the step's hemivariational inequality. What is lost is uniqueness, so the result may depend on the
iteration start (v_n) and on dt. The message names the time step that restores convexity (K* grows like
M/(gamma dt)).
"""

from __future__ import annotations

import warnings
from collections.abc import Callable

import numpy as np

from ..config import ConfigError


def is_convex(diag: np.ndarray, off: np.ndarray, slope: np.ndarray) -> bool:
    """K* - diag(slope) positive definite (tridiagonal LDL' pivots)."""
    pivot = diag[0] - slope[0]
    for i in range(1, len(diag)):
        if pivot <= 0:
            return False
        pivot = diag[i] - slope[i] - off[i - 1] ** 2 / pivot
    return pivot > 0


def check(slope: np.ndarray, kstar: Callable[[float], tuple[np.ndarray, np.ndarray]], dt_s: float,
          nonconvex_step: str) -> None:
    """Raise (``nonconvex_step`` 'error') or warn when K*(dt) - diag(slope) is not positive definite."""
    if not np.any(slope > 0):
        return

    def convex(step_s: float) -> bool:
        return is_convex(*kstar(step_s), slope)

    if convex(dt_s):
        return
    lo_dt, hi_dt = 0.0, dt_s  # K*(dt) - diag(s) is positive definite for a small enough dt: bisect
    for _ in range(60):
        mid = 0.5 * (lo_dt + hi_dt)
        lo_dt, hi_dt = (mid, hi_dt) if convex(mid) else (lo_dt, mid)
    node_i = int(np.argmax(slope))
    where = "the pump" if node_i == len(slope) - 1 else f"rod node {node_i + 1}"
    why = (f"K* - diag(law slopes) is not positive definite; steepest slope {slope[node_i]:.4g} N*s/m at "
           f"{where}")
    if nonconvex_step == "error":
        raise ConfigError("simulation.time_step_s", dt_s,
                          f"a time step in s below {lo_dt:.3g} (the step problem is not convex: {why}; "
                          "set simulation.nonconvex_step: warn to run the DC iterations anyway)")
    warnings.warn(
        f"simulation.time_step_s = {dt_s:g} s: the step problem is not convex ({why}). DC iterations "
        f"still converge to a stationary point of each step, but it may not be unique. A time step "
        f"below {lo_dt:.3g} s restores convexity.", UserWarning, stacklevel=5)
