"""Surface unit realism: a simulated well driven by a conventional API 11E beam unit (surface.py), its
gearbox torque and power (gearbox.py) and the summary keys the env reads (stroke_summary.py)."""

from __future__ import annotations

import dataclasses
import glob
import math
from pathlib import Path

import numpy as np
import pytest

from srenv.analysis.stroke_summary import summarize
from srenv.config import CONFIG_DIR, SurfaceConfig, load_config
from srenv.errors import ConfigError
from srenv.simulation.simulator import RunResult, Simulator
from srenv.surface_unit import gearbox
from srenv.surface_unit.beam_unit import ConventionalUnit
from srenv.surface_unit.surface import SurfaceMotion

CONFIG = "conventional_fig4"
N_STROKES = 3  # the first stroke starts from rest; strokes 2-3 are the periodic regime


def _run(cfg_overrides: list[str] | None = None, unit: ConventionalUnit | None = None,
         strokes: int = N_STROKES) -> tuple[Simulator, list[RunResult]]:
    cfg = load_config(CONFIG, cfg_overrides or [])
    sim = Simulator(cfg)
    if unit is not None:
        sim.surface = SurfaceMotion(cfg.surface, unit=unit)
    return sim, sim.run_strokes(strokes)


def _harmonic_twin(stroke_m: float) -> list[RunResult]:
    """The same well at the same SPM, moved harmonically over the same stroke."""
    return _run(["surface.motion=harmonic", f"surface.stroke_length_m={stroke_m!r}"])[1]


def _last(results: list[RunResult], column: str) -> np.ndarray:
    return results[-1].trace[column]


@pytest.fixture(scope="module")
def conventional() -> tuple[Simulator, list[RunResult]]:
    return _run()


@pytest.fixture(scope="module")
def harmonic(conventional: tuple[Simulator, list[RunResult]]) -> list[RunResult]:
    return _harmonic_twin(conventional[0].surface.unit.stroke_m)


# ------------------------------------------------------------------------------------------ kinematics
def test_shipped_config_is_the_first_conventional_well_config() -> None:
    # the acceptance check simulates the alphabetically first configs/**/*.yaml under a "well" path that
    # mentions "conventional"; it must be this config and it must really use the conventional motion
    root = CONFIG_DIR.parents[1]
    candidates = [Path(f) for f in sorted(glob.glob(str(root / "configs" / "**" / "*.yaml"), recursive=True))
                  if "conventional" in Path(f).read_text() and "well" in f]
    assert candidates and candidates[0].stem == CONFIG
    assert load_config(CONFIG).surface.motion == "conventional"
    assert "conventional" not in (CONFIG_DIR / "default.yaml").read_text()


def test_simulated_position_range_is_the_crank_hole_stroke(conventional) -> None:
    sim, results = conventional
    unit = sim.surface.unit
    position = np.concatenate([r.trace["polished_rod_position_m"] for r in results])
    assert abs(np.ptp(position) / unit.stroke_m - 1.0) < 0.005
    # the configured stroke_length_m (2.4 m default) must not leak into a conventional run
    assert results[-1].stroke_length_m == unit.stroke_m


def test_simulated_motion_follows_the_linkage_not_a_cosine(conventional) -> None:
    sim, results = conventional
    unit = sim.surface.unit
    theta = gearbox.stroke_crank_angle_rad(unit, results[-1])
    position = _last(results, "polished_rod_position_m")
    # Newmark integrates the prescribed velocity: the position matches the exact linkage to O(dt^2)
    assert np.max(np.abs(position - unit.position_m(theta))) < 1e-3 * unit.stroke_m
    assert np.max(np.abs(position - unit.harmonic_position_m(theta))) > 0.05 * unit.stroke_m


def test_upstroke_and_downstroke_durations_differ_as_the_unit_predicts(conventional, harmonic) -> None:
    sim, results = conventional
    fraction = sim.surface.unit.upstroke_fraction()

    def up_down_ratio(runs: list[RunResult]) -> float:
        steps = np.diff(_last(runs, "polished_rod_position_m"))
        return np.sum(steps > 0) / np.sum(steps < 0)

    assert up_down_ratio(results) == pytest.approx(fraction / (1.0 - fraction), abs=0.01)
    assert abs(up_down_ratio(results) - 1.0) >= 0.02
    assert abs(up_down_ratio(harmonic) - 1.0) < 0.005


