"""Seed ensembles: one policy that acts with the mean of several trained models' deterministic actions.

The benchmark trains every agent on several seeds. Each seed's model is one noisy estimate of the same
controller, and their errors are partly independent, so averaging their actions reduces the variance of the
policy itself. This is the plain bagging argument, here applied to actions rather than to returns. It is
not a selection: every seed's model takes part with the same weight, whatever it scored, and no score on
any split chooses the members.

A residual ensemble averages the members' corrections ``r`` (the network outputs) and then composes once,
``clip(b + scale * mean(r))``. Every member saw the same baseline action ``b`` in training, so they share
one base and one scale; :func:`ensemble_spec` checks that.

Where the members disagree they are extrapolating (issue 24, u44): :func:`disagreement` is the members' spread, the
largest over the action's entries of the standard deviation across members of their (clipped) actions; the policy
keeps the last one it acted on (``last_disagreement``), which a guard reads (:mod:`agents.policies.guarded`).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np


def disagreement(acts: np.ndarray) -> np.ndarray:
    """The members' spread of ``acts`` (members first, the action's entries last): the largest over the entries of
    the standard deviation (ddof 0) across the members; one per row of a batch (a scalar for one env)."""
    return np.std(np.asarray(acts, np.float64), axis=0).max(axis=-1)


class EnsemblePolicy:
    """The mean of ``members``' deterministic actions (each an SB3-style ``predict``), for one env."""

    def __init__(self, members: Sequence[Any]) -> None:
        if not members:
            raise ValueError("ensemble: expected at least one member model")
        self.members = list(members)
        self.last_disagreement: np.ndarray | None = None

    def member_actions(self, observation: Any) -> np.ndarray:
        """Every member's deterministic action for ``observation``, stacked (members first)."""
        return np.stack([np.asarray(m.predict(observation, deterministic=True)[0], np.float32) for m in self.members])

    def predict(self, observation: Any, state: Any = None, episode_start: Any = None,
                deterministic: bool = True) -> tuple[np.ndarray, Any]:
        if state is not None:
            raise ValueError("ensemble: members must be feed-forward (no recurrent state)")
        acts = self.member_actions(observation)
        self.last_disagreement = disagreement(acts)
        return np.mean(acts, axis=0).astype(np.float32), None


def ensemble_spec(specs: Sequence[dict[str, Any]]) -> dict[str, Any]:
    """The policy spec of the ensemble of agent ``specs`` (``{"kind": "agent", "path", "obs_norm", ...}``)."""
    if not specs:
        raise ValueError("ensemble: expected at least one member model")
    res = [s.get("residual") for s in specs]
    if any(r != res[0] for r in res):
        raise ValueError("ensemble: members must share one residual base, its parameters and scale")
    out: dict[str, Any] = {"kind": "ensemble",
                           "members": [{"path": s["path"], "obs_norm": s.get("obs_norm")} for s in specs]}
    if res[0]:
        out["residual"] = res[0]
    return out
