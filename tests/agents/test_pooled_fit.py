"""The pooled student's fit and selection (agents/training/pooled_fit.py, issue 24, helper e24): grouped folds never
split an episode, the chosen candidate is the argmin of the held-out MSE (the first of equals), a fit is
deterministic per seed and scoring it at epoch e is the fit of e epochs, the pre-check rule, and every bad
``teacher.pool`` field (generated from POOL_FIELDS) refused in one line naming it."""

from __future__ import annotations

import copy
from pathlib import Path

import numpy as np
import pytest

from agents.evaluation.rollout import Runner
from agents.training import pooled_fit as pf

PK = {"net_arch": [8, 8], "activation_fn": "tanh", "log_std_init": -1.0}
POOL = {"labels": "runs/x/l{k}.npz", "files": 2, "episode_steps": 6, "folds": 3, "epochs": [2, 5],
        "weight_decay": [0.0, 0.01], "net_arch": [[8], [8, 8]], "fit_seeds": [0, 1], "precheck_seed_start": 57000,
        "precheck_episodes": 4, "precheck_ratio": 0.6}


def _labels(tmp_path: Path, files: int = 2, episodes: int = 5, steps: int = 6) -> list[Path]:
    rng = np.random.default_rng(0)
    out = []
    for k in range(files):
        x = rng.normal(size=(episodes * steps, 5)).astype(np.float32)
        y = np.tanh(x[:, :2] + 0.1 * rng.normal(size=(len(x), 2))).astype(np.float32)
        out.append(tmp_path / f"l{k}.npz")
        np.savez(out[-1], x=x, label=y)
    return out


