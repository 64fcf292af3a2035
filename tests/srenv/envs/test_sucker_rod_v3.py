"""srenv/SuckerRod-v3: v2's task with the tagging damage from the contact (its end fixed at onset), the leaks'
lost liquid from the leak's own model, run 7's classifier pinned in the field observation; v2's spaces,
splits, family wells and vector entry point."""

from __future__ import annotations

import hashlib
import math
import warnings

import gymnasium as gym
import numpy as np
import pytest

import srenv  # noqa: F401 - registers the envs
from srenv.analysis.card_classifier import DEFAULT_MODEL, V3_MODEL, CardClassifier
from srenv.analysis.card_shape import features
from srenv.envs import sucker_rod_v2 as v2
from srenv.envs.sucker_rod_v1 import action_from_setpoints
from srenv.envs.sucker_rod_v3 import FIELD_OBS_NAMES, PRIVILEGED_OBS_NAMES, SuckerRodV3Env
from srenv.envs.vector import KernelVectorEnv
from srenv.task import events as ev
from srenv.task import leaks

ID = "srenv/SuckerRod-v3"
RUN7_SHA256 = "30f4a1c29660119d06b4d4585a0e0dfe062cc3e9956f84063e4882915e96c5c1"  # run 7's classifier.npz
SHORT = {"episode_hours": 0.25}


def _forced(label: str | None, severity: float, version: str = ID, **kw) -> SuckerRodV3Env:
    env = gym.make(version, scenario="train", episode_hours=1.0, **kw).unwrapped
    env.reset(seed=3)
    env._schedule = ev.Schedule([ev.Event(label, 0.0, math.inf, severity)] if label else [])
    return env


def _act(env, spm: float, stroke_m: float | None = None) -> np.ndarray:
    stroke = env.cfg.surface.stroke_length_m if stroke_m is None else stroke_m
    return action_from_setpoints(spm, stroke, env.cfg.control).astype(np.float32)


def _rate(label: str, severity: float, spm: float, stroke_m: float | None = None, key: str = "reward_tagging",
          **kw) -> float:
    """The term of the interval after the onset one (the onset at the well's installed point)."""
    env = _forced(label, severity, **kw)
    env.step(_act(env, env.cfg.surface.spm))
    return env.step(_act(env, spm, stroke_m))[4][key]


# ------------------------------------------------------------------------------------------ as v2
@pytest.mark.parametrize("observation", ["field", "privileged"])
def test_checkers_pass_on_v3(observation: str) -> None:
    from gymnasium.utils.env_checker import check_env
    from stable_baselines3.common.env_checker import check_env as sb3_check_env

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        check_env(gym.make(ID, observation=observation, **SHORT).unwrapped, skip_render_check=True)
        sb3_check_env(gym.make(ID, observation=observation, **SHORT).unwrapped, warn=True)


def test_spaces_names_and_spec_are_v2s() -> None:
    assert FIELD_OBS_NAMES == v2.FIELD_OBS_NAMES and PRIVILEGED_OBS_NAMES == v2.PRIVILEGED_OBS_NAMES
    f, p = SuckerRodV3Env(observation="field"), SuckerRodV3Env(observation="privileged")
    assert f.observation_space.shape == (89,) and p.observation_space.shape == (113,)
    assert f.action_space == v2.SuckerRodV2Env().action_space
    assert gym.spec(ID).kwargs == gym.spec("srenv/SuckerRod-v2").kwargs


def test_rewards_sum_and_costs_on_a_tagging_episode() -> None:
    env = _forced("tagging_down", 0.8, observation="privileged")
    for spm in (6.0, 1.0, 4.0):  # running, intermittent (a stop at the bottom), running
        o, r, _, _, info = env.step(_act(env, spm))
        assert r == pytest.approx(sum(v for k, v in info.items() if k.startswith("reward_")), rel=1e-12, abs=1e-9)
        parts = [k for k in info if k.startswith("cost_")]
        assert info["cost"] == pytest.approx(sum(info[k] for k in parts), rel=1e-12, abs=1e-12)
        assert o[PRIVILEGED_OBS_NAMES.index("true_tagging_down")] == 1.0


