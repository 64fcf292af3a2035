"""The validation pilot of oracle-distilled students on the field pump-off WITH alarms (issue 24, design w24).

Why: on validation and on both fresh splits the best tuned baseline was ``alarm_pump_off`` (the lowest constraint
cost too), while the students are a residual on ``pump_off`` (the best tuning score; the shipped reports'
``residual_on``). A residual on ``alarm_pump_off`` is, where the student is unsure (correction 0), the strongest
and cheapest field controller; where the alarms shut the well in, the shut-in is followed (the guard's
``follow_shut_in`` alone, no cost limits: agents/policies/guarded.py), so no correction pumps a parted-rod well.

Two steps, validation only (training wells, seeds 20000..20015, as scripts/guard_pilot.py plays them):

1. ``--distill DIR``: one DAgger student (agents/training/oracle_distill.py, the causal oracle as teacher) on
   training-split episodes from ``--seed-start``, its labels the residual on ``--base``'s tuned action;
2. evaluation: the tuned baselines and the variants (``variants``) on the validation episodes; paired differences
   per episode (USD/h = return / 144) against fillage_pi and alarm_pump_off, and the mean constraint cost.

The gate (written 2026-12-03 16:12 UTC, commit 39b11b5, after the shipped students' two rows and before the DAgger
student's): a variant goes on to a pre-registered test look only if, on these 16 validation episodes, its paired difference over
alarm_pump_off has a 95 % CI above zero AND its mean constraint cost is not higher than alarm_pump_off's - the
judge's own rule, on validation. Otherwise the result is a documented negative and no test episode is played.

The baselines' tuned parameters are the shipped v2 report's (``docs/v2/benchmark.json``: tuned on the 10
training wells by the benchmark's code; the test looks re-tuned and checked them equal).

    nice -n 5 python scripts/alarm_base_pilot.py --distill runs/w24_alarm_s0 --seed 0      # ~1,000 s CPU
    nice -n 5 python scripts/alarm_base_pilot.py --out runs/w24_pilot --student runs/w24_alarm_s0
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Any

from agents.benchmark.config import load_benchmark_config
from agents.evaluation.rollout import Runner
from agents.policies.guarded import guarded_spec
from agents.training.config import load_train_config
from agents.training.oracle_distill import ORACLE_POLICIES, distill_oracle

ROOT = Path(__file__).resolve().parents[1]
CONFIG = ROOT / "configs/benchmark/v2_oracle_distilled.yaml"
REPORT = ROOT / "docs/v2/benchmark.json"
SHIPPED = [ROOT / f"models/oracle_distilled_v2_seed{s}.zip" for s in (0, 1, 2)]
BASELINES = ("pump_off", "fillage_pi", "alarm_pump_off")
FOLLOW_SHUT_IN = {"follow_shut_in": True}  # no cost limit: only the alarms' shut-in is the base's


def tuned_params() -> dict[str, dict[str, Any]]:
    return {k: v["params"] for k, v in json.loads(REPORT.read_text())["tuned"].items()}


def member(zip_path: Path) -> dict[str, str]:
    return {"path": str(zip_path), "obs_norm": str(zip_path.with_name(zip_path.stem + "_obs_norm.npz"))}


def on_base(members: list[dict[str, str]], base: str, tuned: dict[str, Any], scale: float = 0.5) -> dict[str, Any]:
    """The members' ensemble as a residual on ``base``; on alarm_pump_off its shut-in alarms are followed."""
    ens = {"kind": "ensemble", "members": members, "residual": {"base": base, "params": tuned[base], "scale": scale}}
    if base != "alarm_pump_off":
        return ens
    return guarded_spec(ens, "alarm_pump_off", tuned["alarm_pump_off"], FOLLOW_SHUT_IN)


def variants(tuned: dict[str, Any], students: list[Path]) -> dict[str, dict[str, Any]]:
    """The shipped students on both bases, and each DAgger student (seed k = its place in ``students``)."""
    shipped = [member(p) for p in SHIPPED]
    out = {"shipped_ensemble_on_pump_off": on_base(shipped, "pump_off", tuned),  # as trained and test-looked
           "shipped_ensemble_on_alarm_pump_off": on_base(shipped, "alarm_pump_off", tuned)}
    for k, d in enumerate(students):
        out[f"dagger_alarm_seed{k}"] = on_base([member(d / "student.zip")], "alarm_pump_off", tuned)
        # a diagnostic after the gate (no choice rests on it): the same student with the shut-in NOT followed
        out[f"dagger_alarm_seed{k}_unfollowed"] = out[f"dagger_alarm_seed{k}"]["inner"]
    return out


