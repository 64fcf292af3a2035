"""The v2 benchmark's parts: the alarm controller, the causal oracle's frozen future, the tuning code's refusals,
fresh wells, v1 models on v2's observation, and the rliable block's schema."""

import json
import math
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest

import srenv  # noqa: F401
from agents.benchmark.config import load_benchmark_config
from agents.benchmark.fresh import fresh_wells
from agents.benchmark.rliable_stats import normalised_scores, rliable_section
from agents.evaluation.shipped import shipped_report
from agents.evaluation.v1_view import V1ObsView
from agents.policies.alarms import AlarmPumpOffPolicy
from agents.policies.causal_oracle import freeze_future
from agents.training.tuning import TuningSet, refuse_test_split
from srenv.envs.sucker_rod_v2 import FIELD_OBS_NAMES
from srenv.task import events as ev

NAMES = list(FIELD_OBS_NAMES)
REPO = Path(__file__).resolve().parents[2]


def _obs(fill=1.0, pprl=0.8, mprl=0.4, **probs):
    o = np.zeros(len(NAMES), np.float32)
    o[NAMES.index("fillage_est")], o[NAMES.index("pprl")], o[NAMES.index("mprl")] = fill, pprl, mprl
    for k, v in probs.items():
        o[NAMES.index(f"prob_{k}")] = v
    return o


def test_alarm_pump_off_shuts_in_on_a_parted_rod_signature_and_slows_on_gas():
    p = AlarmPumpOffPolicy(NAMES, threshold=0.8, a_spm=0.5, load_drop=0.5, alarm_prob=0.6, gas_slowdown=0.3)
    a, st = p.predict(_obs(), None, np.array([True]))
    assert a[0] == pytest.approx(0.5)
    a, st = p.predict(_obs(gas_interference=0.9), st, np.array([False]))
    assert a[0] == pytest.approx(0.2)  # slowed down on gas
    a, st = p.predict(_obs(pprl=0.45, mprl=0.4), st, np.array([False]))  # load range 0.05 < 0.5 x 0.4
    assert a[0] == -1.0
    a, st = p.predict(_obs(), st, np.array([False]))
    assert a[0] == -1.0  # shut in stays shut in
    with pytest.raises(ValueError, match="alarm_prob"):
        AlarmPumpOffPolicy(NAMES, alarm_prob=1.0 / 12.0)


def test_tuning_refuses_held_out_wells():
    for scenario in ("test", "validation", "family:123"):
        with pytest.raises(ValueError, match="refused"):
            refuse_test_split(scenario, "tune")
        with pytest.raises(ValueError, match="refused"):
            TuningSet([0], scenario, "srenv/SuckerRod-v2")
    refuse_test_split("train", "tune")


def test_causal_oracle_model_has_no_future():
    env = gym.make("srenv/SuckerRod-v2", scenario="train", episode_hours=1.0).unwrapped
    env.reset(seed=2)
    env._schedule = ev.Schedule([ev.Event("tubing_leak", 0.4, math.inf, 0.3)])  # starts at 0.4 h
    env._step_time_s, env._step_fraction = 0.5 * 3600.0, -0.4
    env.step(np.zeros(2, np.float32))
    model = freeze_future(env)
    assert model.inflow_multiplier(0.9 * 3600.0) == pytest.approx(env.sim.annulus.rate_multiplier)
    assert model._schedule.active(0.9) == (None, 0.0)  # the leak to come is unknown to it
    assert model._parting.budget == math.inf


def test_fresh_wells_are_recorded_and_distinct():
    a = fresh_wells(5, 20)
    assert a == fresh_wells(5, 20) and len(set(a)) == 20 and a != fresh_wells(6, 20)


def test_v1_model_view_of_v2_observation():
    class Echo:
        def predict(self, x, state=None, episode_start=None, deterministic=True):
            return x, state

    x = np.arange(89 + 2, dtype=np.float32)  # v2 field obs + a residual's base action
    out, _ = V1ObsView(Echo(), 79).predict(x)
    assert out.shape == (79,) and out[76] == 76 and list(out[-2:]) == [89, 90]
    assert V1ObsView(Echo(), 77).predict(x[:89])[0].shape == (77,)


