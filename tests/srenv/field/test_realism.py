"""True to real wells (issue 27): field units, the card checks, the field-record reader and `srenv validate`
on the two public records in tests/data/field/ (source: vamseeachanta/digitalmodel, MIT; see its README)."""

from __future__ import annotations

import json
import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from srenv import field_units as fu
from srenv.analysis.field_model import _qp_solver
from srenv.analysis.field_record import read_dynacard_json
from srenv.errors import ConfigError
from srenv.surface_unit.card_checks import check_card, loop_work

# tests/data/field/, wherever under tests/ this file sits
DATA = next(p for p in Path(__file__).resolve().parents if p.name == "tests") / "data" / "field"
WELLS = ("11708328", "7699227")


def run_cli(*args: str, cwd: Path | None = None) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "srenv.tools.cli", *args], capture_output=True, text=True,
                          cwd=cwd, check=False)


# ------------------------------------------------------------------------------------------ field units
def test_field_units_exact_factors_and_round_trip():
    assert fu.to_si(1.0, "in") == pytest.approx(0.0254, rel=1e-15)
    assert fu.to_si(1.0, "ft") == pytest.approx(0.3048, rel=1e-15)
    assert fu.to_si(1.0, "lbf") == pytest.approx(4.4482216152605, rel=1e-15)
    assert fu.to_si(1.0, "psi") == pytest.approx(6894.757293168, rel=1e-12)
    assert fu.to_si(1.0, "lb/ft") == pytest.approx(1.48816394, rel=1e-8)
    assert fu.to_si(1.0, "bbl/d") == pytest.approx(0.158987294928, rel=1e-12)
    x = np.array([1.5, 54.0, 120.12])
    assert np.allclose(fu.from_si(fu.to_si(x, "in"), "in"), x, rtol=1e-15)
    # API 10 oil is as dense as water; 141.5/131.5 at API 0
    assert fu.oil_specific_gravity(10.0) == pytest.approx(1.0)
    assert fu.liquid_density_kg_m3(1.0, 1.05, 40.0) == pytest.approx(1.05 * fu.WATER_DENSITY_KG_M3)


def test_field_units_refuse_unknown_and_wrong_dimension():
    with pytest.raises(ConfigError, match="furlong"):
        fu.to_si(1.0, "furlong", "units.length")
    with pytest.raises(ConfigError, match="a unit of m"):
        fu.same_dimension("psi", "m", "position")


# ------------------------------------------------------------------------------------------ card checks
def _card(n: int = 200, reverse: bool = False) -> tuple[np.ndarray, np.ndarray]:
    ph = 2 * math.pi * np.arange(n) / n
    x = 0.75 * (1 - np.cos(ph))               # bottom at ph = 0, top at ph = pi
    f = 30e3 + 8e3 * (np.sin(ph) > 0) + 1e3 * np.sin(ph)   # upstroke (x rising) carries the fluid load
    return (x[::-1].copy(), f[::-1].copy()) if reverse else (x, f)


def test_card_checks_time_direction_and_reverse():
    x, f = _card()
    assert loop_work(x, f) > 0
    check_card(x, f, "card", "fwd")
    xr, fr = _card(reverse=True)
    with pytest.raises(ConfigError, match="reverse time"):
        check_card(xr, fr, "card", "rev")
    x2, f2 = check_card(xr, fr, "card", "rev", reverse=True)
    assert np.allclose(x2, x[::-1][::-1]) or loop_work(x2, f2) > 0
    with pytest.raises(ConfigError, match="drop --reverse"):
        check_card(x, f, "card", "fwd", reverse=True)


@pytest.mark.parametrize("case, match", [
    ("few", "at least 16 samples"), ("nan", "finite load"), ("flat", "zero stroke"),
    ("open", "closed stroke"), ("inches", "at most 20 m"), ("lbf", "loads within"),
])
def test_card_checks_refuse_by_class(case, match):
    x, f = _card()
    if case == "few":
        x, f = x[:10], f[:10]
    elif case == "nan":
        f[5] = np.nan
    elif case == "flat":
        x = np.zeros_like(x)
    elif case == "open":
        x, f = x[:150], f[:150]   # stops three quarters of the way down
    elif case == "inches":
        x = x / 0.0254 * 10
    elif case == "lbf":
        f = f * 1e3
    with pytest.raises(ConfigError, match=match):
        check_card(x, f, "card", case)


