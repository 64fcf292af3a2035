"""The one observation normaliser of a trained policy: ``clip((obs - mean) / scale, -clip, clip)`` in float32,
with frozen statistics read as data (no pickle).

The backends differ only in how the scale is formed, so each has a constructor and one transform serves all:

- SB3's ``VecNormalize``: ``scale = sqrt(var + epsilon)`` (:meth:`ObsNormalizer.from_variance`); stored as the
  benchmark's ``<model>_obs_norm.npz`` (mean, var, clip_obs, epsilon) or the ``<model>_vecnormalize.json``
  that :mod:`agents.evaluation.model_io` reads;
- RLlib's ``MeanStdFilter``: ``scale = std + 1e-6`` in float32 (:meth:`ObsNormalizer.from_rllib`), stored in
  ``srenv_policy.json`` under :data:`OBS_NORMALIZER_KEY`.

The arithmetic is each library's own to the bit (float64 difference over the stored scale), so a replay
reproduces the returns the benchmark recorded.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

import numpy as np

OBS_NORMALIZER_KEY = "obs_normalizer"  # in an RLlib checkpoint's srenv_policy.json
RLLIB_SMALL_NUMBER = 1e-6  # ray.rllib.utils.numpy.SMALL_NUMBER, MeanStdFilter's guard on the std


def obs_norm_path(zip_path: str | Path) -> Path:
    """The observation statistics that go with a model zip: ``<stem>_obs_norm.npz`` beside it (every writer and
    reader of a model's statistics names them so)."""
    p = Path(zip_path)
    return p.with_name(f"{p.stem}_obs_norm.npz")


class ObsNormalizer:
    """``clip((obs - mean) / scale, -clip, clip)`` as float32; callable, and SB3's ``normalize_obs`` too."""

    def __init__(self, mean: Any, scale: Any, clip: float, stats: dict[str, Any] | None = None,
                 obs_dtype: Any = np.float64) -> None:
        self.obs_dtype = obs_dtype  # what the observation is read as before the difference (RLlib: float32)
        self.mean = np.asarray(mean, dtype=np.float64)
        self.scale = np.asarray(scale)
        self.clip = float(clip)
        self.stats = stats or {}  # the statistics it was built from, as stored (save() writes them back)

    @classmethod
    def from_variance(cls, mean: Any, var: Any, clip_obs: float, epsilon: float) -> ObsNormalizer:
        """SB3 ``VecNormalize``'s transform: ``scale = sqrt(var + epsilon)``."""
        mean, var = np.asarray(mean, np.float64), np.asarray(var, np.float64)
        return cls(mean, np.sqrt(var + epsilon), clip_obs,
                   {"mean": mean, "var": var, "clip_obs": float(clip_obs), "epsilon": float(epsilon)})

    @classmethod
    def from_rllib(cls, data: Any, shape: tuple[int, ...], source: Path | str) -> ObsNormalizer:
        """RLlib ``MeanStdFilter``'s transform from ``srenv_policy.json``'s record, checked."""
        ok = (isinstance(data, dict) and {"mean", "std", "clip_std"} <= set(data)
              and np.shape(data["mean"]) == shape and np.shape(data["std"]) == shape
              and isinstance(data["clip_std"], (int, float)) and data["clip_std"] > 0
              and np.all(np.isfinite(data["mean"])) and np.all(np.isfinite(data["std"])))
        if not ok:
            raise ValueError(f"{source}: {OBS_NORMALIZER_KEY} = {str(data)[:80]}: expected mean and std of shape "
                             f"{list(shape)} (finite) and a positive clip_std")
        std = np.asarray(data["std"], dtype=np.float32)
        return cls(data["mean"], std + RLLIB_SMALL_NUMBER, data["clip_std"], {"count": int(data.get("count", 0))},
                   obs_dtype=np.float32)

    @property
    def clip_std(self) -> float:  # RLlib's name for the clip
        return self.clip

    @classmethod
    def load(cls, path: str | Path) -> ObsNormalizer:
        """The benchmark's ``<model>_obs_norm.npz`` (plain arrays, no pickle)."""
        from ..inputs import obs_norm_npz  # checked: keys, shapes, finite values (one line on any defect)

        z = obs_norm_npz(path)
        return cls.from_variance(z["mean"], z["var"], z["clip_obs"], z["epsilon"])

    def save(self, path: str | Path) -> None:
        """Write the VecNormalize statistics as ``.npz`` atomically (what :meth:`load` reads)."""
        tmp = f"{path}.tmp.npz"
        np.savez(tmp, **self.stats)
        os.replace(tmp, path)

    def __call__(self, obs: Any) -> np.ndarray:
        x = (np.asarray(obs, dtype=self.obs_dtype) - self.mean) / self.scale
        return np.clip(x, -self.clip, self.clip).astype(np.float32)

    normalize_obs = __call__
