"""Reward of the sucker-rod env: production minus stick-slip and peak-load penalties (weights in config).

    w = step duration / reference_duration_s
    reward_production = w * production_weight * production_m3_day / production_scale_m3_day
    reward_stick_slip = -w * stick_slip_weight * stick_slip_index
    reward_peak_load  = -w * peak_load_weight * [(PPRL / pprl_rating)^2
                                                + relu(Goodman_max - goodman_limit) / 100
                                                + relu(gearbox_loading - 100) / 100]
    reward_failure    = -failure_penalty on rod failure or solver failure, else 0

The squared PPRL term prices peak load everywhere (so the same production at a lower peak load is
better), the relu terms price exceeding a rating. Every rate term is weighted by the step's duration, so
an episode's return is a time integral: a slow 20 s stroke earns twice what a 10 s stroke at the same
rate earns, and alternating slow and fast strokes gains nothing over pumping steadily (with per-stroke
rates it would). reward = sum of the four terms (tested).
"""

from __future__ import annotations

from ..config import RewardConfig


class SuckerRodReward:
    def __init__(self, cfg: RewardConfig) -> None:
        self.cfg = cfg

    def terms(self, metrics: dict, failed: bool) -> dict[str, float]:
        c = self.cfg
        overload = (max(0.0, metrics["goodman_max_pct"] - c.goodman_limit_pct)
                    + max(0.0, metrics.get("gearbox_loading_pct", 0.0) - 100.0)) / 100.0
        w = metrics["duration_s"] / c.reference_duration_s
        return {
            "reward_production": w * c.production_weight * metrics["production_m3_day"] / c.production_scale_m3_day,
            "reward_stick_slip": -w * c.stick_slip_weight * metrics["stick_slip_index"],
            "reward_peak_load": -w * c.peak_load_weight * ((metrics["pprl_n"] / c.pprl_rating_n) ** 2 + overload),
            "reward_failure": -c.failure_penalty if failed else 0.0,
        }


class RodFailureMonitor:
    """Constraint monitor: rod failure = Goodman loading beyond the failure limit in any taper."""

    def __init__(self, cfg: RewardConfig) -> None:
        self.cfg = cfg

    def failure(self, metrics: dict) -> str | None:
        g = metrics["goodman_max_pct"]
        if g > self.cfg.failure_goodman_pct:
            return f"rod failure: Goodman loading {g:.1f} % > {self.cfg.failure_goodman_pct:.1f} %"
        return None
