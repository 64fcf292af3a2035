"""Run P2 (docs/conditions.md): the pump card's load level against the described well's fluid load, the model file's
feature set, the trainer's --level and srenv classify --config WELL --card pump."""

from __future__ import annotations

import hashlib
import json
from pathlib import Path

import numpy as np
import pytest

from srenv.analysis import pump_level
from srenv.analysis.card_classifier import PUMP_MODEL, CardClassifier
from srenv.analysis.card_shape import features
from srenv.physics.conditions import LABELS
from srenv.task.card_set import write_npz
from srenv.tools.cli import main

HEADER = "polished_rod_position_m,polished_rod_load_n"
WELL = "paper_fig3_vertical"
P1_SHA256 = "c2efba9277954486cda1f3fd7d50324791d58390957aa8fed0e6f167c36363ba"
P2_SHA256 = "2f8da8d6dd262cfe1b08d3347dbec22d413c5a14ca9ba605f2de66d90f18b816"


def _rect(n: int = 200) -> tuple[np.ndarray, np.ndarray]:
    t = np.arange(n) / n
    return 0.5 * (1.0 - np.cos(2 * np.pi * t)), np.where(t < 0.5, 1.0, 0.0) + 0.01 * np.sin(7 * np.pi * t)


def _write(path: Path, x, y) -> Path:
    np.savetxt(path, np.c_[x, y], delimiter=",", header=HEADER, comments="")
    return path


def test_the_described_fluid_load_is_the_valve_laws() -> None:
    from srenv.config import load_config

    # a pump given by its loads: P- - P+ = 9500 - (-2200) N
    assert pump_level.described_fluid_load_n(load_config(WELL)) == pytest.approx(11700.0)


def test_the_level_is_free_of_the_load_convention_and_splits_full_from_parted() -> None:
    x, y = _rect()
    y = 11700.0 * y - 2200.0
    lv = pump_level.level(y, 11700.0)
    assert lv == pytest.approx(1.0, abs=0.02)
    assert pump_level.level(y + 3500.0, 11700.0) == lv  # effective loads: a constant shift at the rod end
    assert pump_level.level(0.034 * (y + 2200.0) - 200.0, 11700.0) < 0.05  # a parted string's ±200 N drag
    f = pump_level.with_level(features(x, y, "pump"), y, 11700.0)
    assert f[-1] == lv and np.array_equal(f[:-1], features(x, y, "pump")[:-1])
    assert pump_level.level(1e6 * y, 11700.0) == pump_level.LEVEL_MAX  # clipped


@pytest.mark.parametrize("fluid", [0.0, -5.0, float("nan"), float("inf")])
def test_a_fluid_load_that_is_not_positive_and_finite_is_refused(fluid) -> None:
    with pytest.raises(pump_level.BadLevel, match="described fluid load"):
        pump_level.level(np.arange(10.0), fluid)


