"""Issue 24, helper d24: more DAgger for the shipped v2 students - does their constraint cost fall?

The design and its gate are pre-registered in configs/benchmark/v2_oracle_distilled_more.yaml (its ``history``):
each shipped student (models/oracle_distilled_v2_seed{k}) continued by 2 DAgger iterations x 16 training-split
episodes from the causal oracle (agents/training/oracle_distill.py with ``teacher.init``; the student acts from the
start), the design = the mean correction of the 3 continued students.

    PYTHONPATH=. nice -n 5 python scripts/oracle_distill_more.py --stage dagger --out runs/d24_more 2> runs/d24_more.log
    PYTHONPATH=. nice -n 5 python scripts/oracle_distill_more.py --stage gate --out runs/d24_more

``--stage dagger``: the three continued students (OUT/models/oracle_distilled_v2_seed{k}.zip + statistics), the
baselines' tuned parameters being docs/v2/benchmark.json's (tuned on training wells 0..9 by the benchmark's code, the
ones the shipped students were distilled with). A student already recorded in OUT/dagger.json is not redone.
``--stage gate``: alarm_pump_off (those tuned parameters), the shipped ensemble and the continued ensemble on the
gate's validation episodes (:data:`GATE_SEEDS`: training wells 0..15 with schedules no earlier design played), and
THE GATE (:func:`gate`), written to OUT/gate.json. Played once.
``--stage fit`` (training labels only, no episode played): each student's MSE against the continuation's labels
(:func:`fit_table`) - the shipped and the continued student of every seed on its own labels (the continued one
in-sample) and on the other seeds' labels (held out from both) - written to OUT/fit.json.

    PYTHONPATH=. python scripts/oracle_distill_more.py --stage fit --out runs/d24_more
"""

from __future__ import annotations

import argparse
import copy
import json
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from estimated_mpc_pilot import arguments
from guard_pilot import INTERVALS, play_validation, summarise

from agents.benchmark.config import load_benchmark_config
from agents.benchmark.runs import oracle_student, residual_spec
from agents.evaluation.replay import load_report
from agents.evaluation.rollout import Runner
from agents.policies.ensemble import ensemble_spec

ROOT = Path(__file__).resolve().parents[1]
CONFIG = ROOT / "configs/benchmark/v2_oracle_distilled_more.yaml"
REPORT = ROOT / "docs/v2/benchmark.json"
SHIPPED = ROOT / "models"
GATE_SEEDS = list(range(20800, 20816))  # THE GATE's validation seeds (the config's history)
BASES = ("alarm_pump_off", "shipped_ensemble")
SHIPPED_SEEDS = [0, 1, 2]  # the shipped ensemble's students
STAGES = ("dagger", "gate", "fit")


def setup(config: Path = CONFIG) -> tuple[dict[str, Any], str, dict[str, Any], dict[str, Any], dict[str, Any]]:
    """(config, run name, its run block, the tuned baselines {name: {params, score}}, the residual spec)."""
    cfg = load_benchmark_config(str(config))
    (name, run), = cfg["agents"]["runs"].items()
    tuned = {k: {"params": v["params"], "score": v.get("score")} for k, v in load_report(REPORT)["tuned"].items()}
    return cfg, name, run, tuned, residual_spec(run, tuned)


def write_json(path: Path, obj: Any) -> None:
    tmp = path.with_name(path.name + ".tmp")
    tmp.write_text(json.dumps(obj, indent=1))
    tmp.replace(path)


def dagger(out: Path, workers: int, design: Callable[[], tuple] = setup) -> dict[str, Any]:
    """Each seed's student continued (the config's teacher block), recorded in OUT/dagger.json as it ends
    (``design``: another design's ``setup``, scripts/v3_oracle_distilled.py's)."""
    cfg, name, run, tuned, res = design()
    rec_path = out / "dagger.json"
    done = json.loads(rec_path.read_text()) if rec_path.exists() else {}
    with Runner(workers) as runner:
        for seed in run["seeds"]:
            if str(seed) not in done:
                done[str(seed)] = oracle_student(cfg, runner, name, seed, tuned, res, out / "models")
                write_json(rec_path, done)
    return done


def students(directory: Path, name: str, seeds: list[int], res: dict[str, Any]) -> list[dict[str, Any]]:
    return [{"kind": "agent", "path": str(directory / f"{name}_v2_seed{s}.zip"), "residual": res,
             "obs_norm": str(directory / f"{name}_v2_seed{s}_obs_norm.npz")} for s in seeds]


def gate(summ: dict[str, Any], design: str = "continued_ensemble") -> bool:
    """THE GATE (the design's config history): (design - alarm_pump_off) paired 95 % CI lower bound > 0 AND the
    design's mean constraint cost <= alarm_pump_off's."""
    row = summ[design]
    return row["vs_alarm_pump_off"]["ci95"][0] > 0 and row["cost"] <= summ["alarm_pump_off"]["cost"]


def play_gate(out: Path, workers: int) -> dict[str, Any]:
    cfg, name, run, tuned, res = setup()
    return play_design_gate(cfg, CONFIG, GATE_SEEDS, {"continued_ensemble": ensemble_spec(
        students(out / "models", name, run["seeds"], res))}, tuned, res, out, workers)