def _write_card_csv(path: Path, x: np.ndarray, f: np.ndarray, units: str | None = None) -> None:
    t = np.arange(len(x)) * 0.05
    rows = ["t_s,polished_rod_position_m,polished_rod_load_n"] + ([units] if units else [])
    rows += [f"{a:.6f},{b:.6f},{c:.3f}" for a, b, c in zip(t, x, f)]
    path.write_text("\n".join(rows) + "\n")


@pytest.mark.parametrize("case, match", [
    ("reversed", "reverse time"), ("open", "closed stroke"), ("bad_unit_row", "unit row"),
    ("wrong_dimension", "a unit of m"),
])
def test_diagnose_refuses_bad_cards_exit_2_one_line_nothing_written(tmp_path, case, match):
    x, f = _card()
    units = None
    if case == "reversed":
        x, f = _card(reverse=True)
    elif case == "open":
        x, f = x[:150], f[:150]
    elif case == "bad_unit_row":
        units = "s,in,furlong"
    elif case == "wrong_dimension":
        units = "s,psi,lbf"
    card = tmp_path / "card.csv"
    _write_card_csv(card, x, f, units)
    out = tmp_path / "pump.csv"
    p = run_cli("diagnose", str(card), "--config", "paper_fig3_vertical", "--out", str(out),
                "--set", f"simulation.qp_solver={_qp_solver()}")
    assert p.returncode == 2, p.stderr
    lines = [ln for ln in p.stderr.splitlines() if ln.strip()]
    assert len(lines) == 1 and match in lines[0] and "Traceback" not in p.stderr, p.stderr
    assert not out.exists() and sorted(q.name for q in tmp_path.iterdir()) == ["card.csv"]


def test_unit_row_converts_field_units(tmp_path):
    from srenv.surface_unit.measured_motion import read_card_csv

    x, f = _card()
    card = tmp_path / "card.csv"
    _write_card_csv(card, x / 0.0254, f / 4.4482216152605, "s,in,lbf")
    cols = read_card_csv(card, "CARD.csv", ("t_s", "polished_rod_position_m", "polished_rod_load_n"))
    assert np.allclose(cols["polished_rod_position_m"], x, atol=1e-6)
    assert np.allclose(cols["polished_rod_load_n"], f, rtol=1e-6, atol=0.01)


# ------------------------------------------------------------------------------------------ the records
def test_record_reader_reads_the_description_in_si():
    rec = read_dynacard_json(DATA / "11708328.json")
    assert not rec.time_reversed and len(rec.load_n) == 187
    assert rec.rod_length_m == pytest.approx((1400 + 3350) * 0.3048)
    assert rec.pump_depth_m == pytest.approx(4844 * 0.3048)
    assert rec.tapers[0]["weight_kg_m"] == pytest.approx(2.224 * 1.48816394, rel=1e-6)
    assert rec.tubing_pressure_pa == pytest.approx(100 * 6894.757, rel=1e-6)
    # 96 % water of SG 1.02 and 4 % oil of 33.9 API
    assert rec.fluid_density_kg_m3 == pytest.approx((0.96 * 1.02 + 0.04 * 141.5 / 165.4) * 999.0, rel=1e-9)
    assert rec.intake_pressure_pa is None and rec.pump_load_n is not None
    assert rec.unit["A"] == pytest.approx(96 * 0.0254) and rec.unit["R"] == pytest.approx(27 * 0.0254)


def test_record_stored_in_reverse_time_is_refused_or_oriented():
    with pytest.raises(ConfigError, match="reverse time"):
        read_dynacard_json(DATA / "7699227.json")
    rec = read_dynacard_json(DATA / "7699227.json", reverse=True)
    auto = read_dynacard_json(DATA / "7699227.json", auto_orient=True)
    assert auto.time_reversed and np.array_equal(rec.load_n, auto.load_n)
    assert loop_work(rec.position_m, rec.load_n) > 0
    assert rec.intake_pressure_pa == pytest.approx(239 * 6894.757, rel=1e-6) and rec.fillage == pytest.approx(0.954)


