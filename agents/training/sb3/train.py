"""Stable-Baselines3 training from an rl-zoo3-style hyperparameter YAML (its schema:
:mod:`agents.training.config`).

Outputs in ``--out DIR``: ``model.zip`` + ``model_vecnormalize.json`` (the normalisation statistics are
part of the policy: without them the network sees unscaled inputs; JSON so that evaluation reads them
without unpickling, the ``.pkl`` beside it is for resuming), ``best/best_model.zip`` +
``best/best_model_vecnormalize.json`` / ``.pkl`` + ``best/best_model.json`` (EvalCallback; its best mean
reward), ``checkpoints/`` (model, VecNormalize and, for
off-policy algorithms, replay buffer every ``checkpoint_freq`` steps), ``tb/`` (TensorBoard) and
``train_config.json`` (the resolved configuration). ``--resume`` continues from the newest readable
checkpoint with its statistics and the step count carried on (``reset_num_timesteps=False``).

The run is put together from :mod:`.builders` (env, policy kwargs, schedules), :mod:`.checkpoints`
(checkpoint files, resume) and :mod:`.callbacks` (the best model's record, evaluation history).
"""

from __future__ import annotations

import json
import math
import sys
import time
from collections.abc import Callable
from dataclasses import asdict
from pathlib import Path
from typing import Any

from ...evaluation.model_io import VECNORM_SUFFIX, algorithms
from ..config import (
    TrainConfig,
)
from .builders import build_policy_kwargs, build_vec_env, schedule
from .callbacks import (
    _eval_reporter,
    _recorded_best,
    _restore_eval_history,
    _save_vecnormalize_callback,
)
from .checkpoints import CHECKPOINT_PREFIX, _load_checkpoint


# ------------------------------------------------------------------------------------------------ train
def train(cfg: TrainConfig, out_dir: str | Path, total_timesteps: int | None = None, resume: bool = False,
          progress_bar: bool = False, log: Callable[[str], None] | None = None) -> dict[str, Any]:
    """Train (or continue) one run; returns the JSON-ready summary."""
    import torch
    from stable_baselines3.common.callbacks import CallbackList, CheckpointCallback, EvalCallback
    from stable_baselines3.common.vec_env import VecNormalize

    log = log or (lambda msg: print(msg, file=sys.stderr, flush=True))
    # The env workers take the cores; a multi-threaded torch in the learner would only fight them.
    torch.set_num_threads(1)
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    target = int(total_timesteps or cfg.n_timesteps)
    n_envs = cfg.resolved_n_envs
    t_start = time.perf_counter()
    venv_raw = build_vec_env(cfg, n_envs, cfg.seed, subproc=cfg.vec_env == "subproc", native=cfg.vec_env == "native")
    eval_env = build_vec_env(cfg, 1, cfg.eval_seed, subproc=False)
    loaded = _load_checkpoint(cfg, venv_raw, out) if resume else None
    resumed_from = None
    if loaded is not None:
        model, venv, path = loaded
        resumed_from = str(path)
        log(f"resume: {path.name} at {model.num_timesteps} steps")
    else:
        if resume:
            log(f"resume: no checkpoint in {out / 'checkpoints'}, starting from scratch")
        venv = VecNormalize(venv_raw, **cfg.normalize) if cfg.normalize is not None else venv_raw
        kwargs = {"device": "cpu", "verbose": 0, **{k: schedule(v) for k, v in cfg.algo_kwargs.items()}}
        model = algorithms()[cfg.algo](cfg.policy, venv, policy_kwargs=build_policy_kwargs(cfg.policy_kwargs),
                                       tensorboard_log=str(out / "tb"), seed=cfg.seed, **kwargs)
    if cfg.normalize is not None:
        # evaluation sees normalised observations but raw rewards; EvalCallback syncs the statistics
        eval_env = VecNormalize(eval_env, training=False, norm_obs=cfg.normalize.get("norm_obs", True),
                                norm_reward=False)
    (out / "train_config.json").write_text(json.dumps(asdict(cfg), indent=2, default=str))
    best_dir = out / "best"
    eval_cb = EvalCallback(
        eval_env, n_eval_episodes=cfg.n_eval_episodes, eval_freq=max(cfg.eval_freq // n_envs, 1),
        best_model_save_path=str(best_dir), log_path=str(out / "eval"), deterministic=True, verbose=0,
        callback_on_new_best=_save_vecnormalize_callback(best_dir / ("best_model" + VECNORM_SUFFIX)),
        callback_after_eval=_eval_reporter())
    if resumed_from is not None:
        _restore_eval_history(eval_cb, out / "eval" / "evaluations.npz", model.num_timesteps)
    if (best_dir / "best_model.zip").is_file():
        # whatever the history says, never replace an existing best_model by a worse one
        eval_cb.best_mean_reward = max(eval_cb.best_mean_reward, _recorded_best(best_dir))
    ckpt_cb = CheckpointCallback(
        save_freq=max(cfg.checkpoint_freq // n_envs, 1), save_path=str(out / "checkpoints"),
        name_prefix=CHECKPOINT_PREFIX, save_vecnormalize=True, save_replay_buffer=cfg.save_replay_buffer)
    remaining = target - model.num_timesteps
    if remaining > 0:
        model.learn(total_timesteps=remaining, callback=CallbackList([ckpt_cb, eval_cb]),
                    reset_num_timesteps=resumed_from is None, tb_log_name=cfg.algo, progress_bar=progress_bar)
    model_path = out / "model.zip"
    model.save(str(model_path))
    stats_path = None
    if model.get_vec_normalize_env() is not None:
        from ...evaluation.model_io import stats_path as json_stats_path
        from ...evaluation.model_io import write_stats

        stats_path = out / ("model" + VECNORM_SUFFIX)
        model.get_vec_normalize_env().save(str(stats_path))  # pickle: what SB3 needs to resume
        write_stats(model.get_vec_normalize_env(), json_stats_path(model_path))  # JSON: what evaluation reads
    venv.close()
    eval_env.close()
    best = best_dir / "best_model.zip"
    return {
        "algo": cfg.algo,
        "num_timesteps": int(model.num_timesteps),
        "target_timesteps": target,
        "n_envs": n_envs,
        "wall_time_s": round(time.perf_counter() - t_start, 2),
        "resumed_from": resumed_from,
        "model": str(model_path),
        "vecnormalize": str(stats_path) if stats_path else None,
        "best_model": str(best) if best.is_file() else None,
        "best_eval_mean_reward": _finite_or_none(eval_cb.best_mean_reward),
        "last_eval_mean_reward": _finite_or_none(eval_cb.last_mean_reward),
        "tensorboard": str(out / "tb"),
    }


def _finite_or_none(x: float) -> float | None:
    return float(x) if math.isfinite(x) else None