def test_vector_env_equals_single_envs() -> None:
    n, steps = 2, 4
    venv = gym.make_vec(ID, num_envs=n, vectorization_mode="vector_entry_point", event_rate_scale=50.0, **SHORT)
    singles = [SuckerRodV3Env(event_rate_scale=50.0, **SHORT) for _ in range(n)]
    actions = np.random.default_rng(0).uniform(-1, 1, (steps, n, 2)).astype(np.float32)
    try:
        assert isinstance(venv, KernelVectorEnv)
        obs, _ = venv.reset(seed=40)
        np.testing.assert_array_equal(obs, np.stack([e.reset(seed=40 + i)[0] for i, e in enumerate(singles)]))
        done = np.zeros(n, bool)
        for k in range(steps):
            obs, rew, term, trunc, _ = venv.step(actions[k])
            for i, e in enumerate(singles):
                o, r, t, u = (e.reset()[0], 0.0, False, False) if done[i] else e.step(actions[k, i])[:4]
                np.testing.assert_array_equal(obs[i], o)
                assert rew[i] == r and term[i] == t and trunc[i] == u
            done = term | trunc
    finally:
        venv.close()


def test_family_wells_are_deterministic() -> None:
    env = gym.make(ID, scenario="family:12", **SHORT)
    o1, i1 = env.reset(seed=4)
    o2, _ = env.reset(seed=4)
    assert np.array_equal(o1, o2) and i1["well_id"] == "family-12"
    a = np.array([0.3, 0.5], np.float32)
    assert env.step(a)[1] == (env.reset(seed=4), env.step(a))[1][1]


# ------------------------------------------------------------------------------------------ the classifier
def test_the_pinned_file_is_run_7s_and_the_observation_reads_it() -> None:
    assert hashlib.sha256(V3_MODEL.read_bytes()).hexdigest() == RUN7_SHA256
    env = SuckerRodV3Env(event_rate_scale=0.0)
    env.reset(seed=3)
    obs, *_ = env.step(np.array([1.0, 1.0], np.float32))
    clf = CardClassifier.load(V3_MODEL)
    tr = env._last.trace
    f = features(tr["polished_rod_position_m"], tr["polished_rod_load_n"])
    pinned = np.asarray(clf.proba_features(f[None, :])[0])[[clf.labels.index(k) for k in ev.LABELS]]
    i = FIELD_OBS_NAMES.index("prob_full")
    np.testing.assert_array_equal(obs[i:i + 12], pinned.astype(np.float32))
    assert V3_MODEL != DEFAULT_MODEL  # its own file: a newer shipped model leaves v3's numbers


# ------------------------------------------------------------------------------------------ tagging
def test_the_contact_end_is_fixed_at_onset_in_v3_and_placed_again_after_a_stop_in_v2() -> None:
    ends = {}
    for version in ("srenv/SuckerRod-v2", ID):
        env = _forced("tagging_down", 1.0, version)
        seen = []
        for spm, stroke in ((8.0, None), (1.0, None), (8.0, 2.0), (1.0, 2.0), (8.0, None)):  # 1 SPM stops
            env.step(_act(env, spm, stroke))
            seen.append((env.sim.contact_ends()["tag_bottom_set"], env.sim.contact_ends()["tag_bottom_m"]))
        ends[version] = seen
    assert len(set(ends[ID])) == 1 and ends[ID][0][0] == 1  # placed once, kept through stops and other strokes
    assert any(s == 0 for s, _ in ends["srenv/SuckerRod-v2"])  # v2: a stop clears it
    assert len({e for s, e in ends["srenv/SuckerRod-v2"] if s}) > 1  # ... and places it again elsewhere


def test_tagging_damage_falls_when_slower_or_shorter_and_is_zero_at_severity_0() -> None:
    fast, slow = _rate("tagging_down", 0.6, 8.0), _rate("tagging_down", 0.6, 3.0)
    assert fast < slow < 0.0 and slow > 0.3 * fast  # 8 -> 3 SPM: fewer strokes, each a softer hit
    full, short = _rate("tagging_down", 0.6, 6.0), _rate("tagging_down", 0.6, 6.0, 1.6)
    assert full < short <= 0.0  # a shorter stroke (the bottom held): a smaller overtravel at the bottom
    assert _rate("tagging_down", 0.0, 8.0) == 0.0 and _rate("tagging_down", 0.0, 8.0, key="cost_tagging") == 0.0
    assert _rate("tagging_down", 0.6, 3.0, key="cost_tagging") < _rate("tagging_down", 0.6, 8.0, key="cost_tagging")


