"""Finite results only: a run or a figure that is not finite is a failure, not a result (and NaN is not JSON).

Shared by the commands that print a summary (``srenv simulate``, ``srenv validate``).
"""

from __future__ import annotations

import math

import numpy as np

from ..errors import NumericFailure


def check_finite(trace: dict, summary: dict) -> None:
    """A run whose numbers are not finite is a failure, not a result (and NaN is not JSON)."""
    for name, col in trace.items():
        if not np.all(np.isfinite(col)):
            raise NumericFailure(name, "the simulation diverged; check the config's magnitudes")

    def walk(key: str, v: object) -> None:
        if isinstance(v, dict):
            for k, w in v.items():
                walk(k, w)
        elif isinstance(v, (list, tuple)):
            for w in v:
                walk(key, w)
        elif isinstance(v, (float, np.floating)) and not math.isfinite(v):
            raise NumericFailure(key, "the summary is not finite; check the config's magnitudes")
    walk("summary", summary)
