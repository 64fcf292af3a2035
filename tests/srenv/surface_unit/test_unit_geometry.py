"""A beam unit by its nameplate (``surface.beam_unit``): exact kinematics and torque factor of the three API
geometries against an independent reference, the wiring through ``srenv simulate`` and the field record, and
bad input by class.

SOURCES. No published numeric torque-factor table (API Spec 11E form, manufacturer catalogue) or worked
example with numbers was reachable from this project's search corpora (docs/surface_unit.md, "What the check
is"): the searched sources hold only their first pages. The tests therefore check each geometry against

* an independent reference written here from the four-bar's geometry alone: the equalizer E is the upper
  intersection of the circles |E - G| = C and |E - pin| = P (no law of cosines, no branch sign, no derivative
  of the loop), and the torque factor from STATICS (moment balance of the beam about the saddle bearing, the
  pitman as a two-force member, the torque on the crank), not as d(position)/dθ;
* the published qualitative facts that fix the conventions: a Mark II turning counterclockwise with the well
  to the right has the longer upstroke (F.P. Kretzer / "Pumping Unit Geometry", Training for Skills and
  Knowledge: "this shifting, accompanied by a specified direction of rotation of the cranks, results in a
  longer time interval for the upstroke"), and a Mark II needs a smaller gearbox than a conventional unit for
  the same well ("usually these special geometry units will require one size smaller gear box size", ibid.);
* the API Spec 11E torque-factor equations in their ψ form (Class I directly; Class III through the
  left-right mirror that turns it into a Class I linkage with the rod's direction reversed);
* for Class I, the measured polished-rod motion of the real well 7699227 (../shared/field, conventional,
  tests/srenv/field/test_realism.py): stroke within 0.2 %, position RMS within 1 % of the stroke.
"""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from declared_helpers import one_line, run_srenv
from scipy.optimize import minimize_scalar

from srenv.config import load_config
from srenv.config_sections import BeamUnitConfig
from srenv.errors import ConfigError
from srenv.surface_unit.inline_unit import inline_unit, record_geometry, record_unit_config
from srenv.surface_unit.unit_catalogue import get_unit

ROOT = Path(__file__).resolve().parents[3]
MARK_II = ROOT / "configs" / "wells" / "mark_ii_fig4.yaml"
CONV = ROOT / "configs" / "wells" / "conventional_fig4.yaml"
IN = 0.0254

# one unit of each geometry (SI). conventional: the catalogue's C-228D-213-86; mark_ii: the shipped example's
# nameplate (configs/wells/mark_ii_fig4.yaml); air_balanced: representative Class III proportions
_C228 = get_unit("C-228D-213-86")
UNITS: dict[str, dict[str, Any]] = {
    "conventional": {"a_m": _C228.a_m, "c_m": _C228.c_m, "i_m": _C228.i_m, "k_m": _C228.k_m, "p_m": _C228.p_m,
                     "r_m": _C228.crank_radii_m[0], "rotation": "clockwise", "torque_rating_nm": 25760.5},
    "mark_ii": {"a_m": 2.032, "c_m": 1.166, "i_m": 1.161, "k_m": 1.732, "p_m": 1.437, "r_m": 0.4526,
                "rotation": "counterclockwise", "torque_rating_nm": 18077.6},
    "air_balanced": {"a_m": 3.0, "c_m": 1.5, "i_m": 1.45, "k_m": 2.25, "p_m": 1.75, "r_m": 0.6,
                     "rotation": "clockwise", "torque_rating_nm": 36155.1},
}


def _block(kind: str) -> BeamUnitConfig:
    return BeamUnitConfig(geometry=kind, **UNITS[kind])


