"""The v3 benchmark (configs/benchmark/v3.yaml, docs/v3/benchmark.md): its config is v2's protocol on v3, ``--quick``
runs end to end on v3 and names it, the tuning code refuses the held-out splits on v3 too, ``--evaluate-only``
plays v3's tuned baselines and the shipped v2 students on v3 (replay reproduces it), and a v3 benchmark never
trains on another env."""

import json
import math
from pathlib import Path

import pytest

from agents.benchmark.config import BenchmarkConfigError, load_benchmark_config
from agents.benchmark.fresh import default_report, load_tuned, with_tuned
from agents.benchmark.stages import tune_baselines
from agents.envs import ENV_ID_V2, ENV_ID_V3, PLAYABLE_REPORTS
from agents.evaluation.replay import ReplayError, load_report
from agents.training.tuning import TuningSet

REPO = Path(__file__).resolve().parents[2]
V3 = REPO / "configs/benchmark/v3.yaml"
V3_QUICK = REPO / "configs/benchmark/v3_quick.yaml"


def test_v3_config_is_v2s_protocol_on_v3():
    v3, v2 = load_benchmark_config(V3), load_benchmark_config(REPO / "configs/benchmark/v2.yaml")
    assert v3["env_id"] == ENV_ID_V3 and v3["env_kwargs"] == v2["env_kwargs"]
    for key in ("tuning", "validation", "test", "baselines", "workers"):
        assert v3[key] == v2[key], key
    assert v3["evaluate_only"]["references"] == v2["evaluate_only"]["references"]  # the causal oracle as v2's
    first = v3["history"][0]
    assert "2026-12-08" in first and "issue 24" in first and "no v3 test or fresh episode" in first
    assert v3["agents"]["runs"] == {}  # no agent design is registered: each gets its own history line first
    for cfg in (load_benchmark_config(V3, quick=True), load_benchmark_config(V3_QUICK)):
        assert cfg["env_id"] == ENV_ID_V3 and cfg["test"]["scenario"] == "validation"  # no test look
        assert cfg["evaluate_only"]["tuned"] == "docs/v3/tuned.json"


def test_tuning_refuses_held_out_wells_on_v3():
    cfg = load_benchmark_config(V3, quick=True)
    for scenario in ("test", "validation", "family:123"):
        with pytest.raises(ValueError, match="refused"):
            TuningSet([0], scenario, ENV_ID_V3)
        with pytest.raises(ValueError, match="refused"):  # before any episode: no runner needed
            tune_baselines({**cfg, "tuning": {"scenario": scenario, "seeds": [0]}}, None, print)


def test_a_v3_benchmark_refuses_a_training_yaml_of_another_env(tmp_path):
    import yaml

    raw = yaml.safe_load(V3_QUICK.read_text())
    raw["agents"]["runs"]["ppo_residual"]["config"] = "configs/train/ppo_residual_v2.yaml"
    bad = tmp_path / "bad.yaml"
    bad.write_text(yaml.safe_dump(raw))
    with pytest.raises(BenchmarkConfigError, match="ppo_residual_v2.yaml: env_id = 'srenv/SuckerRod-v2': expected "
                                                   "the benchmark's env_id 'srenv/SuckerRod-v3'"):
        load_benchmark_config(bad)


def test_quick_runs_end_to_end_on_v3_and_its_report_names_v3(tmp_path):
    from agents.benchmark.run import run_benchmark

    cfg = load_benchmark_config(V3, quick=True)
    cfg.update(workers=1, env_kwargs={**cfg["env_kwargs"], "episode_hours": 0.25})
    cfg["tuning"]["seeds"], cfg["validation"]["seeds"], cfg["test"]["seeds"] = [0], [20000], [100000, 100001]
    bl = cfg["baselines"]
    bl["best_constant"] = {"n_spm": 2, "n_stroke": 1, "refine_iters": 0}
    bl["oracle"] = {**bl["oracle"], "n_spm": 2, "n_stroke": 1, "segments": 1}
    cfg["agents"]["runs"]["ppo_residual"]["overrides"] = {"n_timesteps": 32, "n_steps": 16, "batch_size": 16}
    rep = run_benchmark(cfg, tmp_path / "out", quick=True)
    assert rep["env_id"] == ENV_ID_V3 and rep["quick"] and rep["test"]["scenario"] == "validation"
    assert all(w.startswith("train-") for w in rep["tuning"]["well_ids"])
    assert {"installed", "pump_off", "alarm_pump_off", "ppo_residual"} <= set(rep["policies"])
    assert all(math.isfinite(e["reward"]) for p in rep["policies"].values() for e in p["episodes"])
    assert (tmp_path / "out/benchmark.md").read_text().splitlines()[0].endswith("(srenv/SuckerRod-v3)")
    assert (tmp_path / "out/models/ppo_residual_v3_seed0.zip").is_file()  # named for v3, never v2


