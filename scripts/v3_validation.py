"""Issue 24: v3's validation figures (REPORT ONLY: nothing is chosen, tuned or trained on them; no test or fresh
episode). Committed before it was run.

    PYTHONPATH=. nice -n 5 python scripts/v3_validation.py       # 2 workers -> docs/v3/validation.json

No flags. Plays, on ``srenv/SuckerRod-v3``'s ``validation`` split (field observation), the 50 episodes
``reset(seed=S)`` for S in 21800..21849 (each validation well once: the well is S mod 50; seeds nobody had played):

- v3's tuned baselines (``docs/v3/tuned.json``, scripts/v3_tune.py): installed, best_constant, pump_off,
  fillage_pi, alarm_pump_off;
- the causal oracle with v2's settings (configs/benchmark/v3.yaml ``evaluate_only.references``, as v2.yaml's:
  horizon 6, replan every 3, weighing v3's tuned pump_off and fillage_pi);
- v2's shipped students ``oracle_distilled_ensemble`` (models/oracle_distilled_v2_seed{0,1,2}, rebuilt from
  ``docs/v2/benchmark.json``'s record by :func:`agents.evaluation.replay.policy_specs`, their sha256 pins checked),
  residual on v3's tuned pump_off: a transfer reference, no v3 agent.

The policies are exactly what ``python -m agents benchmark configs/benchmark/v3.yaml --evaluate-only`` plays
(:func:`agents.benchmark.fresh._specs` on :func:`agents.benchmark.fresh.with_tuned`), here on the validation split.
The report (:func:`agents.benchmark.report.build_report`, normalised to the causal oracle as the evaluate-only
report is) adds per policy: USD/h, cost and its parts, the paired difference vs the best tuned baseline (the one
with the highest TRAINING tuning score in docs/v3/tuned.json, chosen before this run) with its 95 % CI over the 50
wells (each once), and per true condition (every interval booked under ``info["condition"]``) the mean reward
rate and cost per interval.
"""

from __future__ import annotations

import json
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
sys.path.insert(0, str(Path(__file__).resolve().parent))
from v3_mechanism import no_arguments
from v3_tune import CONFIG, ROOT, V2_REPORT
from v3_tune import OUT as TUNED

from agents.benchmark.config import load_benchmark_config
from agents.benchmark.fresh import _policies, _renormalise, _specs, fresh_episode_job, load_tuned, with_tuned
from agents.benchmark.report import _atomic_write, _json_clean, build_report, mean_ci
from agents.evaluation.replay import load_report
from agents.evaluation.rollout import Runner
from agents.inputs import check_output_dir

OUT = TUNED.parent / "validation.json"
SEEDS = list(range(21800, 21850))  # validation wells 0..49 once each (seed mod 50); registered here, unplayed
TUNED_BASELINES = ("installed", "best_constant", "pump_off", "fillage_pi", "alarm_pump_off")
# the true conditions the figures are read by (info["condition"]; None/"" is a normal interval)
GROUPS = {"normal": ("", "None", "full", "fluid_pound"), "tagging": ("tagging_down", "tagging_up"),
          "valve_leak": ("travelling_valve_leak", "standing_valve_leak", "both_valves_leak"),
          "tubing_leak": ("tubing_leak",), "gas": ("gas_interference",), "heavy_oil": ("heavy_oil",),
          "flowing": ("flowing",), "parted_rods": ("parted_rods",)}


def best_tuned(tuned: dict[str, Any]) -> str:
    """The tuned field baseline with the highest training score (the tuning's own mean return)."""
    scored = {n: t["score"] for n, t in tuned.items() if n in TUNED_BASELINES and t.get("score") is not None}
    return max(scored, key=scored.get)


def per_condition(trace: dict[str, list]) -> dict[str, dict[str, float]]:
    """Sums over one episode's intervals by condition group: intervals, reward (USD/h x intervals), cost."""
    out: dict[str, dict[str, float]] = {}
    for cond, r, c in zip(trace["condition"], trace["reward"], trace["cost"]):
        group = next((g for g, labels in GROUPS.items() if str(cond) in labels), f"other:{cond}")
        row = out.setdefault(group, {"intervals": 0.0, "reward": 0.0, "cost": 0.0})
        row["intervals"] += 1
        row["reward"] += float(r)
        row["cost"] += float(c) if np.isfinite(c) else 0.0
    return out


def condition_table(episodes: list[dict[str, Any]]) -> dict[str, dict[str, float]]:
    """Per group over every episode: intervals, episodes it occurred in, mean reward rate (USD/h) and mean cost
    per interval."""
    tot: dict[str, dict[str, float]] = {}
    for e in episodes:
        for g, row in e["per_condition"].items():
            t = tot.setdefault(g, {"intervals": 0.0, "episodes": 0.0, "reward": 0.0, "cost": 0.0})
            t["episodes"] += 1
            for k in ("intervals", "reward", "cost"):
                t[k] += row[k]
    return {g: {"intervals": int(t["intervals"]), "episodes": int(t["episodes"]),
                "reward_usd_h": t["reward"] / t["intervals"], "cost_per_interval": t["cost"] / t["intervals"]}
            for g, t in sorted(tot.items())}


