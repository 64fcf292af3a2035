"""Unit tests of srenv.analysis.metrics against constructed traces with analytic answers."""

from __future__ import annotations

import math

import numpy as np
import pytest

from srenv.analysis.metrics import (
    ROD_GRADE_TENSILE_PA,
    card_metrics,
    count_stick_episodes_per_node,
    dominant_frequency_hz,
    goodman_loading_pct,
    goodman_smax_ratio_pct,
    load_oscillation_pp_n,
    plunger_extra_stick_episodes,
    production_m3_day,
    pump_stroke_m,
    resample_card,
    rest_episodes,
    slip_amplitude_m,
    stick_slip_index,
    taper_stress_range,
)

STROKE_PERIOD_S = 10.0  # 6 SPM, the paper's drive
DT_S = 0.01


# ----------------------------------------------------------------------------------------------------
# rest episodes
# ----------------------------------------------------------------------------------------------------
def test_rest_episodes_known_runs_including_edges_and_singletons() -> None:
    v = np.array([0.0, 0.0, 0.3, 0.0, -0.2, 0.0, 0.0, 0.0, 0.1, 1e-13, 0.0, -1e-11, 0.5, 0.0, 0.0])
    # runs of |v| <= 1e-12: [0,1], [3] (single), [5,7], [9,10] (1e-13 counts as rest), [13,14]; 1e-11 breaks.
    assert rest_episodes(v) == [(0, 1), (5, 7), (9, 10), (13, 14)]
    assert rest_episodes(v, min_steps=1) == [(0, 1), (3, 3), (5, 7), (9, 10), (13, 14)]
    assert rest_episodes(v, min_steps=3) == [(5, 7)]
    assert rest_episodes(v, tol=1e-10) == [(0, 1), (5, 7), (9, 11), (13, 14)]


def test_rest_episodes_degenerate_traces() -> None:
    assert rest_episodes(np.array([])) == []
    assert rest_episodes(np.ones(5)) == []
    assert rest_episodes(np.zeros(4)) == [(0, 3)]
    with pytest.raises(ValueError, match="min_steps"):
        rest_episodes(np.zeros(4), min_steps=0)


def _loop_episode_counts(stuck: np.ndarray, min_steps: int) -> np.ndarray:
    counts = np.zeros(stuck.shape[1], dtype=int)
    for j in range(stuck.shape[1]):
        run = 0
        for s in [*stuck[:, j], False]:
            if s:
                run += 1
                continue
            counts[j] += run >= min_steps
            run = 0
    return counts


@pytest.mark.parametrize("min_steps", [1, 2, 3])
@pytest.mark.parametrize("p_stuck", [0.2, 0.5, 0.9])
def test_count_per_node_matches_loop_reference(min_steps: int, p_stuck: float) -> None:
    rng = np.random.default_rng(12345)
    stuck = rng.random((300, 9)) < p_stuck
    stuck[:, 0] = True  # one run spanning the whole trace
    stuck[:, 1] = False
    expected = _loop_episode_counts(stuck, min_steps)
    assert expected[0] == 1
    assert expected[1] == 0
    np.testing.assert_array_equal(count_stick_episodes_per_node(stuck, min_steps), expected)


# ----------------------------------------------------------------------------------------------------
# stick-slip index
# ----------------------------------------------------------------------------------------------------
def _clean_plunger_velocity(n_strokes: float) -> tuple[np.ndarray, np.ndarray]:
    """Harmonic plunger velocity held at exactly 0 around each reversal: two rests per stroke."""
    t = np.arange(0.0, n_strokes * STROKE_PERIOD_S, DT_S)
    v = 0.5 * np.cos(2.0 * np.pi * t / STROKE_PERIOD_S)  # zeros at T/4, 3T/4, ...: all inside the trace
    v[np.abs(v) < 0.1] = 0.0
    return t, v