def test_rliable_block_schema_and_reproducible():
    rep = json.loads(shipped_report().read_text())
    keep = ("installed", "pump_off", "oracle", "ppo", "ppo_residual_distilled_ensemble")
    rep["policies"] = {n: p for n, p in rep["policies"].items() if n in keep}
    for p in rep["policies"].values():  # a small report: 12 episodes
        p["episodes"] = p["episodes"][:12]
    for r in rep["training"]["runs"].values():
        for s in r["per_seed"]:
            s["episodes"] = s["episodes"][:12]
    scores, ref = normalised_scores(rep)
    assert ref == "oracle" and np.allclose(scores["installed"], 0)
    # 1 on every episode but those whose span the floor raised (the installed point near the top)
    assert np.all(scores["oracle"] <= 1 + 1e-12) and np.median(scores["oracle"]) == pytest.approx(1.0)
    assert scores["ppo"].shape == (3, 12)
    a = rliable_section(rep, reps=100, seed=1)
    assert a == rliable_section(rep, reps=100, seed=1)
    iq = a["iqm"]["pump_off"]
    assert iq["ci95"][0] <= iq["iqm"] <= iq["ci95"][1]
    poi = a["probability_of_improvement"]["ppo_residual_distilled_ensemble"]["pump_off"]
    assert 0 <= poi["ci95"][0] <= poi["p"] <= poi["ci95"][1] <= 1
    prof = a["performance_profile"]
    assert len(prof["fraction_above"]["pump_off"]) == len(prof["taus"])
    assert all(np.diff(prof["fraction_above"]["pump_off"]) <= 1e-12)  # a profile falls with tau


def test_v2_configs_load():
    full = load_benchmark_config(REPO / "configs/benchmark/v2.yaml")
    assert full["env_id"] == "srenv/SuckerRod-v2" and full["history"]
    assert full["evaluate_only"]["references"]["causal_oracle"]
    assert load_benchmark_config(REPO / "configs/benchmark/v2_quick.yaml")["test"]["seeds"] == [100000, 100001, 100002]


def test_causal_oracle_plays_and_weighs_the_baselines():
    from agents.evaluation.rollout import run_episode
    from agents.policies.causal_oracle import CausalOraclePolicy

    env = gym.make("srenv/SuckerRod-v2", scenario="train", episode_hours=0.25, event_rate_scale=0.0)
    po = {"threshold": 0.9, "idle_time_s": 900, "a_spm": 0.3, "a_stroke": 1.0}
    pol = CausalOraclePolicy(horizon=2, replan_every=3, steps=(), policies=[["pump_off", po]])
    rec = run_episode(env, pol, 1)
    # one re-plan: the last action and idle (2 steps each) and the pump-off closed loop (2 steps)
    assert rec["steps"] == 3 and pol.sim_steps == 6 and math.isfinite(rec["reward"])
    assert pol.params()["policies"] == [["pump_off", po]]


def test_evaluate_only_writes_the_report_schema_and_replay_reproduces_it(tmp_path):
    from agents.benchmark.fresh import evaluate_fresh
    from agents.evaluation.replay import replay

    cfg = tmp_path / "fresh.yaml"
    cfg.write_text("env_id: srenv/SuckerRod-v2\nenv_kwargs: {observation: field, episode_hours: 0.25}\n"
                   "workers: 1\ntuning: {scenario: train, seeds: [0]}\ntest: {seeds: [100000]}\n"
                   "evaluate_only: {agents: [ppo_residual_distilled_ensemble], references: {}}\n")
    out = tmp_path / "out"
    evaluate_fresh(str(cfg), 11, 1, out)
    rep = json.loads((out / "benchmark.json").read_text())
    assert rep["fresh"]["seed"] == 11 and rep["fresh"]["family_seeds"] == fresh_wells(11, 1)
    for name in ("installed", "pump_off", "alarm_pump_off", "ppo_residual_distilled_ensemble"):
        e = rep["policies"][name]["episodes"][0]
        assert e["well_id"] == f"family-{fresh_wells(11, 1)[0]}" and e["seed"] == 0
        assert math.isfinite(e["reward"]) and e["cost"] >= 0
    res = replay(out / "benchmark.json", ["pump_off", "ppo_residual_distilled_ensemble"], episodes=1, tol=1e-6)
    assert res["reproduced"], res