def figures(report: dict[str, Any], best: str, intervals: int) -> dict[str, Any]:
    """Per policy: USD/h, cost and its parts (episode means), the paired difference vs ``best`` in USD/h (return
    difference / intervals of a full episode) with its 95 % CI over the wells, the normalised score."""
    pol = report["policies"]
    ref = {e["well_id"]: e["reward"] for e in pol[best]["episodes"]}
    out = {}
    for n, p in pol.items():
        eps = p["episodes"]
        d = np.array([e["reward"] - ref[e["well_id"]] for e in eps]) / intervals
        m, lo, hi = mean_ci(d)
        parts = sorted({k for e in eps for k in e if k.startswith(("cost_", "reward_")) and k != "reward_rate_usd_h"})
        out[n] = {"kind": p["kind"], "usd_h": float(np.mean([e["reward_rate_usd_h"] for e in eps])),
                  "cost": float(np.mean([e["cost"] for e in eps])),
                  "parts_episode_mean": {k: float(np.mean([e.get(k, 0.0) for e in eps])) for k in parts},
                  "vs_best_tuned_usd_h": {"baseline": best, "mean": m, "ci95_by_well": [lo, hi],
                                          "n_wells": len(ref)},
                  "normalised_score": report["summary"][n]["normalised_score"],
                  "failures": report["summary"][n]["failures"],
                  "per_condition": condition_table(eps)}
    return out


def play(cfg: dict[str, Any], specs: dict[str, list[dict[str, Any]]],
         seeds: list[int] = SEEDS) -> tuple[list[str], list[dict[str, Any]]]:
    """Every policy's spec on the validation episodes ``seeds`` (this script's 50; scripts/v3_oracle_distilled.py's
    gate its own), traced for the per-condition booking."""
    jobs, owner = [], []
    for n, sps in specs.items():
        for sp in sps:
            for s in seeds:
                jobs.append({"env_id": cfg["env_id"], "env_kwargs": {**cfg["env_kwargs"], "scenario": "validation"},
                             "policy": sp, "seed": s, "trace": True})
                owner.append(n)
    # the causal oracle is the slow one: first, so the two workers finish together
    order = sorted(range(len(jobs)), key=lambda i: owner[i] != "causal_oracle")
    print(f"v3 validation: {len(specs)} policies x {len(seeds)} episodes", file=sys.stderr, flush=True)
    with Runner(cfg["workers"]) as runner:
        done = runner.map([jobs[i] for i in order], fn=fresh_episode_job)
    recs: list[Any] = [None] * len(jobs)
    for i, r in zip(order, done):
        trace = r.pop("trace")
        r["per_condition"] = per_condition(trace)
        recs[i] = r
    return owner, recs


def main(argv: list[str] | None = None) -> None:
    no_arguments("v3_validation.py", argv)
    check_output_dir(OUT.parent, (OUT.name,))  # before any work
    t0 = time.perf_counter()
    cfg = load_benchmark_config(CONFIG)
    tuned = load_tuned(TUNED)
    rep = with_tuned(load_report(V2_REPORT), tuned)
    specs = _specs(cfg, rep, ROOT)  # the evaluate-only policies: pins of the v2 students checked here
    owner, recs = play(cfg, specs)
    policies = _policies(rep, specs, owner, recs, len(SEEDS))
    splits = {"test": {"scenario": "validation", "seeds": SEEDS,
                       "well_ids": [e["well_id"] for e in policies["installed"]["episodes"]]}}
    report = build_report(cfg, policies, splits, tuned, {"shipped_report": str(V2_REPORT.relative_to(ROOT))},
                          {"total": time.perf_counter() - t0})
    _renormalise(report)
    best = best_tuned(tuned)
    intervals = max(e["steps"] for e in policies["installed"]["episodes"])
    report.update(mode="v3_validation_report_only", tuned_from=str(TUNED.relative_to(ROOT)),
                  best_tuned_baseline=best, intervals_per_episode=intervals, condition_groups=GROUPS,
                  figures=figures(report, best, intervals))
    report["wall_time_s"]["total"] = time.perf_counter() - t0
    _atomic_write(OUT, json.dumps(_json_clean(report), indent=1))
    print(json.dumps({n: {k: f[k] for k in ("usd_h", "cost", "normalised_score")} | {"vs_best": f["vs_best_tuned_usd_h"]}
                      for n, f in report["figures"].items()}, default=float))


if __name__ == "__main__":
    main()
