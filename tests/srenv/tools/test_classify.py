"""srenv classify: the shipped classifier (trained on simulated cards only) on a simulated full-pump card in
any units, on the CC0 reference cards (final test only: never used to train, tune or select), and its
answers to bad input."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from srenv.analysis.card_classifier import CardClassifier
from srenv.analysis.condition_card import condition_config, simulate_card
from srenv.config import load_config
from srenv.physics.conditions import LABELS
from srenv.tools.cli import main

DATA = Path(__file__).resolve().parents[2] / "data" / "plate_reference_cards.json"
# reference card -> srenv label; plunger_out_of_barrel and sand (not in this copy) name conditions outside
# the twelve labels, so no answer of the classifier can be right for them
REFERENCE = {"normal": "full", "insufficient_supply_fluid_pound": "fluid_pound",
             "gas_interference": "gas_interference", "rod_part": "parted_rods", "tagging_up": "tagging_up",
             "tagging_down": "tagging_down", "travelling_valve_leak": "travelling_valve_leak",
             "standing_valve_leak": "standing_valve_leak"}
LEFT_OUT = {"plunger_out_of_barrel": "no such label among the twelve", "sand": "no such label among the twelve"}
# measured once for each shipped model after its training and selection on simulated wells: run 2, then run 3's
# look (runs 3 and 3b, not shipped), run 4's one look with run 4 shipped, run 5's with run 5 shipped and run 7's with
# run 7 shipped (docs/conditions.md; run 6, not shipped, looked once after its rule kept run 5: the same three, the
# same labels):
# every run missed the same three with the same labels; the reference cards the classifier
# gets wrong are kept as strict expected failures, a loss reported as such
MISSED: dict[str, str] = {
    "normal": "measured: run 7 classifies it both_valves_leak (1.00; runs 2-6 the same label)",
    "gas_interference": "measured: run 7 classifies it fluid_pound (1.00; runs 2-6 the same)",
    "rod_part": "measured: run 7 classifies it both_valves_leak (0.97; runs 2-6 the same)",
}

# run P1's one look (docs/conditions.md): the pump (downhole) model on the same cards with --card pump, measured
# once after its ship decision; the misses, strict expected failures with the measured label
MISSED_PUMP: dict[str, str] = {
    "normal": "measured: the pump model (run P1) classifies it both_valves_leak (1.00)",
    "gas_interference": "measured: the pump model (run P1) classifies it fluid_pound (0.99)",
    "rod_part": "measured: the pump model (run P1) classifies it fluid_pound (0.60; full 0.22)",
    "tagging_up": "measured: the pump model (run P1) classifies it fluid_pound (1.00)",
    "tagging_down": "measured: the pump model (run P1) classifies it gas_interference (0.37; heavy_oil 0.36)",
}


def write_card(path: Path, x, y) -> None:
    np.savetxt(path, np.c_[x, y], delimiter=",", header="polished_rod_position_m,polished_rod_load_n",
               comments="")


def classify_dir(d: Path, capsys, card: str = "surface") -> dict[str, dict]:
    assert main(["classify", str(d), "--json", "--card", card]) == 0
    out = {}
    for line in capsys.readouterr().out.splitlines():
        row = json.loads(line)
        out[Path(row["file"]).name] = row
    return out


def test_full_card_in_si_and_field_units(tmp_path, capsys) -> None:
    card = simulate_card(condition_config(load_config("paper_fig3_vertical"), "full", 0.0))
    idx = np.linspace(0, len(card.t_s) - 1, 220).astype(int)
    x, y = card.polished_rod_position_m[idx], card.polished_rod_load_n[idx]
    write_card(tmp_path / "si.csv", x, y)
    write_card(tmp_path / "field.csv", x / 0.0254, y / 4.448)
    got = classify_dir(tmp_path, capsys)
    assert {k: v["label"] for k, v in got.items()} == {"si.csv": "full", "field.csv": "full"}
    for row in got.values():
        assert set(row["probabilities"]) == set(LABELS)
        assert sum(row["probabilities"].values()) == pytest.approx(1.0, abs=1e-4)


def test_field_export_headers_name_the_columns(tmp_path, capsys) -> None:
    """A field export's own header ("Load (lbf)" first, "Position (in)" second) reads as the same card; a header
    that names neither column, or two of one kind, is refused."""
    card = simulate_card(condition_config(load_config("paper_fig3_vertical"), "full", 0.0))
    idx = np.linspace(0, len(card.t_s) - 1, 220).astype(int)
    x, y = card.polished_rod_position_m[idx], card.polished_rod_load_n[idx]
    write_card(tmp_path / "si.csv", x, y)
    np.savetxt(tmp_path / "export.csv", np.c_[y / 4.448, x / 0.0254], delimiter=",", header="Load (lbf),Position (in)",
               comments="")
    got = classify_dir(tmp_path, capsys)
    assert got["export.csv"]["label"] == got["si.csv"]["label"] == "full"
    assert got["export.csv"]["probabilities"] == pytest.approx(got["si.csv"]["probabilities"], abs=1e-5)
    (tmp_path / "two.csv").write_text("position_a,position_b\n1,2\n")
    assert main(["classify", str(tmp_path / "two.csv")]) == 2 and "header" in capsys.readouterr().err


@pytest.mark.parametrize("name", sorted(REFERENCE))
def test_reference_cards(name, tmp_path, capsys, request) -> None:
    _reference_card_check(name, tmp_path, capsys, request, MISSED, "surface")


def _reference_card_check(name, tmp_path, capsys, request, missed: dict[str, str], card_type: str) -> None:
    if name in missed:
        request.applymarker(pytest.mark.xfail(strict=True, reason=missed[name]))
    card = json.loads(DATA.read_text())["cards"][name]
    write_card(tmp_path / f"{name}.csv", card["position"], card["load"])
    got = classify_dir(tmp_path, capsys, card_type)
    assert got[f"{name}.csv"]["label"] == REFERENCE[name]


@pytest.mark.parametrize("name", sorted(REFERENCE))
def test_reference_cards_as_pump_cards(name, tmp_path, capsys, request) -> None:
    """The plate's cards are drawn as downhole card shapes (a rectangle for normal): the pump model's reading."""
    _reference_card_check(name, tmp_path, capsys, request, MISSED_PUMP, "pump")


def test_reference_file_names_its_source_and_licence() -> None:
    d = json.loads(DATA.read_text())
    assert d["_provenance"]["doi"] == "10.17632/hnfwm9mjs6.1" and "CC0" in d["_provenance"]["licence"]
    assert set(d["cards"]) == set(REFERENCE) | {"plunger_out_of_barrel"}


@pytest.mark.parametrize("content, what", [
    ("", "empty"),
    ("polished_rod_position_m,polished_rod_load_n\n1,2\n3,x\n", "numbers"),
    ("a,b\n1,2\n", "header"),
    ("polished_rod_position_m,polished_rod_load_n\n" + "1,2\n" * 20, "does not vary"),
    ("polished_rod_position_m,polished_rod_load_n\n1,2\n2,3\n", "at least"),
])
def test_bad_cards_exit_2_in_one_line(tmp_path, capsys, content, what) -> None:
    (tmp_path / "c.csv").write_text(content)
    assert main(["classify", str(tmp_path / "c.csv")]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and what in err


def test_bad_model_exits_2(tmp_path, capsys) -> None:
    card = tmp_path / "c.csv"
    write_card(card, np.sin(np.linspace(0, 2 * np.pi, 50)), np.cos(np.linspace(0, 2 * np.pi, 50)) + 3)
    (tmp_path / "m.npz").write_text("import os; os.system('echo pwned')\n")
    pickled = tmp_path / "p.npz"
    np.savez(pickled, labels=np.array([object()], dtype=object))
    for model in (tmp_path / "m.npz", pickled, tmp_path / "missing.npz"):
        assert main(["classify", str(card), "--model", str(model)]) == 2
        err = capsys.readouterr().err.strip()
        assert len(err.splitlines()) == 1 and "--model" in err


@pytest.mark.parametrize("members, axis, what", [
    (0, 2, "members = [0], expected an integer in [1, 16]"),
    (2, 3, "array b0 has shape (3, 256), expected a leading member axis of 2"),
])
def test_a_model_file_with_a_broken_member_axis_exits_2(tmp_path, capsys, members, axis, what) -> None:
    """An ensemble file (run 10) whose member count or member axis is wrong: one line naming it, exit 2."""
    from srenv.analysis.card_classifier import DEFAULT_MODEL
    from srenv.task.card_set import write_npz

    card = tmp_path / "c.csv"
    write_card(card, np.sin(np.linspace(0, 2 * np.pi, 50)), np.cos(np.linspace(0, 2 * np.pi, 50)) + 3)
    with np.load(DEFAULT_MODEL.with_name("classifier_run5.npz"), allow_pickle=False) as z:
        cols = {k: z[k] if k == "labels" else np.stack([z[k]] * axis) for k in z.files}
    write_npz(str(tmp_path / "e.npz"), {**cols, "members": np.array(members)})
    assert main(["classify", str(card), "--model", str(tmp_path / "e.npz")]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "--model" in err and what in err


def test_shipped_model_is_data() -> None:
    clf = CardClassifier.load()
    assert clf.labels == LABELS


def test_srenv_simulate_csv_is_a_card(tmp_path, capsys) -> None:
    """srenv's own simulate CSV (several strokes, more columns): its last stroke is classified."""
    out = tmp_path / "run.csv"
    assert main(["simulate", "paper_fig3_vertical", "--strokes", "3", "--out", str(out)]) == 0
    capsys.readouterr()
    assert main(["classify", str(out), "--json"]) == 0
    row = json.loads(capsys.readouterr().out.splitlines()[0])
    assert row["label"] == "full" and row["file"] == str(out)


