"""The pump conditions' mechanisms (srenv.physics.conditions, srenv.physics.laws.pump_conditions) and the
labelled card set (srenv cards): each mechanism moves its card the way the physics says, severity 0 is the
full pump, the set is deterministic, split by well, and loads back."""

from __future__ import annotations

import itertools
import json

import numpy as np
import pytest

from srenv.analysis.condition_card import condition_config, simulate_card
from srenv.config import apply_overrides, config_from_dict, load_config, to_dict
from srenv.physics.conditions import LABELS, condition_of, condition_overrides
from srenv.task.card_set import columns, load_cards, make_card, split_of, write_npz

WELL = "paper_fig3_vertical"


@pytest.fixture(scope="module")
def well():
    return load_config(WELL)


def pump_card(well, **pump):
    cfg = condition_config(well, "full", 0.0, {f"pump.{k}": v for k, v in pump.items()})
    return simulate_card(cfg)


def loaded_share(card, rising: bool, level: float, well) -> float:
    """Share of the plunger's travel in one direction with the pump load above P+ + `level` x (P- - P+)."""
    x, y = card.pump_position_m, card.pump_load_n
    dx = np.diff(x)
    lo, hi = well.pump.downstroke_load_n, well.pump.upstroke_load_n
    sel = dx > 0 if rising else dx < 0
    carried = (y[1:] >= lo + level * (hi - lo)) & sel
    return float(np.abs(dx[carried]).sum() / np.abs(dx[sel]).sum())


def test_labels_and_severity_zero_is_full(well) -> None:
    assert LABELS[0] == "full" and len(LABELS) == 12 and len(set(LABELS)) == 12
    full = condition_overrides("full", 0.0, well)
    for label in LABELS:
        assert condition_overrides(label, 0.0, well) == full
    with pytest.raises(ValueError):
        condition_overrides("sticky", 0.5, well)
    with pytest.raises(ValueError):
        condition_overrides("flowing", 1.5, well)


@pytest.mark.parametrize("label", LABELS)
def test_overrides_are_config_keys(well, label) -> None:
    """Every override is a dotted key the loader (and `srenv simulate --set`) accepts; the summary names it."""
    cfg = config_from_dict(apply_overrides(to_dict(well), condition_overrides(label, 0.7, well)))
    if label not in ("fluid_pound", "heavy_oil"):  # these two show in the run / the string, not a pump field
        assert condition_of(cfg) == label


def test_travelling_valve_leak_shortens_the_load_transfer(well) -> None:
    shares = [loaded_share(pump_card(well, travelling_valve_leak_fraction=s), True, 0.9, well)
              for s in (0.0, 0.25, 0.5, 0.75, 1.0, 3.0)]
    assert all(a > b for a, b in itertools.pairwise(shares)), shares
    # 0.9 of the load needs a speed of 0.9 x the leak's: at 1 over the middle 44 % of the travel, at 3 never
    assert shares[0] > 0.9 and 0.3 < shares[-2] < 0.6 and shares[-1] == 0.0


def test_standing_valve_leak_keeps_the_load_on_the_downstroke(well) -> None:
    shares = [loaded_share(pump_card(well, standing_valve_leak_fraction=s), False, 0.5, well)
              for s in (0.0, 0.5, 1.0, 2.0)]
    assert all(a < b for a, b in itertools.pairwise(shares)), shares


def test_tagging_impact_grows_with_overtravel(well) -> None:
    free = pump_card(well)
    up = [pump_card(well, tag_top_overtravel_m=d).pump_load_n.max() for d in (0.05, 0.1, 0.2)]
    down = [pump_card(well, tag_bottom_overtravel_m=d).pump_load_n.min() for d in (0.05, 0.1, 0.2)]
    assert free.pump_load_n.max() < up[0] < up[1] < up[2]
    assert free.pump_load_n.min() > down[0] > down[1] > down[2]


