"""Ray RLlib as the second backend of ``python -m agents train`` (``backend: rllib`` in the training YAML).

The YAML's schema and checks are in :mod:`agents.training.rllib.config`, the checkpoint files in
:mod:`agents.training.rllib.checkpoints`, evaluation in :mod:`agents.evaluation.rllib_model`. Ray runs locally,
bound to the loopback interface and without dashboard, unless ``--address`` names a cluster (``auto`` or
``ray://host:10001``): the cluster's nodes then need srenv installed. Outputs in ``--out DIR``:
``checkpoint/`` (the final algorithm checkpoint: ``python -m agents evaluate --policy DIR/checkpoint``),
``checkpoints/step_<N>/`` (every ``checkpoint_freq`` steps; ``--resume`` continues from the newest that
restores) and ``train_config.json``. Every checkpoint also holds ``srenv_progress.json`` (steps done) and
the policy as data (``srenv_policy.json`` + ``srenv_policy_weights.pt``): ``evaluate`` reads those, never
RLlib's pickles, unless ``--trust-model`` is given.
"""

from __future__ import annotations

import json
import math
import os
import sys
import time
from collections.abc import Callable
from dataclasses import asdict
from pathlib import Path
from typing import Any

from .checkpoints import restore_checkpoint, save_checkpoint
from .config import BACKEND, RLlibTrainConfig, build_algorithm_config


# ------------------------------------------------------------------------------------------------- Ray
def start_ray(address: str | None, num_cpus: int | None, runners: int) -> bool:
    """Connect to ``address`` or start a local Ray on the loopback interface; True if this call started it."""
    import ray

    if ray.is_initialized():
        return False
    # the driver's torch learner and the runners' envs share the cores; runners would fight over threads
    env_vars = {"OMP_NUM_THREADS": "1", "MKL_NUM_THREADS": "1"}
    if address:
        ray.init(address=address, runtime_env={"env_vars": env_vars}, log_to_driver=False)
    else:
        # every runner asks for one CPU, the driver's learner another: on a small machine Ray would wait
        # forever for CPUs it does not have, so it is told the runs' demand (they time-share the cores)
        cpus = num_cpus or max(os.cpu_count() or 1, runners + 1)
        ray.init(_node_ip_address="127.0.0.1", include_dashboard=False, num_cpus=cpus,
                 runtime_env={"env_vars": env_vars}, log_to_driver=False, configure_logging=False)
    return True



def _env_steps(result: dict) -> int:
    """Environment steps sampled in one ``train()`` result (summed over runners)."""
    from ray.rllib.utils.metrics import ENV_RUNNER_RESULTS, NUM_ENV_STEPS_SAMPLED

    return int(result.get(ENV_RUNNER_RESULTS, {}).get(NUM_ENV_STEPS_SAMPLED, 0))


def _episode_return(result: dict) -> float | None:
    from ray.rllib.utils.metrics import ENV_RUNNER_RESULTS, EPISODE_RETURN_MEAN

    v = result.get(ENV_RUNNER_RESULTS, {}).get(EPISODE_RETURN_MEAN)
    return float(v) if v is not None and math.isfinite(float(v)) else None


# ------------------------------------------------------------------------------------------------ train
def train(cfg: RLlibTrainConfig, out_dir: str | Path, total_timesteps: int | None = None, resume: bool = False,
          address: str | None = None, log: Callable[[str], None] | None = None) -> dict[str, Any]:
    """Train (or continue) one RLlib run; returns the JSON-ready summary."""
    log = log or (lambda msg: print(msg, file=sys.stderr, flush=True))
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    target = int(total_timesteps or cfg.n_timesteps)
    t_start = time.perf_counter()
    started = start_ray(address, cfg.num_cpus, cfg.num_env_runners)
    algo = None
    try:
        algo = build_algorithm_config(cfg).build_algo()
        steps, iterations, resumed_from = 0, 0, None
        if resume:
            restored = restore_checkpoint(algo, out, log)
            if restored is None:
                log(f"resume: no checkpoint in {out / 'checkpoints'}, starting from scratch")
            else:
                steps, iterations, path = restored
                resumed_from = str(path)
                log(f"resume: {path.name} at {steps} steps")
        (out / "train_config.json").write_text(json.dumps(asdict(cfg), indent=2, default=str))
        last_return = None
        next_ckpt = (steps // cfg.checkpoint_freq + 1) * cfg.checkpoint_freq
        while steps < target:
            result = algo.train()
            sampled = _env_steps(result)
            if sampled <= 0:
                raise RuntimeError("RLlib sampled no environment steps in a training iteration")
            steps += sampled
            iterations += 1
            last_return = _episode_return(result) if _episode_return(result) is not None else last_return
            log(f"rllib iteration {iterations}: {steps} steps, episode return mean {last_return}")
            if steps >= next_ckpt and steps < target:
                save_checkpoint(algo, cfg, out / "checkpoints" / f"step_{steps}", steps, iterations)
                next_ckpt = (steps // cfg.checkpoint_freq + 1) * cfg.checkpoint_freq
        (out / "checkpoints").mkdir(exist_ok=True)
        save_checkpoint(algo, cfg, out / "checkpoints" / f"step_{steps}", steps, iterations)
        final = save_checkpoint(algo, cfg, out / "checkpoint", steps, iterations)
    finally:
        if algo is not None:
            algo.stop()
        if started:
            import ray

            ray.shutdown()
    return {
        "backend": BACKEND,
        "algo": cfg.algo,
        "num_timesteps": steps,
        "target_timesteps": target,
        "iterations": iterations,
        "num_env_runners": cfg.num_env_runners,
        "num_envs_per_env_runner": cfg.num_envs_per_env_runner,
        "wall_time_s": round(time.perf_counter() - t_start, 2),
        "resumed_from": resumed_from,
        "model": str(final),
        "last_episode_return_mean": last_return,
    }