def test_stick_slip_index_exactly_zero_for_clean_trace() -> None:
    t, v = _clean_plunger_velocity(3)
    assert len(rest_episodes(v)) == 6
    du = 0.3 + 0.01 * t  # smooth Δu (steady stretch drift): nothing oscillates about its moving average
    rod_counts = np.full(12, 6)  # every rod node rests at the 6 reversals only
    result = stick_slip_index(t, v, du, rod_counts, n_strokes=3, window_s=0.7)
    assert result == {
        "plunger_stick_episodes": 6,
        "plunger_extra_stick_episodes": 0,
        "rod_extra_stick_episodes": 0,
        "slip_amplitude_m": 0.0,
        "stick_slip_index": 0.0,
    }


def test_stick_slip_index_grows_with_extra_rests_and_sawtooth_slip() -> None:
    t, v = _clean_plunger_velocity(3)
    for t_stick_s in (0.5, 15.3):  # mid-stroke, where the clean plunger moves fast
        v[(t >= t_stick_s) & (t < t_stick_s + 0.2)] = 0.0
    saw_period_s = 0.5
    saw_pp_m = 0.01
    du = 0.3 + 0.01 * t + saw_pp_m * ((t / saw_period_s) % 1.0)
    rod_counts = np.array([6, 6, 7, 9, 6, 6, 6, 6, 6, 6])  # 1 + 3 extra episodes on 10 nodes
    result = stick_slip_index(t, v, du, rod_counts, n_strokes=3, window_s=saw_period_s, slip_reference_m=0.01)
    assert result["plunger_extra_stick_episodes"] == 2
    assert result["rod_extra_stick_episodes"] == 4
    assert result["slip_amplitude_m"] == pytest.approx(0.5 * saw_pp_m, rel=0.05)
    expected_index = 2 + 4 / 10 + result["slip_amplitude_m"] / 0.01
    assert result["stick_slip_index"] == pytest.approx(expected_index, rel=1e-12)
    # a floor above the slip amplitude removes only the slip term
    floored = stick_slip_index(t, v, du, rod_counts, 3, saw_period_s, slip_floor_m=0.01)
    assert floored["stick_slip_index"] == pytest.approx(2.4, rel=1e-12)


def test_partial_stroke_allowance_rounds_up() -> None:
    _, v = _clean_plunger_velocity(2.5)  # reversals at 0.25, 0.75, ..., 2.25 strokes: five rests
    assert len(rest_episodes(v)) == 5
    assert plunger_extra_stick_episodes(v, n_strokes=2.5) == 0
    assert plunger_extra_stick_episodes(v, n_strokes=2.0) == 1
    # round-off in duration * spm / 60 must not buy an extra allowance
    _, v3 = _clean_plunger_velocity(3)
    v3[(np.arange(v3.size) >= 50) & (np.arange(v3.size) < 60)] = 0.0
    assert plunger_extra_stick_episodes(v3, n_strokes=0.1 * 3 * 10) == 1  # 3.0000000000000004
    # pull-out: no reversals, every rest is extra
    assert plunger_extra_stick_episodes(v, n_strokes=0) == 5


# ----------------------------------------------------------------------------------------------------
# slip amplitude and load oscillation
# ----------------------------------------------------------------------------------------------------
def test_slip_amplitude_of_sine_on_ramp() -> None:
    natural_period_s = 0.68
    t = np.arange(0.0, 30.0, 1e-3)
    du = 0.02 * np.sin(2.0 * np.pi * t / natural_period_s) - 0.05 * t + 0.4
    assert slip_amplitude_m(t, du, natural_period_s) == pytest.approx(0.02, rel=0.02)
    assert slip_amplitude_m(t, -0.05 * t + 0.4, natural_period_s) == 0.0


def test_slip_amplitude_rejects_bad_sampling() -> None:
    t = np.array([0.0, 0.1, 0.3, 0.4, 0.5, 0.6, 0.7])
    with pytest.raises(ValueError, match="uniformly"):
        slip_amplitude_m(t, np.zeros(7), 0.2)
    with pytest.raises(ValueError, match="shorter"):
        slip_amplitude_m(np.arange(5.0), np.zeros(5), 10.0)


