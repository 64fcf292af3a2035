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
from agents.benchmark.stages import tune_baselines
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
    alarm_cfg = load_benchmark_config(REPO / "configs/benchmark/v2.yaml", quick=True)
    assert "alarm_pump_off" in alarm_cfg["baselines"]
    for scenario in ("test", "validation", "family:123"):
        with pytest.raises(ValueError, match="refused"):
            refuse_test_split(scenario, "tune")
        with pytest.raises(ValueError, match="refused"):
            TuningSet([0], scenario, "srenv/SuckerRod-v2")
        # the benchmark's tuning stage, alarm_pump_off included, refuses before any episode (no runner needed)
        with pytest.raises(ValueError, match="refused"):
            tune_baselines({**alarm_cfg, "tuning": {"scenario": scenario, "seeds": [0]}}, None, print)
    refuse_test_split("train", "tune")


def _tiny_v2_quick(episode_hours=1.0):
    """v2.yaml's quick config (its alarm_pump_off block as shipped) on one short tuning episode, coarse searches."""
    cfg = load_benchmark_config(REPO / "configs/benchmark/v2.yaml", quick=True)
    cfg["env_kwargs"] = {**cfg["env_kwargs"], "episode_hours": episode_hours}
    cfg["tuning"]["seeds"] = [0]
    bl = cfg["baselines"]
    bl["best_constant"] = {"n_spm": 2, "n_stroke": 2, "refine_iters": 0}
    bl["pump_off"]["space"] = {"threshold": [0.5, 0.99]}
    bl["fillage_pi"]["space"] = {}
    return cfg


def test_quick_config_tunes_alarm_pump_off_on_training_wells():
    from agents.evaluation.rollout import Runner

    cfg = _tiny_v2_quick()
    space = cfg["baselines"]["alarm_pump_off"]["space"]
    assert set(space) <= {"load_drop", "alarm_prob", "gas_slowdown"} and cfg["baselines"]["alarm_pump_off"]["rounds"] == 1
    with Runner(1) as runner:
        tuned, split = tune_baselines(cfg, runner, lambda m: None)
    assert all(w.startswith("train-") for w in split["well_ids"]) and split["scenario"] == "train"
    alarm, po = tuned["alarm_pump_off"], tuned["pump_off"]
    # it starts from pump-off's TUNED set point (the config names pump_off), with the alarms' init values
    first = alarm["evaluated"][0]
    assert {k: first[k] for k in po["params"]} == po["params"]
    assert (first["load_drop"], first["alarm_prob"], first["gas_slowdown"]) == (0.5, 0.6, 0.3)
    # the search ran over the space: the init and every value of every searched parameter, scored
    assert len(alarm["evaluated"]) == 1 + sum(len(v) for v in space.values())
    for key, values in space.items():
        assert {e[key] for e in alarm["evaluated"]} >= set(values)
    assert alarm["score"] == pytest.approx(max(e["score"] for e in alarm["evaluated"]))
    # on training seed 0 the classifier's false tubing-leak reading shuts the well in at alarm_prob 0.6
    # (docs/agents.md, "The v2 benchmark"): the tuner switches that alarm off and gains
    assert alarm["params"]["alarm_prob"] == 1.0 and alarm["score"] > first["score"]
    assert set(alarm["params"]) == set(po["params"]) | {"load_drop", "alarm_prob", "gas_slowdown"}


def test_alarm_init_must_name_a_baseline_tuned_before(tmp_path):
    import yaml

    raw = yaml.safe_load((REPO / "configs/benchmark/v2_quick.yaml").read_text())
    raw["baselines"]["alarm_pump_off"]["init"]["threshold"] = "oracle"
    p = tmp_path / "bad.yaml"
    p.write_text(yaml.safe_dump(raw))
    with pytest.raises(ValueError, match="baselines.alarm_pump_off.init.threshold = 'oracle'"):
        load_benchmark_config(p)
    raw["baselines"]["alarm_pump_off"]["init"]["threshold"] = "pump_off"
    raw["baselines"]["pump_off"]["init"]["a_spm"] = "alarm_pump_off"  # tuned after pump_off: refused
    p.write_text(yaml.safe_dump(raw))
    with pytest.raises(ValueError, match="baselines.pump_off.init.a_spm"):
        load_benchmark_config(p)