def play_design_gate(cfg: dict[str, Any], config: Path, seeds: list[int], design: dict[str, dict[str, Any]],
                     tuned: dict[str, Any], res: dict[str, Any], out: Path, workers: int,
                     scenario: str = "train", also: dict[str, dict[str, Any]] | None = None,
                     shipped: bool = True) -> dict[str, Any]:
    """alarm_pump_off (the tuned parameters), the shipped ensemble (unless not ``shipped``), ``also`` (reported, not
    judged) and ``design`` ({name: its policy spec}) on the validation ``seeds`` of ``scenario`` (the training wells,
    as every gate so far, or v2's ``validation`` split), THE GATE on the design, written to OUT/gate.json (played
    once)."""
    (dname, dspec), = design.items()
    specs = {"alarm_pump_off": {"kind": "baseline", "name": "alarm_pump_off",
                                "params": tuned["alarm_pump_off"]["params"]}}
    if shipped:
        specs["shipped_ensemble"] = ensemble_spec(students(SHIPPED, "oracle_distilled", SHIPPED_SEEDS, res))
    specs.update({**(also or {}), dname: dspec})
    for spec in specs.values():
        for m in spec.get("members", []):
            if not Path(m["path"]).is_file():
                print(f"{Path(sys.argv[0]).stem}: {m['path']}: no such student (run --stage dagger first)",
                      file=sys.stderr)
                sys.exit(2)
    gcfg = {**copy.deepcopy(cfg), "validation": {"seeds": seeds, "scenario": scenario}}
    eps = play_validation(gcfg, specs, out / "gate", workers)
    summ = summarise(eps, BASES)
    res_out = {"stage": "gate", "config": str(config.relative_to(ROOT)), "seeds": seeds, "scenario": scenario, "specs": specs,
               "summary": summ, "gate": gate(summ, dname), **episode_tables(eps)}
    write_json(out / "gate.json", res_out)
    return res_out


def episode_tables(eps: dict[str, list[dict[str, Any]]]) -> dict[str, Any]:
    """Every policy's mean reward and cost terms (USD/h), mean operating point, the wells played and every
    episode's USD/h and cost: the per-episode part of a gate's (or a selection's) record."""
    return {"terms_usd_h": {k: {t: float(np.mean([e[t] for e in v])) / INTERVALS for t in sorted(v[0])
                                if t.startswith(("reward_", "cost_"))} for k, v in eps.items()},
            "operating_point": {k: {t: float(np.mean([e[t] for e in v])) for t in sorted(v[0]) if t.startswith("mean_")}
                                for k, v in eps.items()},
            "well_id": [e["well_id"] for e in eps.get("alarm_pump_off", next(iter(eps.values())))],
            "per_episode_usd_h": {k: [round(e["reward"] / INTERVALS, 3) for e in v] for k, v in eps.items()},
            "per_episode_cost": {k: [round(e["cost"], 4) for e in v] for k, v in eps.items()}}


def fit_table(out: Path) -> dict[str, Any]:
    """MSE (clipped correction against the oracle's label) of the shipped and the continued student of each seed
    on each seed's continuation labels (OUT/models/*_labels.npz: training episodes only), and the labels' mean
    square (the MSE of correction 0, the base controller)."""
    from agents.evaluation.agent import AgentPolicy

    _, name, run, _, _ = setup()
    labels = {k: np.load(out / "models" / f"{name}_v2_seed{k}_labels.npz") for k in run["seeds"]}
    rows: dict[str, Any] = {"label_mean_square": {str(k): float(np.mean(z["label"] ** 2)) for k, z in labels.items()}}
    for tag, directory in (("shipped", SHIPPED), ("continued", out / "models")):
        for st in students(directory, name, run["seeds"], {}):
            pol = AgentPolicy(st["path"], st["obs_norm"])
            k = int(Path(st["path"]).stem.rsplit("seed", 1)[1])
            rows[f"{tag}_seed{k}"] = {
                str(j): float(np.mean((np.clip(pol.model.predict(pol.norm(z["x"]), deterministic=True)[0], -1, 1)
                                       - z["label"]) ** 2)) for j, z in labels.items()}
    write_json(out / "fit.json", rows)
    return rows


def table(summ: dict[str, Any]) -> list[str]:
    rows = ["| policy | USD/h | cost | vs alarm_pump_off [95 % CI] wins | vs shipped_ensemble [95 % CI] wins |",
            "|---|---|---|---|---|"]
    for k, r in summ.items():
        cells = [f"{r[f'vs_{b}']['mean']:+.2f} [{r[f'vs_{b}']['ci95'][0]:+.2f}, {r[f'vs_{b}']['ci95'][1]:+.2f}] "
                 f"{r[f'vs_{b}']['wins']}/{r[f'vs_{b}']['n']}" if f"vs_{b}" in r else "0" for b in BASES]
        rows.append(f"| {k} | {r['usd_h']:.2f} | {r['cost']:.2f} | {cells[0]} | {cells[1]} |")
    return rows


def main() -> None:
    a = arguments(argparse.ArgumentParser(description=__doc__.splitlines()[0]), STAGES)
    a.out.mkdir(parents=True, exist_ok=True)
    if a.stage == "dagger":
        for seed, spec in dagger(a.out, a.workers).items():
            print(f"seed {seed}: {spec['path']} mse {[round(h['mse'], 5) for h in spec['distill']]} rollout return "
                  f"{[round(h['rollout_mean_return'], 1) for h in spec['distill']]}")
        return
    if a.stage == "fit":
        for k, v in fit_table(a.out).items():
            print(f"{k:22s}", "  ".join(f"labels {j}: {m:.4f}" for j, m in v.items()))
        return
    res = play_gate(a.out, a.workers)
    print("\n".join(table(res["summary"])))
    print("GATE:", "passed" if res["gate"] else "failed")


if __name__ == "__main__":
    main()
