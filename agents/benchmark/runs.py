"""The benchmark's agents: one training run per (algo, seed) in a worker, model export, residual runs.

A run's model is copied to ``OUT/models/<name>_<vN>_seed<k>.zip`` (``vN`` the env's version) with its observation statistics as plain
arrays (``<stem>_obs_norm.npz``); a residual run (``residual: {base, scale}``) trains on
:class:`agents.training.residual_env.ResidualEnv` around a tuned field baseline.
"""

from __future__ import annotations

import os
import shutil
import sys
from pathlib import Path
from typing import Any

from ..envs import env_tag
from ..evaluation.normalizer import ObsNormalizer, obs_norm_path
from ..policies.residual import RESIDUAL_BASES
from ..training.tuning import refuse_test_split
from .config import BenchmarkConfigError


def train_job(job: dict[str, Any]) -> dict[str, Any]:
    """Worker entry: train one (algo, seed) run with :func:`agents.training.sb3.train.train`."""
    import torch

    from ..training.config import load_train_config
    from ..training.sb3.train import train

    torch.set_num_threads(1)
    over = {"seed": job["seed"], **job.get("overrides", {})}
    cfg = load_train_config(job["config"], over)
    refuse_test_split(cfg.env_kwargs.get("scenario", "train"), "train")
    summary = train(cfg, job["out"], progress_bar=False,
                    log=lambda m: print(f"[{job['algo']} seed {job['seed']}] {m}", file=sys.stderr, flush=True))
    summary["seed"] = job["seed"]
    return summary


def export_model(summary: dict[str, Any], dest_zip: Path) -> dict[str, Any]:
    """Copy a trained model to ``dest_zip`` and its observation statistics to ``<stem>_obs_norm.npz``
    (plain arrays: the VecNormalize pickle, our own file from training, is read here and not shipped)."""
    import pickle

    dest_zip.parent.mkdir(parents=True, exist_ok=True)
    tmp = dest_zip.with_suffix(".zip.tmp")
    shutil.copyfile(summary["model"], tmp)
    os.replace(tmp, dest_zip)
    norm_path = None
    if summary.get("vecnormalize"):
        with open(summary["vecnormalize"], "rb") as fh:
            vn = pickle.load(fh)  # written by this benchmark's own training run
        if vn.norm_obs:
            norm_path = obs_norm_path(dest_zip)
            ObsNormalizer.from_variance(vn.obs_rms.mean, vn.obs_rms.var, vn.clip_obs, vn.epsilon).save(str(norm_path))
    return {"kind": "agent", "path": str(dest_zip), "obs_norm": str(norm_path) if norm_path else None}


def _algo_of(run: dict[str, Any]) -> str:
    from ..training.config import load_train_config

    return load_train_config(run["config"]).algo


def _policy_part(spec: dict[str, Any]) -> dict[str, Any]:
    # a guarded spec's parts too (agents/policies/guarded.py): its inner policy, fallback, guard and scale; and a
    # described student's flag (agents/policies/described_features.py: the well file's features on its input)
    return {k: spec[k] for k in ("kind", "path", "obs_norm", "residual", "members", "inner", "fallback", "guard",
                                 "scale", "described") if k in spec}


def residual_spec(run: dict[str, Any], tuned: dict[str, Any]) -> dict[str, Any] | None:
    """``{base, params, scale[, idle_scale]}`` of a residual agent run (``residual: {base: NAME | best_tuned,
    scale, idle_scale}``):
    the base is a tuned field baseline; ``best_tuned`` = the best tuning score (training wells)."""
    res = run.get("residual")
    if not res:
        return None
    base = res.get("base", "best_tuned")
    if base == "best_tuned":
        base = max(RESIDUAL_BASES, key=lambda n: tuned[n]["score"])
    if base not in RESIDUAL_BASES:
        raise BenchmarkConfigError(f"residual base = {base!r}: expected best_constant, pump_off, fillage_pi "
                                   "or best_tuned")
    spec = {"base": base, "params": tuned[base]["params"], "scale": float(res.get("scale", 0.3))}
    if res.get("idle_scale") is not None:
        spec["idle_scale"] = float(res["idle_scale"])
    if res.get("shaping"):
        spec["shaping"] = res["shaping"]  # training only: evaluation drives the plain env
    return spec


