"""Nonmonotone laws (paper §3, Figs. 5-8) and the Hopf threshold of velocity weakening.

See docs/stick_slip.md.
"""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest

from srenv.analysis import metrics
from srenv.config import load_config
from srenv.errors import ConfigError
from srenv.simulation.hopf import (
    SpringBlock,
    find_hopf_velocity,
    hopf_velocity_m_s,
    rod_critical_slope_n_s_m,
    rod_hopf_velocity_m_s,
    rod_impedance_n_s_m,
)
from srenv.simulation.simulator import Simulator

FIG6 = "paper_fig6_nonmonotone"
FIG7 = "paper_fig7_pullout"
P0_N, PINF_N, V0_M_S = 11090.0, 7090.0, 1.0
SETTLE = 0.3  # the start transient excluded from pull-out counts, as in the acceptance check


def _upstroke_oscillation_n(overrides: list[str]) -> float:
    """Peak-to-peak of PRL minus its moving average over 1/f1, on the polished-rod upstroke of stroke 3
    (two strokes first, so the card is periodic rather than the start from static equilibrium)."""
    sim = Simulator(load_config(FIG6, overrides))
    tr = sim.run_strokes(3)[-1].trace
    up = tr["polished_rod_velocity_m_s"] > 0
    return metrics.load_oscillation_pp_n(tr["t_s"], tr["polished_rod_load_n"], 1.0 / sim.f1_hz, up)


def test_fig6_nonmonotone_law_intensifies_upstroke_vibration() -> None:
    nonmono = _upstroke_oscillation_n([])
    at_p0 = _upstroke_oscillation_n(["pump.law=constant"])
    at_pinf = _upstroke_oscillation_n(["pump.law=constant", f"pump.upstroke_load_n={PINF_N}"])
    print(f"\nFig. 6 upstroke PRL oscillation (N, peak-to-peak): nonmonotone {nonmono:.0f}, "
          f"P- = P0 {at_p0:.0f}, P- = P_inf {at_pinf:.0f}")
    # paper: "the nonmonotonicity of the friction law leads to intensification of vibrations". Measured
    # about 2.7x; 1.5x still fails if the weakening only nudged the card (both constant cases differ by 13 %).
    assert nonmono > 1.5 * max(at_p0, at_pinf)


def test_converged_dc_iterations_satisfy_the_law_exactly() -> None:
    """Sliding up, the plunger load is P_inf + (P0 - P_inf) exp(-|v|/v0); at rest it lies in [P+, P0]."""
    sim = Simulator(load_config(FIG6))
    tr = sim.run_strokes(2)[-1].trace
    v, load = tr["pump_velocity_m_s"], tr["pump_load_n"]
    up = v > 0
    law = PINF_N + (P0_N - PINF_N) * np.exp(-np.abs(v[up]) / V0_M_S)
    # DC tolerance 1e-10 m/s times the steepest slope 4e3 N*s/m = 4e-7 N; 1e-5 N leaves round-off room
    assert np.abs(load[up] - law).max() < 1e-5
    rest = v == 0.0
    assert rest.sum() > 0 and load[rest].max() <= P0_N + 1e-6 and load[rest].min() >= -3550.0 - 1e-6
    assert abs(sim.energy_balance()["residual_j"]) < 1e-6  # closes to round-off (work ~1e5 J per stroke)


def test_single_pass_is_the_papers_one_linearisation_per_step() -> None:
    single = Simulator(load_config(FIG6, ["simulation.dc_max_iterations=1"]))
    conv = Simulator(load_config(FIG6))
    r1, rc = single.run_strokes(2)[-1], conv.run_strokes(2)[-1]
    assert r1.dc_iterations == r1.n_steps and rc.dc_iterations > 2 * rc.n_steps
    # the lagged weakening term changes the details, not the card: PPRL within 5 %
    pprl_single, pprl_conv = (r.trace["polished_rod_load_n"].max() for r in (r1, rc))
    assert pprl_single == pytest.approx(pprl_conv, rel=0.05)


