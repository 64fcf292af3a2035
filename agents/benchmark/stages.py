"""The benchmark's stages, each one function over a shared :class:`~agents.evaluation.rollout.Runner`:
tune the baselines, train (and distil) the agents, score them on validation episodes, test every policy.
:func:`agents.benchmark.run.run_benchmark` chains them and :mod:`agents.benchmark.assemble` makes the report's
records of what they return."""

from __future__ import annotations

import json
import sys
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from ..envs import env_tag, make_env
from ..evaluation.rollout import Runner, episode_jobs
from ..policies.ensemble import ensemble_spec
from ..policies.factory import SEARCHED_BASELINES, benchmark_baselines
from ..policies.guarded import guarded_spec
from ..training.distill import distill_job
from ..training.tuning import Evaluator, TuningSet, coordinate_search, search_best_constant
from .runs import (
    _policy_part,
    distill_jobs,
    export_model,
    is_oracle_run,
    model_name,
    oracle_student,
    residual_spec,
    train_job,
    training_overrides,
)


class _Progress:
    """A tqdm bar on stderr for one phase (plain lines when stderr is not a terminal)."""

    def __init__(self, total: int, desc: str) -> None:
        from tqdm import tqdm

        self.bar = tqdm(total=total, desc=desc, file=sys.stderr, dynamic_ncols=True,
                        mininterval=0.5 if sys.stderr.isatty() else 30.0)

    def __call__(self, n: int) -> None:
        self.bar.update(n)

    def close(self) -> None:
        self.bar.close()


def tune_baselines(cfg: dict[str, Any], runner: Runner, log: Any) -> tuple[dict[str, Any], dict[str, Any]]:
    """Tuned parameters of every baseline and the tuning episodes' well ids."""
    bl = cfg["baselines"]
    tset = TuningSet(cfg["tuning"]["seeds"], cfg["tuning"]["scenario"], cfg["env_id"], cfg["env_kwargs"])
    ev = Evaluator(tset, runner)
    tuned: dict[str, Any] = {"installed": {"params": {}}}
    bc = bl.get("best_constant", {})
    n_eps = len(tset.seeds)
    # the optional ones (alarm_pump_off) only when the config lists them: v1's benchmark is unchanged
    searched = [n for n in SEARCHED_BASELINES if n in benchmark_baselines(bl)]
    n_cand = (bc.get("n_spm", 9) * bc.get("n_stroke", 5) + 4 * bc.get("refine_iters", 6)
              + sum(len(v) * bl.get(b, {}).get("rounds", 2) for b in searched
                    for v in bl.get(b, {}).get("space", {}).values()))
    bar = _Progress(n_cand * n_eps, "tuning")
    ev.progress = bar
    t0 = time.perf_counter()
    tuned["best_constant"] = search_best_constant(ev, bc.get("n_spm", 9), bc.get("n_stroke", 5),
                                                  bc.get("refine_iters", 6), bc.get("refine_step"))
    best_a = tuned["best_constant"]["params"]
    for name in searched:
        spec = bl.get(name, {})
        init = {k: _init_value(tuned, k, v) for k, v in spec.get("init", {}).items()}
        tuned[name] = coordinate_search(ev, name, init, spec.get("space", {}), spec.get("rounds", 2))
    bar.close()
    oc = dict(bl.get("oracle", {}))
    anchors = [[best_a["a_spm"], best_a["a_stroke"]]] if oc.pop("anchor_best_constant", True) else []
    # the planner also simulates the tuned field baselines' own trajectories: it is at least as good as
    # each of them on every episode, by construction
    given = [[n, tuned[n]["params"]] for n in ("installed", "pump_off", "fillage_pi")] \
        if oc.pop("include_baselines", True) else []
    tuned["oracle"] = {"params": {**oc, "anchors": anchors, "policies": given}}
    wells = sorted(set(_well_ids(tset)))
    log(f"tuning: {ev.episodes_run} episodes in {time.perf_counter() - t0:.0f} s; " + "; ".join(
        f"{n} {json.dumps(t['params'])}" for n, t in tuned.items() if n != "installed"))
    return tuned, {"scenario": tset.scenario, "seeds": tset.seeds, "well_ids": wells}


