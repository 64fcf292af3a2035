"""The Gymnasium env: contract (spaces, checkers, seeding, pickling, vector envs) and physics it exposes."""

from __future__ import annotations

import math
import pickle
import warnings

import gymnasium as gym
import numpy as np
import pytest

import srenv  # registers the env
from srenv.analysis.metrics import ROD_GRADE_TENSILE_PA
from srenv.analysis.stroke_summary import summarize
from srenv.config import load_config
from srenv.envs import SuckerRodEnv
from srenv.simulation.simulator import Simulator

ENV_ID = "srenv/SuckerRod-v0"
SHORT = {"control__max_episode_steps": 5}
INFO_KEYS = {"pprl_n", "mprl_n", "goodman_pct", "goodman_max_pct", "stick_slip_index", "fillage",
             "production_m3_day", "spm", "stroke_length_m", "fluid_level_m", "intake_pressure_pa",
             "certified_steps", "corrected_steps", "qp_steps", "solver_calls"}


def test_checkers_pass_without_warnings() -> None:
    from gymnasium.utils.env_checker import check_env
    from stable_baselines3.common.env_checker import check_env as sb3_check_env

    # making v0 must not warn either (v1 is registered beside it, and is not its "upgrade": srenv/__init__.py)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        check_env(gym.make(ENV_ID, **SHORT).unwrapped)
        sb3_check_env(gym.make(ENV_ID, **SHORT).unwrapped, warn=True)
        check_env(gym.make("srenv:srenv/SuckerRod-v0", **SHORT).unwrapped)


def test_spaces_match_the_contract() -> None:
    env = gym.make(ENV_ID)
    a = env.action_space
    assert a.shape == (2,) and a.dtype == np.float32 and np.all(a.low == -1) and np.all(a.high == 1)
    o = env.observation_space
    assert o.dtype == np.float32 and len(o.shape) == 1


def _rollout(seed: int, steps: int = 3) -> tuple[np.ndarray, list[float]]:
    env = gym.make(ENV_ID, **SHORT)
    obs, _ = env.reset(seed=seed)
    env.action_space.seed(seed)
    out, rewards = [obs], []
    for _ in range(steps):
        obs, r, *_ = env.step(env.action_space.sample())
        out.append(obs)
        rewards.append(r)
    return np.concatenate(out), rewards


def test_seeding_is_reproducible_and_leaves_global_rng_alone() -> None:
    np.random.seed(123)
    state = np.random.get_state()
    a, ra = _rollout(7)
    b, rb = _rollout(7)
    c, _ = _rollout(8)
    after = np.random.get_state()
    assert np.array_equal(a, b) and ra == rb
    assert not np.array_equal(a, c)
    assert state[0] == after[0] and np.array_equal(state[1], after[1]) and state[2:] == after[2:]


def test_reward_is_the_sum_of_its_info_terms() -> None:
    env = gym.make(ENV_ID, **SHORT)
    env.reset(seed=0)
    for action in ([1, 1], [-1, -1], [0.3, -0.2]):
        _, r, _, _, info = env.step(np.array(action, dtype=np.float32))
        terms = {k: v for k, v in info.items() if k.startswith("reward_")}
        assert {"reward_production", "reward_stick_slip", "reward_peak_load"} <= set(terms)
        assert r == pytest.approx(sum(terms.values()), abs=1e-12)
        assert terms["reward_production"] > 0 and terms["reward_peak_load"] < 0
        assert INFO_KEYS <= set(info), INFO_KEYS - set(info)


def test_nan_action_is_refused_and_out_of_range_is_clipped() -> None:
    env = gym.make(ENV_ID, **SHORT)
    env.reset(seed=0)
    with pytest.raises(ValueError, match="action"):
        env.step(np.array([np.nan, 0.0], dtype=np.float32))
    with pytest.raises(ValueError, match="action"):
        env.step(np.array([np.inf, 0.0], dtype=np.float32))
    results = []
    for action in ([5.0, -3.0], [1.0, -1.0]):
        e = gym.make(ENV_ID, **SHORT)
        e.reset(seed=0)
        obs, r, *_ = e.step(np.array(action, dtype=np.float32))
        results.append((obs, r))
    assert np.array_equal(results[0][0], results[1][0]) and results[0][1] == results[1][1]


