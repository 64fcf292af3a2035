"""RLlib checkpoints of this backend: ``Algorithm.save_to_path`` plus the policy as data and the steps done,
written atomically; the run's ``step_<N>`` directories and restoring the newest that loads."""

from __future__ import annotations

import json
import os
import re
import shutil
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from ...evaluation.rllib_model import POLICY_JSON, POLICY_WEIGHTS
from .config import RLlibTrainConfig

PROGRESS_FILE = "srenv_progress.json"
_STEP_DIR_RE = re.compile(r"^step_(\d+)$")


def step_checkpoints(out_dir: str | Path) -> list[tuple[int, Path]]:
    """(timesteps, path) of ``out_dir/checkpoints/step_<N>``, newest first."""
    d = Path(out_dir) / "checkpoints"
    found = [(int(m.group(1)), p) for p in d.glob("step_*") if p.is_dir() and (m := _STEP_DIR_RE.match(p.name))]
    return sorted(found, reverse=True)


def export_policy(algo: Any, cfg: RLlibTrainConfig, directory: Path) -> None:
    """The policy as data beside RLlib's pickles: the module's tensors (``torch.save`` of a state dict,
    read back with ``weights_only=True``) and a JSON description to rebuild the module from, so that
    ``evaluate`` needs no ``--trust-model`` for a checkpoint this backend wrote. With ``normalize`` on, the
    observation normaliser's statistics go into the same JSON (the module was trained on its output)."""
    import torch
    from ray.rllib.core import DEFAULT_MODULE_ID

    from ...evaluation.normalizer import OBS_NORMALIZER_KEY
    from .obs_filter import export_stats

    module = algo.get_module(DEFAULT_MODULE_ID)  # the env runners' copy: inference-only for PPO
    torch.save({k: v.detach().cpu() for k, v in module.state_dict().items()}, directory / POLICY_WEIGHTS)
    obs, act = module.observation_space, module.action_space
    # the model config the module was built with: the YAML's merged with the algorithm's own defaults
    model_config = dict(algo.config.model_config)
    json.dumps(model_config)  # plain data only, or this export cannot be read back as data
    (directory / POLICY_JSON).write_text(json.dumps({
        "algo": cfg.algo, "model_config": model_config, "inference_only": bool(module.inference_only),
        "module_class": type(module).__name__,
        "observation_shape": list(obs.shape), "action_shape": list(act.shape),
        "action_low": np.asarray(act.low).tolist(), "action_high": np.asarray(act.high).tolist(),
        OBS_NORMALIZER_KEY: export_stats(algo)}, indent=1))


def save_checkpoint(algo: Any, cfg: RLlibTrainConfig, path: Path, num_timesteps: int, iterations: int) -> Path:
    """Atomic: written beside ``path`` and renamed, so a kill never leaves a half checkpoint under its name."""
    tmp = path.with_name(f".tmp_{path.name}")
    shutil.rmtree(tmp, ignore_errors=True)
    algo.save_to_path(str(tmp.resolve()))
    export_policy(algo, cfg, tmp)
    (tmp / PROGRESS_FILE).write_text(json.dumps({"num_timesteps": num_timesteps, "iterations": iterations}))
    old = path.with_name(f".old_{path.name}")
    if path.exists():
        os.replace(path, old)
    os.replace(tmp, path)
    shutil.rmtree(old, ignore_errors=True)
    return path


def restore_checkpoint(algo: Any, out: Path, log: Callable[[str], None]) -> tuple[int, int, Path] | None:
    """Restore the newest checkpoint that loads; (timesteps, iterations, path) or None."""
    for _, path in step_checkpoints(out):
        try:
            from ...inputs import checkpoint_progress  # declared fields, checked before the restore

            steps, iterations = checkpoint_progress(json.loads((path / PROGRESS_FILE).read_text()), path)
            algo.restore_from_path(str(path.resolve()))
        except Exception as exc:  # noqa: BLE001 - an unreadable checkpoint: fall back to the previous one
            log(f"resume: skipping checkpoint {path.name} ({exc})")
            continue
        return steps, iterations, path
    return None