def test_v3_tuned_baselines_replace_a_v2_reports_and_its_students_base():
    tuned = load_tuned(REPO / "docs/v3/tuned.json")
    v2 = load_report(REPO / "docs/v2/benchmark.json")
    rep = with_tuned(v2, tuned)
    for name in ("best_constant", "pump_off", "fillage_pi", "alarm_pump_off"):
        assert rep["policies"][name]["params"] == tuned[name]["params"]
    student = rep["policies"]["oracle_distilled_ensemble"]
    assert student["residual_on"]["params"] == tuned["pump_off"]["params"] and student["residual_on"]["scale"] == 0.5
    assert student["models"] == v2["policies"]["oracle_distilled_ensemble"]["models"]
    assert student["sha256"] == v2["policies"]["oracle_distilled_ensemble"]["sha256"]  # the pins as shipped
    assert v2["policies"]["fillage_pi"]["params"] != tuned["fillage_pi"]["params"]  # the report itself untouched
    # the default report of the v3 config: the shipped v2 one (no v3 agent is shipped), which v3 may play
    assert load_report(default_report(load_benchmark_config(V3)))["env_id"] == ENV_ID_V2
    assert PLAYABLE_REPORTS[ENV_ID_V3][:2] == (ENV_ID_V3, ENV_ID_V2)


def test_a_tuned_archive_that_is_not_one_is_refused_in_one_line(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)  # the config's relative path is found in the checkout from anywhere
    assert load_tuned("docs/v3/tuned.json") == load_tuned(REPO / "docs/v3/tuned.json")
    with pytest.raises(ReplayError, match="evaluate_only.tuned = .*no such file"):
        load_tuned(tmp_path / "missing.json")
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps({"tuned": {"pump_off": {"params": [1, 2]}}}))
    with pytest.raises(ReplayError, match=r"expected a mapping baseline -> \{params"):
        load_tuned(bad)


def test_evaluate_only_plays_v3s_tuned_baselines_and_v2s_students_and_replay_reproduces_it(tmp_path):
    """A pipeline test on one 15-min episode of a family well (as v2's evaluate-only test): no figure is read."""
    from agents.benchmark.fresh import evaluate_fresh
    from agents.cli import main
    from agents.evaluation.replay import replay

    cfg = tmp_path / "fresh.yaml"
    cfg.write_text("env_id: srenv/SuckerRod-v3\nenv_kwargs: {observation: field, episode_hours: 0.25}\n"
                   "workers: 1\ntuning: {scenario: train, seeds: [0]}\ntest: {seeds: [100000]}\n"
                   f"evaluate_only: {{agents: [oracle_distilled_ensemble], tuned: {REPO / 'docs/v3/tuned.json'}, "
                   "references: {}}\n")
    out = tmp_path / "out"
    evaluate_fresh(str(cfg), 11, 1, out)
    rep = json.loads((out / "benchmark.json").read_text())
    tuned = load_tuned(REPO / "docs/v3/tuned.json")
    assert rep["env_id"] == ENV_ID_V3 and rep["tuned_from"].endswith("docs/v3/tuned.json")
    assert rep["policies"]["fillage_pi"]["params"] == tuned["fillage_pi"]["params"]
    assert rep["policies"]["oracle_distilled_ensemble"]["residual_on"]["params"] == tuned["pump_off"]["params"]
    res = replay(out / "benchmark.json", ["fillage_pi", "oracle_distilled_ensemble"], episodes=1, tol=1e-6)
    assert res["reproduced"], res
    v2 = tmp_path / "v2.yaml"  # a v3 report cannot be played on v2: one line, exit 2, nothing written
    v2.write_text(cfg.read_text().replace("SuckerRod-v3", "SuckerRod-v2"))
    bad = tmp_path / "bad"
    assert main(["benchmark", str(v2), "--evaluate-only", "--fresh-seed", "5", "--episodes", "1",
                 "--out-dir", str(bad), "--report", str(out / "benchmark.json")]) == 2 and not bad.exists()


def test_v3_trains_on_its_native_vector_env_and_takes_a_residual():
    from agents.training.native_vec import native_plan
    from agents.training.residual_env import RESIDUAL_ENV_ID, make_residual_env

    kwargs = {"inner_env_id": ENV_ID_V3, "base": "pump_off", "scale": 0.5, "scenario": "train"}
    inner, rest, shaped, residual = native_plan(RESIDUAL_ENV_ID, kwargs)
    assert inner == ENV_ID_V3 and rest == {"scenario": "train"} and not shaped and residual["base"] == "pump_off"
    env = make_residual_env(ENV_ID_V3, "pump_off", scale=0.5, scenario="train", episode_hours=0.25)
    try:
        assert env.unwrapped.spec.id == ENV_ID_V3  # the residual drives v3 itself, not v2
        obs, _ = env.reset(seed=0)
        assert obs.shape == (env.observation_space.shape[0],)
    finally:
        env.close()
