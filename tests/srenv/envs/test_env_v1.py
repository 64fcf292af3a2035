"""srenv/SuckerRod-v1: contract, well family, splits, interval runner, economics (issue: the control task)."""

from __future__ import annotations

import dataclasses
import warnings

import gymnasium as gym
import numpy as np
import pytest

import srenv  # registers the envs
from srenv.analysis.card_features import stick_slip_energy_j
from srenv.analysis.stroke_summary import summarize
from srenv.config import load_config, shipped_configs
from srenv.envs.sucker_rod_v1 import (
    FIELD_OBS_NAMES,
    PRIVILEGED_OBS_NAMES,
    SuckerRodV1Env,
    action_from_setpoints,
    obs_index,
)
from srenv.simulation.simulator import Simulator
from srenv.task import well_family as wf
from srenv.task.economics import COST_TERMS, REWARD_TERMS
from srenv.task.interval import IntervalRunner, string_stiffness_n_m
from srenv.tools.action_sweep import sweep

ID = "srenv/SuckerRod-v1"


@pytest.mark.parametrize("observation", ["field", "privileged"])
def test_checkers_pass_on_v1(observation: str) -> None:
    from gymnasium.utils.env_checker import check_env
    from stable_baselines3.common.env_checker import check_env as sb3_check_env

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        check_env(gym.make(ID, scenario="train", observation=observation).unwrapped, skip_render_check=True)
        sb3_check_env(gym.make(ID, scenario="train", observation=observation).unwrapped, warn=True)


@pytest.mark.parametrize("name", shipped_configs())
def test_every_shipped_config_checks_on_v0_or_is_refused(name: str) -> None:
    from gymnasium.utils.env_checker import check_env

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        # no warning at all: not even gymnasium's "out of date" notice (srenv.register_envs, docs/scale.md)
        try:
            env = gym.make("srenv/SuckerRod-v0", config=name)
        except srenv.ConfigError as exc:
            assert load_config(name).surface.motion == "pullout" and "surface.motion" in str(exc)
            return
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        check_env(env.unwrapped, skip_render_check=True)


def test_spaces_and_observation_layout() -> None:
    f, p = SuckerRodV1Env(observation="field"), SuckerRodV1Env(observation="privileged")
    assert f.observation_space.shape == (len(FIELD_OBS_NAMES),)
    assert p.observation_space.shape == (len(PRIVILEGED_OBS_NAMES),) and len(PRIVILEGED_OBS_NAMES) > len(FIELD_OBS_NAMES)
    assert f.action_space.shape == (2,)
    assert PRIVILEGED_OBS_NAMES[: len(FIELD_OBS_NAMES)] == FIELD_OBS_NAMES
    for hidden in ("level", "intake_pressure", "productivity"):
        assert hidden not in FIELD_OBS_NAMES  # a field controller does not measure these
    assert gym.spec(ID).kwargs == {"scenario": "train", "observation": "field", "episode_hours": 12.0,
                                   "interval_s": 300.0}
    env = gym.make(ID, episode_hours=1.0)
    env.reset(seed=0)
    steps = 0
    while not env.step(np.zeros(2, np.float32))[3]:
        steps += 1
    assert steps + 1 == 12  # 1 h of 5-min intervals


def test_reward_is_the_sum_of_its_terms_and_cost_is_nonnegative() -> None:
    env = gym.make(ID, scenario="train")
    _, info = env.reset(seed=5)
    assert info["well_id"] == "train-005"
    rng = np.random.default_rng(0)
    for _ in range(6):
        _, r, _, _, info = env.step(rng.uniform(-1, 1, 2).astype(np.float32))
        assert set(REWARD_TERMS) <= set(info) and set(COST_TERMS) <= set(info)
        assert r == pytest.approx(sum(info[k] for k in REWARD_TERMS), rel=1e-12, abs=1e-9)
        assert info["cost"] >= 0 and info["cost"] == pytest.approx(sum(info[k] for k in COST_TERMS))
        assert all(np.isfinite(v) for v in info.values() if isinstance(v, float))


def test_same_seed_same_well_and_trajectory() -> None:
    runs = []
    for _ in range(2):
        env = gym.make(ID, scenario="test")
        obs, info = env.reset(seed=3)
        out = [obs, info["well_id"]]
        for a in np.linspace(-0.9, 0.9, 5):
            o, r, *_ = env.step(np.array([a, -a], np.float32))
            out += [o, r]
        runs.append(out)
    for x, y in zip(*runs):
        assert np.array_equal(x, y) if isinstance(x, np.ndarray) else x == y
    other = gym.make(ID, scenario="test")
    assert other.reset(seed=4)[1]["well_id"] != runs[0][1]


