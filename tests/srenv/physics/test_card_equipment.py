"""The card set's ``--equipment field`` (run 7, docs/cards_dataset.md): per card a plunger drag, sinker bars, a
fiberglass top and deviation beyond 35 deg; the default sets keep their bytes."""

from __future__ import annotations

import dataclasses
import hashlib
import json

import numpy as np
import pytest
from conftest import run_on_avx2_numpy

from srenv.physics.conditions import LABELS
from srenv.task import card_equipment as ce
from srenv.task import card_set as cs
from srenv.task import well_family as wf
from srenv.tools.cli import main

# sha256 of `srenv cards --n 3 --seed 4 --out D --workers 1 [--surface v2]`'s cards.npz, made by commit 937808c's
# code (before --equipment existed) on numpy's AVX2 kernels (conftest.run_on_avx2_numpy: on AVX-512 kernels the same
# code writes other last bits, 407d4b57... and b3421f9c...)
PINNED = {"family": "27a3db56f872716848487c4797a94acc39502312ad97ed28622dff2563dc177d",
          "v2": "dd733e2dbe79ca6d6c2b78fc1d392afa42d41d0427beea1848b92a08c62bb7ad"}


def test_default_sets_keep_their_bytes_and_have_no_equipment_column(tmp_path) -> None:
    for surface, digest in PINNED.items():
        out = tmp_path / surface
        args = ["cards", "--n", "3", "--seed", "4", "--out", str(out), "--workers", "1", "--no-progress",
                "--surface", surface, "--equipment", "none"]
        run_on_avx2_numpy(f"from srenv.tools.cli import main; assert main({args!r}) == 0")
        assert hashlib.sha256((out / "cards.npz").read_bytes()).hexdigest() == digest
        cols = cs.load_cards(str(out / "cards.npz"))
        meta = json.loads((out / "dataset_card.json").read_text())
        assert not set(ce.COLUMNS) & set(cols) and "equipment" not in meta


def test_field_draws_keep_every_older_field() -> None:
    for surface in ("family", "v2"):
        for i in range(200):
            a, b = cs.draw(7, i, 0, LABELS, surface), cs.draw(7, i, 0, LABELS, surface, "field")
            assert a.equipment is None and b.equipment is not None
            assert dataclasses.replace(b, equipment=None) == a
    with pytest.raises(ValueError, match="equipment"):
        cs.draw(7, 0, 0, LABELS, "v2", "fiberglass")


def test_equipment_draws_cover_their_documented_ranges() -> None:
    eqs = [ce.draw_equipment(np.random.default_rng(k)) for k in range(2000)]
    drag = np.array([e.plunger_friction_n for e in eqs])
    assert drag.min() >= 200.0 and drag.max() <= 4000.0 and np.mean(drag < 894.4) == pytest.approx(0.5, abs=0.04)
    sinker = [e for e in eqs if e.sinker_bar_diameter_mm > 0]
    glass = [e for e in eqs if e.fiberglass_diameter_mm > 0]
    assert len(sinker) / 2000 == pytest.approx(ce.SINKER_SHARE, abs=0.04)
    assert len(glass) / 2000 == pytest.approx(ce.FIBERGLASS_SHARE, abs=0.04)
    assert {e.sinker_bar_diameter_mm for e in sinker} == set(ce.SINKER_DIAMETERS_MM)
    assert all(0.05 <= e.sinker_fraction <= 0.2 for e in sinker) and all(0.4 <= e.fiberglass_fraction <= 0.7
                                                                         for e in glass)
    incl = np.array([e.max_inclination_deg for e in eqs])
    assert incl.min() >= 8.0 and incl.max() <= 60.0 and np.mean(incl > 35.0) > 0.4  # beyond the family's 35 deg


def test_string_keeps_its_length_sinker_bars_at_the_bottom_fiberglass_on_top() -> None:
    tapers = [{"diameter_mm": 25.4, "length_m": 500.0, "grade": "K"}, {"diameter_mm": 22.225, "length_m": 600.0,
                                                                       "grade": "K"},
              {"diameter_mm": 19.05, "length_m": 100.0, "grade": "K"}]
    eq = ce.Equipment(1500.0, 38.1, 0.15, 25.4, 0.5)
    s = ce.string_with(tapers, eq)
    assert sum(t["length_m"] for t in s) == pytest.approx(1200.0, abs=1e-6)
    assert s[0] == {"diameter_mm": 25.4, "length_m": 600.0, "material": "fiberglass"}
    assert s[-1] == {"diameter_mm": 38.1, "length_m": 180.0, "material": "sinker_bar", "grade": "K"}
    # the 19.05-mm taper (100 m) is all cut by the 180 m of sinker bars, the 22.225-mm one loses 80 m,
    # the fiberglass takes the 25.4-mm taper and 100 m of the next
    assert [(t["diameter_mm"], t["length_m"]) for t in s[1:-1]] == [(22.225, 420.0)]
    assert ce.string_with(tapers, ce.Equipment(800.0)) == tapers  # drag only: the string as designed