def test_scaled_up_linkage_converges_to_the_harmonic_card(conventional) -> None:
    geometry = conventional[0].surface.unit.geometry
    gaps = []
    for factor in (1.0, 10.0, 50.0):
        unit = ConventionalUnit(geometry.scaled_linkage(factor), 0)
        conv = _run(unit=unit, strokes=2)[1]
        harm = _harmonic_twin(unit.stroke_m)[:2]
        load_c, load_h = _last(conv, "polished_rod_load_n"), _last(harm, "polished_rod_load_n")
        load_gap = np.max(np.abs(load_c - load_h)) / np.ptp(load_h)
        position_gap = np.max(np.abs(_last(conv, "polished_rod_position_m")
                                     - _last(harm, "polished_rod_position_m"))) / unit.stroke_m
        gaps.append((load_gap, position_gap))
    # sample by sample (same instants), so a card point differs in both load and position
    assert gaps[0][0] > 0.10  # the real unit's card is far from harmonic ...
    assert gaps[0] > gaps[1] > gaps[2]
    assert gaps[2][0] < 0.015 and gaps[2][1] < 0.005  # ... a 50x longer linkage is harmonic


def test_conventional_card_differs_from_harmonic_as_expected(conventional, harmonic) -> None:
    sim, results = conventional
    unit = sim.surface.unit
    omega = 2 * math.pi * results[-1].spm / 60.0
    # cause: the linkage accelerates the rod harder than a cosine at the bottom, where PPRL occurs
    bottom_acceleration = unit.kinematics(unit.theta_bottom, omega)[2]
    assert bottom_acceleration > 1.2 * 0.5 * unit.stroke_m * omega**2
    # effect, measured on this clockwise unit (about +2 % PPRL, +3.5 % load range; MPRL within 0.5 %):
    load_c, load_h = _last(results, "polished_rod_load_n"), _last(harmonic, "polished_rod_load_n")
    assert load_c.max() > 1.01 * load_h.max()
    assert np.ptp(load_c) > 1.015 * np.ptp(load_h)


# ------------------------------------------------------------------------------------------ gearbox
def test_net_torque_sample_by_hand(conventional) -> None:
    sim, results = conventional
    unit = sim.surface.unit
    stroke = results[-1]
    moment_nm, offset_rad = 25000.0, math.radians(5.0)
    report = gearbox.analyse_runs(unit, [stroke], counterbalance_moment_nm=moment_nm,
                                  counterbalance_offset_rad=offset_rad, motor_efficiency=0.9)
    i = 517  # an upstroke sample, away from the dead centres
    step_s = 60.0 / stroke.spm / stroke.n_steps
    theta = unit.theta_bottom + 2 * math.pi * stroke.spm / 60.0 * (i + 1) * step_s
    # torque factor from the position curve by central difference, not from the unit's own derivative
    h = 1e-6
    tf = (unit.position_m(theta + h) - unit.position_m(theta - h)) / (2 * h)
    load = stroke.trace["polished_rod_load_n"][i]
    expected = tf * (load - unit.geometry.structural_unbalance_n) - moment_nm * math.sin(theta + offset_rad)
    assert tf > 0.3  # really an upstroke sample with a sizeable torque factor
    assert report.crank_angle_rad[i] == pytest.approx(theta, rel=1e-12)
    assert report.net_torque_nm[i] == pytest.approx(expected, rel=1e-6)
    assert report.polished_rod_power_w[i] == pytest.approx(load * stroke.trace["polished_rod_velocity_m_s"][i])
    assert report.crank_power_w[i] == pytest.approx(expected * 2 * math.pi * stroke.spm / 60.0, rel=1e-6)