def test_load_oscillation_pp_with_mask_and_edges() -> None:
    natural_period_s = 0.7
    t = np.arange(0.0, 20.0, 1e-3)
    upstroke = t < 10.0
    amplitude_n = np.where(upstroke, 500.0, 200.0)
    load = 20e3 + 300.0 * t + amplitude_n * np.sin(2.0 * np.pi * t / natural_period_s)
    assert load_oscillation_pp_n(t, load, natural_period_s) == pytest.approx(1000.0, rel=0.01)
    # a ramp is its own moving average; truncated averages at the edges would show up as a large residual
    assert load_oscillation_pp_n(t, 20e3 + 300.0 * t, natural_period_s) < 1e-6
    assert load_oscillation_pp_n(t, load, natural_period_s, mask=upstroke) == pytest.approx(1000.0, rel=0.01)
    settled_downstroke = t > 10.0 + natural_period_s  # the average straddles the switch for half a window
    assert load_oscillation_pp_n(t, load, natural_period_s, mask=settled_downstroke) == pytest.approx(
        400.0, rel=0.01
    )


# ----------------------------------------------------------------------------------------------------
# stresses and Goodman
# ----------------------------------------------------------------------------------------------------
def test_goodman_hand_computation_19mm_grade_d() -> None:
    # Hand computation: A = pi/4 * 0.019^2 = 2.835287e-4 m^2; S_max = 40 kN / A = 141.0792 MPa;
    # S_min = 15 kN / A = 52.9047 MPa; T = 115 ksi = 792.897 MPa;
    # S_A = 792.897/4 + 0.5625 * 52.9047 = 198.2243 + 29.7589 = 227.9832 MPa;
    # range form: (141.0792 - 52.9047) / (227.9832 - 52.9047) = 88.1745 / 175.0785 = 50.363 %;
    # S_max form: 141.0792 / 227.9832 = 61.881 %.
    area_m2 = math.pi / 4 * 0.019**2
    stresses = taper_stress_range(40e3, 15e3, area_m2)
    assert stresses["max_stress_pa"] == pytest.approx(141.0792e6, rel=1e-5)
    assert stresses["min_stress_pa"] == pytest.approx(52.9047e6, rel=1e-5)
    assert stresses["stress_range_pa"] == pytest.approx(88.1745e6, rel=1e-5)
    t_pa = ROD_GRADE_TENSILE_PA["D"]
    assert t_pa == pytest.approx(792.897e6, rel=1e-6)
    s_max, s_min = stresses["max_stress_pa"], stresses["min_stress_pa"]
    assert goodman_loading_pct(s_max, s_min, t_pa) == pytest.approx(50.363, abs=2e-3)
    assert goodman_smax_ratio_pct(s_max, s_min, t_pa) == pytest.approx(61.881, abs=2e-3)
    # service factor 0.9: S_A = 205.1849 MPa -> (88.1745) / (205.1849 - 52.9047) = 57.903 %
    assert goodman_loading_pct(s_max, s_min, t_pa, service_factor=0.9) == pytest.approx(57.903, abs=2e-3)


def test_goodman_vectorised_over_tapers_and_limits() -> None:
    area_m2 = np.pi / 4 * np.array([0.025, 0.022, 0.019]) ** 2
    stresses = taper_stress_range(np.array([52e3, 45e3, 40e3]), np.array([20e3, 17e3, 15e3]), area_m2)
    t_pa = np.array([ROD_GRADE_TENSILE_PA[g] for g in "DKC"])
    s_max, s_min = stresses["max_stress_pa"], stresses["min_stress_pa"]
    scalars = [goodman_loading_pct(s_max[i], s_min[i], t_pa[i]) for i in range(3)]
    np.testing.assert_allclose(goodman_loading_pct(s_max, s_min, t_pa), scalars, rtol=1e-14)
    assert ROD_GRADE_TENSILE_PA["C"] == pytest.approx(620.5e6, rel=1e-4)
    assert ROD_GRADE_TENSILE_PA["K"] == pytest.approx(586.1e6, rel=1e-4)
    # both forms read 100 % when S_max reaches S_A
    s_min = 60e6
    s_a = ROD_GRADE_TENSILE_PA["K"] / 4 + 0.5625 * s_min
    assert goodman_loading_pct(s_a, s_min, ROD_GRADE_TENSILE_PA["K"]) == pytest.approx(100.0)
    assert goodman_smax_ratio_pct(s_a, s_min, ROD_GRADE_TENSILE_PA["K"]) == pytest.approx(100.0)
    # no allowable range left (S_min >= S_A): overloaded
    assert goodman_loading_pct(500e6, 400e6, ROD_GRADE_TENSILE_PA["C"]) == math.inf