def _init_value(tuned: dict[str, Any], key: str, value: Any) -> Any:
    """A search's start value: a number as given, or a baseline's name for its tuned value of ``key``
    (``best_constant``'s ``a_stroke`` for any key but ``a_spm``, as v1's configs use it)."""
    if value == "best_constant":
        return tuned["best_constant"]["params"]["a_spm" if key == "a_spm" else "a_stroke"]
    if isinstance(value, str):
        return tuned[value]["params"][key]  # the config check made sure it was tuned before and has the key
    return value


def _well_ids(tset: TuningSet) -> list[str]:
    """The well drawn by each tuning seed (a zero-length look: reset only, in this process)."""
    env = make_env(tset.env_id, **tset.kwargs)
    try:
        return [str(env.reset(seed=s)[1]["well_id"]) for s in tset.seeds]
    finally:
        env.close()


def _mapped(runner: Runner, jobs: list[dict[str, Any]], desc: str, fn: Any = None) -> list[Any]:
    """``runner.map`` of one phase behind its progress bar."""
    bar = _Progress(len(jobs), desc)
    try:
        return runner.map(jobs, progress=bar, **({"fn": fn} if fn else {}))
    finally:
        bar.close()


def train_agents(cfg: dict[str, Any], runner: Runner, tuned: dict[str, Any], workdir: Path,
                 models_dir: Path) -> tuple[dict[str, list[dict[str, Any]]], dict[str, list[dict[str, Any]]],
                                            dict[str, Any]]:
    """Train every (algo, seed), export the models, distil the students, add the seed ensembles; returns
    (agent specs by policy name, teacher specs by run, residual spec by run)."""
    runs = cfg["agents"]["runs"]
    residuals = {a: residual_spec(r, tuned) for a, r in runs.items()}
    jobs = [{"algo": a, "seed": s, "config": r["config"], "out": str(workdir / f"{a}_seed{s}"),
             "overrides": {**r.get("overrides", {}), **training_overrides(r, residuals[a], cfg)}}
            for a, r in runs.items() if not is_oracle_run(r) for s in r["seeds"]]
    summaries = _mapped(runner, jobs, "training", train_job) if jobs else []
    agent_specs: dict[str, list[dict[str, Any]]] = {}
    teachers: dict[str, list[dict[str, Any]]] = {}
    for job, summ in zip(jobs, summaries):
        run = runs[job["algo"]]
        spec = export_model(summ, models_dir / f"{model_name(job['algo'], run)}_{env_tag(cfg['env_id'])}_seed{job['seed']}.zip")
        if residuals[job["algo"]]:
            spec["residual"] = residuals[job["algo"]]
        spec["train_summary"] = {k: summ[k] for k in ("num_timesteps", "wall_time_s", "seed",
                                                      "best_eval_mean_reward")}
        (teachers if run.get("teacher") else agent_specs).setdefault(job["algo"], []).append(spec)
    # teacher-student runs (agents/training/distill.py): the teachers above teach one student per seed
    train_kwargs = {**cfg["env_kwargs"], "scenario": "train"}
    djobs = distill_jobs(runs, teachers, agent_specs, residuals, cfg["env_id"], train_kwargs, models_dir)
    for job, spec in zip(djobs, _mapped(runner, djobs, "distillation", distill_job) if djobs else []):
        t_wall = sum(s["wall_time_s"] for s in job["teacher_summaries"]) / len(job["teacher_summaries"])
        spec["residual"] = residuals[job["algo"]]
        spec["train_summary"] = {"num_timesteps": job["teacher_summaries"][0]["num_timesteps"],
                                 "wall_time_s": t_wall + spec["wall_time_s"], "seed": job["seed"],
                                 "best_eval_mean_reward": None}
        agent_specs.setdefault(job["algo"], []).append(spec)
    # causal-oracle teachers (agents/training/oracle_distill.py): no PPO training, a fresh student per seed
    for a in [a for a, r in runs.items() if is_oracle_run(r)]:
        agent_specs[a] = [oracle_student(cfg, runner, a, s, tuned, residuals[a], models_dir) for s in runs[a]["seeds"]]
    # seed ensembles (agents/policies/ensemble.py): the mean action of every seed's model, one more policy
    for a in [a for a in agent_specs if runs[a].get("ensemble")]:
        agent_specs[f"{a}_ensemble"] = [{**ensemble_spec(agent_specs[a]), "of": a}]
    if cfg.get("guarded"):  # the design's ensemble under its constraint guard (agents/policies/guarded.py)
        (a,) = runs
        agent_specs[f"{a}_guarded"] = [design_guarded(cfg, tuned, ensemble_spec(agent_specs[a]), a)]
    return agent_specs, teachers, residuals


