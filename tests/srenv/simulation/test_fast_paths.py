"""The per-step fast paths of the env's Python (issue 25, docs/speed.md) give the same numbers, to the bit, as
the numpy forms they replaced: the annulus's scalar TVD, the compiled counterbalance bisection, the kept
stroke motion of a surface."""

from __future__ import annotations

import math

import numpy as np

from srenv.analysis import card_features as cf
from srenv.config import load_config
from srenv.simulation.simulator import Simulator
from srenv.surface_unit import gearbox


def _numpy_bisection(well: np.ndarray, arm: np.ndarray) -> float:
    """optimal_counterbalance_nm's bisection as it was written in numpy (before issue 25's compiled one)."""
    lo, hi = 0.0, 2.0 * float(np.max(np.abs(well))) / float(np.max(np.abs(arm)))
    for _ in range(gearbox._BISECTION_PASSES):
        if hi - lo <= gearbox._BISECTION_RTOL * max(hi, 1.0):
            break
        mid = 0.5 * (lo + hi)
        torque = well - mid * arm
        worst = int(np.argmax(np.abs(torque)))
        slope = -arm[worst] * math.copysign(1.0, torque[worst])
        if slope > 0.0:
            hi = mid
        elif slope < 0.0:
            lo = mid
        else:
            return mid
    return 0.5 * (lo + hi)


def test_scalar_tvd_is_numpy_interp_to_the_bit() -> None:
    sim = Simulator(load_config("paper_fig4_deviated"))
    sv = sim.survey
    grid, z = sv._tvd_table
    assert np.ptp(np.diff(z) / np.diff(grid)) > 0.01  # a deviated well: the slope changes along the table
    rng = np.random.default_rng(3)
    xs = np.r_[rng.uniform(-5.0, grid[-1] + 5.0, 5000), grid[::7], grid[-1], -1.0, grid[-1] + 1.0]
    got = np.array([sv.tvd_at(float(x)) for x in xs])
    assert np.array_equal(got, np.interp(xs, grid, z))
    assert sim.annulus is None or sim.annulus.intake_pressure_pa() == sim.annulus.intake_pressure_pa()


def test_compiled_counterbalance_bisection_is_the_numpy_one() -> None:
    sim = Simulator(load_config("conventional_fig4"))
    results = sim.run_strokes(2)
    unit = sim.surface.unit
    theta = np.concatenate([gearbox.stroke_crank_angle_rad(unit, r) for r in results])
    load = np.concatenate([r.trace["polished_rod_load_n"] for r in results])
    well = np.asarray(unit.net_torque_nm(theta, load, 0.0))
    arm = unit.counterbalance_arm(theta)
    assert gearbox.optimal_counterbalance_nm(unit, theta, load) == _numpy_bisection(well, arm)
    rng = np.random.default_rng(5)
    for _ in range(20):  # random loads on the same crank angles, and ties of |T| (a repeated sample)
        w = well * rng.uniform(0.5, 1.5) + rng.normal(0.0, 0.1 * np.std(well), well.size)
        w[7] = w[3]
        assert gearbox._bisect(w, arm, 2.0 * float(np.max(np.abs(w))) / float(np.max(np.abs(arm)))) \
            == _numpy_bisection(w, arm)


def test_kept_stroke_motion_is_the_computed_one() -> None:
    sim = Simulator(load_config("conventional_fig4"))
    surface = sim.surface
    for spm, stroke, n in ((8.0, 1.0, 1500), (11.5, 0.9, 1044), (8.0, 1.0, 1500)):
        va, start = surface.stroke_motion(spm, stroke, n)
        assert np.array_equal(va, surface.stroke_velocity(spm, stroke, n))
        assert start == surface.stroke_start_state(spm, stroke)
        va[:] = 0.0  # the caller's copy: the kept one is untouched
    assert np.array_equal(surface.stroke_motion(8.0, 1.0, 1500)[0], surface.stroke_velocity(8.0, 1.0, 1500))


def test_impact_speed_reads_the_same_percentiles() -> None:
    tr = Simulator(load_config("paper_fig4_deviated")).run_strokes(2)[-1].trace
    rng = np.random.default_rng(7)
    for f in (tr["pump_load_n"], rng.normal(0.0, 1e4, 1001), rng.normal(0.0, 1e4, 4000)):
        assert (float(np.percentile(f, 90)), float(np.percentile(f, 10))) \
            == tuple(float(q) for q in np.percentile(f, (90, 10)))
    assert cf.impact_speed_m_s(tr["pump_position_m"], tr["pump_velocity_m_s"], tr["pump_load_n"]) >= 0.0
