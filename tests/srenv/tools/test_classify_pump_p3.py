"""Run P3 (docs/conditions.md): the described pump (srenv.simulation.described), the offset of the pump card's lower
plateau against the described P+, the diagnosed card sets (srenv.tools.diagnose_cards), the trainer's --offset and
the model file's feature set shape+level+offset."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from srenv.analysis import pump_level
from srenv.analysis.card_classifier import PUMP_LEVEL_MODEL, BadModel, CardClassifier
from srenv.analysis.card_shape import features
from srenv.physics.conditions import LABELS
from srenv.simulation.described import described_pump
from srenv.task.card_set import described_pumps, load_cards, write_npz

WELL = "paper_fig3_vertical"
FAMILY_SEED = 10_000_000


def _rect(n: int = 200) -> tuple[np.ndarray, np.ndarray]:
    t = np.arange(n) / n
    return 0.5 * (1.0 - np.cos(2 * np.pi * t)), np.where(t < 0.5, 1.0, 0.0) + 0.01 * np.sin(7 * np.pi * t)


def test_the_described_pump_gives_true_loads_for_a_pump_given_by_loads() -> None:
    """paper_fig3_vertical gives its pump as true loads P- = 9500, P+ = -2200 N: the valve law holds them shifted by
    p_pump A_rod (equivalent loads); the described pump must give the config's own numbers back."""
    from srenv.config import load_config
    from srenv.simulation.simulator import Simulator

    cfg = load_config(WELL)
    d = described_pump(cfg)
    assert (d.fluid_load_n, d.upstroke_true_n, d.downstroke_true_n) == pytest.approx((11700.0, 9500.0, -2200.0))
    law = Simulator(cfg).valve_law_now()
    assert law.down_eq_n > d.downstroke_true_n + 100.0  # the shift is real (p_pump A_rod), not zero
    assert pump_level.described_fluid_load_n(cfg) == d.fluid_load_n


def test_a_family_wells_true_p_plus_is_where_its_simulated_full_pump_card_rests() -> None:
    """A pump given by pressures: the card set's pump card (true tension at the string's bottom) of a full pump rests on
    its downstroke at the described true P+, not at the valve law's equivalent P+."""
    from srenv.analysis.condition_card import simulate_card
    from srenv.task.card_set import described_well

    cfg = described_well(FAMILY_SEED)
    d = described_pump(cfg)
    card = simulate_card(cfg)
    lo = float(np.quantile(card.pump_load_n, 0.10))
    assert abs(lo - d.downstroke_true_n) < 0.05 * d.fluid_load_n
    fluid, down = described_pumps(np.array([FAMILY_SEED, FAMILY_SEED]))
    assert fluid.tolist() == [d.fluid_load_n] * 2 and down.tolist() == [d.downstroke_true_n] * 2


def test_the_offset_is_convention_bound_and_splits_a_diagnosed_parted_string_from_full() -> None:
    x, y = _rect()
    full = 11700.0 * y - 2200.0  # a full pump's true loads: lower plateau at P+
    assert pump_level.offset(full, -2200.0, 11700.0) == pytest.approx(0.0, abs=0.02)
    parted = 0.15 * 11700.0 * y - 16000.0  # diagnosed through the intact string: the missing rods' weight below P+
    assert pump_level.offset(parted, -2200.0, 11700.0) == pytest.approx(-13800.0 / 11700.0, abs=0.02)
    assert pump_level.level(parted, 11700.0) == pytest.approx(0.15, abs=0.01)  # the level alone: flowing's range
    assert pump_level.offset(full + 3500.0, -2200.0, 11700.0) > 0.29  # effective loads move it (by p A / F)
    assert pump_level.offset(full - 1e9, -2200.0, 11700.0) == -pump_level.OFFSET_MAX  # clipped
    f = pump_level.with_offset(pump_level.with_level(features(x, full, "pump"), full, 11700.0), full, -2200.0, 11700.0)
    assert f.shape == (66,) and f[64] == pump_level.level(full, 11700.0) and f[65] == pump_level.offset(
        full, -2200.0, 11700.0)


