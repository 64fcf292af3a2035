"""A short observation history for a field student: the last ``K`` field observations, stacked.

Why: the causal oracle a student imitates acts on the annulus trend (is the fluid level rising or
falling?), which one card does not show; the last few cards do. The stack is ``[o_{t-K+1}, ..., o_t]``
(oldest first, so ``K = 1`` is the observation itself, bit for bit). At an episode's start the missing
older entries are padded with the FIRST observation (the well as found: no trend yet), not zeros, whose
scale the student's statistics never saw. One :class:`History` serves the distillation's rollouts
(agents/training/oracle_distill.py) and the evaluation's residual policy (agents/policies/residual.py).
"""

from __future__ import annotations

from typing import Any

import numpy as np

MAX_HISTORY = 16  # a longer stack is a different design (a recurrent student), not this option


def check_history(k: Any) -> int:
    """The one bound on a student's history length (teacher block, policy spec): an integer in 1..MAX_HISTORY."""
    if isinstance(k, bool) or not isinstance(k, (int, np.integer)) or not 1 <= int(k) <= MAX_HISTORY:
        raise ValueError(f"history = {k!r}: expected an integer in 1..{MAX_HISTORY} (field observations stacked)")
    return int(k)


class History:
    """The last ``k`` observations of one env, stacked oldest first; :meth:`reset` at every episode start."""

    def __init__(self, k: int = 1) -> None:
        self.k = check_history(k)
        self.buf: list[np.ndarray] = []

    def reset(self) -> None:
        self.buf = []

    def push(self, obs: np.ndarray) -> np.ndarray:
        o = np.asarray(obs, np.float32)
        if self.k == 1:
            return o
        if not self.buf:  # the episode's first interval: pad with the first observation
            self.buf = [o] * self.k
        else:
            self.buf = self.buf[1:] + [o]
        return np.concatenate(self.buf, axis=-1)