def _fake_episodes(offset, n=6):
    return [{"well_id": f"test-{k % 3}", "seed": 100000 + k, "reward": float(k * 10 + offset), "cost": 0.0,
             "reward_rate_usd_h": float(k + offset), "steps": 4} for k in range(n)]


def test_report_has_the_tuned_alarm_controller_in_every_table():
    from agents.benchmark.assemble import policy_records
    from agents.benchmark.report import build_report, markdown_tables
    from agents.policies.factory import benchmark_baselines

    cfg = load_benchmark_config(REPO / "configs/benchmark/v2.yaml", quick=True)
    v1 = load_benchmark_config(REPO / "configs/benchmark/v1.yaml", quick=True)
    assert "alarm_pump_off" in benchmark_baselines(cfg["baselines"])
    assert "alarm_pump_off" not in benchmark_baselines(v1["baselines"])  # v1's benchmark is unchanged
    names = benchmark_baselines(cfg["baselines"])
    tuned = {n: {"params": {"k": i}} for i, n in enumerate(names)}
    by_entry = {(n, -1): _fake_episodes(i if n != "oracle" else 50) for i, n in enumerate(names)}
    policies, _ = policy_records({**cfg, "agents": {"selection": "mean", "runs": {}}}, tuned, {}, {}, by_entry, {},
                                 REPO / "models")
    assert policies["alarm_pump_off"] == {"kind": "baseline", "params": tuned["alarm_pump_off"]["params"],
                                          "episodes": by_entry[("alarm_pump_off", -1)]}
    policies["agent"] = {"kind": "agent", "episodes": _fake_episodes(3)}
    splits = {"tuning": {}, "validation": {}, "test": {}}
    rep = build_report(cfg, policies, splits, tuned, {}, {"total": 0.0})
    assert "alarm_pump_off" in rep["summary"] and "alarm_pump_off" in rep["paired"]["agent"]
    # agent - alarm_pump_off = 3 - alarm's offset on every episode
    off = names.index("alarm_pump_off")
    assert rep["paired"]["agent"]["alarm_pump_off"]["mean_diff_reward"] == pytest.approx(3 - off)
    assert "| alarm_pump_off | baseline |" in markdown_tables(rep)
    rl = rliable_section(rep, reps=50, seed=0)
    assert "alarm_pump_off" in rl["iqm"] and "alarm_pump_off" in rl["probability_of_improvement"]["agent"]


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


def test_quick_runs_play_the_validation_split_not_the_test_split(tmp_path):
    """A pipeline check spends no look at the test split: both quick configs test on v2's validation wells,
    the full run on the test split; any other scenario is refused before work."""
    import yaml

    from agents.benchmark.config import BenchmarkConfigError
    from agents.evaluation.replay import _scenario

    assert load_benchmark_config(REPO / "configs/benchmark/v2.yaml")["test"]["scenario"] == "test"
    for cfg in (load_benchmark_config(REPO / "configs/benchmark/v2.yaml", quick=True),
                load_benchmark_config(REPO / "configs/benchmark/v2_quick.yaml")):
        assert cfg["test"]["scenario"] == "validation"
    assert _scenario({"test": {"scenario": "validation"}}, 0) == "validation"
    assert _scenario({"test": {}}, 0) == "test"
    raw = yaml.safe_load((REPO / "configs/benchmark/v2_quick.yaml").read_text())
    raw["test"]["scenario"] = "train"
    bad = tmp_path / "bad.yaml"
    bad.write_text(yaml.safe_dump(raw))
    with pytest.raises(BenchmarkConfigError, match="test.scenario"):
        load_benchmark_config(bad)


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