def test_a_field_card_carries_its_equipment_and_heavy_oil_adds_to_the_drag() -> None:
    d = next(d for d in (cs.draw(7, i, 0, ("full",), "v2", "field") for i in range(200))
             if d.equipment.sinker_bar_diameter_mm and d.equipment.fiberglass_diameter_mm)
    cfg = cs.card_config(d)
    mats = [t.material for t in cfg.rod.tapers]
    assert mats[0] == "fiberglass" and mats[-1] == "sinker_bar" and set(mats[1:-1]) == {"steel"}
    assert cfg.rod.tapers[0].youngs_modulus_pa == pytest.approx(4.8e10)  # the config's fiberglass default
    assert cfg.pump.plunger_friction_n == pytest.approx(d.equipment.plunger_friction_n)
    assert sum(t.length_m for t in cfg.rod.tapers) == pytest.approx(cfg.rod_length_m)
    cols = ce.columns(cfg)
    assert cols["sinker_bar_length_m"] == pytest.approx(cfg.rod_length_m * d.equipment.sinker_fraction, abs=1e-2)
    heavy = cs.card_config(dataclasses.replace(d, label="heavy_oil", severity=0.6))
    assert heavy.pump.plunger_friction_n > d.equipment.plunger_friction_n + 100.0
    steep = next(d for d in (cs.draw(7, i, 0, ("full",), "v2", "field") for i in range(400))
                 if d.equipment.max_inclination_deg > 45.0
                 and wf.draw_params(d.well_seed).survey_shape != "vertical")
    incl = max(s.inclination_deg for s in cs.card_config(steep).survey.stations)
    assert incl > 44.0  # the family's wells stop at 35 deg


def test_cards_cli_field_equipment_records_the_columns(tmp_path) -> None:
    out = tmp_path / "field"
    assert main(["cards", "--n", "4", "--seed", "7", "--out", str(out), "--workers", "1", "--no-progress",
                 "--surface", "v2", "--equipment", "field"]) == 0
    cols = cs.load_cards(str(out / "cards.npz"))
    meta = json.loads((out / "dataset_card.json").read_text())
    assert meta["equipment"] == "field" and set(ce.COLUMNS) <= set(meta["well_columns"])
    assert np.all(cols["plunger_friction_n"] >= 200.0) and cols["plunger_friction_n"].shape == (4,)
    assert np.all((cols["sinker_bar_length_m"] > 0) == (cols["sinker_bar_diameter_mm"] > 0))


def test_cards_cli_refuses_an_unknown_equipment_in_one_line(tmp_path, capsys) -> None:
    with pytest.raises(SystemExit) as e:
        main(["cards", "--n", "1", "--out", str(tmp_path / "x"), "--equipment", "steel"])
    assert e.value.code == 2
    err = capsys.readouterr().err.strip()
    assert "--equipment" in err and len(err.splitlines()) == 1


def test_sinker_bars_stay_thinner_than_the_plunger() -> None:
    tapers = [{"diameter_mm": 19.05, "length_m": 800.0, "grade": "D"}]
    eq = ce.Equipment(1000.0, 44.45, 0.1)
    assert ce.string_with(tapers, eq, 57.15)[-1]["diameter_mm"] == 44.45
    assert ce.string_with(tapers, eq, 44.45)[-1]["diameter_mm"] == 38.1
    assert ce.string_with(tapers, eq, 31.75)[-1]["diameter_mm"] == 28.575


def test_robustness_check_e_runs_the_sets_equipment_on_shipped_and_check_wells() -> None:
    import importlib.util
    from pathlib import Path

    from srenv.analysis.card_classifier import DEFAULT_MODEL, CardClassifier

    path = Path(__file__).parents[3] / "scripts" / "conditions_robustness.py"
    spec = importlib.util.spec_from_file_location("conditions_robustness", path)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    stream = list(mod.equipment_cards(["default"], 1, 0.6))
    where = {w for w, _, _ in stream}
    assert where == {"e1/default/sinker", "e1/default/fiberglass", "e2/clscheck-0"}
    assert sum(1 for w, lab, _ in stream if lab == "full") == 3  # the full pump on each well
    assert mod.FIXED_EQUIPMENT["sinker"].sinker_bar_diameter_mm == 38.1
    r = mod.score({"m": CardClassifier.load(DEFAULT_MODEL)}, stream)["m"]
    parts = r["right_of_by_part"]
    assert parts["e1"][1] + parts["e2"][1] == r["of"] == len(stream)
    assert parts["e1"][0] + parts["e2"][0] == r["right"]
