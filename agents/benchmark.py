"""``python -m agents benchmark CONFIG [--quick] [--out-dir DIR]``: tuned baselines vs PPO / SAC on unseen wells.

The protocol (one YAML under ``configs/benchmark/``; :func:`load_benchmark_config` checks it first):

1. **Tune** the baselines on the tuning episodes - ``reset(seed=S)`` on the TRAINING split for the
   config's tuning seeds (:mod:`agents.tuning`; the test split is refused): ``best_constant`` (grid over
   the whole action box + pattern search), then ``pump_off`` and ``fillage_pi`` (coordinate search);
   ``installed`` has nothing to tune; ``oracle`` is a perfect-model lookahead (its candidates include the
   tuned constant).
2. **Train** each algorithm (``agents.runs``: PPO, SAC) on every listed training seed from its training
   YAML (``configs/train/*_v1.yaml``) on the training split, runs in parallel over ``workers`` processes.
   Optionally score each model on validation episodes (training wells, seeds disjoint from tuning and test)
   to pick one seed (``agents.selection: best_on_validation``); the default, ``mean``, reports the
   per-episode reward averaged over all seeds' models: the training procedure, not a lucky seed.
3. **Test** every policy on the same test episodes: ``reset(seed=S)`` on ``scenario="test"`` for the test
   seeds (disjoint from every tuning and validation seed).
4. **Report**: ``OUT/benchmark.json`` (schema in :func:`build_report`), ``OUT/benchmark.md`` (tables,
   verdict, figure ``OUT/figures/benchmark_v1.png``), models in ``OUT/models/<algo>_v1*.zip`` with the
   observation normalisation as ``.npz``. Files are written atomically, nothing partial is left behind.

``--quick`` deep-merges the config's ``quick:`` block (tiny training, fewer episodes) and writes, by
default, to ``runs/benchmark_quick`` instead of ``docs``.
"""

from __future__ import annotations

import json
import shutil
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np

from .baselines_v1 import BASELINE_NAMES, interval_s_of
from .benchmark_agents import (
    _algo_of,
    _policy_part,
    distill_jobs,
    export_model,
    model_name,
    residual_spec,
    train_job,
    training_overrides,
)
from .benchmark_config import BenchmarkConfigError, load_benchmark_config
from .benchmark_figure import figure
from .benchmark_report import (
    _atomic_write,
    _average_episodes,
    _json_clean,
    build_report,
    iqm,
    markdown_tables,
    mean_ci,
    rerender,
    summary_line,
    verdict,
    write_markdown,
)
from .distill_v1 import distill_job
from .ensemble_v1 import ensemble_spec
from .inputs import check_output_dir
from .rollout_v1 import Runner, episode_jobs
from .tuning import Evaluator, TuningSet, coordinate_search, search_best_constant

__all__ = ["BenchmarkConfigError", "benchmark_main", "load_benchmark_config", "mean_ci", "quickstart", "rerender",
           "run_benchmark"]


# -------------------------------------------------------------------------------------------- driver
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
    n_cand = (bc.get("n_spm", 9) * bc.get("n_stroke", 5) + 4 * bc.get("refine_iters", 6)
              + sum(len(v) * bl.get(b, {}).get("rounds", 2) for b in ("pump_off", "fillage_pi")
                    for v in bl.get(b, {}).get("space", {}).values()))
    bar = _Progress(n_cand * n_eps, "tuning")
    ev.progress = bar
    t0 = time.perf_counter()
    tuned["best_constant"] = search_best_constant(ev, bc.get("n_spm", 9), bc.get("n_stroke", 5),
                                                  bc.get("refine_iters", 6), bc.get("refine_step"))
    best_a = tuned["best_constant"]["params"]
    for name in ("pump_off", "fillage_pi"):
        spec = bl.get(name, {})
        init = {k: (best_a["a_spm" if k == "a_spm" else "a_stroke"] if v == "best_constant" else v)
                for k, v in spec.get("init", {}).items()}
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


def _well_ids(tset: TuningSet) -> list[str]:
    """The well drawn by each tuning seed (a zero-length look: reset only, in this process)."""
    from .rollout_v1 import make_env

    env = make_env(tset.env_id, **tset.kwargs)
    try:
        return [str(env.reset(seed=s)[1]["well_id"]) for s in tset.seeds]
    finally:
        env.close()