@pytest.mark.parametrize("kwargs, hours, interval", [
    ({}, 12.0, 300.0),
    ({"episode_hours": 2.0}, 2.0, 300.0),
    ({"task__episode_hours": 1.0}, 1.0, 300.0),
    ({"task__interval_s": 600.0}, 12.0, 600.0),
    ({"overrides": {"task.episode_hours": 0.5, "task.interval_s": 900.0}}, 0.5, 900.0),
], ids=["spec", "kwarg", "section-field-hours", "section-field-interval", "overrides"])
def test_a_task_override_is_not_shadowed_by_the_specs_defaults(kwargs, hours, interval) -> None:
    """The spec passes episode_hours and interval_s always; an override of the same field must win."""
    env = gym.make("srenv/SuckerRod-v1", **kwargs).unwrapped
    env.reset(seed=0)
    assert env.cfg.task.episode_hours == pytest.approx(hours) and env.cfg.task.interval_s == pytest.approx(interval)
    assert env.horizon_s == pytest.approx(hours * 3600.0)


def test_train_and_test_splits_are_disjoint_and_test_is_refused_to_tuning() -> None:
    train = {wf.well_seed("train", k) for k in range(wf.N_TRAIN)}
    test = {wf.well_seed("test", k) for k in range(wf.N_TEST)}
    assert not train & test
    p_train = {dataclasses.astuple(wf.draw_params(s)) for s in list(train)[:50]}
    p_test = {dataclasses.astuple(wf.draw_params(s)) for s in list(test)[:50]}
    assert not p_train & p_test
    for purpose in ("tune", "train", "select"):
        with pytest.raises(ValueError, match="refused"):
            wf.check_split("test", purpose)
    wf.check_split("test", "evaluate")


def _outcomes(params: wf.WellParams) -> np.ndarray:
    """Loads, pumped rate, inflow at full drawdown and inflow decline over the horizon, at a fixed action."""
    spec = wf.spec_from_params(params, "probe")
    sim = Simulator(spec.cfg)
    c = spec.cfg.control
    r = [sim.run_stroke(c.spm_max, c.stroke_max_m) for _ in range(2)]
    m = summarize(sim, r[1:])
    ann = sim.annulus
    ann.volume_m3 = 0.0
    q_full = ann.inflow_m3_s()
    ann.volume_m3 = ann.area_m2 * 0.5 * spec.design["static_level_m"]
    q_half = ann.inflow_m3_s()
    decline = np.exp(-params.decline_per_day * spec.cfg.task.episode_hours / 24.0)
    return np.array([m["pprl_n"], m["mprl_n"], m["production_m3_day"], q_full, q_half, decline,
                     m["goodman_max_pct"]])


@pytest.mark.parametrize("name", sorted(wf.PARAM_RANGES))
def test_every_randomised_parameter_moves_rate_or_loads_by_more_than_1pct(name: str) -> None:
    base = dataclasses.replace(wf.draw_params(wf.well_seed("train", 0)), survey_shape="build_hold",
                               max_inclination_deg=25.0, depth_m=1400.0, plunger_diameter_mm=44.45)
    lo, hi = wf.PARAM_RANGES[name]
    if name == "max_inclination_deg":
        lo = 5.0
    a = _outcomes(dataclasses.replace(base, **{name: lo}))
    b = _outcomes(dataclasses.replace(base, **{name: hi}))
    change = np.abs(b - a) / np.maximum(np.abs(a), 1e-12)
    assert change.max() > 0.01, f"{name}: outcomes move by at most {change.max():.2%}"


@pytest.mark.parametrize("split,index", [("train", k) for k in range(0, 200, 40)] + [("test", k) for k in (0, 17, 49)])
def test_generated_wells_validate_and_run_at_both_ends_of_their_control_range(split: str, index: int) -> None:
    spec = wf.build_spec(split, index)
    c = spec.cfg.control
    for spm, stroke in ((c.spm_min, c.stroke_min_m), (c.spm_max, c.stroke_max_m)):
        sim = Simulator(spec.cfg)
        m = summarize(sim, [sim.run_stroke(spm, stroke) for _ in range(2)][1:])
        assert np.isfinite(m["pprl_n"]) and m["goodman_max_pct"] < spec.cfg.task.failure_goodman_pct


