"""srenv.task.leaks (v3): a valve leak's passed share from the law's nominal stroke, its speed kept in m/s from
the onset, and a hole's fixed drain rate."""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest

from srenv.task import leaks


@pytest.mark.parametrize("r", [0.05, 0.3, 0.7, 0.95])
def test_passed_share_is_the_integral_over_the_nominal_profile(r: float) -> None:
    theta = np.linspace(0.0, math.pi, 200001)
    v = np.sin(theta)  # the law's v_peak sqrt(4 xi (1 - xi)) in time, v_peak = 1
    numeric = np.trapezoid(np.minimum(v, r), theta) / np.trapezoid(v, theta)
    assert leaks.passed_share(r) == pytest.approx(numeric, abs=1e-8)


def test_passed_share_bounds_and_monotone() -> None:
    assert leaks.passed_share(0.0) == 0.0 and leaks.passed_share(1.0) == 1.0 and leaks.passed_share(3.0) == 1.0
    r = np.linspace(0.0, 1.0, 101)
    s = np.array([leaks.passed_share(x) for x in r])
    assert np.all(np.diff(s) > 0) and s[-2] < 1.0  # a faster stroke (smaller r) passes a smaller share


def test_valve_fraction_keeps_the_leak_speed_of_the_onset() -> None:
    over = {"pump.travelling_valve_leak_fraction": 0.5, "pump.intake_gas_fraction": 0.0}
    got = leaks.valve_overrides("travelling_valve_leak", over, (5.0, 2.0), (8.0, 2.0))
    assert got == {"pump.travelling_valve_leak_fraction": pytest.approx(0.5 * 5.0 / 8.0)}
    v_leak = got["pump.travelling_valve_leak_fraction"] * leaks.peak_speed_m_s(8.0, 2.0)
    assert v_leak == pytest.approx(0.5 * leaks.peak_speed_m_s(5.0, 2.0))  # m/s: the same valve
    both = leaks.valve_overrides("both_valves_leak", {"pump.travelling_valve_leak_fraction": 0.3,
                                                      "pump.standing_valve_leak_fraction": 0.3}, (4.0, 1.0), (4.0, 2.0))
    assert set(both.values()) == {0.15}
    assert leaks.valve_overrides("tubing_leak", over, (5.0, 2.0), (8.0, 2.0)) == {}


def test_valve_lost_from_the_config_the_interval_ran() -> None:
    pump = SimpleNamespace(travelling_valve_leak_fraction=0.4, standing_valve_leak_fraction=0.0)
    assert leaks.valve_lost_m3(pump, 2.0) == pytest.approx(2.0 * leaks.passed_share(0.4))
    pump.standing_valve_leak_fraction = 0.4
    s = leaks.passed_share(0.4)
    assert leaks.valve_lost_m3(pump, 2.0) == pytest.approx(2.0 * (1.0 - (1.0 - s) ** 2))


def test_hole_drains_a_rate_per_hour_at_most_the_lifted() -> None:
    pump = SimpleNamespace(plunger_diameter_mm=50.0, load_source="pressures")
    from srenv.physics.pump import plunger_area_m2

    rate = leaks.hole_rate_m3_h({"pump.tubing_leak_fraction": 0.16}, pump, (5.0, 2.0))
    assert rate == pytest.approx(0.16 * plunger_area_m2(pump) * 2.0 * 5.0 * 60.0)
    assert leaks.hole_lost_m3(rate, 0.5, 10.0) == pytest.approx(0.5 * rate)
    assert leaks.hole_lost_m3(rate, 1.0, 10.0) == pytest.approx(2 * leaks.hole_lost_m3(rate, 0.5, 10.0))  # in time
    assert leaks.hole_lost_m3(rate, 10.0, 0.01) == 0.01  # no more than was lifted
    assert leaks.hole_rate_m3_h({}, pump, (5.0, 2.0)) == 0.0