def test_tagging_damage_is_continuous_in_the_action() -> None:
    spm = np.arange(4.5, 5.51, 0.05)
    env = gym.make(ID, scenario="train", episode_hours=1.0, interval_s=60.0).unwrapped
    got = []
    for s in spm:
        env.reset(seed=3)
        env._schedule = ev.Schedule([ev.Event("tagging_down", 0.0, math.inf, 0.6)])
        got.append(env.step(_act(env, s))[4]["reward_tagging"])
    got = np.array(got)
    assert np.all(got < 0) and np.ptp(got) > 1.0  # it moves with the action
    assert np.max(np.abs(np.diff(got))) < 0.15 * np.max(np.abs(got))  # and without a step


# ------------------------------------------------------------------------------------------ leaks
@pytest.mark.parametrize("label", ["travelling_valve_leak", "standing_valve_leak", "tubing_leak"])
def test_a_leak_loses_a_smaller_share_when_pumping_faster(label: str) -> None:
    shares = []
    for spm in (3.0, 5.0, 8.0):
        env = _forced(label, 0.2)
        env.step(_act(env, env.cfg.surface.spm))
        _, _, _, _, info = env.step(_act(env, spm))
        shares.append(-info["reward_lost_production"] / info["reward_revenue"])
    assert shares[0] > shares[1] > shares[2] > 0.0, shares


def test_the_valve_leak_speed_is_fixed_at_onset_and_the_fraction_follows_the_action() -> None:
    env = _forced("travelling_valve_leak", 0.2)
    spm0, stroke0 = env.cfg.surface.spm, env.sim.surface.stroke_length_m(env.cfg.surface.stroke_length_m)
    f0 = ev.condition_overrides("travelling_valve_leak", 0.2, env.cfg)["pump.travelling_valve_leak_fraction"]
    env.step(_act(env, spm0))
    assert env.sim.cfg.pump.travelling_valve_leak_fraction == pytest.approx(f0, rel=1e-5)
    env.step(_act(env, 8.0))
    assert env.sim.cfg.pump.travelling_valve_leak_fraction == pytest.approx(f0 * spm0 / 8.0, rel=1e-5)
    assert env._onset == pytest.approx((spm0, stroke0))


def test_a_hole_drains_a_rate_per_hour_whatever_the_pump_does() -> None:
    lost = []
    for spm in (3.0, 8.0):
        env = _forced("tubing_leak", 0.2)
        env.step(_act(env, env.cfg.surface.spm))
        info = env.step(_act(env, spm))[4]
        lost.append(-info["reward_lost_production"] / env.econ.net_value_usd_m3)  # m3/h
    assert lost[0] == pytest.approx(lost[1], rel=1e-9) and lost[0] == pytest.approx(env._hole_m3_h, rel=1e-9)


@pytest.mark.parametrize("label", sorted(leaks.ACCOUNTED))
def test_a_physics_accounted_loss_is_not_booked_twice(label: str) -> None:
    env = _forced(label, 0.3)
    env.step(_act(env, env.cfg.surface.spm))
    r = env._result
    b, _ = env._booking(label, 0.3, r)
    if label == "tubing_leak":
        model = leaks.hole_lost_m3(env._hole_m3_h, r.duration_s / 3600.0, r.lifted_m3)
    else:
        model = leaks.valve_lost_m3(env.sim.cfg.pump, r.lifted_m3)
    assert b.lost_m3 == pytest.approx(model, rel=1e-12)  # the model's loss alone, not v2's share on top
    v2_share = ev.bookkeeping(label, 0.3, r.lifted_m3, r.strokes).lost_m3
    assert b.lost_m3 != pytest.approx(model + v2_share, rel=1e-6)
