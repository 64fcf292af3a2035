"""The one check every srenv env applies to an incoming action (training loops get a clear ValueError, never a
silent NaN propagated into the simulator)."""

from __future__ import annotations

import math

import numpy as np


def checked_action(action: np.ndarray, meaning: str) -> np.ndarray:
    """`action` as 2 finite float64 numbers, or ``ValueError`` naming the value and what is expected."""
    try:
        a = np.asarray(action, dtype=np.float64).reshape(-1)
    except (TypeError, ValueError):  # a string, a mapping, None, a ragged list: named, not numpy's words
        from ..errors import short_repr

        raise ValueError(f"action = {short_repr(action, 80)}: expected 2 finite numbers in [-1, 1] ({meaning})") \
            from None
    # two scalar checks: np.all(np.isfinite(a)) costs more than the rest of the check, on every env step
    if a.shape != (2,) or not (math.isfinite(a[0]) and math.isfinite(a[1])):
        raise ValueError(f"action = {a.tolist()}: expected 2 finite numbers in [-1, 1] ({meaning})")
    return a
