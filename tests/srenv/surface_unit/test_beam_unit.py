"""Conventional beam-unit kinematics and the unit catalogue."""

from __future__ import annotations

import dataclasses
import itertools
import math

import numpy as np
import pytest

from srenv.surface_unit.beam_unit import BeamUnitGeometry, ConventionalUnit, harmonic_deviation
from srenv.surface_unit.unit_catalogue import (
    PACKAGE_CATALOGUE_PATH,
    REPO_CATALOGUE_PATH,
    get_unit,
    list_units,
    load_catalogue,
    parse_designation,
)

TEST_UNIT = "C-228D-213-86"
ALL_UNITS = list_units()


def _units_and_holes() -> list[tuple[str, int]]:
    return [(name, hole) for name in ALL_UNITS for hole in range(len(get_unit(name).crank_radii_m))]


def _turn(unit: ConventionalUnit, n: int = 360) -> np.ndarray:
    return unit.theta_bottom + np.linspace(0.0, 2.0 * np.pi, n, endpoint=False)


# (a) ------------------------------------------------------------------------------------------------
@pytest.mark.parametrize(("name", "hole"), _units_and_holes())
def test_position_range_equals_stroke(name: str, hole: int) -> None:
    unit = ConventionalUnit(get_unit(name), hole)
    position = unit.position_m(np.linspace(0.0, 2.0 * np.pi, 20001))
    assert position.min() == pytest.approx(0.0, abs=1e-6 * unit.stroke_m)
    assert position.max() == pytest.approx(unit.stroke_m, rel=1e-6)
    assert unit.position_m(unit.theta_bottom) == pytest.approx(0.0, abs=1e-12)
    assert unit.position_m(unit.theta_top) == pytest.approx(unit.stroke_m, rel=1e-12)


@pytest.mark.parametrize("name", ALL_UNITS)
def test_longest_hole_gives_nameplate_stroke_and_holes_shorten(name: str) -> None:
    geometry = get_unit(name)
    strokes = [ConventionalUnit(geometry, hole).stroke_m for hole in range(len(geometry.crank_radii_m))]
    assert abs(strokes[0] / geometry.max_stroke_m - 1.0) <= 0.03
    assert all(np.diff(strokes) < 0)


# (b) ------------------------------------------------------------------------------------------------
def test_upstroke_and_downstroke_durations_differ() -> None:
    unit = ConventionalUnit(get_unit(TEST_UNIT))
    fraction = unit.upstroke_fraction()
    assert abs(fraction - 0.5) / 0.5 > 0.01
    # the counterclockwise mirror image swaps the two halves of the cycle
    mirrored = ConventionalUnit(dataclasses.replace(unit.geometry, rotation="counterclockwise"))
    assert mirrored.upstroke_fraction() == pytest.approx(1.0 - fraction, abs=1e-12)
    # time spent rising, counted directly on a fine grid, matches the closed-form dead centres
    theta = _turn(unit, 100000)
    rising = np.mean(np.asarray(unit.torque_factor_m(theta)) > 0.0)
    assert rising == pytest.approx(fraction, abs=1e-4)


# (c) ------------------------------------------------------------------------------------------------
@pytest.mark.parametrize("name", ALL_UNITS)
@pytest.mark.parametrize("rotation", ["clockwise", "counterclockwise"])
def test_torque_factor_is_derivative_of_position(name: str, rotation: str) -> None:
    unit = ConventionalUnit(dataclasses.replace(get_unit(name), rotation=rotation))
    theta = np.radians(np.arange(360.0))
    h = 1e-5
    numeric = (np.asarray(unit.position_m(theta + h)) - np.asarray(unit.position_m(theta - h))) / (2.0 * h)
    analytic = np.asarray(unit.torque_factor_m(theta))
    assert np.max(np.abs(analytic - numeric)) <= 0.005 * np.max(np.abs(analytic))
    assert unit.velocity_factor_m(1.0) == unit.torque_factor_m(1.0)


