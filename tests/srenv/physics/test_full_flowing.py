"""Full against flowing (issue 23, docs/conditions.md "Full against flowing"): a flowing well's card is a full pump's
card with a smaller fluid load, so the card alone cannot tell them apart; and the card set's ``--plungers api``
(run 8) that reaches the low fluid-load ratios real wells have."""

from __future__ import annotations

import dataclasses
import json

import numpy as np
import pytest

from srenv.analysis.condition_card import condition_config, simulate_card
from srenv.config import load_config
from srenv.physics.conditions import LABELS
from srenv.task import card_equipment as ce
from srenv.task import card_set as cs
from srenv.task import well_family as wf
from srenv.tools.cli import main


def test_a_flowing_card_is_a_full_card_with_a_smaller_fluid_load() -> None:
    well = load_config("paper_fig3_vertical")  # a well given by its two pump loads
    f = 0.9 * 0.6
    flowing = simulate_card(condition_config(well, "flowing", 0.6))
    up, down = well.pump.upstroke_load_n, well.pump.downstroke_load_n
    smaller = simulate_card(condition_config(well, "full", 0.0, {"pump.upstroke_load_n": down + (1 - f) * (up - down)}))
    full = simulate_card(condition_config(well, "full", 0.0))
    span = np.ptp(full.polished_rod_load_n)
    # the same card to round-off; the well's own full card differs by about f x the fluid load
    assert np.max(np.abs(flowing.polished_rod_load_n - smaller.polished_rod_load_n)) < 1e-6 * span
    assert np.max(np.abs(flowing.polished_rod_load_n - full.polished_rod_load_n)) > 0.3 * f * (up - down)


def test_api_plungers_keep_every_older_draw_and_add_the_small_bore() -> None:
    sizes = set()
    for i in range(300):
        a, b = cs.draw(90, i, 0, LABELS, "v2", "field"), cs.draw(90, i, 0, LABELS, "v2", "field", "api")
        assert a.plunger_u is None and 0.0 <= b.plunger_u < 1.0
        assert dataclasses.replace(b, plunger_u=None) == a
        p = wf.draw_params(b.well_seed)
        got = ce.api_plunger(p, b.plunger_u).plunger_diameter_mm
        assert got in (ce.API_SMALL_BORE_MM, *wf.plunger_sizes_mm(p.depth_m))
        sizes.add(got)
    assert ce.API_SMALL_BORE_MM in sizes and len(sizes) >= 4
    assert ce.api_plunger(p, None) is p
    with pytest.raises(ValueError, match="plungers"):
        cs.draw(90, 0, 0, LABELS, "v2", "field", "large")


def test_family_plunger_sizes_are_the_family_draws() -> None:
    for seed in range(200):
        p = wf.draw_params(seed)
        assert p.plunger_diameter_mm in wf.plunger_sizes_mm(p.depth_m)
    assert wf.plunger_sizes_mm(2500.0) == [31.75, 38.1] and wf.plunger_sizes_mm(500.0) == list(wf.PLUNGERS_MM)


def test_a_small_bore_card_has_a_lower_fluid_load_ratio_and_a_sinker_bar_under_its_plunger() -> None:
    d = next(d for d in (cs.draw(90, i, 0, ("full",), "v2", "field", "api") for i in range(400))
             if d.equipment.sinker_bar_diameter_mm > 0 and ce.api_plunger(wf.draw_params(d.well_seed),
                                                                           d.plunger_u).plunger_diameter_mm < 27)
    cfg = cs.card_config(d)
    assert cfg.pump.plunger_diameter_mm == pytest.approx(ce.API_SMALL_BORE_MM)
    assert cfg.rod.tapers[-1].material == "sinker_bar" and cfg.rod.tapers[-1].diameter_mm == 25.4
    assert ce.string_with([{"diameter_mm": 19.05, "length_m": 800.0}], ce.Equipment(1000.0, 31.75, 0.1),
                          ce.API_SMALL_BORE_MM)[-1]["diameter_mm"] == 25.4


def test_cards_cli_api_plungers_records_its_flag(tmp_path, capsys) -> None:
    out = tmp_path / "api"
    assert main(["cards", "--n", "4", "--seed", "90", "--out", str(out), "--workers", "1", "--no-progress",
                 "--surface", "v2", "--equipment", "field", "--plungers", "api"]) == 0
    meta = json.loads((out / "dataset_card.json").read_text())
    assert meta["plungers"] == "api" and meta["equipment"] == "field" and meta["n_cards"] == 4
    with pytest.raises(SystemExit) as e:
        main(["cards", "--n", "1", "--out", str(tmp_path / "x"), "--plungers", "large"])
    assert e.value.code == 2
    err = capsys.readouterr().err.strip()
    assert "--plungers" in err and len(err.splitlines()) == 1
