"""SB3 checkpoints on disk: where a model's VecNormalize statistics are, which checkpoints a run holds,
and loading the newest readable one to resume from."""

from __future__ import annotations

import re
import sys
from pathlib import Path
from typing import Any

from ...evaluation.model_io import algorithms, vecnormalize_path
from ..config import TrainConfig
from .builders import schedule

CHECKPOINT_PREFIX = "rl_model"
_CHECKPOINT_RE = re.compile(rf"^{CHECKPOINT_PREFIX}_(\d+)_steps\.zip$")


def checkpoints(out_dir: str | Path) -> list[tuple[int, Path]]:
    """(timesteps, path) of the checkpoints in ``out_dir/checkpoints``, newest first."""
    d = Path(out_dir) / "checkpoints"
    found = [(int(m.group(1)), p) for p in d.glob("*.zip") if (m := _CHECKPOINT_RE.match(p.name))]
    return sorted(found, reverse=True)


def _schedule_objects(cfg: TrainConfig) -> dict[str, Any]:
    """Schedules are pickled closures; re-create them from the YAML so a checkpoint loads on any install."""
    return {k: schedule(cfg.algo_kwargs[k]) for k in ("learning_rate", "clip_range")
            if k in cfg.algo_kwargs}


def _load_checkpoint(cfg: TrainConfig, venv_raw: Any, out_dir: Path) -> tuple[Any, Any, Path] | None:
    """Newest checkpoint that loads (a kill during a save can leave the newest one truncated)."""
    from stable_baselines3.common.vec_env import VecNormalize

    algo = algorithms()[cfg.algo]
    for steps, path in checkpoints(out_dir):
        try:
            venv = venv_raw
            if cfg.normalize is not None:
                stats = vecnormalize_path(path)
                if stats is None:
                    raise FileNotFoundError(f"no VecNormalize statistics next to {path}")
                venv = VecNormalize.load(str(stats), venv_raw)
                venv.training = True
            model = algo.load(str(path), env=venv, device="cpu",
                              custom_objects=_schedule_objects(cfg))
        except Exception as exc:  # noqa: BLE001 - any unreadable checkpoint: fall back to the previous one
            print(f"resume: skipping checkpoint {path.name} ({exc})", file=sys.stderr)
            continue
        buffer = path.with_name(f"{CHECKPOINT_PREFIX}_replay_buffer_{steps}_steps.pkl")
        if buffer.is_file() and hasattr(model, "load_replay_buffer"):
            try:
                model.load_replay_buffer(str(buffer))
            except Exception as exc:  # noqa: BLE001 - a truncated buffer: continue with an empty one
                print(f"resume: skipping replay buffer {buffer.name} ({type(exc).__name__}: "
                      f"{str(exc)[:120]}); continuing with an empty buffer", file=sys.stderr)
        return model, venv, path
    return None