def test_idle_refills_the_annulus_at_no_compute_and_no_energy() -> None:
    env = SuckerRodV1Env(scenario="train")
    env.reset(seed=2)
    level = env.sim.annulus.level_m
    info = env.step(np.array([-1.0, 0.0], np.float32))[4]
    assert info["strokes"] == 0 and info["exact_strokes"] == 0 and info["duty"] == 0
    assert info["reward_energy"] == 0 and info["reward_revenue"] == 0 and info["fluid_level_m"] > level
    assert info["reward_inventory"] > 0  # the refill is liquid stored, valued at the netback


def test_reward_is_continuous_through_the_vsd_minimum_speed() -> None:
    env = SuckerRodV1Env(scenario="train")
    ctl = env.reset(seed=1) and env.cfg.control
    rewards = []
    for avg in (ctl.spm_min - 1e-3, ctl.spm_min + 1e-3):
        env.reset(seed=1)
        rewards.append(env.step(action_from_setpoints(avg, ctl.stroke_max_m, ctl))[1])
    assert abs(rewards[0] - rewards[1]) < 0.005 * abs(rewards[0])


@pytest.mark.parametrize("seed,level_fraction", [(4, 0.5), (9, 0.0005), (30, 0.02)])
def test_fast_forward_matches_simulating_every_stroke(seed: int, level_fraction: float) -> None:
    """Quasi-steady fast-forward vs the full simulation of every stroke: production and PPRL within 1 %."""
    spec = wf.build_spec("train", seed)
    out = []
    for ff in (True, False):
        sim = Simulator(spec.cfg)
        sim.reset(fluid_level_m=level_fraction * spec.design["static_level_m"])
        run = IntervalRunner(sim)
        c = spec.cfg.control
        run.warm_up(c.spm_max, c.stroke_max_m)
        r = run.run(c.spm_max, c.stroke_max_m, 300.0, fast_forward=ff)
        out.append((r.lifted_m3, r.pprl_n, r.exact_strokes))
    (q_ff, p_ff, n_ff), (q_ex, p_ex, n_ex) = out
    assert n_ff < n_ex  # the fast-forward did skip strokes
    assert q_ff == pytest.approx(q_ex, rel=0.01) and p_ff == pytest.approx(p_ex, rel=0.01)


def test_inventory_makes_draining_the_annulus_worth_nothing_net() -> None:
    env = SuckerRodV1Env(scenario="train")
    env.reset(seed=6)
    _, _, _, _, info = env.step(np.array([1.0, 1.0], np.float32))
    value = env.econ.net_value_usd_m3
    hours = env.cfg.task.interval_s / 3600.0
    inflow_value = value * info["inflow_m3_day"] / 86400.0 * env.cfg.task.interval_s / hours
    assert info["reward_revenue"] + info["reward_inventory"] == pytest.approx(inflow_value, rel=1e-9)


def test_stick_slip_energy_is_zero_on_a_smooth_vertical_well() -> None:
    sim = Simulator(load_config("paper_fig3_vertical"))
    k = string_stiffness_n_m(sim)
    for r in sim.run_strokes(3):
        tr = r.trace
        assert stick_slip_energy_j(tr["pump_position_m"], tr["pump_velocity_m_s"], tr["pump_load_n"], k) == 0.0


def test_stick_slip_energy_grows_as_the_pullout_speed_falls_below_critical() -> None:
    """Paper Fig. 7 case: 0 above the critical speed (~2.5-3 m/s), growing as the speed falls from it."""
    rates = []
    for v in (3.5, 3.0, 2.0, 1.5, 1.0):
        sim = Simulator(load_config("paper_fig7_pullout"))
        tr = sim.run_duration(20.0, pull_velocity_m_s=v).trace
        e = stick_slip_energy_j(tr["pump_position_m"], tr["pump_velocity_m_s"], tr["pump_load_n"],
                                string_stiffness_n_m(sim))
        rates.append(e / 20.0)
    assert rates[0] == 0.0 and rates[1] == 0.0, rates  # smooth sliding above the critical speed
    assert rates[1] < rates[2] < rates[3] < rates[4], rates


def _discontinuities(r: dict) -> np.ndarray:
    """Indices where the reward jumps by more than 2 % of its swept range beyond the local slope (the median of
    the neighbouring differences), excluding the documented threshold: mid-stroke plunger stops (stick-slip
    energy > 0 on either side). The range is floored at 1 USD/h, the resolution that matters to anyone."""
    rw = r["reward"]
    span = max(rw.max() - rw.min(), 1.0)
    d = np.diff(rw)
    ss = r["stick_slip_energy_j"]
    physical = (ss[:-1] > 0) | (ss[1:] > 0)
    smooth = np.where(physical, np.nan, d)
    local = np.array([np.nanmedian(smooth[max(0, i - 3): i + 4]) if np.isfinite(smooth[max(0, i - 3): i + 4]).any()
                      else d[i] for i in range(len(d))])
    jump = np.abs(d - local) > 0.02 * span
    return np.flatnonzero(jump & ~physical)


