"""The annulus level and the active condition a deployable controller can estimate from the field observation
(issue 24, helper s24).

:class:`LevelObserver` is a scalar Kalman filter on the liquid column above the pump (m). Between acoustic shots it
runs an inflow balance, ``d level = (prod * ipr(level) * dt - pumped) / area``: ``ipr`` is a model's inflow at
the reservoir's nominal deliverability, ``prod`` the deliverability estimated online and ``pumped`` the model
pump's displacement times the real card's fillage estimate. It is corrected

* at each acoustic shot (the shot is the level; its small variance is the shot's);
* on a pounding card (the pump drew the annulus down to the intake): a pseudo-shot of the liquid that came in
  during the interval's trailing idle time;
* on a full card while the estimate is below ``floor_m`` (the intake is submerged): lifted to the floor.

``prod`` is re-estimated at each shot from the balance since the previous one, ``(area * d level + pumped) /
integral of ipr dt``, clipped and blended with weight ``gain`` (default :data:`PROD_GAIN`; a shot-to-shot estimate
is noisy: a pounding pump's card fillage is an estimate too). Nothing here reads a simulator's hidden state: the caller hands it observations and a model's
``ipr`` and displacement.

:func:`condition_estimate` is the classifier's most probable non-normal label above a threshold, at the middle of
its severity range (srenv.task.events.EVENTS; 0.5 where no range is drawn), or None.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence

import numpy as np

from srenv.task.events import EVENTS, NORMAL

PROD_RANGE = (0.1, 5.0)   # deliverability multipliers the balance may give (the v2 schedule stays well inside)
PROD_GAIN = 0.5           # weight of a new shot-to-shot estimate against the running one (the default)
GAIN_RANGE = (0.0, 1.0)   # ``gain`` bounds: (0, 1] - 1 takes each shot-to-shot estimate as it is
SHOT_VAR_M2 = 1.0         # an acoustic shot's level error (m^2): the env's shot is the level at the shot
POUND_VAR_M2 = 25.0       # a pounding card: the level is near the intake, up to a few metres of liquid
INFLOW_REL_SD = 0.3       # process noise: the inflow's relative error per interval
NOT_IN_TWIN = ("parted_rods",)  # its physics is the episode's end: nothing a plan can act on


class LevelObserver:
    def __init__(self, area_m2: float, depth_m: float, ipr: Callable[[float], float], level_m: float,
                 prod: float = 1.0, floor_m: float = 0.0, gain: float = PROD_GAIN) -> None:
        if not (area_m2 > 0 and depth_m > 0 and math.isfinite(level_m)):
            raise ValueError(f"LevelObserver: area {area_m2!r} m2, depth {depth_m!r} m, level {level_m!r} m: "
                             "expected positive area and depth and a finite level")
        self.gain = check_gain(gain, "LevelObserver gain")
        self.area_m2, self.depth_m, self.ipr, self.floor_m = float(area_m2), float(depth_m), ipr, float(floor_m)
        self.level_m = float(np.clip(level_m, 0.0, depth_m))
        self.var_m2 = SHOT_VAR_M2
        self.prod = float(prod)
        self._shot_level, self._inflow1_m3, self._pumped_m3 = self.level_m, 0.0, 0.0

    def advance(self, dt_s: float, pumped_m3: float) -> float:
        """One interval of ``dt_s`` in which the pump delivered ``pumped_m3`` from the annulus; the new level."""
        q1 = max(float(self.ipr(self.level_m)), 0.0) * dt_s  # inflow at nominal deliverability
        self._inflow1_m3 += q1
        self._pumped_m3 += max(pumped_m3, 0.0)
        self.level_m = float(np.clip(self.level_m + (self.prod * q1 - pumped_m3) / self.area_m2, 0.0, self.depth_m))
        self.var_m2 += (INFLOW_REL_SD * self.prod * q1 / self.area_m2) ** 2 + (0.1 * pumped_m3 / self.area_m2) ** 2
        return self.level_m

    def _update(self, z_m: float, var_m2: float) -> None:
        k = self.var_m2 / (self.var_m2 + var_m2)
        self.level_m = float(np.clip(self.level_m + k * (z_m - self.level_m), 0.0, self.depth_m))
        self.var_m2 = (1.0 - k) * self.var_m2

    def shot(self, level_m: float) -> None:
        """An acoustic shot: the deliverability from the balance since the last shot, then the level corrected."""
        if self._inflow1_m3 > 1e-6:
            est = (self.area_m2 * (level_m - self._shot_level) + self._pumped_m3) / self._inflow1_m3
            est = float(np.clip(est, *PROD_RANGE))
            self.prod = (1.0 - self.gain) * self.prod + self.gain * est
        self._update(float(level_m), SHOT_VAR_M2)
        self._shot_level, self._inflow1_m3, self._pumped_m3 = float(level_m), 0.0, 0.0

    def card(self, fillage_est: float, idle_s: float, pounded: float, full: float) -> None:
        """The real card: pounding -> the level near the intake (plus the trailing idle time's inflow); full while
        the estimate is below the floor -> lifted to it."""
        if fillage_est < pounded:
            refill = self.prod * max(float(self.ipr(0.0)), 0.0) * max(idle_s, 0.0) / self.area_m2
            self._update(min(refill, self.depth_m), POUND_VAR_M2)
        elif fillage_est >= full and self.level_m < self.floor_m:
            self.level_m = self.floor_m


def check_gain(gain: object, field: str) -> float:
    """A deliverability gain in :data:`GAIN_RANGE` (low excluded), or one line naming ``field``, the value and the
    range."""
    lo, hi = GAIN_RANGE
    if isinstance(gain, bool) or not isinstance(gain, (int, float)) or not lo < gain <= hi:
        raise ValueError(f"{field} = {gain!r}: expected a number in ({lo:g}, {hi:g}]")
    return float(gain)


def condition_estimate(obs: np.ndarray, names: Sequence[str], threshold: float) -> tuple[str | None, float]:
    """The classifier's most probable non-normal label whose probability exceeds ``threshold`` and the middle of
    its severity range, or ``(None, 0.0)``."""
    probs = {n[5:]: float(obs[i]) for i, n in enumerate(names) if n.startswith("prob_")}
    probs = {k: p for k, p in probs.items() if k not in NORMAL and k not in NOT_IN_TWIN}
    if not probs:
        return None, 0.0
    label = max(probs, key=probs.__getitem__)
    if probs[label] <= threshold:
        return None, 0.0
    spec = EVENTS.get(label)
    return label, (0.5 * sum(spec.severity) if spec is not None else 0.5)
