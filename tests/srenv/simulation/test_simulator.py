"""Simulator core against analytic solutions, refined runs and independent QP solvers."""

from __future__ import annotations

import copy
import math

import numpy as np
import pytest

from srenv.analysis import metrics
from srenv.config import load_config
from srenv.physics.pump import ValveLaw
from srenv.physics.rod import GRAVITY_M_S2
from srenv.simulation.simulator import Simulator, concat_traces

UNIFORM_ROD = {
    "rod": {"tapers": [{"diameter_mm": 19.0, "length_m": 1000.0, "youngs_modulus_pa": 2.0e11,
                        "density_kg_m3": 7800.0}]},
    "damping": {"model": "none"},
    "fluid": {"density_kg_m3": 0.0},
    "simulation": {"element_length_m": 10.0, "time_step_s": 0.002},
}


def _flat(d: dict, prefix: str = "") -> dict:
    out = {}
    for k, v in d.items():
        key = f"{prefix}{k}"
        if isinstance(v, dict):
            out.update(_flat(v, key + "."))
        else:
            out[key] = v
    return out


def _config(base: str, extra: dict):
    return load_config(base, _flat(extra))


def test_static_stretch_of_tapered_rod_matches_analytic() -> None:
    """Hanging tapered rod in liquid, plunger holding P+: bottom displacement = int N_eq/(EA) dx."""
    cfg = load_config("paper_fig3_vertical", {"simulation.element_length_m": 50.0})
    sim = Simulator(cfg)
    rho_f = cfg.fluid.density_kg_m3
    tapers = cfg.rod.tapers
    p_pump = rho_f * GRAVITY_M_S2 * cfg.rod_length_m
    a_bottom = math.pi / 4 * (tapers[-1].diameter_mm * 1e-3) ** 2
    n_eq = cfg.pump.downstroke_load_n + p_pump * a_bottom  # equivalent force at the rod end
    stretch = 0.0
    for t in reversed(tapers):  # integrate bottom-up: N_eq grows by the buoyed weight
        area = math.pi / 4 * (t.diameter_mm * 1e-3) ** 2
        w_b = (t.density_kg_m3 - rho_f) * GRAVITY_M_S2 * area
        stretch += (n_eq * t.length_m + 0.5 * w_b * t.length_m ** 2) / (t.youngs_modulus_pa * area)
        n_eq += w_b * t.length_m
    assert sim.u[-1] == pytest.approx(stretch, rel=5e-3)
    # the static state is an equilibrium of the dynamic scheme: a second with the top held still
    # leaves the plunger stuck and the string at rest
    r = sim.run_velocity(np.zeros(200), 0.005)
    assert np.all(r.trace["pump_velocity_m_s"] == 0.0)
    assert sim.u[-1] == pytest.approx(stretch, rel=5e-3)
    # polished-rod load = N_eq at the top (wellhead pressure 0): whole buoyed weight + P+_eq
    assert r.trace["polished_rod_load_n"][-1] == pytest.approx(n_eq, rel=1e-6)


def _zero_crossing_period(t: np.ndarray, x: np.ndarray) -> float:
    x = x - 0.5 * (x.max() + x.min())
    idx = np.flatnonzero((x[:-1] < 0) & (x[1:] >= 0))
    tc = t[idx] - x[idx] * (t[idx + 1] - t[idx]) / (x[idx + 1] - x[idx])  # linear interpolation
    return float(np.mean(np.diff(tc)))


def test_first_natural_frequency_uniform_rod_free_vibration() -> None:
    """Top fixed, bottom free: a step in the end load rings the string at f1 = a / 4L (within 1 %)."""
    cfg = _config("paper_fig3_vertical", UNIFORM_ROD)
    sim = Simulator(cfg)
    sim.law = ValveLaw(5000.0, 5000.0)  # a constant end load: no valve switching, a free end
    dt = cfg.simulation.time_step_s
    r = sim.run_velocity(np.zeros(int(8.0 / dt)), dt)
    a = math.sqrt(2.0e11 / 7800.0)
    f_analytic = a / (4 * 1000.0)
    f_sim = 1.0 / _zero_crossing_period(r.trace["t_s"], r.trace["pump_position_m"])
    assert f_sim == pytest.approx(f_analytic, rel=0.01)
    assert sim.f1_hz == pytest.approx(f_analytic, rel=0.01)


