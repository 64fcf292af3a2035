"""The causal oracle as a DAgger teacher (agents/training/oracle_distill.py) on a tiny v2 env (30 min episodes of 5 min
intervals, no events): its labels are its own actions as residual corrections, the held-out splits are refused, the same seed
gives the same student, a warm start continues the given student, the benchmark config checks the teacher block, and
the design's config runs --quick."""

from __future__ import annotations

import subprocess
import sys
import zipfile
from pathlib import Path

import numpy as np
import pytest
import yaml

import srenv  # noqa: F401
from agents.benchmark.config import load_benchmark_config
from agents.envs import make_env
from agents.evaluation.agent import AgentPolicy
from agents.evaluation.rollout import Runner
from agents.policies.causal_oracle import CausalOraclePolicy
from agents.policies.residual import compose
from agents.training.oracle_distill import distill_oracle, label_of, oracle_episode_job, oracle_jobs

REPO = Path(__file__).resolve().parents[2]
ENV = "srenv/SuckerRod-v2"
KW = {"observation": "field", "episode_hours": 0.5, "event_rate_scale": 0.0}
PO = {"threshold": 0.9, "idle_time_s": 900, "a_spm": 0.3, "a_stroke": 1.0}
FPI = {"setpoint": 0.95, "kp": 0.5, "ki": 0.2, "a_stroke": 0.0}
ORACLE = {"horizon": 2, "replan_every": 2, "steps": [0.3], "policies": [["pump_off", PO], ["fillage_pi", FPI]]}
CONFIG = REPO / "configs/benchmark/v2_oracle_distilled.yaml"
MORE = REPO / "configs/benchmark/v2_oracle_distilled_more.yaml"  # the shipped students continued (issue 24, d24)
POOLED = REPO / "configs/benchmark/v2_oracle_distilled_pooled.yaml"  # one pooled student (issue 24, e24)


def test_label_inverts_compose_and_clips_out_of_reach():
    b = np.array([0.2, -0.4], np.float32)
    a = np.array([0.5, 0.9], np.float32)
    assert label_of(a, b, 0.5) == pytest.approx([0.6, 1.0])  # stroke 1.3 away: clipped at the reach
    np.testing.assert_allclose(compose(b, label_of(a, b, 2.0), 2.0), a, atol=1e-6)
    idle = np.array([-1.0, 0.0], np.float32)  # the base idles: the rate entry's scale is idle_scale
    assert label_of(np.array([0.0, 0.0]), idle, 0.5, idle_scale=2.0)[0] == pytest.approx(0.5)


def test_labels_are_the_oracles_own_actions_when_it_acts():
    """beta 1 and scale 2 (every action within reach): the labelled episode IS the oracle's, decision by decision."""
    res = {"base": "fillage_pi", "params": FPI, "scale": 2.0}
    ep = oracle_episode_job(oracle_jobs(ENV, {**KW, "scenario": "train"}, ORACLE, res, None, [7], 1.0, 0)[0])
    np.testing.assert_allclose(compose(ep["a_base"], ep["label"], 2.0), ep["a_oracle"], atol=1e-6)
    env = make_env(ENV, scenario="train", **KW)
    pol = CausalOraclePolicy(**ORACLE)
    obs, _ = env.reset(seed=7)
    pol.reset(env)
    acts, total, done = [], 0.0, False
    while not done:
        a = pol.predict(obs)[0]
        acts.append(np.asarray(a, np.float32).reshape(2))
        obs, r, term, trunc, _ = env.step(a)
        total, done = total + float(r), term or trunc
    assert ep["steps"] == len(acts) >= 3
    np.testing.assert_allclose(ep["a_oracle"], np.array(acts), atol=1e-5)
    assert ep["reward"] == pytest.approx(total, rel=1e-6)
    assert ep["model_steps"] > 0 and ep["x"].shape == (len(acts), len(env.observation_space.low) + 2)


@pytest.mark.parametrize("scenario", ["validation", "test", "family:5"])
def test_oracle_teacher_refuses_held_out_splits(tmp_path, scenario):
    res = {"base": "fillage_pi", "params": FPI, "scale": 0.5}
    with pytest.raises(ValueError, match="refused"):
        oracle_episode_job(oracle_jobs(ENV, {**KW, "scenario": scenario}, ORACLE, res, None, [7], 1.0, 0)[0])
    with pytest.raises(ValueError, match="refused"):
        distill_oracle(None, {"iterations": 1, "episodes": 1}, ORACLE, res, ENV, {**KW, "scenario": scenario},
                       {"net_arch": [8, 8]}, [50000], 0, tmp_path / "s.zip")