def test_evaluate_only_takes_the_tuned_alarm_params_from_the_report_else_the_fixed_ones():
    from agents.benchmark.fresh import _specs

    cfg = load_benchmark_config(REPO / "configs/benchmark/v2.yaml")
    cfg["evaluate_only"] = {**cfg["evaluate_only"], "agents": [], "references": {}}
    rep = json.loads(shipped_report().read_text())  # the shipped v1 report: no tuned alarm controller
    assert "alarm_pump_off" not in rep["policies"]
    fixed = _specs(cfg, rep, REPO)["alarm_pump_off"][0]["params"]
    assert fixed == {**rep["policies"]["pump_off"]["params"], **cfg["evaluate_only"]["alarm_params"]}
    tuned = {"threshold": 0.9, "idle_time_s": 900.0, "a_spm": 0.4, "a_stroke": 1.0, "load_drop": 0.7,
             "alarm_prob": 0.8, "gas_slowdown": 0.0}
    rep["policies"]["alarm_pump_off"] = {"kind": "baseline", "params": tuned, "episodes": []}
    assert _specs(cfg, rep, REPO)["alarm_pump_off"] == [{"kind": "baseline", "name": "alarm_pump_off",
                                                         "params": tuned}]
    rep["env_id"] = cfg["env_id"]  # a v2 report of this benchmark: the same
    assert _specs(cfg, rep, REPO)["alarm_pump_off"][0]["params"] == tuned
    rep["policies"]["alarm_pump_off"]["params"] = {**tuned, "alarm_prob": 0.05}  # checked as any report field
    with pytest.raises(ValueError, match="alarm_prob"):
        _specs(cfg, rep, REPO)


def test_pilot_config_plays_the_validation_split_and_names_its_env_in_the_report(tmp_path):
    """The v2 pilot (docs/agents.md, "The v2 pilot") spends no look at the test split, and a report's title names
    the env it ran on (it said v1 for every config before)."""
    from agents.benchmark.report import write_markdown

    pilot = load_benchmark_config(REPO / "configs/benchmark/v2_pilot.yaml")
    assert pilot["test"]["scenario"] == "validation" and pilot["env_id"] == "srenv/SuckerRod-v2"
    assert pilot["tuning"]["scenario"] == "train"
    report = json.loads((REPO / "docs/archive/benchmark_v2_pilot.json").read_text())
    assert report["test"]["scenario"] == "validation" and report["env_id"] == "srenv/SuckerRod-v2"
    write_markdown(report, tmp_path / "b.md", None)
    assert (tmp_path / "b.md").read_text().splitlines()[0].endswith("(srenv/SuckerRod-v2)")


def test_evaluate_only_plays_the_report_it_is_given(tmp_path):
    """``--report``: the tuned baselines (and agents) of a benchmark run that is not the shipped one, e.g. a v2
    run's own report for its fresh-split headline; a report of another env is refused before any work."""
    from agents.benchmark.fresh import evaluate_fresh
    from agents.cli import main

    rep = json.loads(shipped_report().read_text())
    rep["env_id"] = "srenv/SuckerRod-v2"
    tuned = {**rep["policies"]["pump_off"]["params"], "threshold": 0.5}  # not the shipped report's
    rep["policies"] = {n: rep["policies"][n] for n in ("installed", "best_constant", "pump_off", "fillage_pi")}
    rep["policies"]["pump_off"] = {**rep["policies"]["pump_off"], "params": tuned}
    (tmp_path / "run").mkdir()
    given = tmp_path / "run" / "benchmark.json"
    given.write_text(json.dumps(rep))
    cfg = tmp_path / "fresh.yaml"
    cfg.write_text("env_id: srenv/SuckerRod-v2\nenv_kwargs: {observation: field, episode_hours: 0.25}\n"
                   "workers: 1\ntuning: {scenario: train, seeds: [0]}\ntest: {seeds: [100000]}\n"
                   "evaluate_only: {agents: [], references: {}}\n")
    out = tmp_path / "out"
    evaluate_fresh(str(cfg), 5, 1, out, report=given)
    got = json.loads((out / "benchmark.json").read_text())
    assert got["shipped_report"] == str(given) and got["policies"]["pump_off"]["params"] == tuned
    v1 = tmp_path / "v1.yaml"  # a v2 report cannot be played on v1: one line, exit 2, nothing written
    v1.write_text(cfg.read_text().replace("SuckerRod-v2", "SuckerRod-v1"))
    bad = tmp_path / "bad"
    argv = ["benchmark", str(v1), "--evaluate-only", "--fresh-seed", "5", "--episodes", "1",
            "--out-dir", str(bad), "--report", str(given)]
    assert main(argv) == 2 and not bad.exists()
    argv[-1] = str(tmp_path / "missing.json")
    assert main(argv) == 2 and not bad.exists()
    assert main(["benchmark", str(cfg), "--report", str(given)]) == 2  # --report only with --evaluate-only