@pytest.mark.parametrize("seed", [4, 11, 30])
@pytest.mark.parametrize("axis,step", [("spm", 0.05), ("stroke", 0.05)])
def test_reward_sweep_has_no_jumps(seed: int, axis: str, step: float) -> None:
    r = sweep("train", seed, axis, step)
    bad = _discontinuities(r)
    assert len(bad) == 0, [(float(r["value"][i]), float(r["reward"][i]), float(r["reward"][i + 1])) for i in bad]


def test_obs_index_names_the_layout() -> None:
    env = SuckerRodV1Env(observation="privileged")
    obs, _ = env.reset(seed=0)
    assert obs[obs_index("time_remaining", "privileged")] == pytest.approx(1.0)
    assert 0.0 <= obs[obs_index("fillage_est")] <= 1.0
    assert obs[obs_index("level", "privileged")] > 0


def test_controller_fillage_sees_pump_off_and_the_gibbs_diagnostic_agrees() -> None:
    """Pumped off at the top of the range: the controller's (downhole-card) fillage drops with the true fillage,
    and Gibbs' diagnostic of the surface card reads the same card within 0.05."""
    readings = {}
    for how in ("pump_card", "diagnose"):
        env = SuckerRodV1Env(scenario="train", task__fillage_estimator=how)
        env.reset(seed=1)
        full = env.step(np.array([1.0, 1.0], np.float32))[4]["fillage_est"]
        env.sim.annulus.volume_m3 = 0.0  # pumped off
        env.runner.running = True
        info = [env.step(np.array([1.0, 1.0], np.float32))[4] for _ in range(3)][-1]
        readings[how] = (full, info["fillage_est"], info["fillage"])
    full, off, true = readings["pump_card"]
    assert full > 0.9 and off < 0.5 and true < 0.5
    assert abs(readings["diagnose"][1] - off) < 0.05


def test_pickles_deep_copies_and_runs_in_subprocvecenv() -> None:
    import copy
    import pickle

    from stable_baselines3.common.env_util import make_vec_env
    from stable_baselines3.common.vec_env import SubprocVecEnv

    env = SuckerRodV1Env(scenario="train")
    env.reset(seed=8)
    twin = pickle.loads(pickle.dumps(env))
    clone = copy.deepcopy(env)
    a = np.array([0.3, 0.2], np.float32)
    r = [e.step(a)[1] for e in (env, twin, clone)]
    assert r[0] == r[1] == r[2]  # the same state continues identically in every copy
    venv = make_vec_env("srenv:srenv/SuckerRod-v1", n_envs=2, seed=0, vec_env_cls=SubprocVecEnv,
                        vec_env_kwargs={"start_method": "spawn"})
    try:
        obs = venv.reset()
        obs, rew, _, infos = venv.step(np.zeros((2, 2), np.float32))
        assert obs.shape == (2, len(FIELD_OBS_NAMES)) and np.all(np.isfinite(rew))
        assert {i["well_id"] for i in infos} <= {f"train-{k:03d}" for k in range(wf.N_TRAIN)}
    finally:
        venv.close()


def test_every_version_makes_without_a_warning_and_the_registry_fixup_is_as_documented() -> None:
    """srenv.register_envs (docs/scale.md, "Why the registry is still touched"): no version gets gymnasium's
    "out of date" DeprecationWarning, even under warnings-as-errors; ids, entry points and kwargs are srenv.ENVS';
    the documented side effects hold (v1/v2 read version None; a further version registered from outside is
    refused), so a gymnasium that changes this lookup shows up here."""
    from gymnasium.error import RegistrationError

    for env_id, (entry_point, kwargs) in srenv.ENVS.items():
        spec = gym.spec(env_id)
        assert (spec.id, spec.entry_point, spec.kwargs) == (env_id, entry_point, kwargs)
        assert spec.version == (0 if env_id == srenv.ENV_ID else None)
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            gym.make(env_id).close()
    with pytest.raises(RegistrationError, match="unversioned environment"):
        gym.register("srenv/SuckerRod-v9", entry_point=srenv.ENVS[srenv.ENV_ID_V1][0])
    assert "srenv/SuckerRod-v9" not in gym.registry