def _student(tmp_path: Path, seed: int) -> tuple[dict, bytes]:
    res = {"base": "fillage_pi", "params": FPI, "scale": 0.5}
    with Runner(1) as runner:
        spec = distill_oracle(runner, {"iterations": 2, "episodes": 1, "beta0": 0.5}, ORACLE, res, ENV,
                              {**KW, "scenario": "train"}, {"net_arch": [8, 8]}, [50000, 50001], seed,
                              tmp_path / "student.zip")
    with zipfile.ZipFile(spec["path"]) as z:
        return spec, z.read("policy.pth")


def test_same_seed_same_student_and_it_fits_the_labels(tmp_path):
    a, wa = _student(tmp_path / "a", 3)
    b, wb = _student(tmp_path / "b", 3)
    _, wc = _student(tmp_path / "c", 4)
    assert wa == wb and wa != wc
    assert [h["labels"] for h in a["distill"]] == [6, 12]  # 30 min of 5 min intervals, 2 iterations
    for ha, hb in zip(a["distill"], b["distill"]):
        assert {k: v for k, v in ha.items() if k != "rollout_cpu_s"} == {k: v for k, v in hb.items()
                                                                         if k != "rollout_cpu_s"}
    za, zb = np.load(tmp_path / "a/student_labels.npz"), np.load(tmp_path / "b/student_labels.npz")
    for k in ("x", "label", "a_oracle", "a_base"):
        np.testing.assert_array_equal(za[k], zb[k])
    # the fitted student is nearer the oracle's corrections than the base controller (correction 0) is
    st = AgentPolicy(a["path"], a["obs_norm"])
    own = np.array([st.predict(x)[0] for x in za["x"]]).reshape(-1, 2)
    assert np.mean((own - za["label"]) ** 2) < np.mean(za["label"] ** 2)
    assert not (tmp_path / "a/student_init.zip").exists()


def test_warm_start_continues_the_given_student_and_fits_it_toward_the_labels(tmp_path):
    """teacher.init: before any fit the run's student IS the given one (its episode, return for return; its statistics
    kept byte for byte), and the fit moves it toward the new labels."""
    from agents.evaluation.rollout import episode_jobs

    first, _ = _student(tmp_path / "a", 3)
    res = {"base": "fillage_pi", "params": FPI, "scale": 0.5}
    init = {"path": str(tmp_path / "a/student.zip"),
            "obs_norm": str(tmp_path / "a/student_obs_norm.npz")}
    with Runner(1) as runner:
        spec = distill_oracle(runner, {"iterations": 1, "episodes": 1, "beta0": 0.0, "init": init}, ORACLE, res, ENV,
                              {**KW, "scenario": "train"}, {"net_arch": [8, 8]}, [50002], 3, tmp_path / "b/more.zip")
        own = runner.map(episode_jobs(ENV, {**KW, "scenario": "train"}, {**first, "residual": res}, [50002]))[0]
    assert spec["distill"][0]["rollout_mean_return"] == pytest.approx(own["reward"], rel=1e-9)
    assert (tmp_path / "b/more_obs_norm.npz").read_bytes() != b""
    za, zb = np.load(first["obs_norm"]), np.load(spec["obs_norm"])
    assert all(np.array_equal(za[k], zb[k]) for k in za.files)
    z = np.load(tmp_path / "b/more_labels.npz")
    assert len(z["x"]) == 6  # this run's labels only, not the first run's
    before, after = AgentPolicy(first["path"], first["obs_norm"]), AgentPolicy(spec["path"], spec["obs_norm"])
    mse = [np.mean((np.array([p.predict(x)[0] for x in z["x"]]).reshape(-1, 2) - z["label"]) ** 2)
           for p in (before, after)]
    assert mse[1] < mse[0]
    assert (tmp_path / "a/student.zip").exists() and not (tmp_path / "b/more_init.zip").exists()


def _raw(path: Path = CONFIG) -> dict:
    return yaml.safe_load(path.read_text())