def test_validate_refuses_bad_records_exit_2(tmp_path):
    d = json.loads((DATA / "11708328.json").read_text())
    d["cardData"]["Position"] = d["cardData"]["Position"][:120]
    d["cardData"]["Load"] = d["cardData"]["Load"][:120]
    bad = tmp_path / "open.json"
    bad.write_text(json.dumps(d))
    plot = tmp_path / "p.png"
    p = run_cli("validate", str(bad), "--plot", str(plot))
    lines = [ln for ln in p.stderr.splitlines() if ln.strip()]
    assert p.returncode == 2 and len(lines) == 1 and "closed stroke" in lines[0], p.stderr
    assert not plot.exists()
    d = json.loads((DATA / "11708328.json").read_text())
    d["equipmentData"]["Rods"][0]["Diameter"] = "seven-eighths"
    bad.write_text(json.dumps(d))
    p = run_cli("validate", str(bad))
    assert p.returncode == 2 and "equipmentData.Rods[0].Diameter" in p.stderr and "in in" in p.stderr, p.stderr
    p = run_cli("validate", str(DATA / "11708328.json"), "--reverse")
    assert p.returncode == 2 and "drop --reverse" in p.stderr, p.stderr


# ------------------------------------------------------------------------------------------ validate figures
@pytest.fixture(scope="module")
def figures() -> dict:
    from srenv.tools.validate import validate

    out = {}
    for w in WELLS:
        rec = read_dynacard_json(DATA / f"{w}.json", auto_orient=True)
        out[w] = validate(rec, [], 4, "effective")[0]
    return out


@pytest.mark.parametrize("well", WELLS)
def test_validate_prints_the_contract_keys(figures, well):
    d = figures[well]
    for k in ("pprl_error_pct", "mprl_error_pct", "card_rms_pct_of_pprl", "pump_card_rms_pct_of_range"):
        assert isinstance(d[k], float) and math.isfinite(d[k]), k
    assert d["pump_state"]["source"] == ("record" if well == "7699227" else "srenv diagnose")