# ----------------------------------------------------------------------------------------------------
# cards, pump stroke, production
# ----------------------------------------------------------------------------------------------------
def _rectangle_card(stroke_m: float, load_hi_n: float, load_lo_n: float, n_side: int = 50) -> tuple:
    up = np.linspace(0.0, stroke_m, n_side)
    pick_up = np.linspace(load_lo_n, load_hi_n, n_side)
    position = np.concatenate((np.zeros(n_side), up, np.full(n_side, stroke_m), up[::-1]))
    load = np.concatenate((pick_up, np.full(n_side, load_hi_n), pick_up[::-1], np.full(n_side, load_lo_n)))
    return position, load


PARALLELOGRAM = (2.4, 0.6, 12e3, 30e3)  # stroke (m), rod stretch (m), low and high load (N)


def _parallelogram_card(n_per_leg: int) -> np.ndarray:
    """Ideal card (position, load) rows: pick-up over the stretch, upstroke, release, downstroke."""
    stroke_m, stretch_m, lo_n, hi_n = PARALLELOGRAM
    vertices = np.array([[0.0, lo_n], [stretch_m, hi_n], [stroke_m, hi_n], [stroke_m - stretch_m, lo_n]])
    legs = [np.linspace(vertices[i], vertices[(i + 1) % 4], n_per_leg, endpoint=False) for i in range(4)]
    return np.concatenate(legs)


def test_card_metrics_rectangle_area_and_sign() -> None:
    position, load = _rectangle_card(2.0, 40e3, 15e3)
    metrics = card_metrics(position, load)
    assert metrics["pprl_n"] == 40e3
    assert metrics["mprl_n"] == 15e3
    assert metrics["stroke_m"] == 2.0
    assert metrics["card_area_j"] == pytest.approx(25e3 * 2.0, rel=1e-12)  # clockwise: positive
    assert card_metrics(position[::-1], load[::-1])["card_area_j"] == pytest.approx(-50e3, rel=1e-12)
    # starting the trace mid-upstroke closes the same loop
    shifted = card_metrics(np.roll(position, -70), np.roll(load, -70))
    assert shifted["card_area_j"] == pytest.approx(50e3, rel=1e-12)


def test_card_area_of_sampled_parallelogram_is_exact() -> None:
    # slanted legs sampled coarsely: only the trapezoid rule integrates them exactly
    stroke_m, stretch_m, lo_n, hi_n = PARALLELOGRAM
    card = _parallelogram_card(3)
    area_j = card_metrics(card[:, 0], card[:, 1])["card_area_j"]
    assert area_j == pytest.approx((hi_n - lo_n) * (stroke_m - stretch_m), rel=1e-12)


def test_pump_stroke() -> None:
    t = np.linspace(0.0, STROKE_PERIOD_S, 1001)
    u_b = 0.3 - 0.8 * (1.0 - np.cos(2.0 * np.pi * t / STROKE_PERIOD_S))  # down-positive, 1.6 m of travel
    assert pump_stroke_m(u_b) == pytest.approx(1.6, rel=1e-12)


def test_production_hand_checked() -> None:
    # 1.5e-3 m^2 * 2 m * 6 /min * 1440 min/day * 0.8 * 0.9 = 18.6624 m^3/day
    assert production_m3_day(2.0, 1.5e-3, 6.0, 0.8, 0.9) == pytest.approx(18.6624, rel=1e-12)
    # oilfield rule Q[bbl/d] = 0.1166 * S[in] * N * D[in]^2 (full pump): 2 in plunger, 100 in stroke, 10 SPM
    q_bbl_day = 0.1166 * 100.0 * 10.0 * 2.0**2
    area_m2 = math.pi / 4 * (2.0 * 0.0254) ** 2
    q = production_m3_day(100.0 * 0.0254, area_m2, 10.0, 1.0)
    assert q == pytest.approx(q_bbl_day * 0.158987294928, rel=1e-3)


