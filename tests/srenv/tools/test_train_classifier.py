"""The trainer's ``--members K`` (run 10): K seeded members of a candidate in one ensemble file, member k what
``--seed`` + k trains alone; a bad K is one line, exit 2."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from srenv.analysis.card_classifier import CardClassifier, members_of
from srenv.task.card_set import write_npz
from srenv.tools.train_classifier import MEMBERS_FLAG, main


def _set(path: Path) -> Path:
    """A tiny set in `srenv cards` columns: full-like surface cards and fluid-pound-like ones, noisy."""
    rng = np.random.default_rng(0)
    n, t = 40, np.arange(256) / 256
    label = np.array([0, 1] * (n // 2))
    x = np.tile(0.5 * (1.0 - np.cos(2 * np.pi * t)), (n, 1))
    up = t < 0.5
    y = np.array([np.where(up, 2.0, 1.0) - (0.6 * ((~up) & (x[0] > 0.6)) if k else 0.0) for k in label])
    y = 1e4 * (y + rng.normal(0.0, 0.01, y.shape))
    split = np.array(["train"] * 24 + ["validation"] * 8 + ["test"] * 8)
    path.mkdir()
    write_npz(str(path / "cards.npz"), {"polished_rod_position_m": x, "polished_rod_load_n": y, "label": label,
                                        "split": split, "well_seed": np.arange(n)})
    return path


def _train(cards: Path, out: Path, *extra: str) -> dict:
    report = out.with_suffix(".json")
    assert main(["--cards", str(cards), "--out", str(out), "--report", str(report), "--epochs", "2",
                 "--candidates", "mlp_aug", *extra]) == 0
    return json.loads(report.read_text())


def _arrays(path: Path) -> dict:
    with np.load(path, allow_pickle=False) as z:
        return {k: z[k] for k in z.files}


def test_members_are_the_seeds_trained_alone_and_the_file_averages_them(tmp_path) -> None:
    pytest.importorskip("torch")
    cards = _set(tmp_path / "set")
    r = _train(cards, tmp_path / "ens.npz", "--members", "2", "--seed", "3")
    alone = [_arrays(tmp_path / f"s{s}.npz") for s in (3, 4) if _train(cards, tmp_path / f"s{s}.npz", "--seed", str(s))]
    ens = members_of(_arrays(tmp_path / "ens.npz"))
    assert len(ens) == 2 and r["members"] == {"count": 2, "seeds": [3, 4]}
    for member, single in zip(ens, alone):
        assert set(single) == set(member)  # each member reads as a one-member file
        for k in single:
            np.testing.assert_array_equal(member[k], single[k])
    assert [m["seed"] for m in r["candidates"]["mlp_aug members"]] == [3, 4]
    f = np.random.default_rng(1).standard_normal((5, len(alone[0]["mean"])))
    want = np.mean([CardClassifier.from_weights(w).proba_features(f) for w in alone], axis=0)
    np.testing.assert_array_equal(CardClassifier.load(tmp_path / "ens.npz").proba_features(f), want)


def test_one_member_writes_the_file_of_every_earlier_run(tmp_path) -> None:
    pytest.importorskip("torch")
    cards = _set(tmp_path / "set")
    r1 = _train(cards, tmp_path / "a.npz")
    r2 = _train(cards, tmp_path / "b.npz", "--members", "1")
    assert (tmp_path / "a.npz").read_bytes() == (tmp_path / "b.npz").read_bytes()
    assert "members" not in _arrays(tmp_path / "a.npz") and "members" not in r1 and r1 == r2


@pytest.mark.parametrize("text", MEMBERS_FLAG.bad_texts())
def test_a_bad_member_count_is_one_line_and_exit_2(capsys, text) -> None:
    with pytest.raises(SystemExit) as exc:
        main(["--cards", "nowhere", "--out", "m.npz", "--members", text])
    err = capsys.readouterr().err
    assert exc.value.code == 2 and err.count("\n") == 1 and "--members" in err and "expected" in err

