"""The causal oracle (agents/policies/causal_oracle.py: MPC on a frozen copy of the true env, no future; horizon 6,
replan every 3, weighing the tuned pump_off and fillage_pi) on the v2 pilot's validation episodes, beside the tuned
baselines' returns the pilot report holds for the same episodes - the headroom a causal controller has on v2.

    PYTHONPATH=. python scripts/causal_oracle_pilot.py --out docs/archive/causal_oracle_pilot.jsonl [--first 0 --last 16]

One JSON line per episode: seed, the oracle's return and cost, its CPU seconds, fillage_pi's and pump_off's returns
from docs/archive/benchmark_v2_pilot.json, and the oracle's stick-slip and revenue terms (episode sums).
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

from agents.evaluation.rollout import _cached_env, run_episode
from agents.evaluation.v1_view import build_policy_any

PILOT = Path(__file__).resolve().parent.parent / "docs" / "archive" / "benchmark_v2_pilot.json"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", required=True, help="JSONL written one episode at a time")
    ap.add_argument("--first", type=int, default=0)
    ap.add_argument("--last", type=int, default=16)
    args = ap.parse_args()
    rep = json.loads(PILOT.read_text())
    pol = rep["policies"]
    params = {"horizon": 6, "replan_every": 3, "policies": [[b, pol[b]["params"]] for b in ("pump_off", "fillage_pi")]}
    env = _cached_env(rep["env_id"], {**rep["env_kwargs"], "scenario": "validation"})
    episodes = list(zip(pol["fillage_pi"]["episodes"], pol["pump_off"]["episodes"]))[args.first:args.last]
    with open(args.out, "w") as out:
        for fpi, po in episodes:
            t0 = time.process_time()
            spec = {"kind": "baseline", "name": "causal_oracle", "params": params}
            r = run_episode(env, build_policy_any(spec, env), fpi["seed"])
            out.write(json.dumps({"seed": fpi["seed"], "reward": r["reward"], "cost": r["cost"],
                                  "cpu_s": time.process_time() - t0, "fillage_pi": fpi["reward"],
                                  "pump_off": po["reward"], "stick": r.get("reward_stick_slip"),
                                  "revenue": r.get("reward_revenue")}) + "\n")
            out.flush()


if __name__ == "__main__":
    main()
