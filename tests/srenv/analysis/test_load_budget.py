"""The static load budget (srenv/analysis/load_budget.py) and the record's TVD column (validate --survey-weight;
docs/realism.md, "The static load budget")."""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import numpy as np
import pytest
from conftest import assert_cli_refuses

from srenv.analysis.field_model import pump_tvd_m, survey_stations
from srenv.analysis.field_record import read_dynacard_json
from srenv.analysis.load_budget import card_plateaus, static_budget
from srenv.errors import ConfigError
from srenv.simulation.simulator import Simulator

RECORD = Path(__file__).resolve().parents[2] / "data" / "field" / "7699227.json"


@pytest.mark.parametrize("name", ["paper_fig3_vertical", "paper_fig4_deviated"])
def test_static_budget_bookkeepings_agree_with_the_simulator(name, with_couplings):
    """True loads (air weight along the survey, couplings' buoyancy, pressure on each taper step and the rod
    end, the pump's load) and effective loads (buoyed weight, wellhead pressure on the top area, the pump's
    effective load) give the same polished-rod load, and it is the simulator's static string (which is solved
    without friction: the budget's friction term is added back)."""
    sim = Simulator(with_couplings(name))
    b = static_budget(sim)
    for stroke in ("upstroke", "downstroke"):
        assert b[stroke]["true_bookkeeping_n"] == pytest.approx(b[stroke]["effective_bookkeeping_n"], rel=1e-6)
    down = b["downstroke"]
    assert down["effective_bookkeeping_n"] - down["rod_tubing_friction_n"] == pytest.approx(
        sim.uav[3] - sim.p_top_pa * sim.area_top_m2, rel=1e-6)
    assert b["wellhead_pressure_force_n"] == pytest.approx(-5e5 * sim.area_top_m2)
    if name == "paper_fig4_deviated":  # friction adds on the upstroke, takes off on the downstroke
        assert b["upstroke"]["rod_tubing_friction_n"] > 0 > down["rod_tubing_friction_n"]
    else:
        assert down["rod_tubing_friction_n"] == 0.0


def test_card_plateaus_read_a_rectangle_card():
    t = np.linspace(0.0, 1.0, 400, endpoint=False)
    x = 0.5 * (1 - np.cos(2 * np.pi * t))
    f = np.where(t < 0.5, 10.0, 2.0)  # the upstroke (rising) carries 10, the downstroke 2
    p = card_plateaus(x, f)
    assert p == {"upstroke_n": 10.0, "downstroke_n": 2.0}


def test_survey_weight_tvd_follows_the_records_tvd_column():
    """7699227's TVD column equals its MD at every station (inclination up to 40 deg): read as ``tvd`` the
    string is vertical; a TVD column consistent with the inclinations gives the inclinations' string back."""
    rec = read_dynacard_json(RECORD, auto_orient=True)
    assert max(s["inclination_deg"] for s in rec.survey) > 39.0
    assert all(s["tvd_m"] == pytest.approx(s["md_m"]) for s in rec.survey)
    assert all(s["inclination_deg"] == 0.0 for s in survey_stations(rec, "tvd"))
    assert pump_tvd_m(rec, "tvd") == pytest.approx(rec.pump_depth_m, rel=1e-6)
    assert pump_tvd_m(rec, "inclination") < 0.95 * rec.pump_depth_m
    # a TVD column computed from the inclinations (trapezoid on cos) reads back the same string
    md = np.array([s["md_m"] for s in rec.survey])
    inc = np.radians([s["inclination_deg"] for s in rec.survey])
    tvd = np.r_[0.0, np.cumsum(np.diff(md) * np.cos(0.5 * (inc[1:] + inc[:-1])))]
    consistent = dataclasses.replace(rec, survey=[{**s, "tvd_m": float(z)} for s, z in zip(rec.survey, tvd)])
    assert pump_tvd_m(consistent, "tvd") == pytest.approx(pump_tvd_m(rec, "inclination"), rel=2e-3)


def test_survey_weight_tvd_refuses_a_record_without_a_tvd_column():
    rec = read_dynacard_json(RECORD, auto_orient=True)
    rows = [dict(s) for s in rec.survey]
    rows[3]["tvd_m"] = None
    with pytest.raises(ConfigError, match=r"surveyData\[3\]\.TVD"):
        survey_stations(dataclasses.replace(rec, survey=rows), "tvd")
    with pytest.raises(ConfigError, match="survey-weight"):
        survey_stations(rec, "md")


def test_validate_refuses_tvd_without_a_tvd_column_in_one_line(tmp_path):
    """`srenv validate R.json --survey-weight tvd` on a record whose survey lacks a TVD: one line, exit 2."""
    d = json.loads(RECORD.read_text())
    del d["surveyData"][5]["TVD"]
    rec = tmp_path / "no_tvd.json"
    rec.write_text(json.dumps(d))
    assert_cli_refuses(["validate", str(rec), "--survey-weight", "tvd", "--plot", str(tmp_path / "p.png")],
                       tmp_path / "p.png", "surveyData[5].TVD", "--survey-weight tvd")


def test_validate_refuses_tvd_for_a_csv_record(tmp_path):
    """srenv's own record (card CSV + YAML) has no TVD column: --survey-weight tvd is refused in one line."""
    card = tmp_path / "c.csv"
    t = np.linspace(0.0, 10.0, 64, endpoint=False)
    x = 0.75 * (1 - np.cos(2 * np.pi * t / 10.0))
    np.savetxt(card, np.c_[t, x, 2e4 + 5e3 * np.sin(2 * np.pi * t / 10.0)], delimiter=",", comments="",
               header="t_s,polished_rod_position_m,polished_rod_load_n")
    assert_cli_refuses(["validate", str(card), "--config", "paper_fig3_vertical", "--survey-weight", "tvd",
                        "--plot", str(tmp_path / "p.png")], tmp_path / "p.png", "--survey-weight", "CSV record")