@pytest.mark.parametrize("change, match", [
    (lambda t, r: t.update(kind="ppo"), "teacher.kind = 'ppo': expected causal_oracle"),
    (lambda t, r: t.update(students_from="x"), r"teacher: unknown key\(s\) \['students_from'\]"),
    (lambda t, r: t.update(iterations=0), r"teacher.iterations = 0: expected an integer in \[1, 20\]"),
    (lambda t, r: t.pop("episodes"), "teacher.episodes = None"),
    (lambda t, r: t.update(beta0=1.5), r"teacher.beta0 = 1.5: expected a number in \[0, 1\]"),
    (lambda t, r: t["params"].update(horizon=0), r"teacher.params.horizon = 0: expected an integer in \[1, 144\]"),
    (lambda t, r: t["params"].update(replan_every=2.5), "teacher.params.replan_every = 2.5"),
    (lambda t, r: t["params"].update(mode="plan"), "teacher.params = "),
    (lambda t, r: t["params"].update(steps=[0.0]), "teacher.params.steps = "),
    (lambda t, r: r.pop("residual"), "expected a residual run"),
    (lambda t, r: t.update(seed_start=19990), "share seeds"),
    (lambda t, r: t.update(init="models/x.zip"), r"teacher.init = 'models/x.zip': expected \{path: STUDENT.zip"),
    (lambda t, r: t.update(init={"path": "models/oracle_distilled_v2_seed{seed}.zip"}), r"teacher.init = .\{'path': .*\}.: expected \{path"),
    (lambda t, r: t.update(init={"path": 3, "obs_norm": "a.npz"}), r"teacher.init = .*expected \{path"),
    (lambda t, r: t.update(init={"path": "models/nothing_seed{seed}.zip", "obs_norm": "models/ppo_v1_obs_norm.npz"}),
     r"teacher.init.path = 'models/nothing_seed0.zip': expected an existing .zip file"),
    (lambda t, r: t.update(init={"path": "models/ppo_v1_seed{k}.zip", "obs_norm": "models/ppo_v1_obs_norm.npz"}),
     r"teacher.init.path = 'models/ppo_v1_seed\{k\}.zip': expected a path whose only placeholder is \{seed\}"),
    (lambda t, r: t.update(init={"path": "models/ppo_v1_seed{seed}.zip", "obs_norm": "models/ppo_v1.zip"}),
     r"teacher.init.obs_norm = 'models/ppo_v1.zip': expected an existing .npz file"),
], ids=["kind", "unknown-key", "iterations-zero", "episodes-missing", "beta0", "horizon", "replan-float",
        "params-key", "steps", "no-residual", "validation-overlap", "init-not-mapping", "init-key-missing",
        "init-not-text", "init-no-file", "init-placeholder", "init-suffix"])
def test_config_refuses_a_bad_oracle_teacher(tmp_path, monkeypatch, change, match):
    monkeypatch.chdir(REPO)  # the init paths are the checkout's models/
    raw = _raw()
    run = raw["agents"]["runs"]["oracle_distilled"]
    change(run["teacher"], run)
    p = tmp_path / "bad.yaml"
    p.write_text(yaml.safe_dump(raw))
    with pytest.raises(ValueError, match=match):
        load_benchmark_config(p)


@pytest.mark.parametrize("config, change, expected", [
    (CONFIG, lambda t: t["params"].update(horizon=-3), "teacher.params.horizon = -3"),
    (MORE, lambda t: t["init"].update(obs_norm="models/none_seed{seed}.npz"),
     "teacher.init.obs_norm = 'models/none_seed0.npz': expected an existing .npz"),
    # the pooled student's block (agents/training/pooled_fit.py, issue 24, e24)
    (POOLED, lambda t: t["pool"].update(folds=1), "teacher.pool.folds = 1: expected an integer in [2, 20]"),
    (POOLED, lambda t: t["pool"].update(precheck_ratio=1.5), "teacher.pool.precheck_ratio = 1.5: expected a number"),
    (POOLED, lambda t: t["pool"].update(precheck_seed_start=20000),
     "teacher.pool.precheck_seed_start = 20000: its episodes share seeds [20000"),
    (POOLED, lambda t: t["pool"].update(precheck_seed_start=56010),
     "teacher.pool.precheck_seed_start = 56010: its episodes share seeds [56010"),
], ids=["horizon", "init-missing-file", "pool-folds", "pool-ratio", "pool-validation-overlap", "pool-dagger-overlap"])
def test_cli_names_the_bad_field_in_one_line(tmp_path, config, change, expected):
    raw = _raw(config)
    change(raw["agents"]["runs"]["oracle_distilled"]["teacher"])
    p = tmp_path / "bad.yaml"
    p.write_text(yaml.safe_dump(raw))
    r = subprocess.run([sys.executable, "-m", "agents", "benchmark", str(p), "--out-dir", str(tmp_path / "o")],
                       check=False, capture_output=True, text=True, cwd=REPO, timeout=120)
    assert r.returncode == 2 and "Traceback" not in r.stderr
    assert expected in r.stderr.strip().splitlines()[-1]


def test_config_refuses_a_symlinked_init_student(tmp_path, monkeypatch):
    monkeypatch.chdir(REPO)
    (tmp_path / "s0.zip").symlink_to(REPO / "models/oracle_distilled_v2_seed0.zip")
    raw = _raw(MORE)
    raw["agents"]["runs"]["oracle_distilled"]["teacher"]["init"]["path"] = str(tmp_path / "s{seed}.zip")
    p = tmp_path / "bad.yaml"
    p.write_text(yaml.safe_dump(raw))
    with pytest.raises(ValueError, match=r"teacher.init.path = .*s0.zip': expected an existing .zip file \(not a sym"):
        load_benchmark_config(p)