def residual_overrides(res: dict[str, Any] | None, run: dict[str, Any], cfg: dict[str, Any]) -> dict[str, Any]:
    """Training-YAML overrides that put a residual run on :class:`agents.training.residual_env.ResidualEnv`."""
    if not res:
        return {}
    from ..training.config import load_train_config
    from ..training.residual_env import RESIDUAL_ENV_ID
    from ..training.shaping import SHAPED_ENV_ID

    tc = load_train_config(run["config"])
    # potential-based shaping (agents/training/shaping.py) wraps the env the residual acts on, for training only
    inner = SHAPED_ENV_ID if res.get("shaping") == "potential" else tc.env_id
    kwargs = {**tc.env_kwargs, "inner_env_id": inner, "base": res["base"], "base_params": res["params"],
              "scale": res["scale"]}
    if res.get("idle_scale") is not None:
        kwargs["idle_scale"] = res["idle_scale"]
    return {"env_id": RESIDUAL_ENV_ID, "env_kwargs": kwargs}



# ------------------------------------------------------------------------ teacher-student runs
def model_name(algo: str, run: dict[str, Any]) -> str:
    """The exported model's stem: a teacher-student run's training jobs train its teachers."""
    return f"{algo}_teacher" if run.get("teacher") else algo


def training_overrides(run: dict[str, Any], res: dict[str, Any] | None, cfg: dict[str, Any]) -> dict[str, Any]:
    """The training-YAML overrides of one run's jobs: a teacher trains on the privileged observation, with
    the teacher's ``idle_scale`` if it has one (agents/training/distill.py)."""
    t = run.get("teacher")
    if not t or not res:
        return residual_overrides(res, run, cfg)
    teacher_res = {**res, **({"idle_scale": float(t["idle_scale"])} if t.get("idle_scale") is not None else {})}
    over = residual_overrides(teacher_res, run, cfg)
    over["env_kwargs"] = {**over["env_kwargs"], "observation": "privileged"}
    return over


def distill_jobs(runs: dict[str, Any], teachers: dict[str, list[dict[str, Any]]],
                 agent_specs: dict[str, list[dict[str, Any]]], residuals: dict[str, Any], env_id: str,
                 train_kwargs: dict[str, Any], models_dir: Path) -> list[dict[str, Any]]:
    """One :func:`agents.training.distill.distill_job` per (teacher-student run, seed): the run's teachers teach
    a copy of ``students_from``'s model of that seed."""
    from .config import distill_seeds

    jobs = []
    for a, tspecs in teachers.items():
        t = runs[a]["teacher"]
        src = agent_specs[t["students_from"]]
        # the config loader checked that students_from has this run's seeds (in order) and residual
        for init, seed in zip(src, runs[a]["seeds"]):
            jobs.append({"algo": a, "seed": seed, "teachers": [_policy_part(s) for s in tspecs],
                         "student_init": _policy_part(init), "residual": residuals[a], "env_id": env_id,
                         "env_kwargs": train_kwargs, "seeds": distill_seeds(t, seed),
                         "iterations": t["iterations"], "dest": str(models_dir / f"{a}_{env_tag(env_id)}_seed{seed}.zip"),
                         "teacher_summaries": [s["train_summary"] for s in tspecs]})
    return jobs


# ------------------------------------------------------------------------ causal-oracle teachers
def is_oracle_run(run: dict[str, Any]) -> bool:
    """A run whose teacher is the causal oracle (agents/training/oracle_distill.py): no PPO training job."""
    t = run.get("teacher")
    return isinstance(t, dict) and t.get("kind") is not None


def oracle_student(cfg: dict[str, Any], runner: Any, algo: str, seed: int, tuned: dict[str, Any],
                   res: dict[str, Any], models_dir: Path) -> dict[str, Any]:
    """One student of a causal-oracle run: DAgger on training-split episodes from the true env state; the
    oracle weighs the tuned pump_off and fillage_pi as the benchmark's causal-oracle reference does."""
    from ..training.config import load_train_config
    from ..training.oracle_distill import ORACLE_POLICIES, distill_oracle
    from .config import distill_seeds

    run = cfg["agents"]["runs"][algo]
    t = run["teacher"]
    oracle = {**t.get("params", {}), "policies": [[b, tuned[b]["params"]] for b in ORACLE_POLICIES]}
    pk = load_train_config(run["config"], run.get("overrides")).policy_kwargs
    spec = distill_oracle(runner, t, oracle, res, cfg["env_id"], {**cfg["env_kwargs"], "scenario": "train"}, pk,
                          distill_seeds(t, seed), seed, models_dir / f"{algo}_{env_tag(cfg['env_id'])}_seed{seed}.zip",
                          log=lambda m: print(m, file=sys.stderr, flush=True))
    spec["residual"] = res
    spec["train_summary"] = {"num_timesteps": spec["distill"][-1]["labels"], "wall_time_s": spec["wall_time_s"],
                             "seed": seed, "best_eval_mean_reward": None}
    return spec
