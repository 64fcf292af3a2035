"""``python -m agents benchmark CONFIG --evaluate-only --fresh-seed S --episodes N --out-dir DIR``.

Evaluates the SHIPPED models and the tuned baselines on N fresh wells of the family - wells nobody has trained,
tuned, selected or evaluated on - with no training and no tuning, and writes the benchmark report's schema
(``DIR/benchmark.json``: ``policies`` -> ``episodes`` records with ``well_id``, ``seed``, ``reward``, ``cost``;
``summary``, ``paired``, ``rliable``; ``DIR/benchmark.md``).

- Wells: ``scenario="family:W"`` for W in :func:`fresh_wells` (N seeds drawn from ``S``; the report records S and
  the W), episode k played from ``reset(seed=k)``.
- Policies: the shipped report's (:func:`agents.evaluation.shipped.shipped_report`) tuned baselines ``installed``,
  ``best_constant``, ``pump_off``, ``fillage_pi`` and the agents listed in the config's ``evaluate_only.agents``;
  ``alarm_pump_off`` with the report's tuned parameters when the report has it (v2's benchmark tunes it), else,
  on v2, pump-off's tuned parameters with the config's fixed ``evaluate_only.alarm_params`` (a report made
  before it was tuned, such as the shipped v1 one); and, when the config lists it, ``causal_oracle`` (the
  reference of the normalised score) and the clairvoyant ``oracle``.
- Which report (:func:`default_report`, or ``--report``): the shipped report that holds the config's agents, the
  config's env version's first - ``configs/benchmark/v2_oracle_distilled.yaml`` plays the shipped v2 agent
  (``docs/v2/benchmark.json``), ``configs/benchmark/v2.yaml`` the shipped v1 agents. v1 agents on v2 see v1's part
  of v2's field observation (its first 77 entries are v1's: :class:`agents.evaluation.v1_view.V1ObsView`), so they
  run unchanged; the conditions and the classifier's output are then unseen by them.
- Models: the report's agents are rebuilt by :func:`agents.evaluation.replay.policy_specs`, so a record that pins
  its files (``sha256``) refuses, before any episode, a member whose file has another digest; the written report
  pins the files it played (:mod:`agents.evaluation.model_pins`), whether or not ``--report`` pinned them.
- ``python -m agents replay DIR/benchmark.json`` re-runs the report's episodes on the same family wells.
"""

from __future__ import annotations

import json
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

from ..envs import PLAYABLE_REPORTS, env_tag
from ..evaluation.model_pins import PINS, member_pins, spec_members
from ..evaluation.replay import ReplayError, load_report, policy_specs
from ..evaluation.rollout import Runner, _cached_env, run_episode
from ..evaluation.v1_view import build_policy_any
from ..inputs import check_output_dir
from .report import _atomic_write, _json_clean, build_report, markdown_tables, verdict

SHIPPED_BASELINES = ("installed", "best_constant", "pump_off", "fillage_pi")
DEFAULT_AGENTS = ("ppo_residual_distilled_ensemble",)
OUT_FILES = ("benchmark.json", "benchmark.md")  # what evaluate_fresh writes in --out-dir


def fresh_wells(fresh_seed: int, n: int) -> list[int]:
    """N family well seeds drawn from ``fresh_seed`` (distinct)."""
    rng = np.random.default_rng([int(fresh_seed), 0xF4E5])
    seeds: list[int] = []
    while len(seeds) < n:
        s = int(rng.integers(0, 2**62))
        if s not in seeds:
            seeds.append(s)
    return seeds


def fresh_episode_job(job: dict[str, Any]) -> dict[str, Any]:
    """Worker entry (as :func:`agents.evaluation.rollout.episode_job`, for any env version)."""
    import torch

    torch.set_num_threads(1)
    env = _cached_env(job["env_id"], job["env_kwargs"])
    return run_episode(env, build_policy_any(job["policy"], env), job["seed"], trace=job.get("trace", False))


def default_report(cfg: dict[str, Any]) -> Path:
    """The shipped report that holds the config's ``evaluate_only.agents``: the config's own env version's first
    (v2_oracle_distilled.yaml: the shipped v2 agent), else an earlier version's whose agents drive the config's env
    (``agents.envs.PLAYABLE_REPORTS``: v2.yaml names v1's agents, played on v2; v3.yaml the shipped v2 students)."""
    from ..evaluation.shipped import shipped_report

    wanted = (cfg.get("evaluate_only") or {}).get("agents", DEFAULT_AGENTS)
    for version in dict.fromkeys(env_tag(e) for e in PLAYABLE_REPORTS.get(cfg["env_id"], (cfg["env_id"],))):
        try:
            path = shipped_report(version)
        except ValueError:  # no agent of that version is shipped
            continue
        if all(str(a) in load_report(path)["policies"] for a in wanted):
            return path
    return shipped_report("v1")


