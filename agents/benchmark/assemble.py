"""The benchmark report's records from what the stages returned: each policy's test episodes (a baseline's,
an agent's averaged over its seeds' models or its validation pick, an ensemble's), the training record of
every run with its shipped model, and the traces of the figure's episode."""

from __future__ import annotations

import shutil
from pathlib import Path
from typing import Any

import numpy as np

from ..envs import env_tag
from ..evaluation.model_pins import PINS, member_pins
from ..evaluation.normalizer import obs_norm_path
from ..policies.factory import benchmark_baselines
from .report import _average_episodes, iqm
from .runs import _algo_of

Episodes = dict[tuple[str, int], list[dict[str, Any]]]


def model_ref(path: str | Path) -> str:
    """How the report names a model file: ``models/<file>``, looked up by
    :func:`agents.evaluation.replay.locate_model` (the report's folder, then the repository's ``models/``)."""
    return f"models/{Path(path).name}"


def _ensemble_record(spec: dict[str, Any], runs: dict[str, Any], eps: list[dict[str, Any]]) -> dict[str, Any]:
    """An ensemble's record; ``described: true`` only for students that read the well file (replay rebuilds it);
    ``sha256`` pins its members' files (:mod:`agents.evaluation.model_pins`)."""
    of, refs = spec["of"], [model_ref(m["path"]) for m in spec["members"]]
    rec = {"kind": "agent", "algo": _algo_of(runs[of]), "ensemble_of": of,
           "selection": f"one policy: the mean action of {of}'s {len(spec['members'])} seeds' models",
           "residual_on": spec.get("residual"), "models": refs, PINS: member_pins(refs, spec["members"]),
           "episodes": eps}
    if spec.get("described"):
        rec["described"] = True
    return rec


def guarded_record(spec: dict[str, Any], runs: dict[str, Any], eps: list[dict[str, Any]]) -> dict[str, Any]:
    """A guarded ensemble's record: the ensemble's, and what replay needs to rebuild the guard around it."""
    rec = _ensemble_record({**spec["inner"], "of": spec["of"]}, runs, eps)
    rec["selection"] += ", under the constraint guard"
    rec["guarded"] = {"fallback": spec["fallback"], "guard": spec["guard"], "scale": spec.get("scale")}
    return rec


def _ship(specs: list[dict[str, Any]], pick: int, a: str, models_dir: Path, tag: str) -> Path:
    """The shipped single model of run ``a``: the validation pick (training wells), else seed 0."""
    shipped = models_dir / f"{a}_{tag}.zip"
    shutil.copyfile(specs[pick]["path"], shipped)
    if specs[pick].get("obs_norm"):
        shutil.copyfile(specs[pick]["obs_norm"], obs_norm_path(shipped))
    return shipped


def _run_record(run: dict[str, Any], specs: list[dict[str, Any]], per_seed: list[list[dict[str, Any]]],
                val: list[float] | None, pick: int, shipped: Path) -> dict[str, Any]:
    seed_means = [float(np.mean([e["reward"] for e in eps])) for eps in per_seed]
    return {
        "config": run["config"], "seeds": run["seeds"], "shipped_model": model_ref(str(shipped)),
        "shipped_seed": specs[pick]["train_summary"]["seed"],
        "iqm_test_reward": iqm([e["reward"] for ep in per_seed for e in ep]),
        "per_seed": [{"seed": sp["train_summary"]["seed"], "mean_test_reward": m,
                      "validation_reward": val[k] if val else None,
                      "num_timesteps": sp["train_summary"]["num_timesteps"],
                      "wall_time_s": sp["train_summary"]["wall_time_s"],
                      "episodes": [{"well_id": e["well_id"], "seed": e["seed"], "reward": e["reward"],
                                    "cost": e["cost"]} for e in per_seed[k]]}
                     for k, (sp, m) in enumerate(zip(specs, seed_means))]}