def test_env_tag_names_the_version():
    from agents.envs import env_tag

    assert env_tag("srenv/SuckerRod-v1") == "v1" and env_tag("srenv/SuckerRod-v2") == "v2"
    with pytest.raises(ValueError, match="env_id"):
        env_tag("srenv/SuckerRod")


@pytest.mark.parametrize("env_id, scenario, error", [
    ("srenv/SuckerRod-v2", None, None), ("srenv/SuckerRod-v2", "validation", None),
    ("srenv/SuckerRod-v1", "validation", "only v2 and later"), ("srenv/SuckerRod-v2", "test", "expected one of"),
    ("srenv/SuckerRod-v2", "family:7", "expected one of")])
def test_the_validation_stage_plays_the_wells_its_config_names(env_id, scenario, error, tmp_path, monkeypatch):
    """Model selection on the training wells (every config so far) or on v2's validation split (wells no tuning or
    training drew: what predicts the test and fresh wells); the stage plays what the config says, a v1 config or
    another split is refused in one line before any work."""
    import yaml

    from agents.benchmark import stages
    from agents.benchmark.config import BenchmarkConfigError

    raw = yaml.safe_load((REPO / "configs/benchmark/v2_quick.yaml").read_text())
    raw["env_id"] = env_id
    raw["validation"] = {"seeds": {"start": 20000, "count": 2}, **({"scenario": scenario} if scenario else {})}
    path = tmp_path / "c.yaml"
    path.write_text(yaml.safe_dump(raw))
    if error:
        with pytest.raises(BenchmarkConfigError, match=error):
            load_benchmark_config(path)
        return
    cfg = load_benchmark_config(path)
    assert cfg["validation"]["scenario"] == (scenario or "train")
    seen = []

    def jobs(env, kwargs, spec, seeds):
        seen.append(kwargs["scenario"])
        return [{"seed": s} for s in seeds]
    monkeypatch.setattr(stages, "episode_jobs", jobs)
    monkeypatch.setattr(stages, "_mapped", lambda runner, js, what: [{"reward": 1.0, "well_id": "w"} for _ in js])
    scores, _ = stages.validate(cfg, None, {"ppo": [{"kind": "agent", "path": "m.zip"}]})
    assert seen == [scenario or "train"] and scores == {"ppo": [1.0]}


@pytest.mark.parametrize("block", ["tuning", "validation", "test"])
def test_a_misspelt_key_in_a_split_block_is_refused_not_defaulted(block, tmp_path):
    """``scenaro: validation`` would otherwise play the default wells silently (a pre-registered gate on the wrong
    split); the splits' keys are declared once (SPLIT_KEYS)."""
    import yaml

    from agents.benchmark.config import BenchmarkConfigError

    raw = yaml.safe_load((REPO / "configs/benchmark/v2_quick.yaml").read_text())
    raw.setdefault(block, {"seeds": {"start": 20000, "count": 2}})["scenaro"] = "validation"
    path = tmp_path / "c.yaml"
    path.write_text(yaml.safe_dump(raw))
    with pytest.raises(BenchmarkConfigError, match=f"{block}: unknown key.*scenaro"):
        load_benchmark_config(path)