def _specs(cfg: dict[str, Any], rep: dict[str, Any], root: Path) -> dict[str, list[dict[str, Any]]]:
    ev = cfg.get("evaluate_only") or {}
    specs = {n: policy_specs(rep, n, root) for n in SHIPPED_BASELINES}
    for a in ev.get("agents", DEFAULT_AGENTS):
        specs[str(a)] = policy_specs(rep, str(a), root)
    if "alarm_pump_off" in rep["policies"]:  # a report whose benchmark tuned it (v2's): its tuned parameters
        specs["alarm_pump_off"] = policy_specs(rep, "alarm_pump_off", root)
    elif cfg["env_id"] != rep["env_id"]:  # an older report without it: pump-off's tuned set point + fixed alarms
        alarms = {**rep["policies"]["pump_off"]["params"], **(ev.get("alarm_params") or {})}
        specs["alarm_pump_off"] = [{"kind": "baseline", "name": "alarm_pump_off", "params": alarms}]
    for name in ("causal_oracle", "oracle"):  # null: not run
        params = (ev.get("references") or {}).get(name)
        if params is not None:
            params = dict(params)
            if name == "causal_oracle":  # it also weighs following each tuned field baseline (its docstring)
                params.setdefault("policies", [[b, rep["policies"][b]["params"]] for b in ("pump_off", "fillage_pi")])
            specs[name] = [{"kind": "baseline", "name": name, "params": params}]
    return specs


def evaluate_fresh(config: str, fresh_seed: int, episodes: int, out_dir: str | Path,
                   workers: int | None = None, report: str | Path | None = None) -> dict[str, Any]:
    """``report``: the benchmark report whose tuned baselines and agents are played (``--report``; its models
    are read next to it), by default :func:`default_report`."""
    from .config import load_benchmark_config

    t0 = time.perf_counter()
    check_output_dir(Path(out_dir), OUT_FILES, "--out-dir")  # first: before the config, report and models are read
    cfg = load_benchmark_config(config)
    path = Path(report) if report is not None else default_report(cfg)
    rep = load_report(path)  # data only (JSON, schema and fields checked)
    playable = PLAYABLE_REPORTS.get(cfg["env_id"], (cfg["env_id"],))
    if rep["env_id"] not in playable:
        raise ReplayError(f"--report {path}: env_id = {rep['env_id']!r}, expected {cfg['env_id']!r} (the config's) "
                          f"or an earlier version whose agents drive it ({', '.join(playable[1:]) or 'none'})")
    tuned_from = (cfg.get("evaluate_only") or {}).get("tuned")
    if tuned_from:
        rep = with_tuned(rep, load_tuned(tuned_from))
    specs = _specs(cfg, rep, path.resolve().parent)
    wells = fresh_wells(fresh_seed, episodes)
    jobs, owner = [], []
    for n, sps in specs.items():
        for sp in sps:
            for k, w in enumerate(wells):
                jobs.append({"env_id": cfg["env_id"], "env_kwargs": {**cfg["env_kwargs"], "scenario": f"family:{w}"},
                             "policy": sp, "seed": k})
                owner.append(n)
    print(f"evaluate-only: {len(specs)} policies on {episodes} fresh family wells (seed {fresh_seed}), "
          f"{len(jobs)} episodes", file=sys.stderr, flush=True)
    with Runner(workers or cfg["workers"]) as runner:
        recs = runner.map(jobs, fn=fresh_episode_job)
    policies = _policies(rep, specs, owner, recs, episodes)
    splits = {"test": {"scenario": "family", "seeds": list(range(episodes)),
                       "well_ids": [f"family-{w}" for w in wells]},
              "fresh": {"seed": int(fresh_seed), "family_seeds": wells, "drawn_by": "agents.benchmark.fresh.fresh_wells"}}
    report = build_report(cfg, policies, splits, rep.get("tuned", {}), {"shipped_report": str(path)},
                          {"total": time.perf_counter() - t0})
    report.update(mode="evaluate_only", shipped_report=str(path), **({"tuned_from": tuned_from} if tuned_from else {}))
    _renormalise(report)
    return _write(report, Path(out_dir))