def policy_records(cfg: dict[str, Any], tuned: dict[str, Any], agent_specs: dict[str, list[dict[str, Any]]],
                   teachers: dict[str, list[dict[str, Any]]], by_entry: Episodes,
                   val_scores: dict[str, list[float]],
                   models_dir: Path) -> tuple[dict[str, Any], dict[str, Any]]:
    """(policies, training) of the report; copies each run's shipped model into ``models_dir``."""
    runs = cfg["agents"]["runs"]
    policies: dict[str, dict[str, Any]] = {n: {"kind": "baseline", "params": tuned[n]["params"],
                                               "episodes": by_entry[(n, -1)]} for n in benchmark_baselines(tuned)}
    training: dict[str, Any] = {"selection": cfg["agents"]["selection"], "runs": {}}
    for a, specs in agent_specs.items():
        per_seed = [by_entry[(a, k)] for k in range(len(specs))]
        val = val_scores.get(a)
        if specs[0]["kind"] in ("ensemble", "guarded"):
            policies[a] = (_ensemble_record if specs[0]["kind"] == "ensemble" else guarded_record)(
                specs[0], runs, per_seed[0])
            training.setdefault("ensembles", {})[a] = {
                "of": specs[0]["of"], "models": policies[a]["models"],
                "iqm_test_reward": iqm([e["reward"] for e in per_seed[0]]),
                "validation_reward": val[0] if val else None}
            continue
        pick = int(np.argmax(val)) if (val or cfg["agents"]["selection"] == "best_on_validation") else 0
        if cfg["agents"]["selection"] == "best_on_validation":
            eps, how = per_seed[pick], f"best_on_validation: seed {specs[pick]['train_summary']['seed']}"
        else:
            eps, how = _average_episodes(per_seed), "mean over training seeds' models, per test episode"
        shipped = _ship(specs, pick, a, models_dir, env_tag(cfg["env_id"]))
        refs = [model_ref(sp["path"]) for sp in specs]
        policies[a] = {"kind": "agent", "algo": _algo_of(runs[a]), "selection": how,
                       "residual_on": specs[0].get("residual"), "models": refs, PINS: member_pins(refs, specs),
                       "episodes": eps}
        training["runs"][a] = _run_record(runs[a], specs, per_seed, val, pick, shipped)
        if runs[a].get("teacher"):
            oracle = a not in teachers  # a causal-oracle teacher (agents/training/oracle_distill.py): no model
            training["runs"][a]["teacher"] = {
                **runs[a]["teacher"], "observation": "true env state" if oracle else "privileged",
                "models": [] if oracle else [model_ref(t["path"]) for t in teachers[a]],
                "distill": [{"seed": sp["train_summary"]["seed"], "iterations": sp["distill"]}
                            for sp in specs]}
    return policies, training


def figure_traces(policies: dict[str, Any], agent_specs: dict[str, Any], by_entry: Episodes,
                  val_scores: dict[str, list[float]], fig_seed: int, interval_s: float) -> dict[str, Any]:
    """The figure's episode of the best agent (its shipped model) and the best tuned baseline; the traces
    are taken out of every episode record (they are for the figure only)."""
    bases = [n for n, p in policies.items() if p["kind"] == "baseline" and n != "oracle"]
    best_b = max(bases, key=lambda n: np.mean([e["reward"] for e in policies[n]["episodes"]]))
    shown = []
    if agent_specs:
        best_a = max(agent_specs, key=lambda a: np.mean([e["reward"] for e in policies[a]["episodes"]]))
        shown.append((best_a, (best_a, int(np.argmax(val_scores[best_a])) if val_scores.get(best_a) else 0)))
    shown.append((best_b, (best_b, -1)))
    traces: dict[str, dict[str, Any]] = {}
    for label, key in shown:
        rec = next(e for e in by_entry[key] if e["seed"] == fig_seed)
        traces[label] = {**{k: rec[k] for k in ("well_id", "seed", "reward")}, "trace": rec["trace"],
                         "interval_s": interval_s}
    for r in by_entry.values():
        for e in r:
            e.pop("trace", None)
    for p in policies.values():
        for e in p["episodes"]:
            e.pop("trace", None)
    return traces