def test_a_card_stored_backwards_reads_the_same() -> None:
    """Field exports are sometimes stored with time reversed: the card's positive work tells the order."""
    from srenv.analysis.card_shape import features

    card = simulate_card(condition_config(load_config("paper_fig3_vertical"), "tagging_down", 0.7))
    x, y = card.polished_rod_position_m, card.polished_rod_load_n
    np.testing.assert_allclose(features(x[::-1], y[::-1]), features(x, y), atol=1e-9)


def test_the_wheel_ships_the_model(wheel) -> None:
    import zipfile

    names = zipfile.ZipFile(wheel).namelist()
    assert "srenv/models/classifier.npz" in names
    assert "srenv/models/classifier_run2.npz" in names  # v2's observation reads run 2's model, pinned
    assert "srenv/models/classifier_run7.npz" in names  # v3's reads run 7's, pinned
    assert "srenv/models/classifier_pump.npz" in names  # srenv classify --card pump (run P1)
    assert "srenv/models/classifier_config.npz" in names  # srenv classify --config on surface cards (run 9)


def test_run_5s_model_is_kept_beside_the_shipped_one() -> None:
    """Run 7 replaced the shipped model (docs/conditions.md, run 7's rule); run 5's weights stay as package data,
    byte for byte, for `srenv classify --model` and for comparisons."""
    import hashlib

    from srenv.analysis.card_classifier import DEFAULT_MODEL

    run5 = DEFAULT_MODEL.with_name("classifier_run5.npz")
    assert hashlib.sha256(run5.read_bytes()).hexdigest() == (
        "1f047a69c4412ca411779c3096768e64ebf7e6ce551f072b3c01ee6dce33bc90")
    assert run5.read_bytes() != DEFAULT_MODEL.read_bytes()
    assert CardClassifier.load(run5).labels == CardClassifier.load(DEFAULT_MODEL).labels == tuple(LABELS)