def test_tubing_leak_and_flow_lower_the_fluid_load(well) -> None:
    def upstroke_load(card):
        x, y = card.pump_position_m, card.pump_load_n
        return float(np.median(y[1:][np.diff(x) > 0]))
    leak = [upstroke_load(pump_card(well, tubing_leak_fraction=f)) for f in (0.0, 0.3, 0.6)]
    flow = [upstroke_load(pump_card(well, flow_through_fraction=f)) for f in (0.0, 0.3, 0.6)]
    assert leak[0] > leak[1] > leak[2]
    p_up, p_down = well.pump.upstroke_load_n, well.pump.downstroke_load_n
    for f, got in zip((0.0, 0.3, 0.6), flow):  # the plunger carries (1 - f) of the fluid load
        assert got == pytest.approx(p_down + (1 - f) * (p_up - p_down), rel=0.05)


def test_parted_rods_and_heavy_oil(well) -> None:
    full = simulate_card(condition_config(well, "full", 0.0))
    parted = simulate_card(condition_config(well, "parted_rods", 0.5))
    y = parted.polished_rod_load_n  # 55 % of the string, no fluid load: low and thin
    assert y.max() < 0.6 * full.polished_rod_load_n.max() and (y.max() - y.min()) < 0.25 * y.max()
    heavy = simulate_card(condition_config(well, "heavy_oil", 0.8))

    def area(c):
        x, y = c.polished_rod_position_m, c.polished_rod_load_n
        return abs(float(np.sum(0.5 * (y[1:] + y[:-1]) * np.diff(x))))
    assert area(heavy) > 1.1 * area(full)


def test_fluid_pound_and_gas_fill_less(well) -> None:
    fills = [simulate_card(condition_config(well, "fluid_pound", s)).fillage for s in (0.3, 0.9)]
    assert 1.0 > fills[0] > fills[1]
    assert simulate_card(condition_config(well, "gas_interference", 0.8)).fillage < 0.8


def test_card_set_is_deterministic_split_by_well_and_loads_back(tmp_path) -> None:
    labels = ("full", "tagging_down")
    a = [make_card(3, i, labels) for i in range(6)]
    b = [make_card(3, i, labels) for i in (0, 1, 2, 3, 4, 5)]
    ca, cb = columns(a), columns(b)
    write_npz(str(tmp_path / "a.npz"), ca)
    write_npz(str(tmp_path / "b.npz"), cb)
    assert (tmp_path / "a.npz").read_bytes() == (tmp_path / "b.npz").read_bytes()
    back = load_cards(str(tmp_path / "a.npz"))
    for k, v in ca.items():
        np.testing.assert_array_equal(back[k], v)
    for seed, split in zip(back["well_seed"], back["split"]):
        assert split == split_of(int(seed))
    assert set(back["label_names"][back["label"]]) <= set(labels)
    splits = {split_of(s) for s in range(20_000_000, 20_000_200)}
    assert splits == {"train", "validation", "test"}


def test_cards_cli(tmp_path, capsys) -> None:
    from srenv.tools.cli import main

    assert main(["cards", "--n", "2", "--seed", "5", "--out", str(tmp_path / "s"), "--workers", "1",
                 "--no-progress", "--conditions", "full,flowing"]) == 0
    meta = json.loads((tmp_path / "s" / "dataset_card.json").read_text())
    assert meta["n_cards"] == 2 and meta["labels"] == list(LABELS)
    capsys.readouterr()
    with pytest.raises(SystemExit) as exc:
        main(["cards", "--n", "2", "--out", str(tmp_path / "t"), "--conditions", "sticky"])
    assert exc.value.code == 2
    assert "--conditions" in capsys.readouterr().err
    (tmp_path / "f").write_text("x")
    (tmp_path / "link").symlink_to(tmp_path / "s")
    for out in ("f", "link", "missing/deeper"):  # a file, a symbolic link, no parent directory
        assert main(["cards", "--n", "1", "--out", str(tmp_path / out), "--no-progress"]) == 2
        err = capsys.readouterr().err.strip()
        assert len(err.splitlines()) == 1 and "--out" in err


def test_stroke_summary_names_the_condition(well) -> None:
    from srenv.analysis.stroke_summary import summarize
    from srenv.simulation.simulator import Simulator

    for label in ("full", "tagging_up"):
        sim = Simulator(condition_config(well, label, 0.5))
        sim.reset()
        assert summarize(sim, sim.run_strokes(2))["condition"] == label
