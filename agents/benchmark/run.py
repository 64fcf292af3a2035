"""``python -m agents benchmark CONFIG [--quick] [--out-dir DIR]``: tuned baselines vs PPO / SAC on unseen wells.

The protocol (one YAML under ``configs/benchmark/``; :func:`load_benchmark_config` checks it first):

1. **Tune** the baselines on the tuning episodes - ``reset(seed=S)`` on the TRAINING split for the
   config's tuning seeds (:mod:`agents.training.tuning`; the test split is refused): ``best_constant`` (grid over
   the whole action box + pattern search), then ``pump_off`` and ``fillage_pi`` (coordinate search), then
   ``alarm_pump_off`` when the config lists it (v2: from pump-off's tuned set point, its alarms searched);
   ``installed`` has nothing to tune; ``oracle`` is a perfect-model lookahead (its candidates include the
   tuned constant).
2. **Train** each algorithm (the config's ``agents.runs``: PPO, SAC) on every listed training seed from its training
   YAML (``configs/train/*_v1.yaml``) on the training split, runs in parallel over ``workers`` processes.
   Optionally score each model on validation episodes (training wells, seeds disjoint from tuning and test)
   to pick one seed (``agents.selection: best_on_validation``); the default, ``mean``, reports the
   per-episode reward averaged over all seeds' models: the training procedure, not a lucky seed.
3. **Test** every policy on the same test episodes: ``reset(seed=S)`` on ``scenario="test"`` for the test
   seeds (disjoint from every tuning and validation seed).
4. **Report**: ``OUT/benchmark.json`` (schema in :func:`build_report`), ``OUT/benchmark.md`` (tables,
   verdict, figure ``OUT/figures/benchmark_v1.png``), models in ``OUT/models/<algo>_<vN>*.zip`` (vN the env's version) with the
   observation normalisation as ``.npz`` (the shipped run, ``OUT`` = docs: in the repository's ``models/``
   with its ``MANIFEST.json``). Files are written atomically, nothing partial is left behind.

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

from ..envs import ENV_ID_V1, env_tag, make_env
from ..evaluation.manifest import MODELS_HOME, shipped_out_dir, shipped_reports, write_manifest
from ..evaluation.rollout import Runner
from ..inputs import check_output_dir
from ..policies.field import interval_s_of
from .assemble import figure_traces, policy_records
from .config import BenchmarkConfigError, load_benchmark_config
from .figure import figure
from .report import (
    _atomic_write,
    _json_clean,
    build_report,
    markdown_tables,
    summary_line,
    verdict,
    write_markdown,
)
from .stages import run_test_episodes, train_agents, tune_baselines, validate

__all__ = ["benchmark_main", "quickstart", "run_benchmark"]


REPORT_FILES = ("benchmark.json", "benchmark.md", "figures/benchmark_v1.png")  # what run_benchmark writes in out_dir


def run_benchmark(cfg: dict[str, Any], out_dir: str | Path, quick: bool = False,
                  log: Any = None, models_dir: str | Path | None = None) -> dict[str, Any]:
    """The protocol of the module doc: tune, train, validate, test (:mod:`.stages`), then the report, its
    markdown and figure in ``out_dir``, the models in ``models_dir`` (default ``out_dir/models``); returns
    the report."""
    log = log or (lambda m: print(m, file=sys.stderr, flush=True))
    out = Path(out_dir)
    check_output_dir(out, REPORT_FILES)  # before any work
    models = Path(models_dir) if models_dir is not None else out / "models"
    t_start = time.perf_counter()
    wall: dict[str, float] = {}
    test_seeds = cfg["test"]["seeds"]
    fig_seed = test_seeds[int(cfg.get("figure_episode", 0)) % len(test_seeds)]
    workdir = Path(tempfile.mkdtemp(prefix="benchmark_runs_", dir=cfg.get("work_dir") or None))
    try:
        with Runner(cfg["workers"]) as runner:
            tuned, tuning_split = tune_baselines(cfg, runner, log)
            wall["tuning"] = time.perf_counter() - t_start
            t = time.perf_counter()
            agent_specs, teachers, _ = train_agents(cfg, runner, tuned, workdir, models)
            wall["training"] = time.perf_counter() - t
            t = time.perf_counter()
            val_scores, val_wells = validate(cfg, runner, agent_specs)
            wall["validation"] = time.perf_counter() - t
            t = time.perf_counter()
            by_entry = run_test_episodes(cfg, runner, tuned, agent_specs, fig_seed)
            wall["test"] = time.perf_counter() - t
    finally:
        shutil.rmtree(workdir, ignore_errors=True)
    policies, training = policy_records(cfg, tuned, agent_specs, teachers, by_entry, val_scores, models)
    test_kwargs = {**cfg["env_kwargs"], "scenario": cfg["test"].get("scenario", "test")}
    traces = figure_traces(policies, agent_specs, by_entry, val_scores, fig_seed,
                           _interval_s(cfg["env_id"], test_kwargs, fig_seed))
    splits = {"tuning": tuning_split,
              "validation": {"scenario": cfg["validation"].get("scenario", "train"), "seeds": cfg["validation"]["seeds"],
                             "well_ids": val_wells},
              "test": {"scenario": test_kwargs["scenario"], "seeds": test_seeds,
                       "well_ids": sorted({e["well_id"] for e in policies["installed"]["episodes"]})}}
    wall["total"] = time.perf_counter() - t_start
    return _write_report(cfg, out, quick, policies, splits, tuned, training, wall, traces)


def _write_report(cfg: dict[str, Any], out: Path, quick: bool, policies: dict[str, Any], splits: dict[str, Any],
                  tuned: dict[str, Any], training: dict[str, Any], wall: dict[str, float],
                  traces: dict[str, Any]) -> dict[str, Any]:
    """benchmark.json, benchmark.md and the figure, each written atomically."""
    report = build_report(cfg, policies, splits, {n: {k: v for k, v in t.items() if k != "evaluated"}
                                                   for n, t in tuned.items()}, training, wall)
    report["quick"] = quick
    report["tuning_history"] = {n: t.get("evaluated", []) for n, t in tuned.items()}
    fig_rel = "figures/benchmark_v1.png"
    figure(report, traces, out / fig_rel)
    if cfg["env_id"] != ENV_ID_V1:  # v2 on: the rliable figures (agents/benchmark/rliable_stats.py)
        from .rliable_stats import rliable_section

        report["rliable"] = rliable_section(report)
    report = _json_clean(report)
    _atomic_write(out / "benchmark.json", json.dumps(report, indent=1))
    write_markdown(report, out / "benchmark.md", fig_rel)
    return report


def _interval_s(env_id: str, kwargs: dict[str, Any], seed: int) -> float:
    env = make_env(env_id, **kwargs)
    try:
        env.reset(seed=seed)
        return interval_s_of(env)
    finally:
        env.close()


def benchmark_main(config: str, quick: bool = False, out_dir: str | None = None) -> dict[str, Any]:
    """``python -m agents benchmark``: the whole protocol; prints the table and returns the JSON summary."""
    if out_dir is not None:  # first: before the config and its training YAMLs are read (run_benchmark checks again)
        check_output_dir(Path(out_dir), REPORT_FILES)
    cfg = load_benchmark_config(config, quick=quick)
    # the shipped run (no --out-dir): its report where the env version's shipped report lives (docs/ for v1,
    # docs/v2/ for v2: one version's run never overwrites another's), its models in the repository's models/
    tag = env_tag(cfg["env_id"])
    home = shipped_out_dir(tag)
    shipped = out_dir is None and not quick and home is not None
    out = Path(out_dir or ("runs/benchmark_quick" if quick else home or f"runs/benchmark_{tag}"))
    report = run_benchmark(cfg, out, quick=quick, models_dir=MODELS_HOME if shipped else None)
    if shipped:
        write_manifest(MODELS_HOME, shipped_reports(MODELS_HOME.parent))
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
    check_output_dir(Path(out_dir), REPORT_FILES, "--out")  # first: before the config is read, the notice, any work
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