def run_benchmark(cfg: dict[str, Any], out_dir: str | Path, quick: bool = False,
                  log: Any = None) -> dict[str, Any]:
    log = log or (lambda m: print(m, file=sys.stderr, flush=True))
    out = Path(out_dir)
    check_output_dir(out, ("benchmark.json", "benchmark.md", "figures/benchmark_v1.png"))  # before any work
    t_start = time.perf_counter()
    wall: dict[str, float] = {}
    env_id, env_kwargs = cfg["env_id"], cfg["env_kwargs"]
    test_kwargs = {**env_kwargs, "scenario": "test"}
    train_kwargs = {**env_kwargs, "scenario": "train"}
    workdir = Path(tempfile.mkdtemp(prefix="benchmark_runs_", dir=cfg.get("work_dir") or None))
    try:
        with Runner(cfg["workers"]) as runner:
            tuned, tuning_split = tune_baselines(cfg, runner, log)
            wall["tuning"] = time.perf_counter() - t_start

            # ---- agents: train every (algo, seed), then export
            t1 = time.perf_counter()
            runs = cfg["agents"]["runs"]
            residuals = {a: residual_spec(r, tuned) for a, r in runs.items()}
            jobs = [{"algo": a, "seed": s, "config": r["config"], "out": str(workdir / f"{a}_seed{s}"),
                     "overrides": {**r.get("overrides", {}), **training_overrides(r, residuals[a], cfg)}}
                    for a, r in runs.items() for s in r["seeds"]]
            bar = _Progress(len(jobs), "training")
            summaries = runner.map(jobs, progress=bar, fn=train_job) if jobs else []
            bar.close()
            models_dir = out / "models"
            agent_specs: dict[str, list[dict[str, Any]]] = {}
            teachers: dict[str, list[dict[str, Any]]] = {}
            for job, summ in zip(jobs, summaries):
                run = runs[job["algo"]]
                spec = export_model(summ, models_dir / f"{model_name(job['algo'], run)}_v1_seed{job['seed']}.zip")
                if residuals[job["algo"]]:
                    spec["residual"] = residuals[job["algo"]]
                spec["train_summary"] = {k: summ[k] for k in ("num_timesteps", "wall_time_s", "seed",
                                                              "best_eval_mean_reward")}
                (teachers if run.get("teacher") else agent_specs).setdefault(job["algo"], []).append(spec)
            # teacher-student runs (agents/distill_v1.py): the teachers above teach one student per seed
            djobs = distill_jobs(runs, teachers, agent_specs, residuals, env_id, train_kwargs, models_dir)
            if djobs:
                bar = _Progress(len(djobs), "distillation")
                students = runner.map(djobs, progress=bar, fn=distill_job)
                bar.close()
                for job, spec in zip(djobs, students):
                    t_wall = sum(s["wall_time_s"] for s in job["teacher_summaries"]) / len(job["teacher_summaries"])
                    spec["residual"] = residuals[job["algo"]]
                    spec["train_summary"] = {"num_timesteps": job["teacher_summaries"][0]["num_timesteps"],
                                             "wall_time_s": t_wall + spec["wall_time_s"], "seed": job["seed"],
                                             "best_eval_mean_reward": None}
                    agent_specs.setdefault(job["algo"], []).append(spec)
            # seed ensembles (agents/ensemble_v1.py): the mean action of every seed's model, one more policy
            for a in [a for a in agent_specs if runs[a].get("ensemble")]:
                agent_specs[f"{a}_ensemble"] = [{**ensemble_spec(agent_specs[a]), "of": a}]
            wall["training"] = time.perf_counter() - t1

            # ---- validation (training wells) for the seed choice
            t2 = time.perf_counter()
            val_seeds = cfg["validation"]["seeds"]
            val_scores: dict[str, list[float]] = {}
            val_wells: list[str] = []
            if val_seeds and agent_specs:
                vjobs = [j for a, specs in agent_specs.items() for sp in specs
                         for j in episode_jobs(env_id, train_kwargs, _policy_part(sp), val_seeds)]
                bar = _Progress(len(vjobs), "validation")
                recs = runner.map(vjobs, progress=bar)
                bar.close()
                val_wells = sorted({r["well_id"] for r in recs})
                i = 0
                for a, specs in agent_specs.items():
                    val_scores[a] = []
                    for _ in specs:
                        val_scores[a].append(float(np.mean([r["reward"] for r in recs[i:i + len(val_seeds)]])))
                        i += len(val_seeds)
            wall["validation"] = time.perf_counter() - t2

            # ---- test: every policy on the same episodes
            t3 = time.perf_counter()
            test_seeds = cfg["test"]["seeds"]
            fig_seed = test_seeds[int(cfg.get("figure_episode", 0)) % len(test_seeds)]
            entries: list[tuple[str, int, dict[str, Any]]] = [
                (n, -1, {"kind": "baseline", "name": n, "params": tuned[n]["params"]}) for n in BASELINE_NAMES]
            for a, specs in agent_specs.items():
                entries += [(a, k, _policy_part(sp)) for k, sp in enumerate(specs)]
            tjobs = []
            for n, k, sp in entries:
                for j in episode_jobs(env_id, test_kwargs, sp, test_seeds):
                    j["trace"] = j["seed"] == fig_seed
                    tjobs.append(j)
            # the oracle is the slow one: start it first so the two workers finish together
            order = sorted(range(len(tjobs)), key=lambda i: tjobs[i]["policy"].get("name") != "oracle")
            bar = _Progress(len(tjobs), "test")
            done = runner.map([tjobs[i] for i in order], progress=bar)
            bar.close()
            recs = [None] * len(tjobs)
            for i, r in zip(order, done):
                recs[i] = r
            wall["test"] = time.perf_counter() - t3
    finally:
        shutil.rmtree(workdir, ignore_errors=True)

    # ---- assemble
    n_t = len(test_seeds)
    by_entry = {}
    for e_i, (n, k, _) in enumerate(entries):
        by_entry[(n, k)] = recs[e_i * n_t:(e_i + 1) * n_t]
    traces: dict[str, dict[str, Any]] = {}
    policies: dict[str, dict[str, Any]] = {}
    for n in BASELINE_NAMES:
        eps = by_entry[(n, -1)]
        policies[n] = {"kind": "baseline", "params": tuned[n]["params"], "episodes": eps}
    training: dict[str, Any] = {"selection": cfg["agents"]["selection"], "runs": {}}
    for a, specs in agent_specs.items():
        per_seed = [by_entry[(a, k)] for k in range(len(specs))]
        if specs[0]["kind"] == "ensemble":
            of, eps = specs[0]["of"], per_seed[0]
            policies[a] = {"kind": "agent", "algo": _algo_of(runs[of]), "ensemble_of": of,
                           "selection": f"one policy: the mean action of {of}'s {len(specs[0]['members'])} "
                                        "seeds' models",
                           "residual_on": specs[0].get("residual"),
                           "models": [_rel(m["path"], out) for m in specs[0]["members"]], "episodes": eps}
            training.setdefault("ensembles", {})[a] = {
                "of": of, "models": policies[a]["models"], "iqm_test_reward": iqm([e["reward"] for e in eps]),
                "validation_reward": val_scores[a][0] if val_scores.get(a) else None}
            continue
        seed_means = [float(np.mean([e["reward"] for e in eps])) for eps in per_seed]
        if cfg["agents"]["selection"] == "best_on_validation":
            pick = int(np.argmax(val_scores[a]))
            eps, how = per_seed[pick], f"best_on_validation: seed {specs[pick]['train_summary']['seed']}"
        else:
            pick = int(np.argmax(val_scores[a])) if val_scores.get(a) else 0
            eps, how = _average_episodes(per_seed), "mean over training seeds' models, per test episode"
        # the shipped single model: the validation pick (training wells), else seed 0
        shipped = out / "models" / f"{a}_v1.zip"
        shutil.copyfile(specs[pick]["path"], shipped)
        if specs[pick].get("obs_norm"):
            shutil.copyfile(specs[pick]["obs_norm"], shipped.with_name(f"{a}_v1_obs_norm.npz"))
        policies[a] = {"kind": "agent", "algo": _algo_of(runs[a]), "selection": how,
                       "residual_on": specs[0].get("residual"),
                       "models": [_rel(sp["path"], out) for sp in specs], "episodes": eps}
        training["runs"][a] = {
            "config": runs[a]["config"], "seeds": runs[a]["seeds"], "shipped_model": _rel(str(shipped), out),
            "shipped_seed": specs[pick]["train_summary"]["seed"],
            "iqm_test_reward": iqm([e["reward"] for ep in per_seed for e in ep]),
            "per_seed": [{"seed": sp["train_summary"]["seed"], "mean_test_reward": m,
                          "validation_reward": val_scores[a][k] if val_scores.get(a) else None,
                          "num_timesteps": sp["train_summary"]["num_timesteps"],
                          "wall_time_s": sp["train_summary"]["wall_time_s"],
                          "episodes": [{"well_id": e["well_id"], "seed": e["seed"], "reward": e["reward"],
                                        "cost": e["cost"]} for e in per_seed[k]]}
                         for k, (sp, m) in enumerate(zip(specs, seed_means))]}
        if runs[a].get("teacher"):
            training["runs"][a]["teacher"] = {
                **runs[a]["teacher"], "observation": "privileged",
                "models": [_rel(t["path"], out) for t in teachers[a]],
                "distill": [{"seed": sp["train_summary"]["seed"], "iterations": sp["distill"]} for sp in specs]}
    # traces for the figure: best agent (the shipped model) and best tuned baseline
    bases = [n for n in BASELINE_NAMES if n != "oracle"]
    best_b = max(bases, key=lambda n: np.mean([e["reward"] for e in policies[n]["episodes"]]))
    shown = []
    if agent_specs:
        best_a = max(agent_specs, key=lambda a: np.mean([e["reward"] for e in policies[a]["episodes"]]))
        shown.append((best_a, (best_a, int(np.argmax(val_scores[best_a])) if val_scores.get(best_a) else 0)))
    shown.append((best_b, (best_b, -1)))
    interval_s = _interval_s(env_id, test_kwargs, fig_seed)
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
    splits = {"tuning": tuning_split,
              "validation": {"scenario": "train", "seeds": val_seeds, "well_ids": val_wells},
              "test": {"scenario": "test", "seeds": test_seeds,
                       "well_ids": sorted({e["well_id"] for e in policies["installed"]["episodes"]})}}
    wall["total"] = time.perf_counter() - t_start
    report = build_report(cfg, policies, splits, {n: {k: v for k, v in t.items() if k != "evaluated"}
                                                   for n, t in tuned.items()}, training, wall)
    report["quick"] = quick
    report["tuning_history"] = {n: t.get("evaluated", []) for n, t in tuned.items()}
    fig_rel = "figures/benchmark_v1.png"
    figure(report, traces, out / fig_rel)
    report = _json_clean(report)
    _atomic_write(out / "benchmark.json", json.dumps(report, indent=1))
    write_markdown(report, out / "benchmark.md", fig_rel)
    return report