@pytest.mark.parametrize("down", [float("nan"), float("inf")])
def test_an_offset_that_is_not_finite_is_refused(down) -> None:
    with pytest.raises(pump_level.BadLevel, match="offset"):
        pump_level.offset(np.arange(10.0), down, 100.0)


def _as_offset_model(path: Path, extra_feature: bool = True) -> Path:
    """P2's weights widened to 66 inputs (the new entry weighted 0) and marked shape+level+offset."""
    with np.load(PUMP_LEVEL_MODEL, allow_pickle=False) as z:
        cols = {k: z[k] for k in z.files}
    if extra_feature:
        cols["mean"], cols["std"] = np.r_[cols["mean"], 0.0], np.r_[cols["std"], 1.0]
        cols["w0"] = np.vstack([cols["w0"], np.zeros((1, cols["w0"].shape[1]))])
    write_npz(str(path), {**cols, "feature_set": np.array("shape+level+offset")})
    return path


def test_an_offset_model_file_reads_66_features_and_needs_the_described_p_plus(tmp_path) -> None:
    clf = CardClassifier.load(_as_offset_model(tmp_path / "m.npz"))
    assert clf.needs_level and clf.needs_offset and clf.card_type == "pump"
    x, y = _rect()
    y = 11700.0 * y - 2200.0
    p2 = CardClassifier.load(PUMP_LEVEL_MODEL)
    # the new entry weighted 0: the widened file answers as P2's
    np.testing.assert_allclose(clf.proba_features(clf.card_features(x, y, 11700.0, -2200.0)),
                               p2.proba_features(p2.card_features(x, y, 11700.0)), rtol=1e-12)
    with pytest.raises(ValueError, match="described pump"):
        clf.card_features(x, y, 11700.0)
    with pytest.raises(BadModel, match="wrong shape"):
        CardClassifier.load(_as_offset_model(tmp_path / "bad.npz", extra_feature=False))


