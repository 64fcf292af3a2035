"""Predictive inputs (srenv/physics/pump_inputs.py, docs/realism.md "Predictive inputs"): a pump below the rod
string's end (pump.depth_m) and an annulus fluid level with its casing pressure instead of an intake pressure,
checked against hand calculations; honoured by simulate and diagnose; bad combinations one line, exit 2."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
from declared_helpers import nothing_left, one_line, run_srenv

from srenv.analysis.diagnose import diagnose_card, summary
from srenv.analysis.pump_card import analyse_pump_card
from srenv.config import load_config, to_dict
from srenv.errors import ConfigError
from srenv.physics.pump import plunger_area_m2
from srenv.physics.rod import GRAVITY_M_S2
from srenv.simulation.simulator import Simulator
from srenv.tools.cli import main

# the env's default well (992 m of rods; survey 0 -> 20 deg at 336 m -> 0 deg at 992 m), pressures from a
# given intake, no inflow model
BASE = ["inflow.model=none", "pump.intake_pressure_pa=2.0e6"]
RHO = 850.0  # the default well's liquid (kg/m^3)


def _sim(*sets: str) -> Simulator:
    return Simulator(load_config("default", [*BASE[:1], *sets]))


def test_a_pump_below_the_rods_lowers_the_valve_laws_intake_by_the_column() -> None:
    """50 m below the rods' end (992 m), where the survey (vertical at its last station) is held vertical:
    the upstroke load (p_d - p_in) A_pl + P_f has p_d 850 g 50 Pa higher at the plunger."""
    base, deep = _sim(BASE[1]), _sim(BASE[1], "pump.depth_m=1042")
    column = RHO * GRAVITY_M_S2 * 50.0  # 416.8 kPa
    a_pl = plunger_area_m2(base.cfg.pump)
    assert deep.law.up_eq_n - base.law.up_eq_n == pytest.approx(column * a_pl, rel=1e-9)
    assert deep.law.down_eq_n == base.law.down_eq_n  # the downstroke: discharge loss and friction only
    # the rod end keeps its own pressure (true load = equivalent - p A at the rod end)
    assert deep.p_pump_pa == base.p_pump_pa
    # the same run as the pump at the rod end with the intake lowered by hand: bit for bit
    by_hand = _sim(f"pump.intake_pressure_pa={2.0e6 - column!r}")
    a, b = deep.run_strokes(2)[-1].trace, by_hand.run_strokes(2)[-1].trace
    assert np.array_equal(a["polished_rod_load_n"], b["polished_rod_load_n"])


def test_a_deviated_column_counts_its_vertical_height() -> None:
    """Fig. 4's survey ends at 992 m with 0 deg: the column is TVD-deep; a survey station at 30 deg at 1100 m
    makes the 50-m column 50 cos(angle) deep along the interpolated inclination."""
    from srenv.physics.pump_inputs import column_below_rods_pa
    from srenv.physics.survey import Survey

    cfg = load_config("default", [*BASE, "pump.depth_m=1042", "survey.stations.2.md_m=1100",
                                  "survey.stations.2.inclination_deg=30"])
    survey = Survey.from_config(cfg.survey, cfg.rod_length_m)
    # inclination linear from 20 deg (336 m) to 30 deg (1100 m): int cos = (sin a2 - sin a1) / (da/ds)
    rate = math.radians(10.0) / (1100.0 - 336.0)
    a1, a2 = math.radians(20.0) + rate * (992 - 336), math.radians(20.0) + rate * (1042 - 336)
    dz = (math.sin(a2) - math.sin(a1)) / rate
    assert column_below_rods_pa(cfg, survey) == pytest.approx(RHO * GRAVITY_M_S2 * dz, rel=1e-5)


def test_the_fluid_level_gives_the_intake_pressure_of_a_hand_calculation() -> None:
    """Level 700 m from the surface, casing 300 kPa, pump at the rods' end (992 m) on the survey whose
    inclination falls linearly from 20 deg at 336 m to 0 at 992 m: p_in = p_c + rho g dTVD with
    dTVD = sin(a(700)) / (da/ds) (closed form of the integral of cos over a linear inclination)."""
    sim = _sim("pump.fluid_level_m=700", "pump.casing_pressure_pa=3.0e5")
    rate = math.radians(20.0) / (992.0 - 336.0)
    dtvd = math.sin(rate * (992.0 - 700.0)) / rate
    hand = 3.0e5 + RHO * GRAVITY_M_S2 * dtvd  # 2.71 MPa
    assert sim.cfg.pump.intake_pressure_pa == pytest.approx(hand, rel=1e-5)
    # the loads follow: the same well given that intake pressure directly runs the same card
    direct = _sim(f"pump.intake_pressure_pa={sim.cfg.pump.intake_pressure_pa!r}")
    a, b = sim.run_strokes(2)[-1].trace, direct.run_strokes(2)[-1].trace
    assert np.array_equal(a["polished_rod_load_n"], b["polished_rod_load_n"])
    # a deeper pump under the same level: its intake is higher by the column, its valve law the same as the
    # pump at the rod end (the column is added to the intake and taken off again, to round-off)
    deep = _sim("pump.fluid_level_m=700", "pump.casing_pressure_pa=3.0e5", "pump.depth_m=1042")
    assert deep.law.up_eq_n == pytest.approx(sim.law.up_eq_n, rel=1e-12)


def test_a_config_with_a_fluid_level_round_trips_and_refuses_an_intake_pressure_too() -> None:
    cfg = load_config("default", ["inflow.model=none", "pump.fluid_level_m=700", "pump.casing_pressure_pa=3e5"])
    assert "intake_pressure_pa" not in to_dict(cfg)["pump"]  # it follows from the level
    assert load_config(cfg, {"pump.fluid_level_m": 650.0}).pump.fluid_level_m == 650.0
    with pytest.raises(ConfigError, match=r"pump\.intake_pressure_pa.*absent when pump\.fluid_level_m"):
        load_config(cfg, {"pump.intake_pressure_pa": 1.0e6})


@pytest.mark.parametrize(("sets", "needles"), [
    (["pump.fluid_level_m=700", "pump.casing_pressure_pa=3e5", "pump.intake_pressure_pa=1e6"],
     ["pump.intake_pressure_pa", "absent when pump.fluid_level_m is given"]),
    (["pump.fluid_level_m=700"], ["pump.fluid_level_m", "given together with pump.casing_pressure_pa"]),
    (["pump.casing_pressure_pa=3e5"], ["pump.casing_pressure_pa", "given together with pump.fluid_level_m"]),
    (["pump.fluid_level_m=1000", "pump.casing_pressure_pa=3e5"], ["pump.fluid_level_m", "above the pump (992 m)"]),
    (["pump.depth_m=900"], ["pump.depth_m", "at or below the rod string's end (992 m"]),
    (["pump.depth_m=-5"], ["pump.depth_m", "-5"]),
    (["pump.fluid_level_m=abc"], ["pump.fluid_level_m", "'abc'"]),
    (["inflow.model=vogel", "pump.depth_m=1000"], ["pump.depth_m", "null with an inflow model"]),
    (["pump.load_source=loads", "pump.depth_m=1000"], ["pump.depth_m", "null when pump.load_source is 'loads'"]),
], ids=["level-and-intake", "level-alone", "casing-alone", "level-below-pump", "depth-above-rods",
        "negative-depth", "level-not-a-number", "depth-with-inflow", "depth-with-loads"])
def test_bad_predictive_inputs_are_one_line_exit_2(sets: list[str], needles: list[str], tmp_path: Path,
                                                   capsys: pytest.CaptureFixture,
                                                   monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(tmp_path)
    if not sets[0].startswith("inflow"):
        sets = ["inflow.model=none", *sets]
    argv = ["simulate", "default", "--strokes", "1", "--out", "o.csv"]
    for s in sets:
        argv += ["--set", s]
    one_line(*run_srenv(argv, capsys), *needles)
    nothing_left(tmp_path, set())


def test_simulate_and_diagnose_honour_the_pump_depth(tmp_path: Path, capsys: pytest.CaptureFixture,
                                                     monkeypatch: pytest.MonkeyPatch) -> None:
    """From the CLI: a deeper pump raises the simulated pump card's upstroke load by the column's load (the
    rods carry it; the downstroke stays), and diagnose reports the intake pressure at the pump (the discharge pressure there is higher by the
    column)."""
    monkeypatch.chdir(tmp_path)
    base = ["simulate", "default", "--strokes", "2", "--set", "inflow.model=none", "--set",
            "pump.intake_pressure_pa=2e6"]
    assert run_srenv([*base, "--out", "a.csv"], capsys)[0] == 0
    assert run_srenv([*base, "--set", "pump.depth_m=1042", "--out", "b.csv"], capsys)[0] == 0
    capsys.readouterr()
    a = np.genfromtxt("a.csv", delimiter=",", names=True)
    b = np.genfromtxt("b.csv", delimiter=",", names=True)
    cfg = load_config("default", [*BASE, "pump.depth_m=1042"])
    column_load = RHO * GRAVITY_M_S2 * 50.0 * plunger_area_m2(cfg.pump)  # 647 N
    up = [analyse_pump_card(c["pump_position_m"], c["pump_load_n"]) for c in (a, b)]
    assert up[1]["upstroke_load_n"] - up[0]["upstroke_load_n"] == pytest.approx(column_load, rel=0.01)
    assert up[1]["downstroke_load_n"] == pytest.approx(up[0]["downstroke_load_n"], abs=0.01 * column_load)
    card = diagnose_card(cfg, a["t_s"], a["polished_rod_position_m"], a["polished_rod_load_n"])
    at_rod_end = summary(load_config("default", BASE), card)
    deeper = summary(cfg, card)
    assert deeper["discharge_pressure_pa"] - at_rod_end["discharge_pressure_pa"] == pytest.approx(
        RHO * GRAVITY_M_S2 * 50.0, rel=1e-9)
    assert deeper["intake_pressure_pa"] - at_rod_end["intake_pressure_pa"] == pytest.approx(
        RHO * GRAVITY_M_S2 * 50.0, rel=1e-9)
    # and through the CLI
    np.savetxt("card.csv", np.c_[a["t_s"], a["polished_rod_position_m"], a["polished_rod_load_n"]],
               delimiter=",", header="t_s,polished_rod_position_m,polished_rod_load_n", comments="")
    rc = main(["diagnose", "card.csv", "--config", "default", "--set", "inflow.model=none", "--set",
               "pump.intake_pressure_pa=2e6", "--set", "pump.depth_m=1042", "--out", "p.csv"])
    assert rc == 0
    out = json.loads(capsys.readouterr().out)
    assert out["intake_pressure_pa"] == pytest.approx(deeper["intake_pressure_pa"], rel=1e-9)


def test_a_run_reports_the_intake_pressure_at_the_pump() -> None:
    """The laws see the intake referred to the rod end; a run reports the one at the pump (given or from the
    level)."""
    deep = _sim(BASE[1], "pump.depth_m=1042")
    assert deep.run_stroke().intake_pressure_pa == 2.0e6
    level = _sim("pump.fluid_level_m=700", "pump.casing_pressure_pa=3.0e5")
    assert level.run_stroke().intake_pressure_pa == level.cfg.pump.intake_pressure_pa > 2.7e6


def test_simulate_takes_the_fluid_level_from_the_command_line(tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
                                                              capsys: pytest.CaptureFixture) -> None:
    """srenv simulate with a level shot runs the card of the intake pressure it implies, and reports it."""
    monkeypatch.chdir(tmp_path)
    base = ["simulate", "default", "--strokes", "1", "--set", "inflow.model=none"]
    assert main([*base, "--set", "pump.fluid_level_m=700", "--set", "pump.casing_pressure_pa=3e5",
                 "--out", "a.csv"]) == 0
    reported = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
    p_in = _sim("pump.fluid_level_m=700", "pump.casing_pressure_pa=3.0e5").cfg.pump.intake_pressure_pa
    assert main([*base, "--set", f"pump.intake_pressure_pa={p_in!r}", "--out", "b.csv"]) == 0
    a = np.genfromtxt("a.csv", delimiter=",", names=True)
    b = np.genfromtxt("b.csv", delimiter=",", names=True)
    assert np.array_equal(a["polished_rod_load_n"], b["polished_rod_load_n"])
    assert reported["intake_pressure_pa"] == pytest.approx(p_in, rel=1e-12)
