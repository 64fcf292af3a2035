"""One field student fitted on every labelled DAgger episode pooled, chosen on held-out TRAINING episodes (issue 24).

The DAgger students of the causal oracle (:mod:`agents.training.oracle_distill`) each fit the ~50-100 episodes
their own run labelled: on those their MSE is ~0.02-0.03, on another seed's episodes ~0.24-0.37 against ~0.5 for
predicting no correction - they memorise their episodes. A *pooled* student is fitted on every labelled
episode at once, its network, Adam weight decay and epoch count picked from a grid fixed in advance
(``teacher.pool`` of the run, :func:`check_pool`) by grouped K-fold held-out MSE (:func:`cv_table`): a fold
holds whole episodes, never part of one, and only training-split labels are ever used. The fit itself is
:func:`agents.training.distill.fit_actor` on a fresh seeded SB3 actor (:func:`fit_student`).
"""

from __future__ import annotations

import itertools
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

# teacher.pool's fields, declared once: (kind, lower, upper, longest list) - the checks and their tests read this
POOL_FIELDS: dict[str, tuple[str, float, float, int]] = {
    "labels": ("path", 1, 4096, 0),           # an .npz pattern, {k} = 0 .. files - 1
    "files": ("int", 1, 20, 0),
    "episode_steps": ("int", 1, 10_000, 0),    # rows per labelled episode (v2: 144 intervals)
    "folds": ("int", 2, 20, 0),
    "epochs": ("ints", 1, 2000, 6),
    "weight_decay": ("floats", 0.0, 0.1, 6),
    "net_arch": ("archs", 1, 1024, 4),
    "fit_seeds": ("ints", 0, 10**6, 10),
    "precheck_seed_start": ("int", 0, 10**9, 0),
    "precheck_episodes": ("int", 1, 500, 0),
    "precheck_ratio": ("float", 1e-3, 1.0, 0),
}
MAX_CANDIDATES = 12


def _is_int(v: Any, lo: float, hi: float) -> bool:
    return isinstance(v, int) and not isinstance(v, bool) and lo <= v <= hi


def _is_float(v: Any, lo: float, hi: float) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool) and np.isfinite(v) and lo <= v <= hi


def _field_ok(kind: str, v: Any, lo: float, hi: float, longest: int) -> bool:
    if kind == "path":
        return isinstance(v, str) and lo <= len(v) <= hi and v.endswith(".npz") and "{k}" in v
    if kind in ("int", "float"):
        return (_is_int if kind == "int" else _is_float)(v, lo, hi)
    if not (isinstance(v, list) and 1 <= len(v) <= longest):
        return False
    if kind == "archs":
        return all(isinstance(a, list) and 1 <= len(a) <= 4 and all(_is_int(w, lo, hi) for w in a) for a in v)
    return all((_is_int if kind == "ints" else _is_float)(e, lo, hi) for e in v)


def check_pool(block: Any, key: str = "teacher.pool") -> dict[str, Any]:
    """``block`` checked against :data:`POOL_FIELDS` (every field required, each bounded) and at most
    :data:`MAX_CANDIDATES` candidates; a ValueError naming the field, its value and what is expected otherwise."""
    if not isinstance(block, dict) or set(block) != set(POOL_FIELDS):
        got = sorted(map(str, block)) if isinstance(block, dict) else type(block).__name__
        raise ValueError(f"{key} = {str(got)[:160]}: expected exactly the keys {sorted(POOL_FIELDS)}")
    for name, (kind, lo, hi, longest) in POOL_FIELDS.items():
        if not _field_ok(kind, block[name], lo, hi, longest):
            what = {"path": "an .npz path with {k}", "int": "an integer", "float": "a number",
                    "ints": "a list of integers", "floats": "a list of numbers",
                    "archs": "a list of layer-width lists"}[kind]
            raise ValueError(f"{key}.{name} = {repr(block[name])[:120]}: expected {what} in [{lo}, {hi}]"
                             + (f" (1 to {longest} entries)" if longest else ""))
    n = len(candidates(block))
    if n > MAX_CANDIDATES:
        raise ValueError(f"{key}: {n} candidates (epochs x weight_decay x net_arch): expected at most "
                         f"{MAX_CANDIDATES}")
    return block


def candidates(pool: dict[str, Any]) -> list[dict[str, Any]]:
    """The grid in its declared order (epochs, then weight decay, then network): ties go to the first."""
    return [{"epochs": e, "weight_decay": float(w), "net_arch": list(a)}
            for e, w, a in itertools.product(pool["epochs"], pool["weight_decay"], pool["net_arch"])]