def load_tuned(path: str | Path) -> dict[str, Any]:
    """The ``tuned`` record of a tuned-baselines archive (``docs/v3/tuned.json``, scripts/v3_tune.py): read as data,
    each baseline's ``params`` a mapping (their values are checked where a policy is built from them). A relative
    path is taken as given, else in the checkout (beside ``models/``, as the shipped reports)."""
    from srenv.input_files import read_json

    from ..evaluation.manifest import MODELS_HOME

    p = Path(path)
    if not (p.is_file() or p.is_absolute()):
        p = MODELS_HOME.parent / p
    if not p.is_file():
        raise ReplayError(f"evaluate_only.tuned = {str(path)!r}: no such file (expected a tuned-baselines JSON)")
    rec = read_json(p, "evaluate_only.tuned", "tuned-baselines archive", 5_000_000)
    tuned = rec.get("tuned") if isinstance(rec, dict) else None
    if not (isinstance(tuned, dict) and tuned and all(isinstance(t, dict) and isinstance(t.get("params"), dict)
                                                      for t in tuned.values())):
        raise ReplayError(f"evaluate_only.tuned = {str(path)!r}: tuned = {str(tuned)[:80]}: expected a mapping "
                          "baseline -> {params: {...}}")
    return tuned


def with_tuned(rep: dict[str, Any], tuned: dict[str, Any]) -> dict[str, Any]:
    """A copy of report ``rep`` on other tuned baselines (another env version's tuning: v3's on v2's report): each
    tuned field baseline's ``params`` (added when the report lacks it), every agent's residual base on the tuned
    parameters of its base, and ``tuned``; the agents' models and pins as they were."""
    import copy

    out = copy.deepcopy(rep)
    pol = out["policies"]
    for name in (*SHIPPED_BASELINES, "alarm_pump_off"):
        if name in tuned:
            pol[name] = {**pol.get(name, {"kind": "baseline", "episodes": []}), "params": tuned[name]["params"]}
    for entry in pol.values():
        res = entry.get("residual_on") if entry.get("kind") == "agent" else None
        if isinstance(res, dict) and res.get("base") in tuned:
            entry["residual_on"] = {**res, "params": tuned[res["base"]]["params"]}
    out["tuned"] = tuned
    return out


def _policies(rep: dict[str, Any], specs: dict[str, list[dict[str, Any]]], owner: list[str],
              recs: list[dict[str, Any]], n_eps: int) -> dict[str, Any]:
    from .report import _average_episodes

    out: dict[str, Any] = {}
    for n, sps in specs.items():
        mine = [r for r, o in zip(recs, owner) if o == n]
        per_model = [mine[i:i + n_eps] for i in range(0, len(mine), n_eps)]
        eps = per_model[0] if len(per_model) == 1 else _average_episodes(per_model)
        kind = "agent" if sps[0]["kind"] != "baseline" else "baseline"
        entry: dict[str, Any] = {"kind": kind, "episodes": eps}
        if kind == "baseline":
            entry["params"] = sps[0].get("params", {})
        else:  # what replay needs to rebuild it (agents/evaluation/replay.py), the files it played pinned
            entry.update({k: v for k, v in rep["policies"][n].items()
                          if k in ("models", "residual_on", "ensemble_of", "algo", "guarded", "described")})
            entry[PINS] = member_pins(entry["models"], [m for sp in sps for m in spec_members(sp)])
        out[n] = entry
    return out


def _renormalise(report: dict[str, Any]) -> None:
    """The normalised score against the causal oracle when it ran (the fair top), else as build_report did."""
    s = report["summary"]
    if "causal_oracle" not in s:
        return
    base, top = s["installed"]["mean_reward"], s["causal_oracle"]["mean_reward"]
    for row in s.values():
        row["normalised_score"] = (row["mean_reward"] - base) / (top - base) if top != base else float("nan")
    report["normalised_score"] = {n: r["normalised_score"] for n, r in s.items()}
    report["normalised_to"] = "causal_oracle"


def _write(report: dict[str, Any], out: Path) -> dict[str, Any]:
    from .rliable_stats import markdown as rliable_md
    from .rliable_stats import rliable_section

    pol = report["policies"]
    if "causal_oracle" in pol or "oracle" in pol:
        report["rliable"] = rliable_section(report)
    # the text from the figures as computed (a CI of one episode is NaN, which the JSON writes as null)
    tables, call = markdown_tables(report), verdict(report)
    title = (f"# Evaluate-only on {len(report['fresh']['family_seeds'])} fresh family wells "
             f"(fresh seed {report['fresh']['seed']})")
    md = [title, "", tables, "", call]
    if "rliable" in report:
        md += ["", rliable_md(report["rliable"])]
    report = _json_clean(report)
    _atomic_write(out / "benchmark.json", json.dumps(report, indent=1))
    _atomic_write(out / "benchmark.md", "\n".join(md) + "\n")
    print(tables, flush=True)
    print(call, flush=True)
    return {"benchmark_json": str(out / "benchmark.json"), "markdown": str(out / "benchmark.md"),
            "fresh_seed": report["fresh"]["seed"], "episodes": len(report["fresh"]["family_seeds"])}
