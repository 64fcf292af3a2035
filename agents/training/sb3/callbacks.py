"""The EvalCallback's companions: the statistics and record kept with the best model, one report line per
evaluation, and the evaluation history carried into a resumed run."""

from __future__ import annotations

import json
import math
import sys
from pathlib import Path
from typing import Any

BEST_RECORD = "best_model.json"


def _save_vecnormalize_callback(path: Path) -> Any:
    """EvalCallback's ``callback_on_new_best``: keep the statistics that the best model was evaluated with
    (pickle for resuming, JSON for evaluation) and the best mean reward, so that a resumed run whose eval
    history is lost still does not overwrite a better best_model with a worse one."""
    from stable_baselines3.common.callbacks import BaseCallback

    from ...evaluation.model_io import stats_path, write_stats

    class SaveVecNormalize(BaseCallback):
        def _on_step(self) -> bool:
            vn = self.model.get_vec_normalize_env()
            if vn is not None:
                vn.save(str(path))
                write_stats(vn, stats_path(path.parent / "best_model.zip"))
            best = float(self.parent.best_mean_reward)
            record = {"best_mean_reward": best, "num_timesteps": int(self.num_timesteps)}
            (path.parent / BEST_RECORD).write_text(json.dumps(record))
            return True

    return SaveVecNormalize()


def _recorded_best(best_dir: Path) -> float:
    """Best mean reward of an earlier run into the same directory (-inf when none is readable)."""
    try:
        value = float(json.loads((best_dir / BEST_RECORD).read_text())["best_mean_reward"])
    except (OSError, ValueError, KeyError, TypeError):
        return -math.inf
    return value if math.isfinite(value) else -math.inf


def _eval_reporter() -> Any:
    """One line per evaluation on stderr: stdout stays for the JSON summary."""
    from stable_baselines3.common.callbacks import BaseCallback

    class Report(BaseCallback):
        def _on_step(self) -> bool:
            parent = self.parent
            print(f"eval @ {self.num_timesteps} steps: mean reward {parent.last_mean_reward:.3f} "
                  f"(best {parent.best_mean_reward:.3f})", file=sys.stderr, flush=True)
            return True

    return Report()


def _restore_eval_history(eval_cb: Any, npz_path: Path, upto_steps: int) -> None:
    """Carry the evaluations before the checkpoint into the resumed EvalCallback.

    A fresh callback starts from best = -inf and rewrites evaluations.npz with its own results only, so
    after a resume the first evaluation would overwrite a better ``best_model`` and the history be lost.
    """
    import numpy as np

    if not npz_path.is_file():
        return
    try:
        with np.load(npz_path, allow_pickle=False) as h:
            keep = h["timesteps"] <= upto_steps
            timesteps = h["timesteps"][keep].tolist()
            results = h["results"][keep].tolist()
            lengths = h["ep_lengths"][keep].tolist()
    except Exception as exc:  # noqa: BLE001 - truncated / not an npz: resume without the history
        print(f"resume: skipping evaluation history {npz_path.name} ({type(exc).__name__}: {str(exc)[:120]})",
              file=sys.stderr)
        return
    eval_cb.evaluations_timesteps, eval_cb.evaluations_results, eval_cb.evaluations_length = (
        timesteps, results, lengths)
    if eval_cb.evaluations_results:
        eval_cb.best_mean_reward = float(max(np.mean(r) for r in eval_cb.evaluations_results))
