"""Deviation survey: inclination, azimuth, true vertical depth and curvature along measured depth.

Inclination and azimuth vary linearly in measured depth between stations (constant build/turn rate per
interval), so ``dalpha/ds`` is piecewise constant. An empty station table is a vertical well.
"""

from __future__ import annotations

import math
from bisect import bisect_right
from dataclasses import dataclass

import numpy as np

from ..config import SurveyConfig


@dataclass(frozen=True)
class Survey:
    md_m: np.ndarray
    inclination_rad: np.ndarray
    azimuth_rad: np.ndarray

    @classmethod
    def from_config(cls, cfg: SurveyConfig, rod_length_m: float) -> Survey:
        if not cfg.stations:
            z = np.zeros(2)
            return cls(np.array([0.0, rod_length_m]), z, z)
        md = np.array([s.md_m for s in cfg.stations], dtype=float)
        inc = np.radians([s.inclination_deg for s in cfg.stations])
        azi = np.radians([s.azimuth_deg for s in cfg.stations])
        if len(md) == 1:
            md, inc, azi = np.r_[md, rod_length_m], np.r_[inc, inc], np.r_[azi, azi]
        return cls(md, inc, azi)

    def inclination(self, s_m: np.ndarray) -> np.ndarray:
        return np.interp(s_m, self.md_m, self.inclination_rad)

    def azimuth(self, s_m: np.ndarray) -> np.ndarray:
        return np.interp(s_m, self.md_m, self.azimuth_rad)

    def _rate(self, values: np.ndarray, s_m: np.ndarray) -> np.ndarray:
        rates = np.diff(values) / np.diff(self.md_m)
        # a node on a station gets the mean of the two intervals' rates (tributary average)
        left = np.clip(np.searchsorted(self.md_m, s_m, side="left") - 1, 0, len(rates) - 1)
        right = np.clip(np.searchsorted(self.md_m, s_m, side="right") - 1, 0, len(rates) - 1)
        return 0.5 * (rates[left] + rates[right])

    def build_rate(self, s_m: np.ndarray) -> np.ndarray:
        """dalpha/ds in rad/m."""
        return self._rate(self.inclination_rad, s_m)

    def turn_rate(self, s_m: np.ndarray) -> np.ndarray:
        """dphi/ds in rad/m."""
        return self._rate(self.azimuth_rad, s_m)

    def __post_init__(self) -> None:
        # TVD table, integrated once: cos(inclination) by the trapezoid rule on a fine grid
        grid = np.unique(np.r_[np.linspace(0.0, self.md_m[-1], 2001), self.md_m])
        cos = np.cos(self.inclination(grid))
        z = np.r_[0.0, np.cumsum(0.5 * (cos[1:] + cos[:-1]) * np.diff(grid))]
        object.__setattr__(self, "_tvd_table", (grid, z))
        object.__setattr__(self, "_tvd_lists", (grid.tolist(), z.tolist()))

    def tvd(self, s_m: np.ndarray | float) -> np.ndarray:
        """True vertical depth at measured depth s_m."""
        grid, z = self._tvd_table
        return np.interp(s_m, grid, z)

    def tvd_at(self, s_m: float) -> float:
        """:meth:`tvd` of one depth without numpy's per-call cost (the annulus asks at every stroke the env
        fast-forwards): the same arithmetic as ``np.interp`` (the interval's slope times the offset from its
        left end, the ends held), so the same bits (tests/srenv/physics/test_pump_inputs.py)."""
        grid, z = self._tvd_lists
        x = float(s_m)
        j = bisect_right(grid, x) - 1
        if math.isnan(x):
            return x
        if j < 0 or j >= len(grid) - 1 or grid[j] == x:
            return z[min(max(j, 0), len(grid) - 1)]
        slope = (z[j + 1] - z[j]) / (grid[j + 1] - grid[j])
        return slope * (x - grid[j]) + z[j]

    def tvd_beyond(self, s_m: float) -> float:
        """True vertical depth at s_m, also below the last station (a pump set deeper than the survey or the
        rods reach): the last station's inclination is held there."""
        end = float(self.md_m[-1])
        return float(self.tvd(min(s_m, end))) + max(s_m - end, 0.0) * float(np.cos(self.inclination_rad[-1]))