# (d) ------------------------------------------------------------------------------------------------
def test_motion_tends_to_harmonic_as_linkage_grows() -> None:
    geometry = get_unit(TEST_UNIT)
    factors = [1.0, 2.0, 4.0, 8.0, 16.0, 32.0, 64.0]
    deviations = [harmonic_deviation(ConventionalUnit(geometry.scaled_linkage(f))) for f in factors]
    assert all(later < earlier for earlier, later in itertools.pairwise(deviations)), deviations
    assert deviations[0] > 0.03  # a real unit is visibly non-harmonic ...
    assert deviations[-1] < 0.01  # ... and the long-linkage limit is the harmonic (S/2)(1 - cos) motion
    scaled = ConventionalUnit(geometry.scaled_linkage(64.0))
    assert scaled.upstroke_fraction() == pytest.approx(0.5, abs=0.002)
    assert scaled.geometry.a_m / scaled.geometry.c_m == pytest.approx(geometry.a_m / geometry.c_m)


# (e) ------------------------------------------------------------------------------------------------
def test_net_torque_matches_hand_computation() -> None:
    unit = ConventionalUnit(get_unit(TEST_UNIT))
    su = unit.geometry.structural_unbalance_n
    assert su == pytest.approx(2001.7)
    prl, moment = 60000.0, 45000.0
    for theta in (0.3, 1.5, 2.8, 4.0, 5.5):
        tf = unit.torque_factor_m(theta)
        hand = tf * (60000.0 - 2001.7) - 45000.0 * math.sin(theta)
        assert unit.net_torque_nm(theta, prl, moment) == pytest.approx(hand, rel=1e-12)
    # at 90 degrees with TF = 1.0360965 m (from the linkage) the numbers are explicit
    theta = math.pi / 2.0
    assert unit.torque_factor_m(theta) == pytest.approx(1.0360965, rel=1e-6)
    assert unit.net_torque_nm(theta, prl, moment) == pytest.approx(1.0360965 * 57998.3 - 45000.0, rel=1e-6)
    # the counterweight-arm offset enters as sin(theta + offset)
    offset = 0.2
    expected = unit.torque_factor_m(1.0) * (prl - su) - moment * math.sin(1.0 + offset)
    assert unit.net_torque_nm(1.0, prl, moment, crank_offset_rad=offset) == pytest.approx(expected, rel=1e-12)
    # vectorised over angle and load together
    thetas = np.array([0.3, 1.5])
    loads = np.array([50000.0, 70000.0])
    vector = unit.net_torque_nm(thetas, loads, moment)
    one_by_one = [unit.net_torque_nm(t, w, moment) for t, w in zip(thetas, loads, strict=True)]
    assert vector == pytest.approx(one_by_one)


def test_polished_rod_power_is_load_times_velocity() -> None:
    unit = ConventionalUnit(get_unit(TEST_UNIT))
    omega = 2.0 * np.pi * 8.0 / 60.0
    theta = np.linspace(0.0, 2.0 * np.pi, 37)
    _, velocity, _ = unit.kinematics(theta, omega)
    assert unit.polished_rod_power_w(theta, omega, 50000.0) == pytest.approx(50000.0 * velocity)


# (f) ------------------------------------------------------------------------------------------------
@pytest.mark.parametrize("rotation", ["clockwise", "counterclockwise"])
def test_kinematics_agree_with_time_finite_differences(rotation: str) -> None:
    unit = ConventionalUnit(dataclasses.replace(get_unit(TEST_UNIT), rotation=rotation), crank_hole=1)
    spm = 7.5
    omega = 2.0 * np.pi * spm / 60.0
    t = np.linspace(0.0, 60.0 / spm, 400, endpoint=False)
    dt = 1e-4
    position, velocity, acceleration = unit.kinematics(unit.crank_angle_rad(t, spm), omega)

    def x(shift: float) -> np.ndarray:
        return np.asarray(unit.position_m(unit.crank_angle_rad(t + shift, spm)))

    assert position == pytest.approx(x(0.0), abs=1e-12)
    fd_velocity = (x(dt) - x(-dt)) / (2.0 * dt)
    fd_acceleration = (x(dt) - 2.0 * x(0.0) + x(-dt)) / dt**2
    assert np.max(np.abs(velocity - fd_velocity)) <= 1e-6 * np.max(np.abs(velocity))
    assert np.max(np.abs(acceleration - fd_acceleration)) <= 1e-4 * np.max(np.abs(acceleration))
    # the motion starts at the bottom of the stroke and rises first
    assert position[0] == pytest.approx(0.0, abs=1e-12)
    assert velocity[1] > 0.0


