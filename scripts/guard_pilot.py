"""The validation pilot of the constraint guard on the oracle-distilled students (issue 24): a few guard variants
(agents/policies/guarded.py) on the benchmark's validation split only, against the tuned baselines.

1. The baselines as the benchmark's own tuning code (:func:`agents.benchmark.stages.tune_baselines`, the config's
   training wells) tuned them in the students' run (its ``--log``); ``--retune`` tunes them again here and checks
   them equal (the test look always does, scripts/v2_test_look.py).
2. Each variant (``VARIANTS``: the residual scale at deployment, the guard's limits and hold) wraps the run's 3
   students' ensemble (read only from ``--run``), fallback the tuned ``alarm_pump_off``.
3. Every variant, ``fillage_pi`` and ``alarm_pump_off`` play the config's validation episodes (training wells,
   seeds 20000..20015, as :func:`agents.benchmark.stages.validate` plays them); paired differences per episode
   (USD/h = return / 144, mean [95 % CI]) against both baselines, and the mean constraint cost per episode.

    nice -n 5 python scripts/guard_pilot.py configs/benchmark/v2_oracle_distilled.yaml \
        --run /work/runs/v2_oracle_distilled --log /work/runs/v2od.log --out runs/guard_pilot
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Any

import numpy as np

from agents.benchmark.config import load_benchmark_config
from agents.benchmark.report import mean_ci
from agents.benchmark.stages import tune_baselines
from agents.evaluation.rollout import Runner, episode_jobs
from agents.policies.guarded import guarded_spec

INTERVALS = 144  # a v2 episode: 24 h of 10-min intervals
BASES = ("fillage_pi", "alarm_pump_off")
# the variants (<= 6, every one reported): (scale, guard); guard None = the ensemble as trained and tested
# (chosen from 8 training-well episodes' per-interval cost beside the last card: the pound cost follows a low
# fillage estimate, the overload cost a high PPRL over the rating; the classifier's pound probability did not track it)
POUND = {"below": {"fillage_est": 0.85}, "hold_intervals": 3}
POUND_LOAD = {"below": {"fillage_est": 0.85}, "above": {"pprl": 0.95}, "hold_intervals": 3, "follow_shut_in": True}
VARIANTS: dict[str, tuple[float, dict[str, Any] | None]] = {
    "ensemble_s0.5": (0.5, None),  # the design as trained and tested (the reference)
    "ensemble_s0.25": (0.25, None),
    "guard_pound_s0.5": (0.5, POUND),
    "guard_pound_load_s0.5": (0.5, POUND_LOAD),
    "guard_pound_load_s0.35": (0.35, POUND_LOAD),
    "guard_pound_load_hold6_s0.5": (0.5, {**POUND_LOAD, "below": {"fillage_est": 0.9}, "hold_intervals": 6}),
    # added after the five above: on validation episodes 4 and 13 the students lose to alarm_pump_off by the
    # stick-slip penalty (a reward term, not a cost) of slow continuous pumping (last interval's spm ~0.37-0.43
    # where it struck); a minimum running speed, as field controllers set, hands those intervals to pump-off
    "guard_pound_minspm_s0.5": (0.5, {"below": {"fillage_est": 0.85, "spm": 0.45}, "hold_intervals": 3}),
}


def tuned_params(cfg: dict[str, Any], out: Path, log: Path, workers: int, retune: bool) -> dict[str, dict[str, Any]]:
    """The baselines as the benchmark's tuning code tuned them in the students' run (its log), or, with
    ``retune``, tuned again here by that code (cached in OUT/tuned.json) and checked equal to the log."""
    from v2_test_look import logged_run  # scripts/ is on sys.path when run as a script

    logged = {n: p for n, p in logged_run(log)[0].items() if n != "oracle"}
    if not retune:
        return logged
    path = out / "tuned.json"
    if path.exists():
        tuned = json.loads(path.read_text())
    else:
        with Runner(workers) as runner:
            t, _ = tune_baselines(cfg, runner, lambda m: print(m, file=sys.stderr, flush=True))
        tuned = {n: v["params"] for n, v in t.items()}
        path.write_text(json.dumps(tuned, indent=1))
    for n, params in logged.items():
        if tuned[n] != params:
            raise SystemExit(f"tuned {n} = {tuned[n]}, the run logged {params}: not the run's tuning")
    return tuned


def ensemble(run_dir: Path, seeds: list[int], tuned: dict[str, Any], scale: float) -> dict[str, Any]:
    members = []
    for s in seeds:
        p = next((run_dir / "models").glob(f"oracle_distilled_v*_seed{s}.zip"))
        members.append({"path": str(p), "obs_norm": str(p.with_name(p.stem + "_obs_norm.npz"))})
    return {"kind": "ensemble", "members": members,
            "residual": {"base": "fillage_pi", "params": tuned["fillage_pi"], "scale": scale}}


def summarise(eps: dict[str, list[dict[str, Any]]]) -> dict[str, Any]:
    rw = {k: np.array([e["reward"] for e in v]) for k, v in eps.items()}
    out: dict[str, Any] = {}
    for k, r in rw.items():
        row: dict[str, Any] = {"usd_h": float(r.mean() / INTERVALS), "cost": float(np.mean([e["cost"] for e in eps[k]])),
                               "cost_terms": {t: float(np.mean([e[t] for e in eps[k]])) for t in eps[k][0]
                                              if t.startswith("cost_")}}
        for b in BASES:
            if k != b:
                m, lo, hi = mean_ci((r - rw[b]) / INTERVALS)
                row[f"vs_{b}"] = {"mean": m, "ci95": [lo, hi], "wins": int(np.sum(r > rw[b])), "n": len(r)}
        out[k] = row
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("config")
    ap.add_argument("--run", type=Path, required=True)
    ap.add_argument("--log", type=Path, required=True)
    ap.add_argument("--out", type=Path, required=True)
    ap.add_argument("--variants", nargs="*", default=None, help="a subset of VARIANTS (default: all)")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--retune", action="store_true", help="tune the baselines again (the log's are the same code's)")
    a = ap.parse_args()
    cfg = load_benchmark_config(a.config)
    a.out.mkdir(parents=True, exist_ok=True)
    tuned = tuned_params(cfg, a.out, a.log, a.workers, a.retune)
    seeds = cfg["agents"]["runs"]["oracle_distilled"]["seeds"]
    specs: dict[str, dict[str, Any]] = {b: {"kind": "baseline", "name": b, "params": tuned[b]} for b in BASES}
    for name in a.variants or VARIANTS:
        scale, guard = VARIANTS[name]
        ens = ensemble(a.run, seeds, tuned, scale)
        specs[name] = ens if guard is None else guarded_spec(ens, "alarm_pump_off", tuned["alarm_pump_off"], guard)
    kw = {**cfg["env_kwargs"], "scenario": "train"}  # the validation split: training wells, its own seeds
    cache = a.out / "episodes.json"
    eps: dict[str, Any] = json.loads(cache.read_text()) if cache.exists() else {}
    todo = [n for n in specs if n not in eps]
    jobs = [j for n in todo for j in episode_jobs(cfg["env_id"], kw, specs[n], cfg["validation"]["seeds"])]
    with Runner(a.workers) as runner:
        recs = runner.map(jobs)
    n_v = len(cfg["validation"]["seeds"])
    for i, n in enumerate(todo):
        eps[n] = recs[i * n_v:(i + 1) * n_v]
    cache.write_text(json.dumps(eps))
    res = {"specs": specs, "summary": summarise(eps)}
    (a.out / "pilot.json").write_text(json.dumps(res, indent=1))
    print("| policy | USD/h | cost | vs fillage_pi [95 % CI] wins | vs alarm_pump_off [95 % CI] wins |")
    print("|---|---|---|---|---|")
    for k, r in res["summary"].items():
        cells = [f"{r[f'vs_{b}']['mean']:+.2f} [{r[f'vs_{b}']['ci95'][0]:+.2f}, {r[f'vs_{b}']['ci95'][1]:+.2f}] "
                 f"{r[f'vs_{b}']['wins']}/{r[f'vs_{b}']['n']}" if f"vs_{b}" in r else "0" for b in BASES]
        print(f"| {k} | {r['usd_h']:.2f} | {r['cost']:.2f} | {cells[0]} | {cells[1]} |")


if __name__ == "__main__":
    main()