def test_pickles_and_runs_in_subproc_vec_env() -> None:
    from stable_baselines3.common.vec_env import SubprocVecEnv

    env = gym.make(ENV_ID, **SHORT).unwrapped
    env.reset(seed=1)
    clone = pickle.loads(pickle.dumps(env))
    act = np.array([0.2, 0.4], dtype=np.float32)
    assert np.array_equal(env.step(act)[0], clone.step(act)[0])
    # the module-qualified id imports srenv in the worker process, which registers the env there
    venv = SubprocVecEnv([lambda: gym.make("srenv:" + ENV_ID, **SHORT)] * 2)
    try:
        venv.seed(3)
        obs = venv.reset()
        obs2, rew, _, infos = venv.step(np.array([[1, 1], [-1, -1]], dtype=np.float32))
        assert obs.shape == obs2.shape == (2, env.observation_space.shape[0])
        assert np.all(np.isfinite(rew)) and infos[0]["spm"] > infos[1]["spm"]
    finally:
        venv.close()


def _pump_card_after_top(trace: dict) -> tuple[float, float]:
    """Plunger travel after the top reversal during which the pump still carries the upstroke load."""
    pos, load = trace["pump_position_m"], trace["pump_load_n"]
    top = int(np.argmax(pos))
    p_up = load[:top].max()
    after = np.arange(top, len(pos))
    dropped = after[load[after] < 0.5 * p_up]
    first_drop = dropped[0] if len(dropped) else after[-1]
    return float(pos[top] - pos[first_drop]), float(np.ptp(pos))


def test_fast_pumping_with_low_inflow_pounds_and_slow_pumping_fills() -> None:
    low_inflow = {"inflow.initial_fluid_level_m": 0.5, "inflow.max_rate_m3_day": 10.0}
    env = SuckerRodEnv(overrides=low_inflow)
    env.reset(seed=0, options={"randomize": False})
    for _ in range(4):
        _, _, _, _, info = env.step(np.array([1.0, 1.0], dtype=np.float32))
    assert info["fillage"] < 0.8
    delay_m, stroke_m = _pump_card_after_top(env._trace)
    # fluid pound: the load stays on for a finite plunger travel into the downstroke
    assert delay_m > 0.3 * (1 - info["fillage"]) * stroke_m and delay_m > 0.1
    slow = SuckerRodEnv(overrides={"inflow.initial_fluid_level_m": 50.0})
    slow.reset(seed=0, options={"randomize": False})
    for _ in range(4):
        _, _, _, _, info = slow.step(np.array([-1.0, -1.0], dtype=np.float32))
    assert info["fillage"] > 0.98
    delay_m, _ = _pump_card_after_top(slow._trace)
    assert delay_m < 0.05  # full barrel: load released at the top


def test_goodman_matches_hand_computation_for_the_top_taper() -> None:
    cfg = load_config("paper_fig4_deviated")
    sim = Simulator(cfg)
    r = sim.run_stroke()
    m = summarize(sim, [r])
    d = cfg.rod.tapers[0].diameter_mm * 1e-3
    area = math.pi / 4 * d * d
    # top of taper 1 = element 0; wellhead pressure 0 so true = equivalent force there
    s_max = r.element_force_max_eq_n[0] / area
    s_min = r.element_force_min_eq_n[0] / area
    t = ROD_GRADE_TENSILE_PA["D"]  # 115 ksi
    s_a = t / 4 + 0.5625 * s_min
    expected = 100 * (s_max - s_min) / (s_a - s_min)
    assert m["goodman_pct"][0] == pytest.approx(expected, rel=1e-12)
    # and the element envelope at the top agrees with the polished-rod load to the top half-element's
    # weight and inertia (a few hundred N out of ~45 kN)
    assert r.element_force_max_eq_n[0] == pytest.approx(r.trace["polished_rod_load_n"].max(), rel=0.02)


def test_randomisation_draws_from_the_env_rng() -> None:
    env = SuckerRodEnv()
    env.reset(seed=0)
    a = env.cfg
    env.reset(seed=1)
    b = env.cfg
    env.reset(seed=0)
    assert env.cfg == a != b
    env.reset(seed=5, options={"randomize": False})
    assert env.cfg == env.base_cfg


def test_truncation_and_render() -> None:
    env = gym.make(ENV_ID, render_mode="rgb_array", control__max_episode_steps=2)
    env.reset(seed=0)
    _, _, term, trunc, _ = env.step(env.action_space.sample())
    assert not trunc
    _, _, term, trunc, _ = env.step(env.action_space.sample())
    assert trunc and not term
    img = env.render()
    assert img.dtype == np.uint8 and img.ndim == 3 and img.shape[2] == 3 and img.std() > 0