# (g) ------------------------------------------------------------------------------------------------
@pytest.mark.parametrize(
    ("field", "value"),
    [
        ("a_m", -2.8),
        ("c_m", 0.0),
        ("i_m", float("nan")),
        ("k_m", float("inf")),
        ("p_m", -1.0),
        ("max_load_n", float("nan")),
        ("torque_rating_nm", -1.0),
        ("structural_unbalance_n", float("nan")),
        ("crank_radii_m", (0.9, float("nan"))),
        ("crank_radii_m", (0.5, 0.9)),
        ("rotation", "anticlockwise"),
        ("rotation", "CW"),
    ],
)
def test_bad_geometry_names_the_field(field: str, value: object) -> None:
    with pytest.raises(ValueError, match=field):
        dataclasses.replace(get_unit(TEST_UNIT), **{field: value})


def test_pitman_too_short_cannot_assemble() -> None:
    geometry = get_unit(TEST_UNIT)
    # farthest pin position is K + R from the saddle; C + P just short of it cannot reach
    too_short = geometry.k_m + geometry.crank_radii_m[0] - geometry.c_m - 0.01
    with pytest.raises(ValueError, match="p_m") as caught:
        dataclasses.replace(geometry, p_m=too_short)
    assert "m with" in str(caught.value)  # the message carries the expected unit
    # just long enough assembles
    dataclasses.replace(geometry, p_m=too_short + 0.02)


def test_pitman_too_long_and_oversized_crank_rejected() -> None:
    geometry = get_unit(TEST_UNIT)
    with pytest.raises(ValueError, match="p_m"):
        dataclasses.replace(geometry, p_m=geometry.c_m + geometry.k_m)
    with pytest.raises(ValueError, match="crank_radii_m"):
        dataclasses.replace(geometry, crank_radii_m=(geometry.k_m * 1.01,))
    with pytest.raises(ValueError, match="crank_hole"):
        ConventionalUnit(geometry, crank_hole=len(geometry.crank_radii_m))


def test_height_instead_of_k() -> None:
    geometry = get_unit(TEST_UNIT)
    fields = {f.name: getattr(geometry, f.name) for f in dataclasses.fields(geometry) if f.name != "k_m"}
    rebuilt = BeamUnitGeometry.from_height(h_m=geometry.h_m, **fields)
    assert rebuilt.k_m == pytest.approx(geometry.k_m, rel=1e-12)
    with pytest.raises(ValueError, match="h_m"):
        BeamUnitGeometry.from_height(h_m=-1.0, **fields)


# (h) ------------------------------------------------------------------------------------------------
def test_catalogue_copies_identical() -> None:
    assert PACKAGE_CATALOGUE_PATH.read_bytes() == REPO_CATALOGUE_PATH.read_bytes()


def test_every_catalogue_entry_loads_and_matches_its_designation() -> None:
    from_repo = load_catalogue(REPO_CATALOGUE_PATH)
    assert 4 <= len(ALL_UNITS) <= 6
    assert list(from_repo) == ALL_UNITS
    for name in ALL_UNITS:
        geometry = get_unit(name)
        assert geometry == from_repo[name]
        assert isinstance(geometry.crank_radii_m, tuple)
        torque, load, stroke = parse_designation(name)
        assert geometry.torque_rating_nm == pytest.approx(torque, rel=1e-4)
        assert geometry.max_load_n == pytest.approx(load, rel=1e-4)
        assert geometry.max_stroke_m == pytest.approx(stroke, rel=1e-4)
        ConventionalUnit(geometry, len(geometry.crank_radii_m) - 1)


def test_designation_conversion() -> None:
    torque, load, stroke = parse_designation("C-228D-213-86")
    assert torque == pytest.approx(228000 * 0.112984829, rel=1e-9)
    assert load == pytest.approx(21300 * 4.4482216152605, rel=1e-12)
    assert stroke == pytest.approx(86 * 0.0254, rel=1e-12)


def test_unknown_unit_lists_known_ones() -> None:
    with pytest.raises(KeyError) as caught:
        get_unit("C-999D-999-999")
    assert all(name in str(caught.value) for name in ALL_UNITS)
