"""The compiled per-stroke summary (srenv/analysis/stroke_pass.py) gives the values of the metrics functions it replaced.

The reference is the summary as it was computed before the one-pass version: the public metrics functions
(`metrics.card_metrics`, `metrics.stick_slip_index`, `pump_card.analyse_pump_card`, `metrics.goodman_loading_pct`)
composed as `stroke_summary.summarize` composed them, kept here only for this comparison.
"""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

import srenv  # noqa: F401 - registers the envs
from srenv.analysis import metrics
from srenv.analysis.pump_card import analyse_pump_card
from srenv.analysis.stroke_pass import pump_card_figures
from srenv.analysis.stroke_summary import SLIP_FLOOR_M, _card_class, _taper_top_data, slip_window_s, summarize
from srenv.config import load_config
from srenv.physics.inflow import SECONDS_PER_DAY
from srenv.simulation.simulator import Simulator, concat_traces

RTOL = 1e-12


def _reference_summary(sim: Simulator, results: list) -> dict:
    """The pre-change composition of the metrics functions (stroke_summary.summarize before stroke_pass)."""
    tr = results[0].trace if len(results) == 1 else concat_traces(results)
    n = len(results)
    card = metrics.card_metrics(tr["polished_rod_position_m"], tr["polished_rod_load_n"])
    last = metrics.card_metrics(results[-1].trace["polished_rod_position_m"], results[-1].trace["polished_rod_load_n"])
    pump_stroke = float(np.mean([metrics.pump_stroke_m(r.trace["pump_position_m"]) for r in results]))
    pump_card = analyse_pump_card(results[-1].trace["pump_position_m"], results[-1].trace["pump_load_n"])
    du = tr["polished_rod_position_m"] - tr["pump_position_m"]
    rod_eps = np.sum([r.rod_stick_episodes for r in results], axis=0)
    ss = metrics.stick_slip_index(tr["t_s"], tr["pump_velocity_m_s"], du, rod_eps, n,
                                  slip_window_s(tr["t_s"], sim.f1_hz), slip_floor_m=SLIP_FLOOR_M)
    fmax = np.max([r.element_force_max_eq_n for r in results], axis=0)
    fmin = np.min([r.element_force_min_eq_n for r in results], axis=0)
    e, area, shift, tensile = _taper_top_data(sim)
    s = metrics.taper_stress_range(fmax[e] - shift, fmin[e] - shift, area)
    goodman = np.atleast_1d(metrics.goodman_loading_pct(s["max_stress_pa"], s["min_stress_pa"], tensile))
    duration_s = sum(r.duration_s for r in results)
    ref = {
        "strokes": n, "spm": results[-1].spm, "pprl_n": card["pprl_n"], "mprl_n": card["mprl_n"],
        "last_stroke_pprl_n": last["pprl_n"], "last_stroke_mprl_n": last["mprl_n"],
        "polished_rod_stroke_m": card["stroke_m"], "pump_stroke_m": pump_stroke,
        "fillage": float(np.mean([r.fillage for r in results])),
        "card_class": pump_card["card_class"], "card_fillage": pump_card["fillage"],
        "production_m3_day": SECONDS_PER_DAY * sum(r.pumped_m3 for r in results) / duration_s,
        "duration_s": duration_s, "card_work_j_per_stroke": card["card_area_j"] / n,
        "goodman_pct": goodman.tolist(), "goodman_max_pct": float(goodman.max()),
        **{k: (float(v) if isinstance(v, float) else int(v)) for k, v in ss.items()},
        "intake_pressure_pa": results[-1].intake_pressure_pa,
    }
    gearbox = sim.surface.gearbox_report(results)
    if gearbox is not None:
        ref.update(gearbox.summary())
    return ref


def _assert_same(got: dict, ref: dict) -> None:
    for key, want in ref.items():
        have = got[key]
        assert type(have) is type(want), (key, type(have), type(want))
        if isinstance(want, str | int) and not isinstance(want, bool):
            assert have == want, (key, have, want)
        else:
            np.testing.assert_allclose(have, want, rtol=RTOL, atol=0.0, err_msg=key)


@pytest.mark.parametrize("name", ["paper_fig3_vertical", "paper_fig4_deviated", "paper_fig6_nonmonotone",
                                  "conventional_fig4"])
@pytest.mark.parametrize("strokes", [1, 3])
def test_summary_equals_the_metrics_functions(name: str, strokes: int) -> None:
    sim = Simulator(load_config(name))
    results = [sim.run_stroke(record=True) for _ in range(strokes)]
    _assert_same(summarize(sim, results), _reference_summary(sim, results))


def _reference_prescribed_card(x: np.ndarray, f: np.ndarray, n_points: int) -> np.ndarray:
    """metrics.resample_prescribed_card in numpy, as it was before it was compiled."""
    span_m = float(x.max() - x.min())
    if span_m <= 1e-9:
        return np.full(2 * n_points, float(f.mean()))
    p = (x - x.min()) / span_m
    top = int(np.argmax(p))
    grid = np.linspace(0.0, 1.0, n_points)
    return np.concatenate((np.interp(grid, p[: top + 1], f[: top + 1]), np.interp(grid, p[top:][::-1], f[top:][::-1])))


@pytest.mark.parametrize("name", ["paper_fig3_vertical", "paper_fig4_deviated", "conventional_fig4"])
def test_compiled_card_resampling_equals_numpy(name: str) -> None:
    sim = Simulator(load_config(name))
    for _ in range(2):
        tr = sim.run_stroke(record=True).trace
        x, f = tr["polished_rod_position_m"], tr["polished_rod_load_n"]
        for n_points in (8, 32):
            np.testing.assert_allclose(metrics.resample_prescribed_card(x, f, n_points),
                                       _reference_prescribed_card(x, f, n_points), rtol=RTOL, atol=0.0)
    flat = np.full(50, 0.3)
    np.testing.assert_allclose(metrics.resample_prescribed_card(flat, np.arange(50.0), 4), np.full(8, 24.5))


