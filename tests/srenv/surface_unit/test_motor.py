"""The unit's motor (surface.motor, srenv/surface_unit/motor.py): a NEMA motor's torque-slip line, the crank speed
it gives through a stroke at the stroke's SPM, and a simulated well driven through it (docs/surface_unit.md,
"The motor")."""

from __future__ import annotations

import math

import numpy as np
import pytest

from srenv.analysis.stroke_summary import summarize
from srenv.config import apply_overrides, config_from_dict, load_config, read_raw
from srenv.errors import ConfigError
from srenv.simulation.simulator import Simulator
from srenv.surface_unit.motor import (
    GRID,
    NEMA_DESIGNS,
    CrankProfile,
    MotorLaw,
    crank_speed_rad_s,
    torque_on_grid,
)

SPM = 6.0
PERIOD = 60.0 / SPM
ANGLES = 2 * np.pi * np.arange(GRID) / GRID


def _period(omega: np.ndarray) -> float:
    return 2 * np.pi / omega.size * float(np.sum(1.0 / omega))


def test_rated_torque_runs_at_rated_slip_and_the_period_is_the_spm():
    """A constant net torque equal to the rated torque runs the crank at (1 - s_r) of its synchronous speed; the
    mean speed is the SPM's whatever the torque (the sheaves set it): Ω_s = ω / (1 - s_r)."""
    law = MotorLaw("D", 10e3, NEMA_DESIGNS["D"][0])
    mean = 2 * np.pi / PERIOD
    rated = law.rated_crank_torque_nm(mean / (1 - law.rated_slip))
    w = crank_speed_rad_s(law, np.full(GRID, rated), SPM)
    assert np.allclose(w, mean, rtol=1e-10)
    torque = rated * (1.0 + 0.8 * np.sin(ANGLES))  # a swing: slow where it pulls, fast where it eases
    w = crank_speed_rad_s(law, torque, SPM)
    assert _period(w) == pytest.approx(PERIOD, rel=1e-10)
    # on the slip line: ω = Ω_s (1 - s_r T / T_r(Ω_s)), one Ω_s for every angle
    omega_s = np.mean(w) / (1.0 - law.rated_slip * np.mean(torque) / rated)  # first guess, then exact below
    for _ in range(50):
        omega_s = float(np.mean(w + law.rated_slip * torque / law.rated_crank_torque_nm(omega_s) * omega_s))
    assert np.allclose(w, omega_s * (1.0 - law.rated_slip * torque / law.rated_crank_torque_nm(omega_s)), rtol=1e-9)
    assert w[np.argmax(torque)] == w.min() and w[np.argmin(torque)] == w.max()
    # the slip scales with the rated slip: a NEMA D slows more than a NEMA B under the same torque
    wb = crank_speed_rad_s(MotorLaw("B", 10e3, NEMA_DESIGNS["B"][0]), torque, SPM)
    assert np.ptp(wb) < 0.6 * np.ptp(w)


def test_inertia_smooths_the_speed_and_none_is_the_slip_line():
    """J dω/dt = T_m(ω) - T_net: a small J follows the quasi-static line, a large one holds the speed up (the
    swing shrinks, the period stays the SPM's)."""
    law = MotorLaw("D", 10e3, 0.065)
    torque = 12e3 * (1.0 + np.sin(ANGLES) + 0.5 * np.sin(2 * ANGLES))
    w0 = crank_speed_rad_s(law, torque, SPM)
    w_small = crank_speed_rad_s(MotorLaw("D", 10e3, 0.065, 1.0), torque, SPM)
    w_big = crank_speed_rad_s(MotorLaw("D", 10e3, 0.065, 2e6), torque, SPM)
    assert np.max(np.abs(w_small - w0)) < 1e-3 * np.mean(w0)
    assert np.ptp(w_big) < 0.5 * np.ptp(w0)  # tau = J s_r Ω_s / T_r ~ 5 s, a turn ~ 10 s
    for w in (w_small, w_big):
        assert _period(w) == pytest.approx(PERIOD, rel=1e-9)


def test_a_motor_too_small_for_the_torque_is_refused():
    law = MotorLaw("D", 1e3, 0.065)
    with pytest.raises(ConfigError) as ex:
        crank_speed_rad_s(law, 50e3 * (1.0 + np.sin(ANGLES)), SPM)
    assert ex.value.field == "surface.motor.rated_power_w" and "stalls above 2.75" in str(ex.value)