def test_rod_failure_terminates_with_info() -> None:
    env = SuckerRodEnv(overrides={"reward.failure_goodman_pct": 5.0})
    env.reset(seed=0)
    _, _, term, trunc, info = env.step(np.zeros(2, dtype=np.float32))
    assert term and not trunc and "Goodman" in info["failure"]
    assert info["reward_failure"] == -env.cfg.reward.failure_penalty


def test_goodman_in_info_matches_a_hand_computation_from_the_card() -> None:
    """Top of taper 1 = the polished rod; its true load is the trace's polished-rod load (the simulator
    already subtracts wellhead pressure x area). The env reports the element envelope just below it, so the
    two agree to the top half-element's weight and inertia (~1 %)."""
    env = SuckerRodEnv(control__randomize=False)
    env.reset(seed=0)
    for action in ([1.0, 1.0], [-1.0, -1.0]):
        _, _, _, _, info = env.step(np.array(action, dtype=np.float32))
        load = env._trace["polished_rod_load_n"]
        d_m = env.cfg.rod.tapers[0].diameter_mm * 1e-3
        area_m2 = math.pi / 4 * d_m * d_m
        s_max, s_min = load.max() / area_m2, load.min() / area_m2
        s_a = ROD_GRADE_TENSILE_PA[env.cfg.rod.tapers[0].grade] / 4 + 0.5625 * s_min
        assert info["goodman_pct"][0] == pytest.approx(100 * (s_max - s_min) / (s_a - s_min), rel=0.02)
        assert info["pprl_n"] == load.max() and info["mprl_n"] == load.min()


def test_default_well_pumps_off_at_the_top_of_the_range_within_an_episode() -> None:
    """The tuning of configs/wells/default.yaml that makes speed control matter: flat out, the pump outruns
    the inflow before the time limit; at the bottom of the range the barrel stays full but production is
    low."""
    env = SuckerRodEnv(control__randomize=False)
    fills, prods = {}, {}
    for name, action in (("fast", [1.0, 1.0]), ("slow", [-1.0, -1.0])):
        env.reset(seed=0)
        fills[name], prods[name] = [], []
        truncated = False
        while not truncated:
            _, _, terminated, truncated, info = env.step(np.array(action, dtype=np.float32))
            assert not terminated
            fills[name].append(info["fillage"])
            prods[name].append(info["production_m3_day"])
    assert min(fills["fast"]) < 0.8 and fills["fast"][0] > 0.98  # pumped off during, not before, the episode
    assert min(fills["slow"]) > 0.98
    assert max(prods["slow"]) < 0.5 * np.mean(prods["fast"])


def test_solver_failure_mid_episode_ends_it_with_only_the_failure_term(monkeypatch: pytest.MonkeyPatch) -> None:
    env = SuckerRodEnv(**SHORT)
    env.reset(seed=0)

    def fail(*_args: object, **_kw: object) -> None:
        raise srenv.SolverFailure(0, 0.0, "injected")

    monkeypatch.setattr(env.sim, "run_stroke", fail)
    obs, r, term, trunc, info = env.step(np.zeros(2, dtype=np.float32))
    assert term and not trunc and "injected" in info["failure"]
    assert r == info["reward_failure"] == -env.cfg.reward.failure_penalty
    assert info["reward_production"] == info["reward_stick_slip"] == info["reward_peak_load"] == 0.0
    assert env.observation_space.contains(obs)


def test_gearbox_overload_of_a_conventional_unit_joins_the_peak_load_penalty() -> None:
    """Without counterweights the reducer is overloaded; the penalty carries relu(loading - 100) / 100."""
    env = SuckerRodEnv(config="conventional_fig4", overrides={"surface.counterbalance_moment_nm": 0.0})
    env.reset(seed=0, options={"randomize": False})
    _, _, _, _, info = env.step(np.zeros(2, dtype=np.float32))
    c = env.cfg.reward
    assert info["gearbox_loading_pct"] > 100.0
    w = info["duration_s"] / c.reference_duration_s
    overload = (max(0.0, info["goodman_max_pct"] - c.goodman_limit_pct) + info["gearbox_loading_pct"] - 100) / 100
    expected = -w * c.peak_load_weight * ((info["pprl_n"] / c.pprl_rating_n) ** 2 + overload)
    assert info["reward_peak_load"] == pytest.approx(expected, rel=1e-12)