# ------------------------------------------------------------------------------ independent reference
def _reference(kind: str, theta: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(horsehead angle η, torque factor from statics) at crank angles θ (direction of rotation, from 12)."""
    u = UNITS[kind]
    lever = 1.0 if kind == "conventional" else -1.0
    g = np.array([lever * u["i_m"], math.sqrt(u["k_m"] ** 2 - u["i_m"] ** 2)])
    s = 1.0 if u["rotation"] == "clockwise" else -1.0
    eta, tf = [], []
    for th in np.atleast_1d(theta):
        pin = u["r_m"] * np.array([math.sin(s * th), math.cos(s * th)])
        d = np.linalg.norm(pin - g)
        # circle-circle intersection: foot along G->pin, then the two points off it; E is the upper one
        along = (u["c_m"] ** 2 - u["p_m"] ** 2 + d**2) / (2 * d)
        off = math.sqrt(u["c_m"] ** 2 - along**2)
        e_dir = (pin - g) / d
        cands = [g + along * e_dir + sgn * off * np.array([-e_dir[1], e_dir[0]]) for sgn in (1.0, -1.0)]
        e = max(cands, key=lambda p: p[1])
        head = lever * (g - e) / u["c_m"]  # the horsehead's direction from G: away from E on Class I
        eta.append(math.atan2(head[1], head[0]))
        # statics: rods W = 1 N hang tangent to the arc, moment A*W about G, carried by the pitman (along pin->E)
        along_p = (e - pin) / u["p_m"]
        arm_e = e - g
        f = u["a_m"] / (arm_e[0] * along_p[1] - arm_e[1] * along_p[0])
        torque_z = pin[0] * f * along_p[1] - pin[1] * f * along_p[0]
        tf.append(-s * torque_z)  # the gearbox's torque in the direction of rotation, per newton of load
    return np.array(eta), np.array(tf)


def _reference_fraction(kind: str, theta: np.ndarray) -> np.ndarray:
    """Position as a fraction of the stroke: η between its extremes over a turn (found by minimisation)."""
    ends = []
    for sign in (1.0, -1.0):
        grid = np.linspace(0, 2 * np.pi, 721)
        start = grid[np.argmin(sign * _reference(kind, grid)[0])]
        res = minimize_scalar(lambda t, sg=sign: sg * _reference(kind, np.array([t]))[0][0],
                              bracket=(start - 0.01, start, start + 0.01), tol=1e-12)
        ends.append(sign * res.fun)
    lo, hi = ends
    return (_reference(kind, theta)[0] - lo) / (hi - lo)


THETA_15 = np.radians(np.arange(0.0, 360.0, 15.0))


@pytest.mark.parametrize("kind", list(UNITS))
def test_position_and_torque_factor_match_the_independent_reference_every_15_deg(kind: str) -> None:
    """PR(θ) (fraction of stroke) and TF(θ) at 15° crank increments, the API table form: the exact linkage
    against the circle-intersection + statics reference, to 1e-7 of the stroke and 1e-7 m of TF."""
    unit = inline_unit(_block(kind))
    pr = np.asarray(unit.position_m(THETA_15)) / unit.stroke_m
    assert np.max(np.abs(pr - _reference_fraction(kind, THETA_15))) < 1e-7
    assert np.max(np.abs(np.asarray(unit.torque_factor_m(THETA_15)) - _reference(kind, THETA_15)[1])) < 1e-7


def _api_psi_form(kind: str) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(θ, PR, TF) of a clockwise Class I unit parametrised by ψ, the angle at the saddle between K and C:
    the API Spec 11E torque-factor equations (ψ form, as the public API 11E implementation in
    vamseeachanta/digitalmodel ``dynacard/gear_box_loading.py`` (MIT) states them):
    ψ_b,t = acos((C² + K² - (P ± R)²)/(2CK)), E = √(C² + K² - 2CK cos ψ), α = ±acos((P² + R² - E²)/(2PR)),
    ε = ±acos((E² + P² - R²)/(2EP)), β = acos((C² + E² - K²)/(2CE)) - ε, θ = β + ψ + φ - α (φ = asin(I/K)),
    TF = A·R·sin α / (C·sin β), PR = (ψ_b - ψ)/(ψ_b - ψ_t); + on the upstroke, - on the downstroke."""
    u = UNITS[kind]
    a, c, i, k, p, r = (u[f"{n}_m"] for n in "acikpr")
    psi_b = math.acos((c * c + k * k - (p + r) ** 2) / (2 * c * k))
    psi_t = math.acos((c * c + k * k - (p - r) ** 2) / (2 * c * k))
    rows = []
    for d in (1.0, -1.0):
        for psi in np.linspace(psi_t + 1e-3, psi_b - 1e-3, 40):
            e = math.sqrt(c * c + k * k - 2 * c * k * math.cos(psi))
            alpha = d * math.acos((p * p + r * r - e * e) / (2 * p * r))
            eps = d * math.acos((e * e + p * p - r * r) / (2 * e * p))
            beta = math.acos((c * c + e * e - k * k) / (2 * c * e)) - eps
            rows.append((beta + psi + math.asin(i / k) - alpha, (psi_b - psi) / (psi_b - psi_t),
                         a * r / c * math.sin(alpha) / math.sin(beta)))
    theta, pr, tf = np.array(rows).T
    return theta, pr, tf


def test_conventional_matches_the_api_11e_psi_form() -> None:
    unit = inline_unit(_block("conventional"))  # clockwise, as the form is written
    theta, pr, tf = _api_psi_form("conventional")
    assert np.max(np.abs(np.asarray(unit.position_m(theta)) / unit.stroke_m - pr)) < 1e-12
    assert np.max(np.abs(np.asarray(unit.torque_factor_m(theta)) - tf)) < 1e-12


def test_mark_ii_matches_the_api_11e_psi_form_mirrored() -> None:
    """Mirrored left-right, a Class III linkage turning counterclockwise IS a Class I linkage turning
    clockwise (the saddle comes in front of the crank, E behind it), with the rod's direction reversed: the
    rod rises when E rises. So PR_III = 1 - PR_I and TF_III = -TF_I at the same θ."""
    unit = inline_unit(_block("mark_ii"))
    theta, pr, tf = _api_psi_form("mark_ii")
    assert np.max(np.abs(np.asarray(unit.position_m(theta)) / unit.stroke_m - (1.0 - pr))) < 1e-12
    assert np.max(np.abs(np.asarray(unit.torque_factor_m(theta)) + tf)) < 1e-12


@pytest.mark.parametrize("kind", list(UNITS))
def test_torque_factor_is_the_derivative_of_position_and_positive_on_the_upstroke(kind: str) -> None:
    unit = inline_unit(_block(kind))
    th = np.linspace(0, 2 * np.pi, 400, endpoint=False)
    h = 1e-6
    fd = (np.asarray(unit.position_m(th + h)) - np.asarray(unit.position_m(th - h))) / (2 * h)
    assert np.allclose(unit.torque_factor_m(th), fd, atol=1e-6 * unit.stroke_m)
    up = (th - unit.theta_bottom) % (2 * np.pi) < (unit.theta_top - unit.theta_bottom) % (2 * np.pi)
    tf = np.asarray(unit.torque_factor_m(th))
    assert np.all(tf[up] >= -1e-9) and np.all(tf[~up] <= 1e-9)
    omega = 2 * np.pi * 7 / 60
    a = unit.kinematics(th, omega)[2]
    dv = (np.asarray(unit.kinematics(th + h, omega)[1]) - np.asarray(unit.kinematics(th - h, omega)[1])) / (2 * h)
    assert np.allclose(a, dv * omega, atol=1e-6 * unit.stroke_m * omega**2)


def test_mark_ii_counterclockwise_has_the_longer_upstroke_and_its_mirror_the_shorter() -> None:
    unit = inline_unit(_block("mark_ii"))
    assert unit.upstroke_fraction() > 0.505  # 182.8 of 360 deg
    mirror = inline_unit(dataclasses.replace(_block("mark_ii"), rotation="clockwise"))
    assert mirror.upstroke_fraction() == pytest.approx(1.0 - unit.upstroke_fraction(), abs=1e-12)
    # Class III: the top of the stroke is near 12 o'clock, the bottom near 6 (Class I: the reverse)
    assert min(unit.theta_top, 2 * np.pi - unit.theta_top) < math.radians(10)
    conv = inline_unit(_block("conventional"))
    assert min(conv.theta_bottom, 2 * np.pi - conv.theta_bottom) < math.radians(25)


def test_catalogue_unit_given_inline_is_the_same_unit() -> None:
    """A catalogue designation and the same nameplate inline: identical kinematics (one implementation)."""
    from srenv.surface_unit.unit_catalogue import conventional_unit

    cat = conventional_unit("C-228D-213-86", 0)
    inline = inline_unit(_block("conventional"))
    th = np.linspace(0, 2 * np.pi, 97)
    assert np.array_equal(cat.position_m(th), inline.position_m(th))
    assert np.array_equal(cat.torque_factor_m(th), inline.torque_factor_m(th))


# ------------------------------------------------------------------------------ simulate, end to end
def test_simulate_with_an_inline_mark_ii_runs_and_its_gearbox_is_lighter(tmp_path: Path,
                                                                           capsys: pytest.CaptureFixture) -> None:
    """Same well, same 64 in stroke: the Mark II's phased counterbalance carries it with a lower peak torque
    than the conventional unit (published: one gearbox size smaller); crank and polished-rod power agree."""
    import json

    from srenv.tools.cli import main

    out = {}
    for name, cfg in (("m", MARK_II), ("c", CONV)):
        assert main(["simulate", str(cfg), "--strokes", "2", "--out", str(tmp_path / f"{name}.csv")]) == 0
        out[name] = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
    m, c = out["m"], out["c"]
    assert abs(m["polished_rod_stroke_m"] - c["polished_rod_stroke_m"]) < 0.01
    assert m["peak_gearbox_torque_nm"] < 0.9 * c["peak_gearbox_torque_nm"]
    assert m["counterbalance_moment_nm"] == 25700.0


@pytest.mark.parametrize("kind", list(UNITS))
def test_crank_power_equals_polished_rod_power_over_whole_strokes(kind: str) -> None:
    """The counterbalance (weights or air at constant pressure) and SU only store and return energy."""
    from srenv.surface_unit.gearbox import analyse

    unit = inline_unit(_block(kind))
    th = unit.theta_bottom + np.linspace(0, 2 * np.pi, 4000, endpoint=False)
    load = 40e3 + 15e3 * (np.asarray(unit.torque_factor_m(th)) > 0)
    omega = 2 * np.pi * 6 / 60
    _, v, _ = unit.kinematics(th, omega)
    rep = analyse(unit, th, load, v, omega, 1.0, counterbalance_moment_nm=30e3 if kind != "air_balanced" else 45e3,
                  counterbalance_offset_rad=0.2)
    assert rep.mean_crank_power_w == pytest.approx(rep.mean_polished_rod_power_w, rel=1e-6)
    keys = set(rep.summary())
    assert ("counterbalance_force_n" in keys) == (kind == "air_balanced")


def test_air_balanced_counterbalance_is_pressure_times_area_through_the_beam() -> None:
    from srenv.surface_unit.inline_unit import counterbalance

    block = dataclasses.replace(_block("air_balanced"), air_pressure_pa=2.0e6, air_piston_area_m2=0.05,
                                air_arm_m=1.2)
    force, offset = counterbalance(block)
    assert force == pytest.approx(2.0e6 * 0.05 * 1.2 / 3.0) and offset == 0.0
    unit = inline_unit(block)
    th = np.radians([60.0, 200.0])
    t = unit.net_torque_nm(th, 50e3, 0.0, 0.0, force)
    assert np.allclose(t, np.asarray(unit.torque_factor_m(th)) * (50e3 - force))


# ------------------------------------------------------------------------------ field records
def test_record_geometry_strings_are_recognised_not_read_as_conventional() -> None:
    assert record_geometry("C") == "conventional" and record_geometry("M") == "mark_ii"
    assert record_geometry("Mark II") == "mark_ii" and record_geometry("A") == "air_balanced"
    assert record_geometry("Air Balanced") == "air_balanced" and record_geometry("X") is None
    base = {"A": 2.032, "C": 1.166, "I": 1.161, "K": 1.732, "P": 1.437, "R": 0.4526, "rotation": "C. Clockwise",
            "geometry": "M", "structural_unbalance_n": -500.0, "phase_angle_deg": 10.0}
    block = record_unit_config(base)
    assert block["geometry"] == "mark_ii" and block["rotation"] == "counterclockwise"
    assert block["crank_offset_deg"] == 10.0 and block["a_m"] == 2.032
    assert record_unit_config({**base, "geometry": "Q"}) is None
    assert record_unit_config({**base, "K": None}) is None


def test_a_record_naming_mark_ii_builds_a_class_iii_unit() -> None:
    from srenv.analysis.field_model import unit_from_record
    from srenv.analysis.field_record import read_dynacard_json

    rec = read_dynacard_json(ROOT / "tests" / "data" / "field" / "7699227.json", auto_orient=True)
    conv = unit_from_record(rec)
    mark = unit_from_record(dataclasses.replace(rec, unit={**rec.unit, "geometry": "M"}))
    assert conv.geometry.kind == "conventional" and mark.geometry.kind == "mark_ii"
    # same triangle O-G-E, so the same stroke; but the Class III stroke starts half a turn later
    assert mark.stroke_m == pytest.approx(conv.stroke_m, rel=1e-12)
    gap = (mark.theta_bottom - conv.theta_bottom) % (2 * np.pi)
    assert abs(gap - np.pi) < math.radians(30)
    # a nameplate that cannot close gives no unit (the record stays usable for validate), not an error
    assert unit_from_record(dataclasses.replace(rec, unit={**rec.unit, "P": 0.2})) is None
    assert unit_from_record(dataclasses.replace(rec, unit={**rec.unit, "geometry": "Q"})) is None


# ------------------------------------------------------------------------------ bad input, by class
def _numeric_fields() -> list[tuple[str, dict]]:
    return [(f.name, dict(f.metadata)) for f in dataclasses.fields(BeamUnitConfig) if "check" in f.metadata]


def _bad_values(meta: dict) -> list[Any]:
    lo = meta.get("lo", 0.0)
    out: list[Any] = ["abc", None, True, [1.0], float("nan"), float("inf"), 10**400, meta["hi"] * 1.5 + 1]
    out.append(0.0 if meta["check"] == "positive" else lo - (0.5 * abs(lo) + 1.0))
    return out


BAD_CASES = [pytest.param(name, v, id=f"{name}={v!r:.12}") for name, meta in _numeric_fields()
             for v in _bad_values(meta)]


def test_every_numeric_unit_field_has_a_finite_range() -> None:
    fields = _numeric_fields()
    assert len(fields) >= 13 and all("hi" in meta for _, meta in fields)


@pytest.mark.parametrize(("name", "value"), BAD_CASES)
def test_every_numeric_unit_field_refuses_bad_values(name: str, value: Any) -> None:
    with pytest.raises(ConfigError) as ex:
        load_config(MARK_II, {f"surface.beam_unit.{name}": value})
    assert f"surface.beam_unit.{name}" in str(ex.value) and len(str(ex.value).splitlines()) == 1


LINKAGE_CASES = [
    ("surface.beam_unit.p_m=0.9", ["surface.beam_unit.p_m", "c_m", "k_m", "r_m", "cannot close"]),
    ("surface.beam_unit.p_m=3.0", ["surface.beam_unit.p_m", "|c_m - p_m|", "cannot close"]),
    ("surface.beam_unit.r_m=1.9", ["surface.beam_unit.r_m", "k_m"]),
    ("surface.beam_unit.i_m=1.8", ["surface.beam_unit.i_m", "k_m"]),
    ("surface.beam_unit.geometry=walking", ["surface.beam_unit.geometry", "mark_ii"]),
    ("surface.beam_unit.rotation=cw", ["surface.beam_unit.rotation", "counterclockwise"]),
    ("surface.beam_unit.air_pressure_pa=1e6", ["surface.beam_unit.air_pressure_pa", "air_balanced"]),
    ("surface.beam_unit.designation=M228", ["surface.beam_unit.designation", "C-228D-213-86"]),
    ("surface.counterbalance_moment_nm=100", ["surface.counterbalance_moment_nm", "beam_unit"]),
    ("surface.motion=harmonic", ["surface.beam_unit", "null"]),
]


@pytest.mark.parametrize(("setting", "needles"), LINKAGE_CASES, ids=[c[0].split(".")[-1] for c in LINKAGE_CASES])
def test_impossible_or_inconsistent_unit_is_one_line_exit_2(setting: str, needles: list[str], tmp_path: Path,
                                                            capsys: pytest.CaptureFixture) -> None:
    rc, err = run_srenv(["simulate", str(MARK_II), "--set", setting, "--out", str(tmp_path / "o.csv")], capsys)
    one_line(rc, err, *needles)
    assert not (tmp_path / "o.csv").exists()


def test_a_missing_dimension_or_block_is_named(tmp_path: Path) -> None:
    import yaml

    data = yaml.safe_load(MARK_II.read_text())
    del data["surface"]["beam_unit"]["k_m"]
    with pytest.raises(ConfigError, match=r"surface\.beam_unit\.k_m.*required"):
        load_config(_write(tmp_path, data))
    del data["surface"]["beam_unit"]
    with pytest.raises(ConfigError, match=r"'surface\.beam_unit' = None.*nameplate"):
        load_config(_write(tmp_path, data))


def _write(tmp_path: Path, data: dict) -> Path:
    import yaml

    p = tmp_path / "w.yaml"
    p.write_text(yaml.safe_dump(data))
    return p


def test_a_catalogue_entry_can_be_a_class_iii_unit(tmp_path: Path) -> None:
    """The catalogue is a list of named nameplates: ``kind`` makes an entry a Mark II (default conventional)."""
    import yaml

    from srenv.surface_unit.beam_unit import ConventionalUnit
    from srenv.surface_unit.unit_catalogue import load_catalogue

    m = UNITS["mark_ii"]
    entry = {"designation": "M-160D-173-64", "kind": "mark_ii", "rotation": "counterclockwise",
             **{k: m[k] for k in ("a_m", "c_m", "i_m", "k_m", "p_m")}, "crank_radii_m": [m["r_m"]],
             "torque_rating_nm": 18077.6, "max_load_n": 76954.2, "max_stroke_m": 1.6256, "structural_unbalance_n": 0.0}
    path = tmp_path / "cat.yaml"
    path.write_text(yaml.safe_dump({"units": [entry]}))
    unit = ConventionalUnit(load_catalogue(path)["M-160D-173-64"])
    th = np.linspace(0, 2 * np.pi, 50)
    assert unit.geometry.kind == "mark_ii"
    assert np.allclose(unit.torque_factor_m(th), inline_unit(_block("mark_ii")).torque_factor_m(th), atol=1e-12)
