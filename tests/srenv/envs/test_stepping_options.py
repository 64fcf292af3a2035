"""Issue 25: the interval runner's opt-in stepping options (srenv/task/stepping.py) - exact_min (K exact strokes an
interval, their mean repeated) and follow_drift (the repeated stroke's figures along the intake-pressure slopes) -
and the stroke-to-stroke variability tool (srenv/tools/stroke_variability.py). Off by default: v1's and v2's
pinned digests (test_rl_digest.py, test_kernel_regression.py) cover that they do not move."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from srenv.envs.sucker_rod_v2 import SuckerRodV2Env
from srenv.task import reuse, stepping
from srenv.task.interval import IntervalResult, IntervalRunner, StrokeFigures
from srenv.tools import stroke_variability as sv
from srenv.tools.stepping_error import compare

SCALAR_FIELDS = [f.name for f in dataclasses.fields(IntervalResult) if f.name not in ("last", "solver")]


def _stroke(work: float, damage: float, impact: float, pprl: float, goodman: float = 50.0) -> StrokeFigures:
    return StrokeFigures(summary={"pprl_n": pprl, "mprl_n": 1.0e4, "goodman_max_pct": goodman,
                                  "gearbox_loading_pct": 80.0}, trace={}, lifted_m3=1e-3, displacement_m3=2e-3,
                         fillage=0.5, fillage_est=0.5, work_j=work, damage=damage, stick_slip_j=0.0,
                         impact_m_s=impact, power_mean_w=1.0, power_peak_w=2.0)


def _env(seed: int = 11) -> SuckerRodV2Env:
    env = SuckerRodV2Env(episode_hours=1.0, event_rate_scale=0.0)
    env.reset(seed=seed)
    return env


def _intervals(runner: IntervalRunner, n: int, **kw) -> list[IntervalResult]:
    # 10 SPM in 300 s: 50 whole strokes, no fractional stroke to fast-forward
    return [runner.run(10.0, 1.6, 300.0, **kw) for _ in range(n)]


def test_the_options_are_off_by_default_and_bad_values_are_refused() -> None:
    env = _env()
    assert env.runner.exact_min == 0 and env.runner.follow_drift is False
    for bad in (-1, 1.5, True, "2", None):
        with pytest.raises(ValueError, match="exact_min"):
            IntervalRunner(env.sim, exact_min=bad)
    with pytest.raises(TypeError, match="follow_drift"):
        IntervalRunner(env.sim, carry=True, follow_drift=1)
    with pytest.raises(ValueError, match="carry"):
        IntervalRunner(env.sim, follow_drift=True)


def test_exact_min_covering_the_interval_gives_every_stroke_to_the_bit() -> None:
    """K at or above an interval's strokes simulates every stroke: the same interval sums as run(fast_forward=
    False), even with v2's reuse and carry on (exact_min skips the reuse) and with follow_drift (nothing is
    fast-forwarded for it to move)."""
    ref_env, opt_env = _env(), _env()
    ref = _intervals(IntervalRunner(ref_env.sim, draw_at_top=True), 3, fast_forward=False)
    got = _intervals(IntervalRunner(opt_env.sim, reuse_periodic=True, carry=True, draw_at_top=True, exact_min=50,
                                    follow_drift=True), 3)
    for a, b in zip(ref, got):
        assert b.exact_strokes == 50 and b.fast_forward_strokes == 0.0
        assert [getattr(a, k) for k in SCALAR_FIELDS] == [getattr(b, k) for k in SCALAR_FIELDS]
    assert ref_env.sim.time_s == opt_env.sim.time_s and ref_env.sim.annulus.volume_m3 == opt_env.sim.annulus.volume_m3


def test_exact_min_simulates_k_strokes_an_interval_and_the_options_are_deterministic() -> None:
    runs = []
    for _ in range(2):
        env = _env()
        runner = IntervalRunner(env.sim, reuse_periodic=True, carry=True, draw_at_top=True, exact_min=4,
                                follow_drift=True)
        runs.append(_intervals(runner, 3))
    for a, b in zip(*runs):
        assert a.exact_strokes >= 4 and a.fast_forward_strokes > 0  # no reuse: K strokes every interval
        assert [getattr(a, k) for k in SCALAR_FIELDS] == [getattr(b, k) for k in SCALAR_FIELDS]
    plain = _intervals(IntervalRunner(_env().sim, reuse_periodic=True, carry=True, draw_at_top=True), 3)
    assert plain[-1].exact_strokes < 4  # v2's default reuses the kept stroke instead


def test_follow_drift_moves_the_fast_forwarded_figures_without_more_exact_strokes() -> None:
    """Full speed on a train well that pumps down: once two kept strokes give slopes (the third interval), the
    drift-following run books other fatigue and energy than v2's default, with the same exact strokes and
    production."""
    infos = {}
    for drift in (False, True):
        env = _env()
        env.runner.follow_drift = stepping.check(0, drift, env.runner.carry)[1]  # the fresh runner, as if built so
        infos[drift] = [env.step(np.float32([1.0, 1.0]))[4] for _ in range(5)]
    a, b = infos[False], infos[True]
    assert [i["exact_strokes"] for i in a] == [i["exact_strokes"] for i in b]
    assert [i["reward_revenue"] for i in a] == [i["reward_revenue"] for i in b]  # the annulus is not the option's
    assert a[:3] == b[:3]  # no slopes before the third interval's kept stroke: nothing to follow
    assert all(x["reward_fatigue"] != y["reward_fatigue"] and x["reward_energy"] != y["reward_energy"]
               for x, y in zip(a[3:], b[3:]))


def test_mean_stroke_and_drift_arithmetic() -> None:
    a, b = _stroke(1.0e4, 1e-8, 0.3, 4.0e4), _stroke(3.0e4, 3e-8, 0.4, 4.2e4)
    m = reuse.mean_stroke([a, b])
    assert m.work_j == 2.0e4 and m.damage == pytest.approx(2e-8)
    assert m.impact_m_s == pytest.approx(np.sqrt((0.09 + 0.16) / 2))  # the pound sums squares
    assert m.summary is b.summary and reuse.mean_stroke([a]) is a
    flat = reuse.slopes(a, 1.0e6, dataclasses.replace(a), 2.0e6)  # the same stroke at two pressures: no slope
    sums, peaks = reuse.drift(a, flat, 1.0e6, 10.0, 1.0e6, 1.5e6)
    assert all(v == 0.0 for v in sums.values()) and peaks == [a.summary, a.summary]
    c = _stroke(2.0e4, 2e-8, 0.3, 4.1e4, goodman=60.0)
    s = reuse.slopes(a, 1.0e6, c, 2.0e6)  # work +0.01 J/Pa, PPRL +0.001 N/Pa, Goodman +1e-5 %/Pa
    sums, peaks = reuse.drift(a, s, 1.0e6, 10.0, 1.0e6, 1.4e6)  # the run's mean pressure is 0.2 MPa on
    assert sums["work_j"] == pytest.approx(10.0 * 0.01 * 0.2e6)
    assert [p["pprl_n"] for p in peaks] == pytest.approx([4.0e4, 4.0e4 + 400.0])
    cube = reuse.drift(a, s, 1.0e6, 6.0, 1.0e6, 1.4e6, damage_of=lambda g: g ** 3)[0]["damage"]
    exact = 6.0 * (54.0 ** 4 - 50.0 ** 4) / (4 * 4.0)  # Simpson is exact for a cubic: the run's mean of G^3 x 6
    assert cube == pytest.approx(exact - 6.0 * a.damage, rel=1e-12)


def test_the_error_tool_takes_runner_options_and_drift_stays_within_the_bound_on_a_steady_sample() -> None:
    r = compare("vsd_minimum", 11, 0.5, scenario="train", version="v2",
                options={"drift": {"runner": {"follow_drift": True}}, "k2": {"runner": {"exact_min": 2}}})
    err = r["drift"]["relative_error"]
    for key in ("production_m3", "pprl_max_n", "return"):
        assert err[key] < 0.005, (key, err[key])
    assert r["k2"]["figures"]["exact_strokes"] >= 2 * r["k2"]["figures"]["steps"]


def test_variability_counts() -> None:
    flat = np.full(20, 3.0)
    assert sv.k_se(flat, 0.005) == 1.0 and sv.k_direct(flat, 0.005) == 1
    assert sv.detrended_cv(flat) == pytest.approx(0.0, abs=1e-12)
    line = np.linspace(1.0, 2.0, 21)
    assert sv.detrended_cv(line) == pytest.approx(0.0, abs=1e-12)
    assert sv.k_direct(line, 0.005) == 21  # a drift: only the whole interval's strokes give its mean
    cycle = np.tile([1.0, 3.0], 10)  # a 2-stroke cycle: every even count of first strokes has the mean
    assert sv.k_direct(cycle, 0.005) == 20 and sv.k_direct(cycle, 0.06) == 8  # odd K: 1/K off
    assert sv.k_se(cycle, 0.005) == 20.0  # by the standard error (strokes taken as independent): all of them
    assert sv.k_direct(np.array([1.0, 5.0, 2.0]), 0.005, peak=True) == 2
    assert sv.episode_error([cycle], 2) == 0.0 and sv.episode_error([cycle], 1) == pytest.approx(0.5)