def _card_set(path: Path, rng: np.random.Generator) -> None:
    """A tiny set: the same rectangle for full and parted rods, 30x lower loads for parted rods (the level alone
    tells them apart); the well seeds are family wells (their described fluid loads come from the seeds)."""
    n = 48
    label = np.array([LABELS.index("full"), LABELS.index("parted_rods")] * (n // 2))
    x, y = _rect(256)
    scale = np.where(label == 0, 1.5e4, 450.0)[:, None]
    cards = {"position_m": np.tile(x, (n, 1)), "load_n": scale * y + rng.normal(0, 20.0, (n, 256))}
    path.mkdir()
    both = {f"{kind}_{k}": v for kind in ("pump", "polished_rod") for k, v in cards.items()}
    write_npz(str(path / "cards.npz"), {**both, "label": label, "well_seed": np.full(n, 10_000_000),
                                        "split": np.repeat(["train", "validation", "test"], [32, 8, 8])})


def test_trainer_trains_a_level_model_that_tells_full_from_parted(tmp_path) -> None:
    pytest.importorskip("torch")
    from srenv.tools.train_classifier import main as train

    _card_set(tmp_path / "set", np.random.default_rng(0))
    out, report = tmp_path / "m.npz", tmp_path / "r.json"
    assert train(["--card", "pump", "--level", "--cards", str(tmp_path / "set"), "--out", str(out),
                  "--report", str(report), "--epochs", "20", "--candidates", "mlp_aug"]) == 0
    clf = CardClassifier.load(out)
    r = json.loads(report.read_text())
    assert clf.card_type == "pump" and clf.feature_set == "shape+level" and clf.needs_level
    assert r["feature_set"] == "shape+level" and r["description_error"] == pump_level.DESCRIPTION_ERROR
    assert r["test_accuracy_clean"] == 1.0  # the shapes are equal: only the level can do this


@pytest.mark.parametrize("argv, what", [
    (["--level"], "expected --card pump"),
    (["--card", "pump", "--level", "--compare", str(PUMP_MODEL)],
     "a model with features shape, expected features shape+level"),
])
def test_trainer_refuses_level_flags_in_one_line(capsys, argv, what) -> None:
    from srenv.tools.train_classifier import main as train

    with pytest.raises(SystemExit) as exc:
        train(["--cards", "nowhere", "--out", "m.npz", *argv])
    err = capsys.readouterr().err
    assert exc.value.code == 2 and err.count("\n") == 1 and what in err


def test_an_old_pump_model_file_without_the_feature_set_loads_and_behaves_as_before() -> None:
    """Run P1's file has no feature_set entry: it reads as ``shape`` and ignores a described fluid load."""
    with np.load(PUMP_MODEL, allow_pickle=False) as z:
        assert "feature_set" not in z.files
    clf = CardClassifier.load(PUMP_MODEL)
    assert clf.feature_set == "shape" and not clf.needs_level
    x, y = _rect()
    assert clf.classify(x, y) == clf.classify(x, y, fluid_load_n=1.0)
    np.testing.assert_array_equal(clf.card_features(x, y, 1.0), features(x, y, "pump"))


def _level_model(tmp_path: Path) -> Path:
    """P1's weights marked as a level model (a file of the level feature set, whatever it learned)."""
    with np.load(PUMP_MODEL, allow_pickle=False) as z:
        cols = {k: z[k] for k in z.files}
    write_npz(str(tmp_path / "level.npz"), {**cols, "feature_set": np.array("shape+level")})
    return tmp_path / "level.npz"


def test_a_level_model_without_a_config_is_refused_in_one_line(tmp_path, capsys) -> None:
    f = _write(tmp_path / "c.csv", *_rect())
    assert main(["classify", str(f), "--card", "pump", "--model", str(_level_model(tmp_path))]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "--config" in err and "load level" in err


def test_a_bad_feature_set_in_the_model_file_is_refused(tmp_path, capsys) -> None:
    with np.load(PUMP_MODEL, allow_pickle=False) as z:
        cols = {k: z[k] for k in z.files}
    write_npz(str(tmp_path / "m.npz"), {**cols, "feature_set": np.array("shape+spectrum")})
    f = _write(tmp_path / "c.csv", *_rect())
    assert main(["classify", str(f), "--card", "pump", "--model", str(tmp_path / "m.npz")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "feature_set" in err and "shape+spectrum" in err


def test_a_config_whose_pump_lifts_no_fluid_load_is_refused_in_one_line(tmp_path, capsys) -> None:
    cfg = tmp_path / "w.yaml"
    cfg.write_text("name: no_lift\nrod:\n  tapers:\n    - {diameter_mm: 22.0, length_m: 1000.0, grade: D}\n"
                   "pump:\n  load_source: pressures\n  plunger_diameter_mm: 44.45\n  intake_pressure_pa: 5.0e+8\n")
    f = _write(tmp_path / "c.csv", *_rect())
    assert main(["classify", str(f), "--config", str(cfg), "--card", "pump",
                 "--model", str(_level_model(tmp_path))]) == 2
    cap = capsys.readouterr()
    assert cap.out == "" and cap.err.count("\n") == 1 and "intake_pressure_pa" in cap.err


def test_a_card_whose_level_is_not_finite_is_refused_in_one_line(tmp_path, capsys, monkeypatch) -> None:
    from srenv.analysis.condition_card import condition_config, simulate_card
    from srenv.config import load_config

    c = simulate_card(condition_config(load_config(WELL), "full", 0.0))
    f = _write(tmp_path / "c.csv", c.polished_rod_position_m[:-1], c.polished_rod_load_n[:-1])
    from srenv.simulation import described

    # finite, > 0: level inf
    monkeypatch.setattr(described, "described_pump", lambda cfg: described.DescribedPump(1e-320, 1e-320, 0.0))
    assert main(["classify", str(f), "--config", WELL, "--card", "pump",
                 "--model", str(_level_model(tmp_path))]) == 2
    cap = capsys.readouterr()
    assert cap.out == "" and cap.err.count("\n") == 1 and "c.csv" in cap.err and "not finite" in cap.err


def _surface_cards(tmp_path: Path, labels: tuple[str, ...]) -> Path:
    """paper_fig3_vertical's simulated surface cards (SI, one stroke) in ``labels`` at severity 0.7."""
    from srenv.analysis.condition_card import condition_config, simulate_card
    from srenv.config import load_config

    well = load_config(WELL)
    for k in labels:
        c = simulate_card(condition_config(well, k, 0.0 if k == "full" else 0.7))
        _write(tmp_path / f"{k}.csv", c.polished_rod_position_m[:-1], c.polished_rod_load_n[:-1])
    return tmp_path


def _labels(capsys, argv: list[str]) -> dict[str, str]:
    assert main(argv) == 0
    return {Path(r["file"]).stem: r["label"] for r in map(json.loads, capsys.readouterr().out.splitlines())}


def test_the_shipped_level_model_is_run_p2s_data() -> None:
    from srenv.analysis.card_classifier import PUMP_LEVEL_MODEL, PUMP_P3_MODEL
    from srenv.tools.classify import default_model

    clf = CardClassifier.load(PUMP_LEVEL_MODEL)
    assert clf.card_type == "pump" and clf.feature_set == "shape+level" and clf.needs_level
    assert hashlib.sha256(PUMP_LEVEL_MODEL.read_bytes()).hexdigest() == P2_SHA256  # run P3 left it as it was
    assert hashlib.sha256(PUMP_MODEL.read_bytes()).hexdigest() == P1_SHA256
    assert default_model("pump", True) == str(PUMP_P3_MODEL)  # run P3 shipped: the default with a config since
    assert default_model("pump", False) == str(PUMP_MODEL)  # without a config: run P1's model, as before


def test_with_a_config_the_level_splits_the_rectangle_group_end_to_end(tmp_path, capsys, monkeypatch) -> None:
    """--config WELL --card pump: the full, flowing and parted-rods cards of one well, diagnosed; run P1 read the
    full one parted_rods (0.41) and flowing parted_rods (0.46). Dropping the level (its entry 0) changes the answer."""
    from srenv.analysis.card_classifier import PUMP_LEVEL_MODEL

    d = _surface_cards(tmp_path, ("full", "flowing", "parted_rods"))
    argv = ["classify", str(d), "--config", WELL, "--card", "pump", "--json", "--model", str(PUMP_LEVEL_MODEL)]
    got = _labels(capsys, argv)
    assert got["full"] == "full" and got["flowing"] == "flowing" and got["parted_rods"] != got["full"]
    monkeypatch.setattr(pump_level, "level", lambda load, fluid: 0.0)  # the feature dropped
    assert _labels(capsys, argv)["full"] != "full"


def test_p2_reads_a_parted_strings_diagnosed_card_flowing(tmp_path, capsys) -> None:
    """Run P2's miss, kept as P2's measured answer: trained on the string end's true cards (parted: +-200 N), it reads
    the card diagnosed through the described intact string (-16 kN, level 0.15) as flowing (docs/conditions.md)."""
    from srenv.analysis.card_classifier import PUMP_LEVEL_MODEL

    d = _surface_cards(tmp_path, ("parted_rods",))
    assert _labels(capsys, ["classify", str(d), "--config", WELL, "--card", "pump", "--json",
                            "--model", str(PUMP_LEVEL_MODEL)]) == {"parted_rods": "flowing"}


def test_with_a_config_run_p3_reads_all_twelve_diagnosed_cards_and_uses_the_offset(tmp_path, capsys,
                                                                                monkeypatch) -> None:
    """Run P3 (the default with a config): trained on diagnosed cards, it reads all twelve of the well's cards, the
    parted string among them (P2's strict expected failure until P3). The offset is where the physics says: the full
    pump's diagnosed lower plateau at the described true P+, the parted string's a missing string's weight below it
    (an equivalent-load P+ would put full at -0.3); dropping the offset (0) changes the heavy-oil answer."""
    from srenv.config import load_config
    from srenv.simulation.described import described_pump
    from srenv.tools.classify import diagnosed, read_card

    d = _surface_cards(tmp_path, LABELS)
    argv = ["classify", str(d), "--config", WELL, "--card", "pump", "--json"]
    assert _labels(capsys, argv) == {k: k for k in LABELS}
    cfg = load_config(WELL)
    pump = described_pump(cfg)
    off = {k: pump_level.offset(diagnosed(cfg, *read_card(d / f"{k}.csv"), d / f"{k}.csv")[1],
                                pump.downstroke_true_n, pump.fluid_load_n) for k in ("full", "parted_rods")}
    assert abs(off["full"]) < 0.05 and off["parted_rods"] < -0.8
    monkeypatch.setattr(pump_level, "offset", lambda load, down, fluid: 0.0)  # the feature dropped
    assert _labels(capsys, argv)["heavy_oil"] != "heavy_oil"