# ----------------------------------------------------------------------------------------------------
# dominant frequency
# ----------------------------------------------------------------------------------------------------
def test_dominant_frequency_decaying_noisy_sinusoid() -> None:
    f_hz = 1.46  # fig4 string's first natural frequency
    rng = np.random.default_rng(7)
    t = np.arange(0.0, 15.0, 2e-3)
    x = 800.0 * np.exp(-0.2 * t) * np.sin(2 * np.pi * f_hz * t + 0.4) + 20e3 + 50.0 * t
    x += 40.0 * rng.standard_normal(t.size)
    assert dominant_frequency_hz(t, x) == pytest.approx(f_hz, rel=0.01)


@pytest.mark.parametrize("phase", [0.0, 0.8, 1.6, 2.4])
def test_dominant_frequency_three_cycles(phase: float) -> None:
    f_hz = 1.46
    t = np.arange(0.0, 3.0 / f_hz, 5e-3)
    assert dominant_frequency_hz(t, np.sin(2 * np.pi * f_hz * t + phase)) == pytest.approx(f_hz, rel=0.01)


@pytest.mark.parametrize("f_hz", [1.30, 1.4433, 1.46])
def test_dominant_frequency_interpolates_between_bins(f_hz: float) -> None:
    # 7.3 s record: padded bins 1/(65536 * 2 ms) = 7.6 mHz (0.5 % of f) apart; the refinement does the rest
    t = np.arange(0.0, 7.3, 2e-3)
    assert dominant_frequency_hz(t, np.sin(2 * np.pi * f_hz * t + 0.3)) == pytest.approx(f_hz, rel=1e-4)


def test_dominant_frequency_fmin_skips_stroke_frequency() -> None:
    t = np.arange(0.0, 60.0, 1e-2)
    x = 5e3 * np.sin(2 * np.pi * 0.1 * t) + 300.0 * np.sin(2 * np.pi * 1.3 * t)
    assert dominant_frequency_hz(t, x) == pytest.approx(0.1, rel=0.01)
    assert dominant_frequency_hz(t, x, fmin_hz=0.5) == pytest.approx(1.3, rel=0.01)


# ----------------------------------------------------------------------------------------------------
# card resampling
# ----------------------------------------------------------------------------------------------------
def test_resample_parallelogram_card_gives_line_loads() -> None:
    stroke_m, stretch_m, lo_n, hi_n = PARALLELOGRAM
    card = _parallelogram_card(37)
    n_points = 25
    resampled = resample_card(card[:, 0] + 0.5, card[:, 1], n_points)  # offset: normalisation is relative
    x = np.linspace(0.0, 1.0, n_points) * stroke_m
    up = np.interp(x, [0.0, stretch_m, stroke_m], [lo_n, hi_n, hi_n])
    down = np.interp(x, [0.0, stroke_m - stretch_m, stroke_m], [lo_n, lo_n, hi_n])
    assert resampled.shape == (2 * n_points,)
    np.testing.assert_allclose(resampled, np.concatenate((up, down)), rtol=0, atol=1e-8)


def test_resample_card_never_nan() -> None:
    load = np.linspace(10e3, 20e3, 40)
    flat = resample_card(np.full(40, 1.2) + 1e-13 * np.arange(40), load, 10)
    np.testing.assert_array_equal(flat, np.full(20, 15e3))
    one_way = resample_card(np.linspace(0.0, 1.0, 40), load, 10)  # no down branch
    assert not np.isnan(one_way).any()
    np.testing.assert_allclose(one_way[:10], np.linspace(10e3, 20e3, 10))
    np.testing.assert_array_equal(one_way[10:], np.full(10, 15e3))