@pytest.mark.parametrize("well", WELLS)
def test_validate_figures_held_today(figures, well):
    """What the realistic model reaches today without fitting (docs/realism.md): PPRL within 5 % (7699227) and
    10 % (11708328, whose pump state is now read off its diagnosis by the load lines: -9.6 %), MPRL within
    9.5 % (11708328) and 13.5 %, the card within 9 % of PPRL, the load spectrum above the 20th harmonic within
    3x the measured share (38-39x with the previous damping). Since the couplings' buoyancy (docs/realism.md,
    "The static load budget") the strings weigh 0.36-0.39 kN less: 11708328 PPRL -8.9 -> -9.6 %, MPRL -7.9 ->
    -9.1 %, card 5.19 -> 5.58 %, pump card 2.5 -> 4.2 % (a loss: the vendor's card sits lower still)."""
    d = figures[well]
    assert abs(d["pprl_error_pct"]) <= (10.0 if well == "11708328" else 5.0)
    assert abs(d["mprl_error_pct"]) <= (9.5 if well == "11708328" else 13.5)
    assert d["card_rms_pct_of_pprl"] <= 9.0
    assert d["spectrum"]["ratio_above_h20"] <= 3.0
    if well == "11708328":  # srenv's diagnosis against the vendor's pump card, in its effective convention
        assert d["pump_card_rms_pct_of_range"] <= 4.5
        # its position channel is a synthesised cosine: driven by its own unit's four-bar, the card meets the
        # goal (7.1 -> 5.75 % of PPRL) while MPRL (-11.6 -> -13.0 %) and harmonics 4-20 (2.2x -> 3.1x) move off;
        # the record's 20 hp NEMA D motor then lets the crank slow under the torque: 5.68 %, -12.7 %, 2.92x;
        # the pump state read off the diagnosis by the load lines (4.13 MPa, fillage 0.63 instead of 284 kPa,
        # 0.815): PPRL +1.1 -> -8.9 %, MPRL -12.7 -> -7.9 %, card 5.68 -> 5.19 %, harmonics 2.92 -> 3.15x
        assert d["position_synthesised"] and d["motion_source"] == "record unit"
        assert d["card_rms_pct_of_pprl"] <= 5.7 and d["spectrum"]["ratio_h4_20"] <= 3.3
        assert d["pump_state"]["intake_pressure_pa"] > 3e6 and d["pump_state"]["plunger_friction_n"] < 1.0
        assert d["motor"]["used"] and d["motor"]["nema_design"] == "D" and d["motor"]["converged"]
        # its pump state is read off the same card: the energy balance would hold for any damping, so the
        # default keeps the fixed nu = 0.02 and says why (analysis/damping_balance.py)
        assert not d["damping_rule"]["applied"] and "degenerate" in d["damping_rule"]["reason"]
        assert d["model"]["damping_factor"] == 0.02
    else:
        assert not d["position_synthesised"] and d["motion_source"] == "card"
        assert not d["motor"]["used"]  # a measured position already carries the motor's slip
        assert d["spectrum"]["ratio_h4_20"] <= 1.3
        # 7699227's diagnosed pump card against the vendor's: with the fixed nu = 0.02 shifted (+1.2 kN) and
        # 1.2 kN short (upstroke +1.24, downstroke +2.48 kN); the energy balance (the default since d27: the
        # record's fluid load and fillage leave the string 1.1 kJ of the 50.8 kJ polished-rod work to dissipate)
        # finds nu = 0.0008, and the card's height comes within 0.3 kN of the vendor's (+1.73 / +2.02 kN): what
        # is left is a level, the deviated string's weight (the vendor's diagnosis follows the record's vertical
        # TVD column; docs/realism.md). PPRL +2.4 -> +1.8 %, MPRL +5.9 -> +7.4 %, card 8.13 -> 8.15 %, pump card
        # 10.0 -> 9.6 %, harmonics 4-20 0.63 -> 0.70x
        rule = d["damping_rule"]
        assert rule["applied"] and rule["bracketed"] and rule["damping_factor"] < 0.005
        assert d["model"]["damping_factor"] == rule["damping_factor"]
        off = d["pump_card_offset_n"]
        assert abs(off["downstroke"] - off["upstroke"]) < 500.0 and 1500.0 < off["upstroke"] < 2200.0
        assert d["pump_card_rms_pct_of_range"] <= 9.8


@pytest.mark.xfail(strict=True, reason="issue 27's goal, not reached yet: 11708328's PPRL 9.6 % and MPRL 9.1 % "
                   "low, its harmonics 4-20 3.2x the measured share, its pump card 4.2 %; 7699227's MPRL 7.4 % "
                   "high, its card 8.2 % of PPRL RMS (a constant 2.9 kN) and its diagnosed pump card 9.6 % of "
                   "range (docs/realism.md)")
@pytest.mark.parametrize("well", WELLS)
def test_validate_meets_the_issue_goal(figures, well):
    d = figures[well]
    assert abs(d["pprl_error_pct"]) <= 5 and abs(d["mprl_error_pct"]) <= 5
    assert d["card_rms_pct_of_pprl"] <= 6 and d["pump_card_rms_pct_of_range"] <= 3
    assert d["spectrum"]["ratio_h4_20"] <= 1.3