def test_dc_iterations_equal_with_and_without_solver_calls() -> None:
    """Both nonmonotone laws at once (pump and rod friction): the certified active-set path and the
    ProxSuite-every-sub-problem path give the same trajectory. Coarse mesh: the QP path is slow."""
    ov = ["simulation.element_length_m=100", "friction.law=nonmonotone", "friction.kinetic_coefficient=0.05",
          "friction.reference_velocity_m_s=0.1"]
    fast, ref = Simulator(load_config(FIG6, ov)), Simulator(load_config(FIG6, ov), always_qp=True)
    a, b = fast.run_stroke(), ref.run_stroke()
    assert b.qp_calls > b.n_steps  # several DC sub-problems per step went through the solver
    scale = np.abs(a.trace["polished_rod_load_n"]).max()
    assert np.abs(a.trace["polished_rod_load_n"] - b.trace["polished_rod_load_n"]).max() < 1e-8 * scale
    assert np.abs(a.trace["pump_velocity_m_s"] - b.trace["pump_velocity_m_s"]).max() < 1e-8
    for sim in (fast, ref):
        assert abs(sim.energy_balance()["residual_j"]) < 1e-6


def test_nonconvex_step_is_refused_by_default() -> None:
    steep = ["pump.reference_velocity_m_s=0.1"]  # slope (P0 - P_inf)/v0 = 4e4 N*s/m > condensed K*
    with pytest.raises(ConfigError, match="simulation.time_step_s.*not convex"):
        Simulator(load_config(FIG6, steep))


def test_nonconvex_step_warns_when_allowed_and_names_a_convex_time_step() -> None:
    steep = ["pump.reference_velocity_m_s=0.1", "simulation.nonconvex_step=warn"]
    with pytest.warns(UserWarning, match="not convex") as rec:
        sim = Simulator(load_config(FIG6, steep))
    dt_ok = float(str(rec[0].message).split("time step below ")[1].split(" s")[0])
    assert 0 < dt_ok < 0.005
    # still runs: DC iterations reach a stationary point of every step, energy closes
    sim.run_stroke()
    assert abs(sim.energy_balance()["residual_j"]) < 1e-6
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        Simulator(load_config(FIG6, steep + [f"simulation.time_step_s={0.95 * dt_ok}"]))
        Simulator(load_config(FIG6))  # the paper's law: 4e3 N*s/m is far below the condensed stiffness


def _pullout(speed_m_s: float, overrides: list[str] | None = None) -> tuple[Simulator, dict]:
    sim = Simulator(load_config(FIG7, overrides))
    return sim, sim.run_duration(60.0, speed_m_s).trace


def _late(tr: dict) -> np.ndarray:
    t = tr["t_s"]
    return t >= t[0] + SETTLE * (t[-1] - t[0])


def test_fig7_low_pulling_velocity_gives_periodic_stick_slip() -> None:
    sim, tr = _pullout(0.05)
    late = _late(tr)
    assert len(metrics.rest_episodes(tr["pump_velocity_m_s"][late])) >= 3
    # periodic du = u_B - u_A: the two halves of the late window have the same dominant frequency and
    # amplitude (measured equal to 0.1 %; 2 % / 10 % would still fail on a drifting or decaying cycle)
    t = tr["t_s"][late]
    du = (tr["polished_rod_position_m"] - tr["pump_position_m"])[late]
    h = len(t) // 2
    f1, f2 = (metrics.dominant_frequency_hz(t[s], du[s]) for s in (slice(None, h), slice(h, None)))
    a1, a2 = (metrics.slip_amplitude_m(t[s], du[s], 1 / sim.f1_hz) for s in (slice(None, h), slice(h, None)))
    assert f2 == pytest.approx(f1, rel=0.02) and a2 == pytest.approx(a1, rel=0.1) and a1 > 1e-3