def test_continued_design_starts_from_the_shipped_students_on_unused_seeds(monkeypatch):
    """configs/benchmark/v2_oracle_distilled_more.yaml: the shipped students, acting from the start, continued on
    training seeds neither the shipped run (50000 + 1000 k + 0..59) nor tuning nor validation used."""
    from agents.benchmark.config import distill_seeds

    monkeypatch.chdir(REPO)
    cfg = load_benchmark_config(MORE)
    run, shipped = cfg["agents"]["runs"]["oracle_distilled"], load_benchmark_config(CONFIG)["agents"]["runs"]
    t = run["teacher"]
    assert t["beta0"] == 0.0 and (t["iterations"], t["episodes"]) == (2, 16) and run["ensemble"]
    assert t["init"]["path"].format(seed=1) == "models/oracle_distilled_v2_seed1.zip"
    assert {**t, "init": None, "beta0": None, "iterations": None, "episodes": None, "seed_start": None} == {
        **shipped["oracle_distilled"]["teacher"], "init": None, "beta0": None, "iterations": None, "episodes": None,
        "seed_start": None}
    ours = {s for k in run["seeds"] for s in distill_seeds(t, k)}
    before = {s for k in run["seeds"] for s in distill_seeds(shipped["oracle_distilled"]["teacher"], k)}
    assert len(ours) == 96 and not ours & before and not ours & (set(range(10)) | set(range(20000, 21000)))


@pytest.mark.parametrize("config", [CONFIG, MORE, POOLED], ids=["oracle_distilled", "oracle_distilled_more",
                                                    "oracle_distilled_pooled"])
def test_design_config_keeps_v2s_splits_baselines_and_protocol(config, monkeypatch):
    monkeypatch.chdir(REPO)
    for quick in (False, True):
        ours, v2 = load_benchmark_config(config, quick=quick), load_benchmark_config(REPO / "configs/benchmark/v2.yaml",
                                                                                     quick=quick)
        for k in ("env_id", "env_kwargs", "workers", "tuning", "validation", "test", "baselines", "figure_episode"):
            assert ours[k] == v2[k], k
        assert list(ours["agents"]["runs"]) == ["oracle_distilled"]
        assert ours["agents"]["runs"]["oracle_distilled"]["teacher"]["kind"] == "causal_oracle"
        assert ours["evaluate_only"] == load_benchmark_config(CONFIG, quick=quick)["evaluate_only"]
    assert load_benchmark_config(config, quick=True)["test"]["scenario"] == "validation"  # --quick spends no look


def test_quick_run_trains_the_student_and_reports_it(tmp_path):
    """The design's --quick pipeline, shrunk further (30 min episodes, one tuning well, coarse searches)."""
    from agents.benchmark.run import run_benchmark

    cfg = load_benchmark_config(CONFIG, quick=True)
    cfg["env_kwargs"] = {**cfg["env_kwargs"], "episode_hours": 0.5}
    cfg["tuning"]["seeds"], cfg["validation"]["seeds"], cfg["test"]["seeds"] = [0], [20000], [100000, 100001]
    cfg["workers"] = 1
    bl = cfg["baselines"]
    bl["best_constant"] = {"n_spm": 2, "n_stroke": 2, "refine_iters": 0}
    for name in ("pump_off", "fillage_pi", "alarm_pump_off"):
        bl[name]["space"] = {}
    rep = run_benchmark(cfg, tmp_path / "out", quick=True, log=lambda m: None)
    pol = rep["policies"]["oracle_distilled"]
    assert pol["kind"] == "agent" and len(pol["episodes"]) == 2
    assert pol["residual_on"]["base"] in ("best_constant", "pump_off", "fillage_pi")
    t = rep["training"]["runs"]["oracle_distilled"]["teacher"]
    assert t["kind"] == "causal_oracle" and t["observation"] == "true env state" and t["models"] == []
    assert t["distill"][0]["iterations"][0]["labels"] == 6  # one 30 min episode of 5 min intervals
    assert (tmp_path / "out/benchmark.json").exists()
    # a v2 run's models carry v2's tag, never v1's (they were named *_v1_* before)
    assert pol["models"] == ["models/oracle_distilled_v2_seed0.zip"]
    assert rep["training"]["runs"]["oracle_distilled"]["shipped_model"] == "models/oracle_distilled_v2.zip"
    assert not list((tmp_path / "out/models").glob("*_v1*"))
