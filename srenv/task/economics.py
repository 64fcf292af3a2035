"""The v1 reward: the well's economics in USD per hour of well time, and the constraint cost.

Every term is a rate averaged over the control interval (USD/h), so an episode's mean reward is the well's
mean profit rate and the return is the profit over the horizon divided by the interval in hours. With
``v = oil_price (1 - water_cut) - water_handling water_cut`` the net value of a cubic metre of liquid:

| term | USD/h | meaning |
|---|---|---|
| ``reward_revenue`` | ``v Q_lifted / h`` | liquid lifted to surface and sold |
| ``reward_inventory`` | ``v (V_end - V_start) / h`` | value of the change of liquid stored in the annulus: drawing the
  annulus down earns nothing net (it was going to be sold anyway), so the horizon cannot reward draining it. Revenue
  + inventory = the value of what the *reservoir* delivered, which the controller raises by keeping the level low. |
| ``reward_energy`` | ``-price_kWh max(W, 0) / (eta 3.6e6) / h`` | electricity: polished-rod (card) work W through the motor |
| ``reward_fatigue`` | ``-workover sum_strokes (G/100)^m / N_life / h`` | rod fatigue (Miner's rule on the Goodman loading G)|
| ``reward_stick_slip`` | ``-c_ss E_ss / h`` | elastic energy released by extra plunger stops (0 when smooth) |
| ``reward_peak_load`` | ``-c_ol f_pump [relu(PPRL/R - 1)^2 + relu(G/100 - 1)^2 + relu(GB/100 - 1)^2]`` | over a rating |
| ``reward_pound`` | ``-c_p sum_strokes v_impact^2 / h`` | fluid pound: plunger speed when it meets the liquid |
| ``reward_ramp`` | ``-c_r (d avg_spm)^2 / h`` | VSD ramp between intervals (no stroke-to-stroke chatter) |
| ``reward_failure`` | ``-failure_usd / h`` | rod failure (Goodman above ``task.failure_goodman_pct``; ends the episode) |

``h`` = interval in hours, ``f_pump`` the fraction of the interval the unit ran. The constraint cost (``info["cost"]``,
the safe-RL convention, >= 0, unitless) is ``cost_overload`` (summed relative excess over the PPRL, Goodman and
gearbox ratings) + ``cost_compression`` (polished-rod compression / rating) + ``cost_pound`` (mean impact speed in
m/s), each weighted by ``f_pump``.

Scale: a well lifting 20 m3/day at 50 % water cut earns ~180 USD/h of revenue; electricity ~1 USD/h per 8 kW;
fatigue 0.1-3 USD/h; overloads, pounding and stick-slip from 0 to tens of USD/h when a controller abuses the well.
"""

from __future__ import annotations

from ..config import EconomicsConfig
from .interval import IntervalResult

REWARD_TERMS = ("reward_revenue", "reward_inventory", "reward_energy", "reward_fatigue", "reward_stick_slip",
                "reward_peak_load", "reward_pound", "reward_ramp", "reward_failure")
COST_TERMS = ("cost_overload", "cost_compression", "cost_pound")


def relu(x: float) -> float:
    return max(0.0, x)


class EconomicReward:
    def __init__(self, cfg: EconomicsConfig) -> None:
        self.cfg = cfg

    @property
    def net_value_usd_m3(self) -> float:
        c = self.cfg
        return c.oil_price_usd_m3 * (1.0 - c.water_cut) - c.water_handling_usd_m3 * c.water_cut

    def terms(self, r: IntervalResult, d_avg_spm: float, failed: bool) -> dict[str, float]:
        c = self.cfg
        hours = r.duration_s / 3600.0
        v = self.net_value_usd_m3
        f = r.pumping_fraction
        over = 0.0
        if r.strokes > 0:
            over = (relu(r.pprl_n / c.pprl_rating_n - 1.0) ** 2 + relu(r.goodman_max_pct / 100.0 - 1.0) ** 2
                    + relu(r.gearbox_loading_pct / 100.0 - 1.0) ** 2)
        return {
            "reward_revenue": v * r.lifted_m3 / hours,
            "reward_inventory": v * (r.annulus_end_m3 - r.annulus_start_m3) / hours,
            "reward_energy": -c.electricity_usd_kwh * relu(r.work_j) / (c.motor_efficiency * 3.6e6) / hours
            if c.motor_efficiency > 0 else 0.0,
            "reward_fatigue": -c.workover_usd * r.damage / hours,
            "reward_stick_slip": -c.stick_slip_usd_per_j * r.stick_slip_j / hours,
            "reward_peak_load": -c.overload_usd_h * f * over,
            "reward_pound": -c.pound_usd_per_m2_s2 * r.impact_sq_sum / hours,
            "reward_ramp": -c.ramp_usd_per_spm2 * d_avg_spm * d_avg_spm / hours,
            "reward_failure": -c.failure_usd / hours if failed else 0.0,
        }

    def costs(self, r: IntervalResult) -> dict[str, float]:
        c = self.cfg
        if r.strokes <= 0:
            return {k: 0.0 for k in COST_TERMS}
        f = r.pumping_fraction
        return {
            "cost_overload": f * (relu(r.pprl_n / c.pprl_rating_n - 1.0) + relu(r.goodman_max_pct / 100.0 - 1.0)
                                  + relu(r.gearbox_loading_pct / 100.0 - 1.0)),
            "cost_compression": f * relu(-r.mprl_n) / c.pprl_rating_n,
            "cost_pound": f * r.impact_sum / r.strokes,
        }