def test_fig8_high_pulling_velocity_stops_sticking() -> None:
    sim, tr = _pullout(10.0)
    late = _late(tr)
    assert len(metrics.rest_episodes(tr["pump_velocity_m_s"][late])) == 0
    last = tr["t_s"] >= tr["t_s"][-1] - 10.0  # the start transient has decayed (rate ~0.2 1/s)
    du = tr["polished_rod_position_m"] - tr["pump_position_m"]
    assert metrics.slip_amplitude_m(tr["t_s"][last], du[last], 1 / sim.f1_hz) < 1e-3


# ----------------------------------------------------------------------------------------------- Hopf
def test_hopf_velocity_formula_edge_cases() -> None:
    assert hopf_velocity_m_s(4000.0, 1.0, 500.0) == pytest.approx(math.log(8.0))
    assert hopf_velocity_m_s(4000.0, 1.0, 4000.0) == 0.0  # slope never exceeds the damper
    assert hopf_velocity_m_s(0.0, 1.0, 500.0) == 0.0


def test_spring_block_through_the_kernel_recovers_the_hopf_velocity() -> None:
    """Bisection on growth/decay of a small kick around steady sliding, each run by kernel.advance."""
    block = SpringBlock(mass_kg=10.0, stiffness_n_m=7.5e4, damping_n_s_m=500.0, static_force_n=P0_N,
                        kinetic_force_n=PINF_N, reference_velocity_m_s=V0_M_S)
    analytic = math.log((P0_N - PINF_N) / (V0_M_S * 500.0)) * V0_M_S  # ln(c_v (C0 - C)/b)/c_v
    found = find_hopf_velocity(block, 0.5 * analytic, 2.0 * analytic)
    print(f"\nspring-block Hopf velocity: simulated {found:.4f} m/s, analytic {analytic:.4f} m/s")
    # requirement 5 %; the trapezoidal rule keeps the stability boundary exactly, so what is left is the
    # 0.1 % bisection tolerance and the tiny nonlinearity of the 1e-4 V kick: 1 % is already generous
    assert found == pytest.approx(analytic, rel=0.01)


def test_spring_block_hopf_point_is_subcritical() -> None:
    """Above v_H steady sliding is stable to small kicks only: a large one lands on a stick-slip cycle
    (the effective damping b + F'(V) + F'''(V) A^2/8 falls with the amplitude A since F''' < 0). This is
    why the bisection kicks by 1e-4 V."""
    block = SpringBlock(10.0, 7.5e4, 500.0, P0_N, PINF_N, V0_M_S)
    speed = 1.1 * block.hopf_velocity_m_s
    period_s = 2 * math.pi * math.sqrt(10.0 / 7.5e4)
    _, small = block.simulate(speed, 80 * period_s, period_s / 80, 1e-4 * speed)
    _, large = block.simulate(speed, 80 * period_s, period_s / 80, 0.9 * speed)
    last = slice(-10 * 80, None)  # the last 10 periods
    assert np.abs(small[last] - speed).max() < 1e-9 * speed  # decayed by > 1e5 from the 1e-4 V kick
    assert np.sum(large[last] == 0.0) > 10  # sticks (velocity exactly 0) in the final periods


def test_rod_threshold_lies_between_lumped_estimate_and_simulation() -> None:
    """The lumped estimate (b = Z) says the paper's law can never destabilise the string (slope 4e3 < Z);
    the FE string's modes, reflected at the top, go unstable at a far smaller slope, and pull-outs a
    little below / above the resulting Hopf velocity do / do not stick."""
    sim = Simulator(load_config(FIG7))
    z = rod_impedance_n_s_m(sim)
    assert z == pytest.approx(math.sqrt(2e11 * 7800) * math.pi / 4 * 0.019 ** 2, rel=1e-12)
    assert rod_hopf_velocity_m_s(sim, z) == 0.0
    s_crit = rod_critical_slope_n_s_m(sim)
    assert s_crit < 0.05 * z
    v_h = rod_hopf_velocity_m_s(sim)
    _, below = _pullout(0.8 * v_h)
    _, above = _pullout(1.1 * v_h)
    assert len(metrics.rest_episodes(below["pump_velocity_m_s"][_late(below)])) >= 3
    assert len(metrics.rest_episodes(above["pump_velocity_m_s"][_late(above)])) == 0