def test_grouped_folds_never_split_an_episode(tmp_path):
    pool = pf.load_pool(_labels(tmp_path), 6)
    assert len(pool["x"]) == 60 and pool["group"].max() == 9 and np.array_equal(pool["file"], pool["group"] // 5)
    folds = pf.grouped_folds(pool["key"], 3)
    held = np.concatenate([te for _, te in folds])
    assert sorted(held) == list(range(60))  # every row held out exactly once
    for tr, te in folds:
        assert not set(pool["group"][tr]) & set(pool["group"][te])  # no episode on both sides
        assert len(set(pool["group"][te])) * 6 == len(te)  # whole episodes only
        assert set(pool["key"][te] // 1 % 3) == {pool["key"][te][0] % 3}


def test_episode_keys_refuse_a_partial_episode():
    assert list(pf.episode_keys(6, 3)) == [0, 0, 0, 1, 1, 1]
    with pytest.raises(ValueError, match="7 rows: expected whole episodes of 3 rows"):
        pf.episode_keys(7, 3)


def test_load_pool_refuses_a_symlinked_label_file(tmp_path):
    (tmp_path / "s.npz").symlink_to(_labels(tmp_path)[0])
    with pytest.raises(ValueError, match="expected an existing .npz file \\(not a symlink\\)"):
        pf.load_pool([tmp_path / "s.npz"], 6)


@pytest.mark.parametrize("mses, chosen", [([0.3, 0.1, 0.2], 1), ([0.2, 0.1, 0.1], 1), ([0.05, 0.1], 0)])
def test_the_chosen_candidate_is_the_argmin_first_of_equals(mses, chosen):
    assert pf.choose([{"heldout_mse": m} for m in mses]) == chosen


def test_candidates_in_declared_order():
    c = pf.candidates(POOL)
    assert len(c) == 8 and c[0] == {"epochs": 2, "weight_decay": 0.0, "net_arch": [8]}
    assert c[1]["net_arch"] == [8, 8] and c[2]["weight_decay"] == 0.01 and c[4]["epochs"] == 5


def test_fit_is_deterministic_per_seed_and_scoring_at_epoch_e_is_the_fit_of_e_epochs(tmp_path):
    pool = pf.load_pool(_labels(tmp_path), 6)
    x, y, held = pool["x"][:48], pool["label"][:48], (pool["x"][48:], pool["label"][48:])
    cand = {"epochs": 5, "weight_decay": 0.01, "net_arch": [8, 8], "score_at": [2, 5]}
    a, sa = pf.fit_student(x, y, cand, PK, 3, tmp_path / "a.zip", held)
    b, sb = pf.fit_student(x, y, cand, PK, 3, tmp_path / "b.zip", held)
    c, _ = pf.fit_student(x, y, cand, PK, 4, tmp_path / "c.zip", held)
    short, _ = pf.fit_student(x, y, {**cand, "epochs": 2}, PK, 3, tmp_path / "s.zip")
    pred = [m.model.predict(m.norm(held[0]), deterministic=True)[0] for m in (a, b, c, short)]
    assert sa == sb and set(sa) == {2, 5} and np.array_equal(pred[0], pred[1]) and not np.allclose(pred[0], pred[2])
    assert sa[2] == pytest.approx(pf.clipped_mse(pred[3], held[1]), rel=1e-6)
    assert sa[5] == pytest.approx(pf.clipped_mse(pred[0], held[1]), rel=1e-6)
    assert sa[5] < float(np.mean(held[1] ** 2))  # it learns: better than no correction
    assert not (tmp_path / "a_init.zip").exists() and (tmp_path / "a_obs_norm.npz").is_file()


def test_cv_table_scores_every_candidate_and_fold(tmp_path):
    paths = _labels(tmp_path)
    pool = pf.load_pool(paths, 6)
    np.savez(tmp_path / "pool.npz", x=pool["x"], label=pool["label"])
    with Runner(1) as runner:
        rows = pf.cv_table(runner, tmp_path / "pool.npz", POOL, pool["key"], PK, 0, tmp_path / "cv")
    assert [{k: r[k] for k in ("epochs", "weight_decay", "net_arch")} for r in rows] == pf.candidates(POOL)
    assert all(len(r["heldout_mse_folds"]) == 3 and r["heldout_mse"] == pytest.approx(np.mean(r["heldout_mse_folds"]))
               for r in rows)


@pytest.mark.parametrize("m, ref, ratio, passed", [(0.12, 0.2, 0.6, True), (0.1201, 0.2, 0.6, False),
                                                   (0.05, 0.2, 0.6, True), (float("nan"), 0.2, 0.6, False)])
def test_the_precheck_rule(m, ref, ratio, passed):
    assert pf.precheck_passes(m, ref, ratio) is passed


def _bad_values() -> list[tuple[str, object]]:
    """For every declared field: below its bound, above it, and the wrong type."""
    out = []
    for name, (kind, lo, hi, longest) in pf.POOL_FIELDS.items():
        if kind == "path":
            out += [(name, "runs/l.npz"), (name, "runs/l{k}.txt"), (name, 3)]
        elif kind in ("int", "float"):
            out += [(name, lo - 1), (name, hi + 1), (name, "7"), (name, True)]
        elif kind == "archs":
            out += [(name, [[0]]), (name, [[hi + 1]]), (name, [8]), (name, []), (name, [[8]] * (longest + 1))]
        else:
            out += [(name, [lo - 1]), (name, [hi + 1]), (name, []), (name, 3), (name, [lo] * (longest + 1))]
    return out


@pytest.mark.parametrize("name, value", _bad_values())
def test_every_bad_pool_field_is_refused_in_one_line(name, value):
    block = {**copy.deepcopy(POOL), name: value}
    with pytest.raises(ValueError, match=rf"^teacher\.pool\.{name} = .*: expected ") as e:
        pf.check_pool(block)
    assert "\n" not in str(e.value)


def test_pool_keys_and_grid_size_checked():
    with pytest.raises(ValueError, match="teacher.pool = .*expected exactly the keys"):
        pf.check_pool({k: v for k, v in POOL.items() if k != "folds"})
    with pytest.raises(ValueError, match="teacher.pool = .*expected exactly the keys"):
        pf.check_pool({**POOL, "extra": 1})
    with pytest.raises(ValueError, match="teacher.pool: 18 candidates .*: expected at most 12"):
        pf.check_pool({**POOL, "epochs": [1, 2, 3], "weight_decay": [0.0, 0.1, 0.01]})
    assert pf.check_pool(copy.deepcopy(POOL)) == POOL