def test_record_unit_kinematics_follow_the_measured_motion():
    """The exact conventional four-bar (beam_unit.py) built from 7699227's inline API dimensions (A 136, C 118,
    I 125.63, K 188.25, P 142.63, R 50 in, rotation 'C. Clockwise') at constant crank speed reproduces the
    measured polished-rod position: stroke within 0.2 %, RMS within 1 % of the stroke; the mirror rotation
    does not (its upstroke takes the other share of the turn)."""
    from srenv.analysis.field_model import unit_from_record, unit_kinematics_check

    rec = read_dynacard_json(DATA / "7699227.json", auto_orient=True)
    k = unit_kinematics_check(rec)
    assert k["unit_rotation"] == "counterclockwise"
    assert abs(k["unit_stroke_error_pct"]) <= 0.2 and k["unit_position_rms_pct_of_stroke"] <= 1.0
    import dataclasses

    cu = unit_from_record(rec)
    mirrored = dataclasses.replace(rec, unit={**rec.unit, "rotation": "Clockwise"})
    assert unit_from_record(mirrored).upstroke_fraction() == pytest.approx(1 - cu.upstroke_fraction(), abs=1e-9)
    assert unit_kinematics_check(mirrored)["unit_position_rms_pct_of_stroke"] > 1.5


def test_kelvin_voigt_damping_closes_the_energy_balance_and_damps_high_modes():
    """damping.stiffness_proportional_s (tau): element force EA/L (du + tau dv). Its work is booked, so the
    energy balance still closes; it damps mode k by zeta_k = tau w_k / 2, so the share of the polished-rod
    load's energy above the 20th harmonic falls, while the fundamental's response (the load levels) hardly
    moves."""
    from srenv.analysis.card_compare import harmonic_shares, resample_stroke
    from srenv.config import load_config
    from srenv.simulation.simulator import Simulator

    out = {}
    for tau in (0.0, 0.03):
        cfg = load_config("paper_fig3_vertical", [f"damping.stiffness_proportional_s={tau}",
                                                  f"simulation.qp_solver={_qp_solver()}"])
        sim = Simulator(cfg)
        r = sim.run_strokes(3)[-1]
        f = resample_stroke(r.trace["t_s"], r.trace["polished_rod_load_n"], r.duration_s, 400)
        work = float(np.trapezoid(r.trace["polished_rod_load_n"], r.trace["polished_rod_position_m"]))
        out[tau] = (harmonic_shares(f)[1], sim.energy_balance()["residual_j"], f.max(), abs(work))
    (s0, e0, p0, _), (s1, e1, p1, w1) = out[0.0], out[0.03]
    assert s1 < 0.5 * s0
    assert abs(e1) <= 1e-7 * w1 and abs(e0) <= 1e-7 * w1
    assert p1 == pytest.approx(p0, rel=0.06)


def test_per_taper_damping_scale():
    """rod.tapers[i].damping_scale multiplies that taper's viscous damping per length; 1 leaves it as it was."""
    from srenv.config import apply_overrides, config_from_dict, read_raw
    from srenv.physics.rod import build_mesh, damping_per_length

    raw = apply_overrides(read_raw("paper_fig3_vertical"), [f"simulation.qp_solver={_qp_solver()}"])
    base = config_from_dict(raw)
    raw["rod"]["tapers"][0]["damping_scale"] = 2.0
    scaled = config_from_dict(raw)
    m0, m1 = build_mesh(base.rod, 25.0), build_mesh(scaled.rod, 25.0)
    c0, c1 = damping_per_length(m0, base.damping), damping_per_length(m1, scaled.damping)
    first = m0.taper == 0
    assert np.allclose(c1[first], 2 * c0[first]) and np.array_equal(c1[~first], c0[~first])
    assert m0.damping_scale is None


@pytest.mark.parametrize("edit, match", [
    (lambda d: d.__setitem__("equipmentData", [1, 2]), "equipmentData"),
    (lambda d: d["equipmentData"]["Pump"].__setitem__("Depth", True), "equipmentData.Pump.Depth"),
    (lambda d: d["equipmentData"]["Pump"].__setitem__("Depth", 1e9), "within"),
    (lambda d: d["InputParameters"].__setitem__("StrokesPerMinute", float("nan")), "StrokesPerMinute"),
    (lambda d: d.__setitem__("dynaoutputData", "x") or d["equipmentData"].pop("DampingCoefficient", None),
     "dynaoutputData"),
    (lambda d: d["cardData"].__setitem__("Load", d["cardData"]["Load"][:-3]), "one load per position"),
    (lambda d: d["cardData"].__setitem__("Position", [p * 100 for p in d["cardData"]["Position"]]), "at most 20 m"),
])
def test_record_defects_are_one_config_error(tmp_path, edit, match):
    d = json.loads((DATA / "11708328.json").read_text())
    edit(d)
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps(d))
    with pytest.raises(ConfigError, match=match):
        read_dynacard_json(bad)


