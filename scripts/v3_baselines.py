"""Issue 24, item 5 (report only): the tuned baselines of docs/v2/benchmark.json and a "slow down when tagging /
leak" rule on srenv/SuckerRod-v2 and srenv/SuckerRod-v3, on the SAME 16 training-split episodes (scenario
``train``, seeds 59600..59615; never validation, test or fresh wells), reward and cost per condition.

    PYTHONPATH=. nice -n 5 python scripts/v3_baselines.py > v3_baselines.json

No flags and no files written: one JSON object on stdout. Nothing is tuned or selected here: the baselines are
the report's ``policies`` (``installed``, ``best_constant``, ``pump_off``, ``fillage_pi``, ``alarm_pump_off``,
built by ``agents.evaluation.replay.policy_specs`` as the report's replay does; the ``oracle`` of the ``tuned``
record is a planner, not run here), and the rule is ``alarm_pump_off`` with its tuned parameters whose average
SPM action drops by its own tuned ``gas_slowdown`` (0.6 action units, not below idle) while the field
observation's probability of tagging (up or down) or of a leak (either valve, both, tubing) is above its tuned
``alarm_prob`` (0.6).

Per (env, policy): every interval is booked under its true condition (``info["condition"]``): the intervals,
the sum of the reward (USD/h x intervals: divide by the intervals for the mean rate), of ``info["cost"]``, of
``reward_tagging`` and ``reward_lost_production``; and the episodes' mean reward rate (USD/h) and cost.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
sys.path.insert(0, str(Path(__file__).resolve().parent))
from v3_mechanism import no_arguments

from agents.envs import make_env
from agents.evaluation.agent import build_policy
from agents.evaluation.replay import load_report, policy_specs
from agents.evaluation.rollout import play
from agents.policies.alarms import AlarmPumpOffPolicy, slowed

ROOT = Path(__file__).resolve().parents[1]
REPORT = ROOT / "docs" / "v2" / "benchmark.json"
SEEDS = range(59600, 59616)  # training split: well seed mod 200
VERSIONS = ("srenv/SuckerRod-v2", "srenv/SuckerRod-v3")
BASELINES = ("installed", "best_constant", "pump_off", "fillage_pi", "alarm_pump_off")
SLOW_LABELS = ("tagging_up", "tagging_down", "travelling_valve_leak", "standing_valve_leak", "both_valves_leak",
               "tubing_leak")
TERMS = ("reward_tagging", "reward_lost_production")


class SlowOnAlarm(AlarmPumpOffPolicy):
    """alarm_pump_off that slows down by ``gas_slowdown`` while tagging or a leak is above ``alarm_prob``."""

    name = "alarm_pump_off_slow"

    def __init__(self, obs_names, **params: Any) -> None:
        super().__init__(obs_names, **params)
        self.i_slow = [list(obs_names).index(f"prob_{k}") for k in SLOW_LABELS]
        self.width = len(obs_names)

    def predict(self, observation: Any, state: Any = None, episode_start: Any = None, deterministic: bool = True):
        action, st = super().predict(observation, state, episode_start, deterministic)
        obs = np.asarray(observation, np.float64).reshape(-1, self.width)
        a = np.array(action, np.float64).reshape(-1, 2)
        alarm = obs[:, self.i_slow].max(axis=1) > self.alarm_prob
        a[:, 0] = slowed(a[:, 0], alarm, self.gas_slowdown)
        return a.reshape(np.shape(action)).astype(np.asarray(action).dtype), st


def policies(env: Any) -> dict[str, Any]:
    rep = load_report(REPORT)
    out = {}
    for name in BASELINES:
        (spec,) = policy_specs(rep, name, ROOT)
        out[name] = build_policy(spec, env)
    out["alarm_pump_off_slow"] = SlowOnAlarm(env.unwrapped.obs_names, **rep["policies"]["alarm_pump_off"]["params"])
    return out


def episodes(env: Any, policy: Any) -> dict[str, Any]:
    by: dict[str, dict[str, float]] = {}
    rates, costs = [], []
    for seed in SEEDS:
        _, steps = play(env, policy, seed)
        ret = cost = 0.0
        n = 0
        for _, reward, _, _, info in steps:
            row = by.setdefault(str(info["condition"]), dict.fromkeys(("intervals", "reward", "cost", *TERMS), 0.0))
            row["intervals"] += 1
            row["reward"] += float(reward)
            row["cost"] += float(info["cost"])
            for k in TERMS:
                row[k] += float(info[k])
            ret, cost, n = ret + float(reward), cost + float(info["cost"]), n + 1
        rates.append(ret / max(n, 1))
        costs.append(cost)
    return {"per_condition": by, "mean_reward_rate_usd_h": float(np.mean(rates)), "mean_episode_cost":
            float(np.mean(costs)), "episode_reward_rate_usd_h": rates}


def main(argv: list[str] | None = None) -> None:
    no_arguments("v3_baselines", argv)
    out: dict[str, Any] = {"seeds": [SEEDS.start, SEEDS.stop - 1], "scenario": "train"}
    for env_id in VERSIONS:
        env = make_env(env_id, scenario="train", observation="field")
        out[env_id] = {name: episodes(env, pol) for name, pol in policies(env).items()}
    print(json.dumps(out))


if __name__ == "__main__":
    main()