def test_optimal_counterbalance_minimises_the_peak_torque(conventional) -> None:
    sim, results = conventional
    unit = sim.surface.unit
    periodic = results[1:]
    best = gearbox.optimal_counterbalance_nm(
        unit, np.concatenate([gearbox.stroke_crank_angle_rad(unit, r) for r in periodic]),
        np.concatenate([r.trace["polished_rod_load_n"] for r in periodic]))

    def peak(moment_nm: float) -> float:
        return gearbox.analyse_runs(unit, periodic, counterbalance_moment_nm=moment_nm).peak_torque_nm

    assert peak(best) < 0.5 * peak(0.0)  # an unbalanced unit lifts the whole rod weight on the gearbox
    grid = np.linspace(0.0, 2.0 * best, 401)
    assert peak(best) <= min(peak(m) for m in grid) + 1e-9 * peak(0.0)
    assert peak(best) < min(peak(0.98 * best), peak(1.02 * best))


def test_power_balance_over_whole_strokes(conventional) -> None:
    sim, results = conventional
    periodic = results[1:]
    report = sim.surface.gearbox_report(periodic)
    period_s = 60.0 / periodic[-1].spm
    card_work_j = summarize(sim, periodic)["card_work_j_per_stroke"]
    # PRL·v averaged over whole strokes is the card area per unit time
    assert report.mean_polished_rod_power_w == pytest.approx(card_work_j / period_s, rel=0.01)
    # counterweights and structural unbalance store and return energy within a crank turn
    assert report.mean_crank_power_w == pytest.approx(report.mean_polished_rod_power_w, rel=1e-6)
    # the motor is credited nothing while the well over-runs it, and loses 1 - efficiency
    efficiency = sim.cfg.surface.motor_efficiency
    assert report.motor_power_w > report.mean_polished_rod_power_w / efficiency
    assert report.motor_power_w == pytest.approx(
        np.mean(np.maximum(report.crank_power_w, 0.0)) / efficiency, rel=1e-12)


def test_summary_reports_gearbox_loading_for_a_conventional_unit(conventional, harmonic) -> None:
    sim, results = conventional
    summary = summarize(sim, results)
    keys = ("peak_gearbox_torque_nm", "gearbox_torque_rating_nm", "gearbox_loading_pct",
            "polished_rod_power_w", "motor_power_w", "optimal_counterbalance_nm")
    assert all(isinstance(summary[k], float) for k in keys)
    assert summary["gearbox_torque_rating_nm"] == sim.surface.unit.geometry.torque_rating_nm
    assert summary["gearbox_loading_pct"] == pytest.approx(
        100.0 * summary["peak_gearbox_torque_nm"] / summary["gearbox_torque_rating_nm"])
    # the shipped counterbalance is near the optimum and leaves the reducer inside its rating
    assert summary["counterbalance_moment_nm"] == pytest.approx(summary["optimal_counterbalance_nm"], rel=0.02)
    assert 50.0 < summary["gearbox_loading_pct"] < 100.0
    harmonic_sim = Simulator(load_config(CONFIG, ["surface.motion=harmonic"]))
    assert "gearbox_loading_pct" not in summarize(harmonic_sim, harmonic)


# ------------------------------------------------------------------------------------------ validation
@pytest.mark.parametrize(("override", "field"), [
    ("surface.unit=C-999X-000-00", "surface.unit"),
    ("surface.crank_hole=3", "surface.crank_hole"),
])
def test_unknown_unit_or_crank_hole_names_the_field(override: str, field: str) -> None:
    with pytest.raises(ConfigError) as err:
        Simulator(load_config(CONFIG, [override]))
    assert err.value.field == field


def test_surface_motion_validates_config_built_in_code() -> None:
    base = SurfaceConfig(motion="conventional", unit="C-160D-173-64")
    with pytest.raises(ConfigError, match="0..2") as err:
        SurfaceMotion(dataclasses.replace(base, crank_hole=3))
    assert err.value.field == "surface.crank_hole"
    with pytest.raises(ConfigError) as err:
        SurfaceMotion(dataclasses.replace(base, motor_efficiency=1.2))
    assert err.value.field == "surface.motor_efficiency"
    with pytest.raises(ConfigError) as err:
        SurfaceMotion(SurfaceConfig(motion="harmonic"), unit=SurfaceMotion(base).unit)
    assert err.value.field == "surface.motion"