def test_pump_fillage_is_a_predictive_input():
    """pump.fillage < 1: the gas fraction whose compression takes (1 - fillage) of the stroke; the simulated
    pump card's fillage (read off the card as the diagnosis reads it) comes back within a few points."""
    from srenv.analysis.stroke_summary import summarize
    from srenv.config import load_config
    from srenv.simulation.simulator import Simulator

    for target in (0.6, 0.85):
        cfg = load_config("default", ["inflow.model=none", f"pump.fillage={target}",
                                      f"simulation.qp_solver={_qp_solver()}"])
        sim = Simulator(cfg)
        s = summarize(sim, sim.run_strokes(3))
        assert s["fillage"] == pytest.approx(target, abs=0.06), s["fillage"]
    with pytest.raises(ConfigError, match="pump.fillage"):
        load_config("default", ["inflow.model=none", "pump.fillage=0.7", "pump.intake_gas_fraction=0.1"])
    with pytest.raises(ConfigError, match="pump.fillage"):
        load_config("default", ["pump.fillage=0.7"])  # the default well's inflow model sets its fill
    with pytest.raises(ConfigError, match="tubing.anchored"):
        load_config("default", ["inflow.model=none", "pump.fillage=0.7", "tubing.anchored=false"])


def test_validate_reproduces_srenv_own_card(tmp_path):
    """srenv's own record (card CSV + the well YAML it came from): the model driven by the card's measured
    motion reproduces the card (the pipeline adds no error of its own: resampling, period, alignment)."""
    import yaml

    from srenv.config import apply_overrides, read_raw

    raw = apply_overrides(read_raw("default"), [f"simulation.qp_solver={_qp_solver()}"])
    well = tmp_path / "well.yaml"
    well.write_text(yaml.safe_dump(raw, sort_keys=False))
    card = tmp_path / "card.csv"
    p = run_cli("simulate", str(well), "--strokes", "3", "--out", str(card))
    assert p.returncode == 0, p.stderr
    p = run_cli("validate", str(card), "--config", str(well))
    assert p.returncode == 0, p.stderr
    d = json.loads(p.stdout.strip().splitlines()[-1])
    assert abs(d["pprl_error_pct"]) < 0.1 and abs(d["mprl_error_pct"]) < 0.1 and d["card_rms_pct_of_pprl"] < 0.1
    assert d["pump_card_rms_pct_of_range"] is None and d["pump_state"]["source"] == "config"


def test_fluid_column_inertia_closes_the_energy_balance_and_loads_the_upstroke():
    """pump.fluid_column_mass_kg: the liquid lifted with the rising plunger adds its inertia to the pump
    load (booked as the pump's work, so the energy balance still closes); PPRL rises, the downstroke (the
    column left behind) keeps its load."""
    from srenv.config import load_config
    from srenv.physics.pump import fluid_column_mass_kg
    from srenv.simulation.simulator import Simulator

    m = fluid_column_mass_kg(1000.0, 1500.0, math.pi / 4 * 0.04445 ** 2, math.pi / 4 * 0.062 ** 2,
                             math.pi / 4 * 0.01905 ** 2)
    assert m == pytest.approx(1000 * 1500 * (math.pi / 4 * 0.04445 ** 2) ** 2
                              / (math.pi / 4 * (0.062 ** 2 - 0.01905 ** 2)))
    out = {}
    for mass in (0.0, m):
        cfg = load_config("default", ["inflow.model=none", f"pump.fluid_column_mass_kg={mass}",
                                      f"simulation.qp_solver={_qp_solver()}"])
        sim = Simulator(cfg)
        r = sim.run_strokes(3)[-1]
        work = abs(float(np.trapezoid(r.trace["polished_rod_load_n"], r.trace["polished_rod_position_m"])))
        out[mass] = (r.trace["polished_rod_load_n"].max(), sim.energy_balance()["residual_j"], work,
                     r.trace["pump_load_n"].min())
    (p0, _, _, d0), (p1, e1, w1, d1) = out[0.0], out[m]
    assert p1 > p0 * 1.01
    assert abs(e1) <= 1e-7 * w1
    assert d1 == pytest.approx(d0, rel=0.1)


