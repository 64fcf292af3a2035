"""Reproducible tuning of the v1 baselines on TRAINING wells only.

Every candidate is scored on the same fixed evaluation set - ``reset(seed=S)`` for the tuning seeds S on
the training split, i.e. fixed (train well x inflow schedule) episodes - so candidates are compared on
common random numbers and a rerun finds the same answer. The score is the mean episode return.
Building a :class:`TuningSet` on ``scenario="test"`` raises ``ValueError``: the test wells are for the
final evaluation only (``srenv.task.well_family.check_split`` when the env provides it, and our own guard).

- :func:`search_best_constant` - grid over the WHOLE action box, then a pattern search (step halving)
  around the grid's best.
- :func:`coordinate_search` - one parameter at a time over a list of values, the others held at their
  current best, repeated for a few rounds (pump-off and fillage-PI parameters).

Candidates of one sweep are scored in parallel (:class:`agents.evaluation.rollout.Runner`).
"""

from __future__ import annotations

import itertools
import json
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..envs import ENV_ID_V1
from ..evaluation.rollout import Runner, episode_jobs


def refuse_test_split(scenario: str, purpose: str = "tune") -> None:
    """Raise ``ValueError`` when tuning or training would touch the held-out test split."""
    try:
        from srenv.task.well_family import check_split
    except ImportError:  # an env without the family module (the tests' fake): our guard alone
        check_split = None
    if check_split is not None and scenario in ("train", "test"):  # a fixed well name is no split
        check_split(scenario, purpose)
    if str(scenario).strip().lower() == "test":
        raise ValueError(f"{purpose}: scenario 'test' is the held-out test split; tuning and training "
                         "on it are refused (use scenario 'train')")


@dataclass
class TuningSet:
    """The fixed tuning episodes: ``reset(seed=S)`` on ``scenario`` for S in ``seeds``."""

    seeds: Sequence[int]
    scenario: str = "train"
    env_id: str = ENV_ID_V1
    env_kwargs: dict[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        refuse_test_split(self.scenario, "tune")
        refuse_test_split(self.env_kwargs.get("scenario", self.scenario), "tune")
        if "scenario" in self.env_kwargs:
            raise ValueError("TuningSet: give the split as scenario=, not inside env_kwargs")
        if not self.seeds:
            raise ValueError("TuningSet: seeds is empty: expected at least one tuning seed")
        self.seeds = [int(s) for s in self.seeds]

    @property
    def kwargs(self) -> dict[str, Any]:
        return {**self.env_kwargs, "scenario": self.scenario}


class Evaluator:
    """Scores policy specs on a :class:`TuningSet` (mean return), caching every candidate it has seen."""

    def __init__(self, tset: TuningSet, runner: Runner,
                 progress: Callable[[int], None] | None = None) -> None:
        self.tset, self.runner, self.progress = tset, runner, progress
        self.cache: dict[str, float] = {}
        self.episodes_run = 0

    @staticmethod
    def key(spec: dict[str, Any]) -> str:
        return json.dumps(spec, sort_keys=True, default=float)

    def scores(self, specs: Sequence[dict[str, Any]]) -> list[float]:
        todo = [s for s in dict.fromkeys(self.key(s) for s in specs) if s not in self.cache]
        jobs = [j for k in todo for j in episode_jobs(self.tset.env_id, self.tset.kwargs, json.loads(k),
                                                       self.tset.seeds)]
        recs = self.runner.map(jobs, progress=self.progress)
        self.episodes_run += len(recs)
        n = len(self.tset.seeds)
        for i, k in enumerate(todo):
            self.cache[k] = float(np.mean([r["reward"] for r in recs[i * n:(i + 1) * n]]))
        return [self.cache[self.key(s)] for s in specs]


def _spec(name: str, params: dict[str, Any]) -> dict[str, Any]:
    return {"kind": "baseline", "name": name, "params": {k: _plain(v) for k, v in params.items()}}


def _plain(v: Any) -> Any:
    return round(float(v), 6) if isinstance(v, (float, np.floating)) else v


def search_best_constant(ev: Evaluator, n_spm: int = 9, n_stroke: int = 5, refine_iters: int = 6,
                         refine_step: float | None = None) -> dict[str, Any]:
    """Best constant action over the whole box [-1, 1]^2: an ``n_spm x n_stroke`` grid (a0 = -1, full
    idle, included), then a pattern search around the grid's best: try +-step on each axis, move to the
    best neighbour if it improves, otherwise halve the step; ``refine_iters`` rounds."""
    grid = [(float(a), float(b)) for a, b in itertools.product(np.linspace(-1, 1, n_spm),
                                                               np.linspace(-1, 1, n_stroke))]
    specs = [_spec("best_constant", {"a_spm": a, "a_stroke": b}) for a, b in grid]
    scores = ev.scores(specs)
    i = int(np.argmax(scores))
    best, best_score = np.array(grid[i]), scores[i]
    history = [{"a_spm": a, "a_stroke": b, "score": s} for (a, b), s in zip(grid, scores)]
    grid_best = {"a_spm": float(best[0]), "a_stroke": float(best[1]), "score": float(best_score)}
    step = refine_step if refine_step is not None else 0.5 * min(2 / max(n_spm - 1, 1), 2 / max(n_stroke - 1, 1))
    for _ in range(refine_iters):
        nbrs = [np.clip(best + d, -1, 1) for d in (np.array([step, 0]), np.array([-step, 0]),
                                                    np.array([0, step]), np.array([0, -step]))]
        nspecs = [_spec("best_constant", {"a_spm": n[0], "a_stroke": n[1]}) for n in nbrs]
        nscores = ev.scores(nspecs)
        history += [{"a_spm": float(n[0]), "a_stroke": float(n[1]), "score": s} for n, s in zip(nbrs, nscores)]
        j = int(np.argmax(nscores))
        if nscores[j] > best_score:
            best, best_score = nbrs[j], nscores[j]
        else:
            step /= 2
    return {"params": {"a_spm": round(float(best[0]), 6), "a_stroke": round(float(best[1]), 6)},
            "score": float(best_score), "grid_best": grid_best, "evaluated": history}


def coordinate_search(ev: Evaluator, name: str, init: dict[str, Any], space: dict[str, Sequence[Any]],
                      rounds: int = 2) -> dict[str, Any]:
    """Coordinate search of baseline ``name``: for each parameter of ``space`` in order, score all its
    values with the other parameters at their current best and keep the best; ``rounds`` passes, stopping
    early when a pass changes nothing. Returns the best parameters, their score and every candidate."""
    best = dict(init)
    best_score = ev.scores([_spec(name, best)])[0]
    history = [{**best, "score": best_score}]
    for _ in range(rounds):
        changed = False
        for key, values in space.items():
            cands = [{**best, key: v} for v in values]
            scores = ev.scores([_spec(name, c) for c in cands])
            history += [{**c, "score": s} for c, s in zip(cands, scores)]
            j = int(np.argmax(scores))
            if scores[j] > best_score + 1e-9:
                best, best_score, changed = cands[j], scores[j], True
        if not changed:
            break
    return {"params": {k: _plain(v) for k, v in best.items()}, "score": float(best_score),
            "evaluated": history}