def _rel(path: str, root: Path) -> str:
    try:
        return str(Path(path).resolve().relative_to(root.resolve()))
    except ValueError:
        return str(path)


def _interval_s(env_id: str, kwargs: dict[str, Any], seed: int) -> float:
    from .rollout_v1 import make_env

    env = make_env(env_id, **kwargs)
    try:
        env.reset(seed=seed)
        return interval_s_of(env)
    finally:
        env.close()



def benchmark_main(config: str, quick: bool = False, out_dir: str | None = None) -> dict[str, Any]:
    """``python -m agents benchmark``: the whole protocol; prints the table and returns the JSON summary."""
    cfg = load_benchmark_config(config, quick=quick)
    out = Path(out_dir or ("runs/benchmark_quick" if quick else "docs"))
    report = run_benchmark(cfg, out, quick=quick)
    print(markdown_tables(report), flush=True)
    print(verdict(report), flush=True)
    print(f"benchmark: wall time {report['wall_time_s']['total']:.0f} s; wrote {out / 'benchmark.json'}, "
          f"{out / 'benchmark.md'}", file=sys.stderr, flush=True)
    return {"benchmark_json": str(out / "benchmark.json"), "markdown": str(out / "benchmark.md"),
            **summary_line(report)}


def quickstart(config: str, out_dir: str, total_timesteps: int | None = None, episodes: int | None = None,
               first_seed: int | None = None) -> dict[str, Any]:
    """``python -m agents quickstart``: the benchmark on a small scale, its table and a one-line verdict on
    stdout; the long JSON goes to ``OUT/benchmark.json``."""
    cfg = load_benchmark_config(config, quick=False)
    if total_timesteps:
        for run in cfg["agents"]["runs"].values():
            run.setdefault("overrides", {})["n_timesteps"] = int(total_timesteps)
    if episodes or first_seed is not None:
        seeds = cfg["test"]["seeds"]
        start = seeds[0] if first_seed is None else first_seed
        cfg["test"]["seeds"] = list(range(start, start + (episodes or len(seeds))))
        clash = set(cfg["test"]["seeds"]) & (set(cfg["tuning"]["seeds"]) | set(cfg["validation"]["seeds"]))
        if clash:
            raise BenchmarkConfigError(f"quickstart: --seed/--episodes = test seeds {sorted(clash)[:5]} ...: "
                                       "expected seeds disjoint from the tuning and validation seeds")
    print(f"quickstart: tuning the baselines, training {', '.join(cfg['agents']['runs']) or 'no agents'}, "
          f"testing on {len(cfg['test']['seeds'])} unseen wells' episodes -> {out_dir}", file=sys.stderr)
    report = run_benchmark(cfg, Path(out_dir), quick=True)
    print(markdown_tables(report), flush=True)
    print(verdict(report), flush=True)
    return {"benchmark_json": str(Path(out_dir) / "benchmark.json"),
            "markdown": str(Path(out_dir) / "benchmark.md"), **summary_line(report)}