def _reference_obs(env, tr: dict, m: dict) -> np.ndarray:
    """The v0 observation as sucker_rod_v0._observe composed it before the one-pass summary."""
    c = env.cfg
    rating = c.reward.pprl_rating_n
    card = _reference_prescribed_card(tr["polished_rod_position_m"], tr["polished_rod_load_n"],
                                      env.card_points) / rating
    ctl = c.control

    def unit(x: float, lo: float, hi: float) -> float:
        return 2.0 * (x - lo) / (hi - lo) - 1.0 if hi > lo else 0.0

    tail = [unit(env._spm, ctl.spm_min, ctl.spm_max), unit(env._stroke, ctl.stroke_min_m, ctl.stroke_max_m),
            env.sim.annulus.level_m / 100.0, m["intake_pressure_pa"] / 1e7, m["fillage"], m["pprl_n"] / rating,
            m["goodman_max_pct"] / 100.0, m["stick_slip_index"] / 10.0]
    return np.clip(np.concatenate([card, tail]).astype(np.float32), -10.0, 10.0)


def test_env_steps_through_pump_off_keep_every_info_value() -> None:
    """A low-inflow well pumped fast pumps off (full -> fluid pound): every step's info and observation match
    the reference summary and observation."""
    env = gym.make("srenv/SuckerRod-v0", overrides={"inflow.initial_fluid_level_m": 0.5,
                                                   "inflow.max_rate_m3_day": 10.0}).unwrapped
    env.reset(seed=0, options={"randomize": False})
    run_stroke, results = env.sim.run_stroke, []

    def recorded(*args, **kw):
        results.append(run_stroke(*args, **kw))
        return results[-1]

    env.sim.run_stroke = recorded
    classes = set()
    for _ in range(8):
        results.clear()
        obs, _, _, _, info = env.step(np.ones(2, dtype=np.float32))
        ref = _reference_summary(env.sim, results)
        _assert_same(info, ref)
        np.testing.assert_allclose(obs, _reference_obs(env, results[-1].trace, ref), rtol=1e-6, atol=1e-7)
        classes.add(info["card_class"])
    assert {"full", "fluid_pound"} <= classes, classes


def _synthetic_card(rng: np.random.Generator, n: int, fill: float, spread: float, shift: int) -> tuple:
    """A pump card: up at the fluid load, down at 0 after a transfer at `fill` (spread over `spread` of the
    stroke), noise, the record starting `shift` samples into the stroke (downstroke wrapping round the end)."""
    phase = np.linspace(0.0, 2.0 * np.pi, n, endpoint=False)
    x = 0.5 * (1.0 - np.cos(phase))  # bottom -> top -> bottom
    down = phase > np.pi
    f = np.where(down, np.clip((x - fill + spread / 2) / max(spread, 1e-9), 0.0, 1.0), 1.0) * 2e4
    f += rng.normal(0.0, 50.0, n)
    return np.roll(x, -shift), np.roll(f, -shift)


@pytest.mark.parametrize("fill,spread,shift", [(0.0, 0.02, 0), (0.5, 0.02, 0), (0.5, 0.4, 0),
                                               (0.6, 0.02, 1500), (0.3, 0.3, 1900), (1.0, 0.02, 700)])
def test_pump_card_pass_reads_the_card_as_analyse_pump_card(fill: float, spread: float, shift: int) -> None:
    x, f = _synthetic_card(np.random.default_rng(1), 2000, fill, spread, shift)
    ref = analyse_pump_card(x, f)
    cls, fillage = _card_class(*pump_card_figures(x, f))
    assert cls == ref["card_class"]
    assert fillage == pytest.approx(ref["fillage"], rel=RTOL, abs=0.0)


def test_pump_card_pass_classes_cover_every_branch() -> None:
    rng = np.random.default_rng(2)
    seen = {_card_class(*pump_card_figures(*_synthetic_card(rng, 2000, fill, spread, 0)))[0]
            for fill, spread in [(0.0, 0.02), (0.5, 0.02), (0.5, 0.4), (0.95, 0.02)]}
    assert seen == {"full", "fluid_pound", "gas_interference", "no_fluid_load"}


def test_a_jittered_time_grid_is_still_refused() -> None:
    sim = Simulator(load_config("paper_fig3_vertical"))
    r = sim.run_stroke(record=True)
    r.trace = dict(r.trace, t_s=r.trace["t_s"].copy())
    r.trace["t_s"][10] += 0.3 * (r.trace["t_s"][1] - r.trace["t_s"][0])
    with pytest.raises(ValueError, match="uniformly sampled"):
        summarize(sim, [r])


@pytest.mark.parametrize("n", [2, 3, 7, 100, 2001])
def test_compiled_percentiles_equal_numpy_on_ties_and_plateaus(n: int) -> None:
    rng = np.random.default_rng(n)
    for f in (rng.normal(size=n), np.round(rng.normal(size=n), 1), np.sort(rng.normal(size=n)),
              np.sort(rng.normal(size=n))[::-1].copy(), np.full(n, 3.0)):
        x = np.sin(np.linspace(0.0, 2.0 * np.pi, n))
        _, down, up, *_ = pump_card_figures(x, f)
        ref = analyse_pump_card(x, f)  # its 'linear' rule by np.partition
        assert (down, up) == (ref["downstroke_load_n"], ref["upstroke_load_n"])
        np.testing.assert_allclose((down, up), np.percentile(f, (10.0, 85.0)), rtol=1e-14)