def design_guarded(cfg: dict[str, Any], tuned: dict[str, Any], ens: dict[str, Any], of: str) -> dict[str, Any]:
    """The guarded spec of the config's ``guarded:`` block on the ensemble ``ens`` of run ``of``'s models."""
    g = cfg["guarded"]
    spec = guarded_spec(_policy_part(ens), g["fallback"], tuned[g["fallback"]]["params"], g["guard"], g.get("scale"))
    return {**spec, "of": of}


def validate(cfg: dict[str, Any], runner: Runner,
             agent_specs: dict[str, list[dict[str, Any]]]) -> tuple[dict[str, list[float]], list[str]]:
    """Each model's mean return on the validation episodes (the training wells, or v2's validation split with
    ``validation.scenario: validation``), for the seed choice; and the wells those episodes drew."""
    val_seeds = cfg["validation"]["seeds"]
    val_scores: dict[str, list[float]] = {}
    if not (val_seeds and agent_specs):
        return val_scores, []
    val_kwargs = {**cfg["env_kwargs"], "scenario": cfg["validation"].get("scenario", "train")}
    vjobs = [j for a, specs in agent_specs.items() for sp in specs
             for j in episode_jobs(cfg["env_id"], val_kwargs, _policy_part(sp), val_seeds)]
    recs = _mapped(runner, vjobs, "validation")
    i = 0
    for a, specs in agent_specs.items():
        val_scores[a] = []
        for _ in specs:
            val_scores[a].append(float(np.mean([r["reward"] for r in recs[i:i + len(val_seeds)]])))
            i += len(val_seeds)
    return val_scores, sorted({r["well_id"] for r in recs})


def run_test_episodes(cfg: dict[str, Any], runner: Runner, tuned: dict[str, Any],
                      agent_specs: dict[str, list[dict[str, Any]]], fig_seed: int,
                      policies: Sequence[str] | None = None) -> dict[tuple[str, int], list[dict[str, Any]]]:
    """Every policy on the same test episodes: records by (policy name, model index; -1 for a baseline), the
    episode ``fig_seed`` with its trace for the figure. ``policies``: the tuned baselines played (default every
    one the benchmark reports; a test look leaves out what its judge does not read, scripts/v2_test_look.py)."""
    test_seeds = cfg["test"]["seeds"]
    test_kwargs = {**cfg["env_kwargs"], "scenario": cfg["test"].get("scenario", "test")}
    names = benchmark_baselines(tuned) if policies is None else policies
    entries: list[tuple[str, int, dict[str, Any]]] = [
        (n, -1, {"kind": "baseline", "name": n, "params": tuned[n]["params"]}) for n in names]
    for a, specs in agent_specs.items():
        entries += [(a, k, _policy_part(sp)) for k, sp in enumerate(specs)]
    tjobs = []
    for n, k, sp in entries:
        for j in episode_jobs(cfg["env_id"], test_kwargs, sp, test_seeds):
            j["trace"] = j["seed"] == fig_seed
            tjobs.append(j)
    # the oracle is the slow one: start it first so the two workers finish together
    order = sorted(range(len(tjobs)), key=lambda i: tjobs[i]["policy"].get("name") != "oracle")
    done = _mapped(runner, [tjobs[i] for i in order], "test")
    recs: list[Any] = [None] * len(tjobs)
    for i, r in zip(order, done):
        recs[i] = r
    n_t = len(test_seeds)
    return {(n, k): recs[e_i * n_t:(e_i + 1) * n_t] for e_i, (n, k, _) in enumerate(entries)}