def test_coulomb_damped_oscillator_decrement_and_stop() -> None:
    """One stiff element + heavy end mass = 1-DOF oscillator; the plunger law [P+, P-] = [-F, F] is Coulomb
    friction. Amplitude drops by 4F/k per cycle and the mass stops where the analytic solution says."""
    length, d_mm, mass_kg, f_n = 10.0, 19.0, 500.0, 5000.0
    area = math.pi / 4 * (d_mm * 1e-3) ** 2
    extra = 2 * mass_kg / length - 7800.0 * area  # smeared so the bottom node carries mass_kg
    cfg = _config("paper_fig3_vertical", {
        "rod": {"tapers": [{"diameter_mm": d_mm, "length_m": length, "density_kg_m3": 7800.0,
                            "coupling_mass_kg_per_m": extra}]},
        "damping": {"model": "none"}, "fluid": {"density_kg_m3": 0.0},
        "pump": {"upstroke_load_n": f_n, "downstroke_load_n": -f_n},
        "simulation": {"element_length_m": length, "time_step_s": 2e-4},
    })
    sim = Simulator(cfg)
    k = 2.0e11 * area / length
    u_free = sim._f_all[-1] / k  # equilibrium of the frictionless spring under the node's weight
    x0 = 0.02
    sim.u[-1] = u_free + x0
    r = sim.run_velocity(np.zeros(int(0.6 / 2e-4)), 2e-4)
    x = -r.trace["pump_position_m"] - u_free  # displacement from the frictionless equilibrium
    v = r.trace["pump_velocity_m_s"]
    # turning points: where the direction of motion changes (a reversal may or may not include samples
    # of exact rest, depending on where in a time step the velocity crosses zero)
    direction = np.sign(v)
    moving = np.flatnonzero(direction != 0)
    flips = moving[1:][direction[moving[1:]] != direction[moving[:-1]]]
    turning = x[flips - 1]
    # analytic: |X_n| = x0 - 2 n F/k while |X_n| > F/k, then it stays
    step = 2 * f_n / k
    expected, xn, sign = [], x0, -1.0
    while xn > f_n / k:
        xn -= step
        expected.append(sign * xn)
        sign = -sign
    # every half cycle but the last ends in a reversal; the last ends in the final rest
    assert len(turning) == len(expected) - 1
    np.testing.assert_allclose(turning, expected[:-1], rtol=0.01, atol=1e-3 * step)
    decrement = abs(turning[0]) - abs(turning[2])
    assert decrement == pytest.approx(4 * f_n / k, rel=0.01)
    last_motion = moving[-1]
    assert last_motion < len(v) - 100 and np.all(v[last_motion + 1:] == 0.0), "the mass must stay stuck"
    assert x[-1] == pytest.approx(expected[-1], rel=0.01)


@pytest.fixture(scope="module")
def fig3_stroke() -> dict:
    sim = Simulator(load_config("paper_fig3_vertical"))
    res = sim.run_strokes(3)
    return res[-1].trace


def test_fig3_card_four_segments(fig3_stroke: dict) -> None:
    tr = fig3_stroke
    x = tr["polished_rod_position_m"]
    assert np.ptp(x) == pytest.approx(2.4, rel=1e-3)
    rests = [(i0, i1) for i0, i1 in metrics.rest_episodes(tr["pump_velocity_m_s"]) if i1 - i0 >= 20]
    load = tr["pump_load_n"]
    # the plunger is exactly at rest over finite intervals, during which the pump load travels between
    # the two valve loads: up at the bottom reversal, down at the top
    transfers = [(load[max(i0 - 1, 0)], load[min(i1 + 1, len(load) - 1)]) for i0, i1 in rests]
    assert any(a == pytest.approx(-2200, abs=1) and b == pytest.approx(9500, abs=1) for a, b in transfers)
    assert any(a == pytest.approx(9500, abs=1) and b == pytest.approx(-2200, abs=1) for a, b in transfers)
    moving = tr["pump_velocity_m_s"] != 0.0
    up, down = moving & (tr["pump_velocity_m_s"] > 0), moving & (tr["pump_velocity_m_s"] < 0)
    assert np.allclose(load[up], 9500.0) and np.allclose(load[down], -2200.0)
    assert up.sum() > 100 and down.sum() > 100


def test_fig4_stick_slip_rings_at_natural_frequency() -> None:
    sim = Simulator(load_config("paper_fig4_deviated"))
    res = sim.run_strokes(3)
    tr = concat_traces(res)
    t, v, prl = tr["t_s"], tr["pump_velocity_m_s"], tr["polished_rod_load_n"]
    all_rests = metrics.rest_episodes(v)
    assert len(all_rests) > 6, "stick-slip: more rests than the two valve reversals per stroke"
    # the valve transitions: the two longest rests of each stroke (load transfer P+ <-> P-)
    period = 60.0 / sim.cfg.surface.spm
    rests = []
    for k in range(3):
        in_stroke = [r for r in all_rests if k * period <= t[r[0]] < (k + 1) * period]
        rests += sorted(in_stroke, key=lambda r: r[1] - r[0])[-2:]
    window = 2.5 / sim.f1_hz
    freqs = []
    for _, i1 in rests:
        sel = (t > t[i1]) & (t <= t[i1] + window)
        if t[i1] + window > t[-1]:
            continue
        # remove the slow stroke-frequency part with a quadratic fit before the FFT
        tt, yy = t[sel], prl[sel]
        yy = yy - np.polyval(np.polyfit(tt, yy, 2), tt)
        freqs.append(metrics.dominant_frequency_hz(tt, yy, fmin_hz=0.5))
    assert len(freqs) >= 4
    np.testing.assert_allclose(freqs, sim.f1_hz, rtol=0.10)