def distill_student(out: Path, res: dict[str, Any], seed: int, seed_start: int, iterations: int, episodes: int,
                    workers: int, teacher_extra: dict[str, Any] | None = None) -> tuple[list[int], dict[str, Any]]:
    """One DAgger student of the causal oracle (the shipped design's teacher block, ``iterations`` x ``episodes``
    training episodes from ``seed_start``) as the residual ``res``, written to ``out/student.zip``; the pilots' one
    trainer. Returns the training seeds and the student's spec."""
    cfg = load_benchmark_config(str(CONFIG))
    tuned = tuned_params()
    run = cfg["agents"]["runs"]["oracle_distilled"]
    teacher = {**run["teacher"], "iterations": iterations, "episodes": episodes, **(teacher_extra or {})}
    oracle = {**teacher["params"], "policies": [[b, tuned[b]] for b in ORACLE_POLICIES]}
    pk = load_train_config(run["config"]).policy_kwargs
    seeds = list(range(seed_start, seed_start + iterations * episodes))
    out.mkdir(parents=True, exist_ok=True)
    with Runner(workers) as runner:
        spec = distill_oracle(runner, teacher, oracle, res, cfg["env_id"], {**cfg["env_kwargs"], "scenario": "train"},
                              pk, seeds, seed, out / "student.zip", log=lambda m: print(m, file=sys.stderr, flush=True))
    return seeds, spec


def distill(out: Path, base: str, seed: int, seed_start: int, iterations: int, episodes: int, workers: int) -> None:
    res = {"base": base, "params": tuned_params()[base], "scale": 0.5}
    seeds, spec = distill_student(out, res, seed, seed_start, iterations, episodes, workers)
    (out / "distill.json").write_text(json.dumps({"residual": res, "seeds": seeds, "spec": spec}, indent=1))


def evaluate(out: Path, students: list[Path], workers: int) -> None:
    sys.path.insert(0, str(ROOT / "scripts"))
    from guard_pilot import BASES, play_validation, summarise  # the guard pilot's player and paired table

    cfg = load_benchmark_config(str(CONFIG))
    tuned = tuned_params()
    specs = {b: {"kind": "baseline", "name": b, "params": tuned[b]} for b in BASELINES}
    specs.update(variants(tuned, students))
    eps = play_validation(cfg, specs, out, workers)
    res = {"specs": specs, "summary": summarise(eps)}
    (out / "pilot.json").write_text(json.dumps(res, indent=1))
    print("| policy | USD/h | cost | vs fillage_pi [95 % CI] wins | vs alarm_pump_off [95 % CI] wins |")
    print("|---|---|---|---|---|")
    for k, r in res["summary"].items():
        cells = [f"{r[f'vs_{b}']['mean']:+.2f} [{r[f'vs_{b}']['ci95'][0]:+.2f}, {r[f'vs_{b}']['ci95'][1]:+.2f}] "
                 f"{r[f'vs_{b}']['wins']}/{r[f'vs_{b}']['n']}" if f"vs_{b}" in r else "0" for b in BASES]
        print(f"| {k} | {r['usd_h']:.2f} | {r['cost']:.2f} | {cells[0]} | {cells[1]} |")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--distill", type=Path, help="train one DAgger student into this directory")
    ap.add_argument("--base", default="alarm_pump_off", choices=BASELINES)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--seed-start", type=int, default=60000, help="training-split episodes (outside 0..9, 20000..)")
    ap.add_argument("--iterations", type=int, default=3)
    ap.add_argument("--episodes", type=int, default=16)
    ap.add_argument("--out", type=Path, help="evaluate the variants on validation into this directory")
    ap.add_argument("--student", type=Path, nargs="*", default=[],
                    help="--distill directories of seeds 0, 1, ...: their students join the variants")
    ap.add_argument("--workers", type=int, default=1)
    a = ap.parse_args()
    if a.distill:
        distill(a.distill, a.base, a.seed, a.seed_start, a.iterations, a.episodes, a.workers)
    if a.out:
        evaluate(a.out, a.student, a.workers)


if __name__ == "__main__":
    main()
