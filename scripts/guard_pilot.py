"""The validation pilot of a constraint guard on the shipped oracle-distilled students (issue 24): guard variants
(agents/policies/guarded.py) on the benchmark's validation split only, against the tuned baselines.

1. The students' ensemble is rebuilt from the shipped report's record (``--report``, default docs/v2/benchmark.json)
   by :func:`agents.evaluation.replay.policy_specs` - the function ``replay`` and ``--evaluate-only --report`` use -
   so it is a residual on the base the students were trained on (the record's ``residual_on``: pump_off, scale 0.5),
   never a hard-coded one. (The first pilot, 2026-12-03, composed them on fillage_pi: docs/archive/guard_pilot.json,
   the correction in docs/agents.md.) The baselines' tuned parameters are the same report's (tuned on the 10 training
   wells by the benchmark's code; the test looks re-tuned and checked them equal).
2. Each variant (``VARIANTS``) wraps that ensemble in a guard, fallback the tuned ``alarm_pump_off``.
3. The baselines and every variant play the config's validation episodes (training wells, seeds 20000..20015, as
   :func:`agents.benchmark.stages.validate` plays them); paired differences per episode (USD/h = return / 144,
   mean [95 % CI]) against the baselines, and the mean constraint cost per episode and its terms.

THE GATE (written and committed 2026-12-03 17:05 UTC, commit abdd912, before any number of the variants below was seen): a variant
goes on to a pre-registered test look only if, on these 16 validation episodes, against alarm_pump_off (the best
tuned baseline on validation), with d = (variant's return - alarm_pump_off's) / 144 per episode,
  (a) the 95 % CI of mean d (normal approximation, agents.benchmark.report.mean_ci) is above zero, OR
  (b) mean d >= 0.10 x alarm_pump_off's mean USD/h on these episodes (+8.98 USD/h = +10 %),
AND (both cases) its mean constraint cost per episode (info["cost"] summed) is not higher than alarm_pump_off's.
If several pass, the one with the highest mean d is the design (one look). ``ensemble_unguarded`` and
``guard_pound_minspm`` are references, not candidates: both were already played on test (the unguarded ensemble's
look; the guarded look played exactly this guard on pump_off). Every variant is reported whatever it shows.

    PYTHONPATH=. nice -n 5 python scripts/guard_pilot.py configs/benchmark/v2_oracle_distilled_guarded.yaml \
        --out runs/guard_pilot_pump_off                       # docs/archive/guard_pilot_pump_off.json
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path
from typing import Any

import numpy as np

from agents.benchmark.config import load_benchmark_config
from agents.benchmark.report import mean_ci
from agents.evaluation.replay import load_report, policy_specs
from agents.evaluation.rollout import Runner, episode_jobs
from agents.policies.guarded import guarded_spec

ROOT = Path(__file__).resolve().parents[1]
REPORT = ROOT / "docs/v2/benchmark.json"
AGENT = "oracle_distilled_ensemble"  # the shipped students' record in the report
INTERVALS = 144  # a v2 episode: 24 h of 10-min intervals
BASES = ("fillage_pi", "alarm_pump_off")
FALLBACK = "alarm_pump_off"
# the variants (written before their numbers; None = no guard). The overload cost (srenv/task/economics.py) is the
# excess of PPRL over the rod/unit rating (and Goodman, gearbox); the field observation's ``pprl`` is that ratio for
# the last card, so a limit just under 1 hands the next intervals to pump-off before the excess, 0.9 earlier
POUND_MINSPM = {"below": {"fillage_est": 0.85, "spm": 0.45}, "hold_intervals": 3}  # the first pilot's choice
VARIANTS: dict[str, dict[str, Any] | tuple[dict[str, Any], float] | None] = {  # guard, or (guard, deployed scale)
    "ensemble_unguarded": None,  # reference: as trained and test-looked
    "guard_pound_minspm": POUND_MINSPM,  # reference: the guard the guarded look played (on pump_off)
    "guard_load95": {"above": {"pprl": 0.95}, "hold_intervals": 3},
    "guard_load90": {"above": {"pprl": 0.90}, "hold_intervals": 3},
    "guard_pound_load95": {"below": {"fillage_est": 0.85}, "above": {"pprl": 0.95}, "hold_intervals": 3},
    "guard_minspm_load95": {"below": {"fillage_est": 0.85, "spm": 0.45}, "above": {"pprl": 0.95}, "hold_intervals": 3},
    # round 2, added at 17:11 UTC after the six above were seen (none passed; the guards cut cost but not reward up),
    # the same gate: a larger deployed residual scale under the pound+load guard, and a 1-interval hold
    "guard_pound_load95_s0.75": ({"below": {"fillage_est": 0.85}, "above": {"pprl": 0.95}, "hold_intervals": 3}, 0.75),
    "guard_pound_load95_s1.0": ({"below": {"fillage_est": 0.85}, "above": {"pprl": 0.95}, "hold_intervals": 3}, 1.0),
    "guard_pound_load95_hold1": {"below": {"fillage_est": 0.85}, "above": {"pprl": 0.95}, "hold_intervals": 1},
}


def shipped(report: Path = REPORT, agent: str = AGENT) -> tuple[dict[str, Any], dict[str, dict[str, Any]]]:
    """(the students' ensemble spec as the report records it - its models on its ``residual_on`` base -, the
    report's tuned baseline parameters)."""
    rep = load_report(report)
    (ens,) = policy_specs(rep, agent, report.resolve().parent)
    return ens, {k: v["params"] for k, v in rep["tuned"].items()}


def variant_specs(ens: dict[str, Any], tuned: dict[str, Any], variants: dict[str, Any]) -> dict[str, dict[str, Any]]:
    out = {}
    for n, v in variants.items():
        g, scale = v if isinstance(v, tuple) else (v, None)
        out[n] = ens if g is None else guarded_spec(ens, FALLBACK, tuned[FALLBACK], g, scale)
    return out


def gate(row: dict[str, Any], base: dict[str, Any]) -> bool:
    """THE GATE (module docstring) on one summary row against alarm_pump_off's."""
    d = row[f"vs_{FALLBACK}"]
    return (d["ci95"][0] > 0 or d["mean"] >= 0.10 * base["usd_h"]) and row["cost"] <= base["cost"]


def summarise(eps: dict[str, list[dict[str, Any]]], bases: tuple[str, ...] = BASES) -> dict[str, Any]:
    rw = {k: np.array([e["reward"] for e in v]) for k, v in eps.items()}
    out: dict[str, Any] = {}
    for k, r in rw.items():
        row: dict[str, Any] = {"usd_h": float(r.mean() / INTERVALS), "cost": float(np.mean([e["cost"] for e in eps[k]])),
                               "cost_terms": {t: float(np.mean([e[t] for e in eps[k]])) for t in eps[k][0]
                                              if t.startswith("cost_")}}
        for b in bases:
            if k != b and b in rw:
                m, lo, hi = mean_ci((r - rw[b]) / INTERVALS)
                row[f"vs_{b}"] = {"mean": m, "ci95": [lo, hi], "wins": int(np.sum(r > rw[b])), "n": len(r)}
        out[k] = row
    return out


def play_validation(cfg: dict[str, Any], specs: dict[str, dict[str, Any]], out: Path,
                    workers: int) -> dict[str, list[dict[str, Any]]]:
    """Every spec on the config's validation episodes (the validation seeds on the training wells, or on v2's
    validation split with ``validation.scenario: validation``), cached by name in ``out/episodes.json``: a later
    call plays only the names not there yet. The pilots' one player."""
    kw = {**cfg["env_kwargs"], "scenario": cfg["validation"].get("scenario", "train")}
    out.mkdir(parents=True, exist_ok=True)
    cache = out / "episodes.json"
    eps: dict[str, Any] = json.loads(cache.read_text()) if cache.exists() else {}
    todo = [n for n in specs if n not in eps]
    jobs = [j for n in todo for j in episode_jobs(cfg["env_id"], kw, specs[n], cfg["validation"]["seeds"])]
    with Runner(workers) as runner:
        recs = runner.map(jobs)
    n_v = len(cfg["validation"]["seeds"])
    for i, n in enumerate(todo):
        eps[n] = recs[i * n_v:(i + 1) * n_v]
    cache.write_text(json.dumps(eps))
    return eps


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("config")
    ap.add_argument("--report", type=Path, default=REPORT, help="the shipped report holding the students' record")
    ap.add_argument("--out", type=Path, required=True)
    ap.add_argument("--variants", nargs="*", default=None, help="a subset of VARIANTS (default: all)")
    ap.add_argument("--workers", type=int, default=2)
    a = ap.parse_args()
    cfg = load_benchmark_config(a.config)
    a.out.mkdir(parents=True, exist_ok=True)
    ens, tuned = shipped(a.report)
    specs: dict[str, dict[str, Any]] = {b: {"kind": "baseline", "name": b, "params": tuned[b]} for b in BASES}
    specs.update(variant_specs(ens, tuned, {n: VARIANTS[n] for n in a.variants or VARIANTS}))
    eps = play_validation(cfg, specs, a.out, a.workers)
    summ = summarise(eps)
    passed = {n: gate(summ[n], summ[FALLBACK]) for n in summ if n in VARIANTS}
    res = {"report": str(a.report), "seeds": cfg["validation"]["seeds"], "specs": specs, "summary": summ,
           "gate": passed, "per_episode_usd_h": {k: [round(e["reward"] / INTERVALS, 3) for e in v] for k, v in eps.items()}}
    (a.out / "pilot.json").write_text(json.dumps(res, indent=1))
    print("| policy | USD/h | cost | vs fillage_pi [95 % CI] wins | vs alarm_pump_off [95 % CI] wins | gate |")
    print("|---|---|---|---|---|---|")
    for k, r in summ.items():
        cells = [f"{r[f'vs_{b}']['mean']:+.2f} [{r[f'vs_{b}']['ci95'][0]:+.2f}, {r[f'vs_{b}']['ci95'][1]:+.2f}] "
                 f"{r[f'vs_{b}']['wins']}/{r[f'vs_{b}']['n']}" if f"vs_{b}" in r else "0" for b in BASES]
        print(f"| {k} | {r['usd_h']:.2f} | {r['cost']:.2f} | {cells[0]} | {cells[1]} | {passed.get(k, '-')} |")


if __name__ == "__main__":
    main()