@pytest.mark.parametrize("solver", ["osqp", "clarabel"])
def test_qp_backends_agree_on_fig4(solver: str) -> None:
    cfg = load_config("paper_fig4_deviated")
    ref = concat_traces(Simulator(cfg, always_qp=True).run_strokes(1))["polished_rod_load_n"]
    other = concat_traces(Simulator(cfg, always_qp=True, qp_solver=solver).run_strokes(1))["polished_rod_load_n"]
    assert np.max(np.abs(other - ref)) / np.max(np.abs(ref)) < 1e-6


def test_certified_reuse_equals_always_qp() -> None:
    cfg = load_config("paper_fig4_deviated")
    a_sim, b_sim = Simulator(cfg), Simulator(cfg, always_qp=True)
    a = a_sim.run_strokes(2)
    b = b_sim.run_strokes(2)
    la, lb = concat_traces(a)["polished_rod_load_n"], concat_traces(b)["polished_rod_load_n"]
    assert np.max(np.abs(la - lb)) / np.max(np.abs(la)) < 1e-8
    assert sum(r.qp_calls for r in a) < 0.05 * sum(r.n_steps for r in a)
    assert sum(r.qp_steps for r in b) == sum(r.n_steps for r in b)


def test_raw_proxqp_solution_agrees_without_polishing() -> None:
    """The QP's own answer, before the exact active-set polish, already matches to its tolerance."""
    cfg = load_config("paper_fig4_deviated")
    ref = Simulator(cfg)
    raw = Simulator(cfg, always_qp=True)
    raw.polish = False
    la = concat_traces(ref.run_strokes(1))["polished_rod_load_n"]
    lb = concat_traces(raw.run_strokes(1))["polished_rod_load_n"]
    assert np.max(np.abs(la - lb)) / np.max(np.abs(la)) < 1e-6


@pytest.mark.parametrize("name", ["paper_fig3_vertical", "paper_fig4_deviated"])
def test_halving_time_step_changes_pprl_below_one_percent(name: str) -> None:
    def pprl(dt: float) -> float:
        cfg = load_config(name, {"simulation.time_step_s": dt})
        return float(concat_traces(Simulator(cfg).run_strokes(3)[1:])["polished_rod_load_n"].max())

    dt = load_config(name).simulation.time_step_s
    assert abs(pprl(dt / 2) - pprl(dt)) / pprl(dt / 2) < 0.01


def test_switch_config_to_gas_acts_like_a_well_built_with_gas():
    """A chamber switched on at a stroke boundary (a gas slug in v2) runs the gas law in the kernel, as a well built
    with it does; its rod must stay the same (a new string is a new Simulator)."""
    base = load_config("default")
    gas = load_config(base, {"pump.intake_gas_fraction": 0.5})
    built = Simulator(gas)
    for _ in range(4):
        ref = built.run_stroke(record=True)
    switched = Simulator(base)
    switched.run_strokes(2)
    full = switched.run_stroke(record=True)
    switched.switch_config(gas)
    for _ in range(4):
        got = switched.run_stroke(record=True)
    assert got.fillage == pytest.approx(ref.fillage, abs=0.01) and got.fillage < full.fillage - 0.1
    n = min(len(got.trace["pump_load_n"]), len(ref.trace["pump_load_n"]))
    span = np.ptp(ref.trace["pump_load_n"])
    assert np.abs(got.trace["pump_load_n"][:n] - ref.trace["pump_load_n"][:n]).max() < 0.05 * span
    with pytest.raises(ValueError, match="rod string"):
        switched.switch_config(load_config(base, {"rod.tapers.0.diameter_mm": base.rod.tapers[0].diameter_mm + 1.0}))


def test_fast_forward_can_draw_at_the_upstrokes_end_like_an_exact_stroke():
    """v2's fast-forward draws a stroke's liquid when the upstroke ends, as an exact stroke does: the downstroke's
    inflow is then in the annulus at the bottom (v1's draws at the stroke's end and leaves it empty)."""
    sim = Simulator(load_config("default"))
    sim.run_strokes(2)
    period = 60.0 / sim.surface.default_spm(sim.cfg.surface.spm)
    up = sim.upstroke_s(period)
    assert 0.0 < up < period
    states = []
    for draw_at in (None, sim.time_s + up):
        s = copy.deepcopy(sim)
        s.annulus.accumulate(s.time_s)
        s.annulus.volume_m3 = 0.0  # a pumped-off well: what the pump draws is what flowed in
        q = s.annulus.inflow_m3_s()
        t0 = s.time_s
        taken = s.fast_forward(t0 + period, 1.0, draw_at)  # a displacement larger than any inflow
        states.append((taken, s.annulus.volume_m3, q))
    (taken_end, left_end, q), (taken_top, left_top, _) = states
    assert left_end == 0.0 and taken_end == pytest.approx(q * period, rel=1e-3)
    assert taken_top == pytest.approx(q * up, rel=1e-3) and left_top == pytest.approx(q * (period - up), rel=1e-3)