def episode_keys(n_rows: int, steps: int) -> np.ndarray:
    """Each row's episode index within its file (rows are whole episodes of ``steps`` intervals, in order)."""
    if n_rows % steps:
        raise ValueError(f"labels: {n_rows} rows: expected whole episodes of {steps} rows")
    return np.repeat(np.arange(n_rows // steps), steps)


def load_pool(paths: Sequence[Path], steps: int) -> dict[str, np.ndarray]:
    """The pooled labels: x (raw inputs), label, ``group`` (a pool-wide episode id), ``key`` (the episode's
    index within its file, which sets its fold) and ``file`` (the file's index)."""
    parts: dict[str, list[np.ndarray]] = {"x": [], "label": [], "group": [], "key": [], "file": []}
    n_groups = 0
    for i, p in enumerate(paths):
        if p.is_symlink() or not p.is_file():
            raise ValueError(f"labels {str(p)[:160]!r}: expected an existing .npz file (not a symlink)")
        with np.load(p, allow_pickle=False) as z:
            x, y = np.asarray(z["x"], np.float32), np.asarray(z["label"], np.float32)
        key = episode_keys(len(x), steps)
        parts["x"].append(x)
        parts["label"].append(y)
        parts["key"].append(key)
        parts["group"].append(key + n_groups)
        parts["file"].append(np.full(len(key), i))
        n_groups += int(key.max()) + 1
    return {k: np.concatenate(v) for k, v in parts.items()}


def grouped_folds(key: np.ndarray, folds: int) -> list[tuple[np.ndarray, np.ndarray]]:
    """(train rows, held-out rows) per fold: episode ``key`` goes to fold ``key mod folds``, whole."""
    fold = np.asarray(key) % folds
    return [(np.flatnonzero(fold != f), np.flatnonzero(fold == f)) for f in range(folds)]


def clipped_mse(pred: np.ndarray, label: np.ndarray) -> float:
    return float(np.mean((np.clip(np.asarray(pred, np.float64), -1.0, 1.0) - label) ** 2))


def fit_student(x: np.ndarray, y: np.ndarray, cand: dict[str, Any], policy_kwargs: dict[str, Any], seed: int,
                dest_zip: Path, held: tuple[np.ndarray, np.ndarray] | None = None) -> tuple[Any, dict[int, float]]:
    """A fresh seeded actor (``policy_kwargs`` with the candidate's network) fitted to (x, y) for the
    candidate's epochs and weight decay, its statistics those of ``x``, written to ``dest_zip`` (+ _obs_norm.npz);
    (the student, {epoch: held-out MSE on ``held`` = (x, y)} at every epoch count the grid declares)."""
    from ..evaluation.agent import AgentPolicy
    from ..evaluation.normalizer import obs_norm_path
    from .distill import fit_actor, write_student
    from .oracle_distill import fresh_student, save_obs_norm

    init = dest_zip.with_name(dest_zip.stem + "_init.zip")
    norm = obs_norm_path(dest_zip)
    fresh_student(x.shape[1], {**policy_kwargs, "net_arch": cand["net_arch"]}, seed, init)
    save_obs_norm(x, norm)
    student = AgentPolicy(str(init), str(norm))
    scores: dict[int, float] = {}
    xh = None if held is None else student.norm(held[0])

    def score(epoch: int) -> None:
        if xh is not None and epoch in cand.get("score_at", ()):
            scores[epoch] = clipped_mse(student.model.predict(xh, deterministic=True)[0], held[1])

    fit_actor(student.model, student.norm(x), y, seed, cand["epochs"], cand["weight_decay"], score)
    write_student(init, student.model, dest_zip)
    init.unlink(missing_ok=True)
    return AgentPolicy(str(dest_zip), str(norm)), scores


def cv_job(job: dict[str, Any]) -> dict[str, Any]:
    """Worker entry: one (network, weight decay, fold) fit run to the largest epoch count, scored at each."""
    import torch

    torch.set_num_threads(1)
    with np.load(job["pool"], allow_pickle=False) as z:
        x, y = z["x"], z["label"]
    tr, te = job["train"], job["held"]
    cand = {**job["cand"], "score_at": job["score_at"]}
    _, scores = fit_student(x[tr], y[tr], cand, job["policy_kwargs"], job["seed"], Path(job["dest"]), (x[te], y[te]))
    return {"fold": job["fold"], "scores": scores}


def cv_table(runner: Any, pool_npz: Path, pool: dict[str, Any], key: np.ndarray, policy_kwargs: dict[str, Any],
             seed: int, workdir: Path) -> list[dict[str, Any]]:
    """Every candidate's held-out MSE per fold and its mean (the grid's order); one fit per (network, weight
    decay, fold), scored after each declared epoch count."""
    folds = grouped_folds(key, pool["folds"])
    top = max(pool["epochs"])
    jobs = [{"pool": str(pool_npz), "train": tr, "held": te, "fold": f, "seed": seed, "score_at": pool["epochs"],
             "cand": {"epochs": top, "weight_decay": float(w), "net_arch": list(a)}, "policy_kwargs": policy_kwargs,
             "dest": str(workdir / f"cv_w{w}_a{'x'.join(map(str, a))}_f{f}.zip")}
            for w, a in itertools.product(pool["weight_decay"], pool["net_arch"]) for f, (tr, te) in enumerate(folds)]
    out = runner.map(jobs, fn=cv_job)
    rows = []
    for c in candidates(pool):
        per = [o["scores"][c["epochs"]] for j, o in zip(jobs, out)
               if j["cand"]["weight_decay"] == c["weight_decay"] and j["cand"]["net_arch"] == c["net_arch"]]
        rows.append({**c, "heldout_mse_folds": per, "heldout_mse": float(np.mean(per))})
    return rows


def choose(rows: Sequence[dict[str, Any]]) -> int:
    """The candidate with the least mean held-out MSE (the first of equals)."""
    return int(np.argmin([r["heldout_mse"] for r in rows]))


def precheck_passes(m_pooled: float, m_reference: float, ratio: float) -> bool:
    """THE PRE-CHECK (the pooled design's config history): the pooled ensemble's MSE on fresh training episodes is
    at most ``ratio`` x the reference students' mean MSE on the same labels."""
    return bool(np.isfinite(m_pooled) and np.isfinite(m_reference) and m_pooled <= ratio * m_reference)