def test_crank_profile_times_and_angles():
    law = MotorLaw("D", 10e3, 0.08)
    p = CrankProfile(crank_speed_rad_s(law, 12e3 * (1.0 + np.sin(ANGLES)), SPM), PERIOD)
    theta, _omega = p.angle_and_speed(np.array([0.0, PERIOD, 2 * PERIOD, 0.25 * PERIOD]))
    assert theta[:3] == pytest.approx([0.0, 2 * np.pi, 4 * np.pi], abs=1e-9)
    t = np.linspace(0.0, PERIOD, 4001)
    th, om = p.angle_and_speed(t)
    assert np.max(np.abs(np.gradient(th, t)[1:-1] - om[1:-1])) < 2e-3 * np.mean(om)
    # a resampled torque on the grid is the same torque
    assert np.allclose(torque_on_grid(ANGLES[::-1], np.sin(ANGLES[::-1])), np.sin(ANGLES), atol=1e-12)


def _runs(name: str, motor: dict | None, strokes: int = 4):
    raw = read_raw(name)
    if motor is not None:
        raw = apply_overrides(raw, {"surface.motor": motor})
    sim = Simulator(config_from_dict(raw))
    return sim, sim.run_strokes(strokes)


def test_a_simulated_unit_driven_through_its_motor():
    """mark_ii_fig4_motor (7.5 hp NEMA D on the Mark II example): the crank speed varies through the stroke, its
    time mean is the SPM's, the polished rod still runs the unit's stroke, PPRL and the gearbox peak fall
    against constant speed, the crank power still balances the polished-rod power, and the first stroke (before
    any torque is known) is the constant-speed one bit for bit."""
    cfg = load_config("mark_ii_fig4_motor")
    assert cfg.surface.motor.nema_design == "D" and cfg.surface.motor.rated_power_w == 5593.0
    plain, rp = _runs("mark_ii_fig4", None)
    sim, rm = _runs("mark_ii_fig4_motor", None)
    assert np.array_equal(rm[0].trace["polished_rod_load_n"], rp[0].trace["polished_rod_load_n"])
    assert not np.array_equal(rm[-1].trace["polished_rod_load_n"], rp[-1].trace["polished_rod_load_n"])
    m = sim.surface.motor
    theta, omega = m.crank_of(sim.surface.unit, rm[-1])
    mean = 2 * math.pi * SPM / 60.0
    assert float(np.mean(omega)) == pytest.approx(mean, rel=2e-3)  # equal time steps: the time mean
    assert omega.min() < 0.97 * mean and omega.max() > 1.03 * mean
    assert rm[-1].duration_s == pytest.approx(PERIOD)
    stroke = sim.surface.unit.stroke_m
    assert np.ptp(rm[-1].trace["polished_rod_position_m"]) == pytest.approx(stroke, rel=1e-3)
    assert m.last_change_pct < 0.1  # two iterates of the motion agree within 1e-3 of the stroke
    pprl = [float(r[-1].trace["polished_rod_load_n"].max()) for r in (rp, rm)]
    assert pprl[1] < pprl[0]
    g_plain = plain.surface.gearbox_report(rp[-1:])
    g = sim.surface.gearbox_report(rm[-1:])
    assert g.peak_torque_nm < 0.97 * g_plain.peak_torque_nm
    assert np.array_equal(g.crank_angle_rad, theta)
    assert g.mean_crank_power_w == pytest.approx(g.mean_polished_rod_power_w, rel=5e-3)
    s = summarize(sim, rm[1:])["motor"]
    assert s["motor_counterbalance_source"] == "configured" and s["crank_speed_pct_of_mean"]["max_pct_of_mean"] > 103


def test_without_a_counterbalance_the_motor_meets_the_balanced_unit():
    """A configured moment of 0 is 'not given': the motor drives the unit balanced at each stroke's optimum."""
    sim, _rm = _runs("mark_ii_fig4", {"rated_power_w": 5593.0}, strokes=2)
    raw = apply_overrides(read_raw("mark_ii_fig4"), {"surface.beam_unit.counterbalance_moment_nm": 0.0,
                                                     "surface.motor": {"rated_power_w": 5593.0}})
    sim0 = Simulator(config_from_dict(raw))
    r0 = sim0.run_strokes(2)
    assert sim.surface.motor.summary()["motor_counterbalance_source"] == "configured"
    s0 = sim0.surface.motor.summary()
    assert s0["motor_counterbalance_source"] == "optimal"
    best = sim0.surface.gearbox_report(r0[-1:]).optimal_counterbalance_nm
    assert s0["motor_counterbalance_nm"] == pytest.approx(best, rel=0.05)


def test_a_motor_on_a_motion_without_cranks_is_refused():
    with pytest.raises(ConfigError) as ex:
        config_from_dict(apply_overrides(read_raw("default"), {"surface.motor": {"rated_power_w": 5000.0}}))
    assert ex.value.field == "surface.motor"
    with pytest.raises(ConfigError) as ex:
        config_from_dict(apply_overrides(read_raw("mark_ii_fig4"), {"surface.motor": {"rated_power_w": 5000.0,
                                                                                      "nema_design": "E"}}))
    assert ex.value.field == "surface.motor.nema_design"