def _set_dir(path: Path, rng: np.random.Generator) -> Path:
    """A tiny set: full cards, and 'parted' cards of the same shape and spread sitting 1.2 fluid loads lower (what
    a parted string diagnosed through the intact string looks like): the level cannot tell them, the offset can."""
    fluid, down = (v[0] for v in described_pumps(np.array([FAMILY_SEED])))
    n = 48
    label = np.array([LABELS.index("full"), LABELS.index("parted_rods")] * (n // 2))
    x, y = _rect(256)
    base = np.where(label == 0, down, down - 1.2 * fluid)[:, None]
    cards = {"position_m": np.tile(x, (n, 1)), "load_n": base + fluid * y + rng.normal(0, 0.002 * fluid, (n, 256))}
    path.mkdir()
    both = {f"{kind}_{k}": v for kind in ("pump", "polished_rod") for k, v in cards.items()}
    write_npz(str(path / "cards.npz"), {**both, "label": label, "well_seed": np.full(n, FAMILY_SEED),
                                        "split": np.repeat(["train", "validation", "test"], [32, 8, 8])})
    return path


def test_trainer_trains_an_offset_model_that_tells_what_the_level_cannot(tmp_path) -> None:
    pytest.importorskip("torch")
    from srenv.tools.train_classifier import main as train

    d = _set_dir(tmp_path / "set", np.random.default_rng(0))
    for flags, name in ((["--offset"], "p3"), ([], "p2")):
        assert train(["--card", "pump", "--level", *flags, "--cards", str(d), "--out", str(tmp_path / f"{name}.npz"),
                      "--report", str(tmp_path / f"{name}.json"), "--epochs", "20", "--candidates", "mlp_aug"]) == 0
    r3, r2 = (json.loads((tmp_path / f"{n}.json").read_text()) for n in ("p3", "p2"))
    assert CardClassifier.load(tmp_path / "p3.npz").feature_set == "shape+level+offset"
    assert r3["feature_set"] == "shape+level+offset" and r3["offset_error"] == pump_level.OFFSET_ERROR
    assert r3["test_accuracy_clean"] == 1.0
    assert r2["test_accuracy_clean"] < 0.9  # equal shapes and spreads: without the offset it is a guess


def test_trainer_refuses_offset_without_level_in_one_line(capsys) -> None:
    from srenv.tools.train_classifier import main as train

    with pytest.raises(SystemExit) as exc:
        train(["--cards", "nowhere", "--out", "m.npz", "--card", "pump", "--offset"])
    err = capsys.readouterr().err
    assert exc.value.code == 2 and err.count("\n") == 1 and "--offset" in err and "--level" in err


def _surface_set(path: Path) -> Path:
    """Two simulated cards of one family well (full; the second with a non-finite load: not diagnosable)."""
    from srenv.task.card_set import columns, make_card

    cards = [make_card(7, i, ("full",)) for i in range(2)]
    cols = columns(cards)
    cols["polished_rod_load_n"][1, 5] = np.nan
    path.mkdir()
    write_npz(str(path / "cards.npz"), cols)
    (path / "dataset_card.json").write_text(json.dumps({"seed": 7}))
    return path


def test_diagnose_cards_writes_the_diagnosed_pump_cards_as_a_derived_set(tmp_path, capsys) -> None:
    from srenv.analysis.diagnose import diagnose_card
    from srenv.task.card_set import described_well
    from srenv.tools.diagnose_cards import main as diag

    src = _surface_set(tmp_path / "src")
    assert diag(["--cards", str(src), "--out", str(tmp_path / "dst")]) == 0
    a, b = load_cards(str(src / "cards.npz")), load_cards(str(tmp_path / "dst" / "cards.npz"))
    assert set(a) == set(b) and np.array_equal(a["polished_rod_load_n"][0], b["polished_rod_load_n"][0])
    assert not np.array_equal(a["pump_load_n"][0], b["pump_load_n"][0])
    x, y, period = a["polished_rod_position_m"][0], a["polished_rod_load_n"][0], float(a["period_s"][0])
    m = len(x) - 1
    c = diagnose_card(described_well(int(a["well_seed"][0])), np.arange(m) * (period / m), x[:m], y[:m],
                      period_s=period)
    np.testing.assert_array_equal(b["pump_load_n"][0], np.r_[c.pump_load_n, c.pump_load_n[0]])
    assert np.all(np.isnan(b["pump_load_n"][1]))  # not diagnosable: NaN, the trainer's degenerate card
    meta = json.loads((tmp_path / "dst" / "dataset_card.json").read_text())
    assert meta["pump_source"] == "diagnosed" and meta["diagnosis_failed"] == 1 and meta["seed"] == 7
    capsys.readouterr()
    with pytest.raises(SystemExit) as exc:  # never over a set
        diag(["--cards", str(src), "--out", str(tmp_path / "dst")])
    err = capsys.readouterr().err
    assert exc.value.code == 2 and err.count("\n") == 1 and "--out" in err


def test_diagnose_cards_refuses_an_output_through_a_link_before_any_work(tmp_path, capsys) -> None:
    from srenv.tools.diagnose_cards import main as diag

    src = _surface_set(tmp_path / "src")
    (tmp_path / "real").mkdir()
    (tmp_path / "link").symlink_to(tmp_path / "real")
    (tmp_path / "d2").mkdir()
    (tmp_path / "d2" / "dataset_card.json").symlink_to(tmp_path / "elsewhere.json")
    for out in (tmp_path / "link", tmp_path / "d2"):
        with pytest.raises(SystemExit) as exc:
            diag(["--cards", str(src), "--out", str(out)])
        err = capsys.readouterr().err
        assert exc.value.code == 2 and err.count("\n") == 1 and "--out" in err and "link" in err, err
    assert not list((tmp_path / "real").iterdir()) and not (tmp_path / "d2" / "cards.npz").exists()