def test_record_without_rod_weights_takes_the_api_table_and_says_so(tmp_path):
    """A taper with no weight gets API RP 11L's figure for its size (the records' own 7/8-in and 3/4-in weights
    are exactly the table's) or a steel bar's; a rod string far from the pump depth is named in the notes."""
    from srenv.analysis.field_record import rod_weight_lb_ft

    d = json.loads((DATA / "11708328.json").read_text())
    given = read_dynacard_json(DATA / "11708328.json")
    for r in d["equipmentData"]["Rods"]:
        r["Weight"] = None
    d["equipmentData"]["Rods"] = d["equipmentData"]["Rods"][:1]
    path = tmp_path / "r.json"
    path.write_text(json.dumps(d))
    rec = read_dynacard_json(path)
    assert rec.tapers[0]["weight_kg_m"] == pytest.approx(given.tapers[0]["weight_kg_m"], rel=1e-12)
    assert any("API RP 11L" in n for n in rec.notes) and any("pump depth" in n for n in rec.notes)
    assert not given.notes
    w, how = rod_weight_lb_ft(1.5)  # a sinker bar: the steel body, 3.40 lb/ft per square inch
    assert w == pytest.approx(3.40 * math.pi / 4 * 1.5 ** 2) and "steel" in how


def test_vendor_prediction_is_read_checked_and_scored_like_srenv(tmp_path, figures):
    """The record's own wave-equation prediction (the vendor's "ideal card", stored in N and m) is read only when
    its stroke matches the measured one, and scored by the same PPRL/MPRL errors as srenv's prediction."""
    d = json.loads((DATA / "7699227.json").read_text())
    perf = d["Performance"]
    lbf = 4.4482216152605
    loads = np.asarray(d["cardData"]["Load"], float) * lbf
    v = figures["7699227"]["record_prediction"]
    assert v["pprl_error_pct"] == pytest.approx(100 * (perf["IdealCardSimulation_SurfaceCard_Load_max"]
                                                       / loads.max() - 1), rel=1e-9)
    assert v["mprl_error_pct"] == pytest.approx(100 * (perf["IdealCardSimulation_SurfaceCard_Load_min"]
                                                       / loads.min() - 1), rel=1e-9)
    assert figures["7699227"]["record_card_type"] == "Startup"
    # 11708328 stores no prediction (its vendor analysis failed): null, not a made-up figure
    assert figures["11708328"]["record_prediction"] is None and figures["11708328"]["record_card_type"] == "Shutdown"
    # a prediction in other units (a stroke of 120 "m") is left out with a note, never scored
    perf["IdealCardSimulation_SurfaceCard_Position_max"] = 120.0
    bad = tmp_path / "inches.json"
    bad.write_text(json.dumps(d))
    rec = read_dynacard_json(bad, auto_orient=True)
    assert rec.reference_prediction is None and any("IdealCardSimulation" in n for n in rec.notes)
    perf["IdealCardSimulation_SurfaceCard_Load_max"] = "n/a"
    bad.write_text(json.dumps(d))
    assert read_dynacard_json(bad, auto_orient=True).reference_prediction is None


@pytest.mark.parametrize("well", WELLS)
def test_card_difference_splits_into_level_and_shape(figures, well):
    """card RMS² = offset² + shape RMS² (the same difference, resampled on position); 7699227's prediction sits a
    constant 2.9 kN above its measured card (3.3 before the couplings' buoyancy; docs/realism.md "The static load
    budget": no term of the description explains it) and its shape is within 6 % of PPRL; 11708328's error is
    mostly its shape (4.5 %), over a level 1.8 kN low (1.4 before the couplings' buoyancy) since its pump state
    is read off the load lines (a fluid load too small for the top of its upstroke)."""
    d = figures[well]
    pprl = d["measured_pprl_n"]
    total = math.hypot(100 * d["card_offset_n"] / pprl, d["card_shape_rms_pct_of_pprl"])
    assert total == pytest.approx(d["card_rms_pct_of_pprl"], rel=1e-9)
    if well == "7699227":
        assert 2500 < d["card_offset_n"] < 4000 and d["card_shape_rms_pct_of_pprl"] < 6.0
    else:
        assert -2000 < d["card_offset_n"] < -1000 and d["card_shape_rms_pct_of_pprl"] < 5.0


def test_a_synthesised_position_channel_is_recognised_and_replaced_by_the_records_unit():
    """A load-only controller writes x = S (1 - cos wt)/2: such a card is recognised (any phase), a four-bar's
    motion (measured on 7699227, or computed) is not; the motion that replaces it is the record's unit at
    constant crank speed, bottom on the card's bottom sample, scaled to the card's stroke."""
    from srenv.analysis.field_model import position_is_synthesised, unit_from_record, unit_position_for_card

    n = 200
    for phase in (0.0, 0.7, 2.0):
        assert position_is_synthesised(0.7 * (1 - np.cos(2 * np.pi * np.arange(n) / n + phase)))
    real = read_dynacard_json(DATA / "7699227.json", auto_orient=True)
    assert not position_is_synthesised(real.position_m)
    cu = unit_from_record(real)
    assert not position_is_synthesised(np.asarray(cu.position_m(cu.theta_bottom + 2 * np.pi * np.arange(n) / n)))
    rec = read_dynacard_json(DATA / "11708328.json", auto_orient=True)
    assert position_is_synthesised(rec.position_m)
    x = unit_position_for_card(rec)
    k0 = int(np.argmin(rec.position_m))
    assert x[k0] == 0.0 and x.min() >= -1e-12 and np.ptp(x) == pytest.approx(np.ptp(rec.position_m), rel=2e-3)
    assert not position_is_synthesised(x)   # the four-bar's second harmonic is back


def test_validate_plot_shows_both_pump_cards_in_the_compared_convention():
    """The pump-card panel draws srenv's diagnosis in the convention the figures compare (it drew true loads
    beside the vendor's effective ones, a p A gap the figures do not have)."""
    from srenv.analysis.diagnose import load_in_convention
    from srenv.tools.validate import validate
    from srenv.tools.validate_plot import pump_card_lines

    rec = read_dynacard_json(DATA / "11708328.json", auto_orient=True)
    out, (card, _, pump_card) = validate(rec, [], 2, "effective")
    assert card.motion_from_unit and out["motion_source"] == "record unit"
    for conv in ("effective", "true"):
        ours, ref = pump_card_lines(card, pump_card, conv)
        want = load_in_convention(pump_card.pump_load_n, conv, pump_card.rod_end_pressure_pa,
                                  pump_card.rod_end_area_m2)
        assert np.array_equal(ours[1], want) and conv in ours[2]
        assert np.array_equal(ref[1], rec.pump_load_n)
    assert pump_card.rod_end_pressure_pa * pump_card.rod_end_area_m2 > 1000.0  # the gap was real: > 1 kN


def test_a_synthesised_position_without_a_unit_is_kept_and_named(tmp_path):
    from srenv.tools.validate import card_motion

    d = json.loads((DATA / "11708328.json").read_text())
    d["equipmentData"]["SurfaceUnit"]["PumpingUnitGeometry"] = "Z"   # a geometry srenv does not know
    p = tmp_path / "nounit.json"
    p.write_text(json.dumps(d))
    rec = read_dynacard_json(p, auto_orient=True)
    card = card_motion(rec)
    assert not card.motion_from_unit and np.array_equal(card.position_m, rec.position_m)
    assert any("no unit" in n for n in card.notes)
    real = read_dynacard_json(DATA / "7699227.json", auto_orient=True)
    assert card_motion(real) is real
