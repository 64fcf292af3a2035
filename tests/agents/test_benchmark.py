"""The v1 benchmark harness: baselines' logic, the tuning guard and search, and the ``--quick`` run's JSON.

Most tests drive the fake env of ``tests/conftest.py``, a tank model implementing only the v1 env contract (names, info
keys, splits), so they check the harness in milliseconds; what the real env scores is in
docs/benchmark.md.
"""

from __future__ import annotations

import copy
import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import yaml
from conftest import FAKE_ENV, FIELD_OBS_NAMES

from agents.benchmark.config import load_benchmark_config
from agents.benchmark.report import mean_ci
from agents.envs import make_env
from agents.evaluation.rollout import Runner, run_episode
from agents.policies.field import (
    ConstantPolicy,
    FillagePIPolicy,
    InstalledPolicy,
    PumpOffPolicy,
    action_from_setpoints,
)
from agents.policies.oracle import OraclePolicy
from agents.training.tuning import Evaluator, TuningSet, refuse_test_split, search_best_constant

FAKE = FAKE_ENV
NAMES = FIELD_OBS_NAMES
I_FILL = NAMES.index("fillage_est")
REPO = Path(__file__).resolve().parents[2]


@pytest.fixture()
def env():
    e = make_env(FAKE, scenario="train")
    yield e
    e.close()


def _obs(fill: list[float]) -> np.ndarray:
    o = np.zeros((len(fill), len(NAMES)), np.float32)
    o[:, I_FILL] = fill
    return o


# ------------------------------------------------------------------------------------------- baselines
def test_installed_is_each_wells_configured_point(env) -> None:
    pol = InstalledPolicy()
    for seed in (0, 3):
        obs, _ = env.reset(seed=seed)
        pol.reset(env)
        a, _ = pol.predict(obs)
        cfg = env.unwrapped.cfg
        c = cfg.control
        assert 0.5 * (a[0] + 1) * c.spm_max == pytest.approx(cfg.surface.spm, rel=1e-5)
        assert c.stroke_min_m + 0.5 * (a[1] + 1) * (c.stroke_max_m - c.stroke_min_m) == \
            pytest.approx(cfg.surface.stroke_length_m, rel=1e-5)
    with pytest.raises(RuntimeError, match="reset"):
        InstalledPolicy().predict(obs)


def test_pump_off_idles_for_the_set_time_after_a_low_card_then_restarts() -> None:
    pol = PumpOffPolicy(NAMES, threshold=0.7, idle_time_s=950.0, a_spm=0.4, a_stroke=0.2, interval_s=300.0)
    assert pol.idle_intervals == 3  # 950 s rounds to 3 intervals of 300 s
    # two envs: env 0's card falls below the threshold after the first interval, env 1's never does
    fills = [[1.0, 1.0], [0.5, 0.9], [0.5, 0.9], [0.5, 0.9], [0.5, 0.9], [0.9, 0.9]]
    a0, state = [], None
    for k, f in enumerate(fills):
        a, state = pol.predict(_obs(f), state=state, episode_start=np.array([k == 0] * 2))
        a0.append(a[:, 0].copy())
        assert np.allclose(a[:, 1], 0.2)
    a0 = np.array(a0)
    # env 0: pump, pump (its card says 0.5 now), idle x3 (stale cards ignored), restart
    assert np.allclose(a0[:, 0], [0.4, -1, -1, -1, 0.4, 0.4])
    assert np.allclose(a0[:, 1], 0.4)
    # the first card of an episode (before we pumped) is not a pump-off signal
    a, _ = pol.predict(_obs([0.1])[0], state=None)
    assert a.shape == (2,) and a[0] == pytest.approx(0.4)


def test_fillage_pi_slows_on_low_fillage_speeds_up_on_high_and_goes_intermittent() -> None:
    pol = FillagePIPolicy(NAMES, setpoint=0.8, kp=0.5, ki=0.3, a_stroke=0.5, u0=0.0, u_min=-0.95)
    a, st = pol.predict(_obs([0.4, 1.0]))  # first interval: hold the start speed
    assert np.allclose(a[:, 0], 0.0)
    a, st = pol.predict(_obs([0.4, 1.0]), state=st, episode_start=np.array([False, False]))
    assert a[0, 0] < 0.0 < a[1, 0]
    for _ in range(40):
        a, st = pol.predict(_obs([0.4, 1.0]), state=st, episode_start=np.array([False, False]))
    # saturates at the floor (below spm_min: intermittent, still pumping a little) and at full speed
    assert a[0, 0] == pytest.approx(-0.95, abs=1e-6) and a[1, 0] == pytest.approx(1.0)
    # anti-windup: one interval of the opposite error moves it off the limit at once
    a, st = pol.predict(_obs([1.0, 0.4]), state=st, episode_start=np.array([False, False]))
    assert a[0, 0] > -0.95 and a[1, 0] < 1.0


def test_oracle_lookahead_picks_the_best_candidate_one_step_ahead(env) -> None:
    obs, _ = env.reset(seed=5)
    orc = OraclePolicy(mode="lookahead", steps=(0.3,), horizon=1, anchors=[(0.5, 0.5)])
    orc.reset(env)
    cands = orc.candidates()
    rewards = [copy.deepcopy(env.unwrapped).step(c)[1] for c in cands]
    a, _ = orc.predict(obs)
    assert env.step(a)[1] == pytest.approx(max(rewards))
    assert orc.sim_steps == len(cands)


def test_oracle_plan_is_played_exactly_and_beats_its_candidates(env) -> None:
    """The planner's simulated return is the realised one (perfect model), and it is at least the best
    constant of its grid and each baseline it was given, on this very episode."""
    po = {"threshold": 0.9, "idle_time_s": 600, "a_spm": 1.0, "a_stroke": 1.0}
    orc = OraclePolicy(n_spm=3, n_stroke=2, segments=3, rounds=1, step=0.3, policies=[["pump_off", po]])
    rec = run_episode(env, orc, seed=7)
    assert rec["reward"] == pytest.approx(orc.planned_reward, rel=1e-9)
    others = [run_episode(env, ConstantPolicy(a, b), 7)["reward"] for a in (-1, 0, 1) for b in (-1, 1)]
    others.append(run_episode(env, PumpOffPolicy(NAMES, **po), 7)["reward"])
    assert rec["reward"] >= max(others) - 1e-9
    assert 0 < orc.sim_steps < 40 * rec["steps"]  # bounded: grid + refinement + one baseline


# -------------------------------------------------------------------------------------------- tuning
def test_tuning_refuses_the_test_split() -> None:
    with pytest.raises(ValueError, match="test"):
        TuningSet([0, 1], scenario="test", env_id=FAKE)
    with pytest.raises(ValueError, match="test"):
        refuse_test_split("test", "train")
    with pytest.raises(ValueError, match="test"):
        TuningSet([0, 1], env_id=FAKE, env_kwargs={"scenario": "test"})
    TuningSet([0, 1], scenario="train", env_id=FAKE)  # the training split is fine


def test_benchmark_config_refuses_overlapping_seeds_and_test_tuning(tmp_path) -> None:
    cfg = _quick_cfg(tmp_path)
    cfg["test"]["seeds"] = [1, 2, 50]  # tuning uses 0..2
    p = tmp_path / "bad.yaml"
    p.write_text(yaml.safe_dump(cfg))
    with pytest.raises(ValueError, match="tuning.seeds and test.seeds share"):
        load_benchmark_config(p)
    cfg = _quick_cfg(tmp_path)
    cfg["tuning"]["scenario"] = "test"
    p.write_text(yaml.safe_dump(cfg))
    with pytest.raises(ValueError, match="test"):
        load_benchmark_config(p)


def test_best_constant_search_finds_the_best_of_its_grid() -> None:
    """Against an independent brute force: every grid action rolled out here, the best picked by hand."""
    seeds = [0, 1, 2]
    with Runner(1) as runner:
        ev = Evaluator(TuningSet(seeds, "train", FAKE), runner)
        res = search_best_constant(ev, n_spm=4, n_stroke=3, refine_iters=0)
    env = make_env(FAKE, scenario="train")
    brute = {}
    for a0 in np.linspace(-1, 1, 4):
        for a1 in np.linspace(-1, 1, 3):
            brute[(a0, a1)] = np.mean([run_episode(env, ConstantPolicy(a0, a1), s)["reward"] for s in seeds])
    best = max(brute, key=brute.get)
    assert (res["params"]["a_spm"], res["params"]["a_stroke"]) == pytest.approx(best)
    assert res["score"] == pytest.approx(brute[best])
    # the grid is not flat: the search had something to find
    assert max(brute.values()) - min(brute.values()) > 1.0
    # refinement only ever improves on the grid's best
    with Runner(1) as runner:
        ev = Evaluator(TuningSet(seeds, "train", FAKE), runner)
        refined = search_best_constant(ev, n_spm=4, n_stroke=3, refine_iters=3)
    assert refined["score"] >= res["score"]


def test_action_map_matches_the_contract() -> None:
    from types import SimpleNamespace

    c = SimpleNamespace(spm_min=3.0, spm_max=10.0, stroke_min_m=1.0, stroke_max_m=3.0)
    assert np.allclose(action_from_setpoints(0.0, 1.0, c), [-1, -1])
    assert np.allclose(action_from_setpoints(5.0, 2.0, c), [0, 0], atol=1e-6)
    assert np.allclose(action_from_setpoints(10.0, 3.0, c), [1, 1])


def test_mean_ci_is_the_normal_interval() -> None:
    m, _lo, hi = mean_ci(np.array([1.0, 2.0, 3.0, 4.0]))
    assert m == 2.5 and hi - m == pytest.approx(1.96 * np.std([1, 2, 3, 4], ddof=1) / 2, rel=1e-3)


# --------------------------------------------------------------------------------------- quick run
def _quick_cfg(tmp_path: Path, env_id: str = FAKE, env_kwargs: dict | None = None) -> dict:
    env_kwargs = env_kwargs or {}
    train = {"env_id": env_id, "env_kwargs": {"scenario": "train", **env_kwargs}, "n_envs": 1, "vec_env": "dummy",
             "policy_kwargs": {"net_arch": [8, 8]}, "checkpoint_freq": 10**9, "eval_freq": 10**9,
             "n_eval_episodes": 1, "save_replay_buffer": False}
    (tmp_path / "ppo.yaml").write_text(yaml.safe_dump({**train, "algo": "ppo", "n_timesteps": 96,
                                                       "n_steps": 48, "batch_size": 24, "n_epochs": 1,
                                                       "normalize": {"norm_obs": True, "norm_reward": True}}))
    (tmp_path / "sac.yaml").write_text(yaml.safe_dump({**train, "algo": "sac", "n_timesteps": 60,
                                                       "learning_starts": 30, "batch_size": 16}))
    return {
        "env_id": env_id, "env_kwargs": env_kwargs, "workers": 2,
        "tuning": {"scenario": "train", "seeds": [0, 1, 2]},
        "validation": {"seeds": [500, 501]},
        "test": {"seeds": {"start": 1000, "count": 5}},
        "baselines": {"best_constant": {"n_spm": 3, "n_stroke": 2, "refine_iters": 1},
                      "pump_off": {"init": {"threshold": 0.8, "idle_time_s": 600, "a_spm": 0.5, "a_stroke": 1.0},
                                   "space": {"threshold": [0.6, 0.9]}, "rounds": 1},
                      "fillage_pi": {"init": {"setpoint": 0.8, "kp": 0.5, "ki": 0.3, "a_stroke": 1.0},
                                     "space": {"ki": [0.1, 0.5]}, "rounds": 1},
                      "oracle": {"n_spm": 3, "n_stroke": 2, "segments": 2, "rounds": 1}},
        "agents": {"selection": "mean",
                   "runs": {"ppo": {"config": str(tmp_path / "ppo.yaml"), "seeds": [0, 1], "ensemble": True},
                            "sac": {"config": str(tmp_path / "sac.yaml"), "seeds": [0]},
                            "ppo_residual": {"config": str(tmp_path / "ppo.yaml"), "seeds": [0],
                                             "residual": {"base": "best_tuned", "scale": 0.3,
                                                          "idle_scale": 2.0}},
                            "ppo_residual_shaped": {"config": str(tmp_path / "ppo.yaml"), "seeds": [0],
                                                    "residual": {"base": "best_tuned", "scale": 0.5,
                                                                 "shaping": "potential"}}}},
        "history": ["Run 0 (a test line): kept in the report"],
        "quick": {"test": {"seeds": {"start": 1000, "count": 4}}},
    }


def _has_v1() -> bool:
    try:
        import srenv.envs.sucker_rod_v1  # noqa: F401
    except ImportError:
        return False
    return True


# end to end only on the real env: the training tools refuse env ids outside srenv's own (no module imports
# from a training YAML, docs/reliability.md), so the fake env cannot be trained through the CLI
@pytest.mark.parametrize("real", [pytest.param(True, marks=pytest.mark.skipif(
    not _has_v1(), reason="srenv/SuckerRod-v1 not in this checkout"))], ids=["v1-env"])
def test_quick_benchmark_writes_the_schema_on_disjoint_splits_same_episodes(tmp_path, real) -> None:
    """``benchmark --quick`` end to end (the real v1 env with 1-hour episodes, or the fake one)."""
    cfg = _quick_cfg(tmp_path, "srenv/SuckerRod-v1", {"task__episode_hours": 1.0}) if real else _quick_cfg(tmp_path)
    shaped = cfg["agents"]["runs"]["ppo_residual_shaped"]
    cfg["agents"]["runs"]["distilled"] = {  # a teacher-student run (agents/training/distill.py)
        "config": shaped["config"], "seeds": [0], "residual": dict(shaped["residual"]),
        "teacher": {"students_from": "ppo_residual_shaped", "iterations": 1, "episodes": 1, "seed_start": 40000,
                    "idle_scale": 1.0}}
    cfg_path = tmp_path / "bench.yaml"
    cfg_path.write_text(yaml.safe_dump(cfg))
    out = tmp_path / "out"
    tests_dir = str(Path(__file__).resolve().parents[1])  # tests/: conftest.py, the fake env's module
    import agents
    import srenv

    # the child imports agents and srenv from where this test did
    roots = dict.fromkeys(str(Path(m.__file__).resolve().parent.parent) for m in (agents, srenv))
    env = {"PYTHONPATH": os.pathsep.join([*roots, tests_dir]), "PATH": "/usr/bin:/bin"}
    proc = subprocess.run([sys.executable, "-m", "agents", "benchmark", str(cfg_path), "--quick",
                           "--out-dir", str(out)], check=False, capture_output=True, text=True, env=env, timeout=600,
                          cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr[-3000:]
    last = json.loads(proc.stdout.strip().splitlines()[-1])
    assert last["test_episodes"] == 4  # the quick block applied
    d = json.loads((out / "benchmark.json").read_text())
    P = d["policies"]
    assert set(P) == {"installed", "best_constant", "pump_off", "fillage_pi", "oracle", "ppo", "sac",
                      "ppo_residual", "ppo_residual_shaped", "ppo_ensemble", "distilled"}
    # the teacher-student run ships its student (the shaped run's seed-0 zip with new weights) and its teacher
    assert P["distilled"]["kind"] == "agent" and P["distilled"]["residual_on"] == P["ppo_residual_shaped"]["residual_on"]
    teacher = d["training"]["runs"]["distilled"]["teacher"]
    assert teacher["observation"] == "privileged" and teacher["distill"][0]["iterations"][0]["labels"] == 12
    assert teacher["models"] == ["models/distilled_teacher_v1_seed0.zip"] and (out / teacher["models"][0]).is_file()
    import zipfile

    with zipfile.ZipFile(out / "models" / "distilled_v1_seed0.zip") as a, \
            zipfile.ZipFile(out / "models" / "ppo_residual_shaped_v1_seed0.zip") as b:
        assert [n for n in a.namelist() if a.read(n) != b.read(n)] == ["policy.pth"]
    assert {P[n]["kind"] for n in ("ppo", "sac", "ppo_residual", "ppo_residual_shaped", "ppo_ensemble")} == {"agent"}
    from agents.evaluation.manifest import sha256
    from agents.evaluation.model_pins import obs_norm_path

    for n in ("ppo", "sac", "ppo_residual", "ppo_residual_shaped", "ppo_ensemble", "distilled"):  # pinned by content
        files = {*P[n]["models"], *(obs_norm_path(m).as_posix() for m in P[n]["models"])}
        assert P[n]["sha256"] == {f: sha256(out / f) if (out / f).is_file() else None for f in files}, n
    # the seed ensemble is one more policy, made of the run's own models
    assert P["ppo_ensemble"]["ensemble_of"] == "ppo" and P["ppo_ensemble"]["models"] == P["ppo"]["models"]
    assert len(P["ppo"]["models"]) == 2 and "ppo_ensemble" in d["paired"]
    assert d["training"]["ensembles"]["ppo_ensemble"]["validation_reward"] is not None
    assert P["ppo_residual_shaped"]["residual_on"]["shaping"] == "potential"
    assert "ppo_residual_shaped" in d["paired"]
    tuned = d["tuned"]
    best_tuned = max(("best_constant", "pump_off", "fillage_pi"), key=lambda n: tuned[n]["score"])
    assert P["ppo_residual"]["residual_on"]["base"] == best_tuned
    ref = None
    for name, p in P.items():
        keys = [(e["well_id"], e["seed"]) for e in p["episodes"]]
        for e in p["episodes"]:
            assert {"well_id", "seed", "reward", "cost", "reward_revenue"} <= set(e)
        ref = ref or keys
        assert keys == ref, name  # every policy on the same test episodes
    assert [s for _, s in ref] == [1000, 1001, 1002, 1003]
    assert all(w.startswith("test-") for w, _ in ref)
    for k in ("well_ids", "seeds"):
        assert not set(map(str, d["tuning"][k])) & set(map(str, d["test"][k]))
        assert not set(map(str, d["validation"][k])) & set(map(str, d["test"][k]))
    assert all(w.startswith("train-") for w in d["tuning"]["well_ids"] + d["validation"]["well_ids"])
    # normalised score anchors and paired differences recomputed from the episodes
    assert d["normalised_score"]["installed"] == pytest.approx(0.0, abs=1e-9)
    assert d["normalised_score"]["oracle"] == pytest.approx(1.0)
    r = {n: np.array([e["reward"] for e in p["episodes"]]) for n, p in P.items()}
    for a in ("ppo", "sac"):
        for b in ("installed", "best_constant", "pump_off", "fillage_pi", "oracle"):
            assert d["paired"][a][b]["mean_diff_reward"] == pytest.approx(float(np.mean(r[a] - r[b])))
    # the agent entry is the per-episode mean over its seeds' models (2 PPO seeds)
    per = d["training"]["runs"]["ppo"]["per_seed"]
    assert len(per) == 2
    assert r["ppo"] == pytest.approx(np.mean([[e["reward"] for e in s["episodes"]] for s in per], axis=0))
    assert "iqm_test_reward" in d["training"]["runs"]["ppo"] and d["wall_time_s"]["total"] > 0
    assert d["machine"]["cpu_count"] >= 1
    md = (out / "benchmark.md").read_text()
    assert md.count("| ppo |") >= 1
    assert d["history"] == cfg["history"] and "- Run 0 (a test line): kept in the report" in md
    assert (out / "figures" / "benchmark_v1.png").stat().st_size > 10_000
    assert (out / "models" / "ppo_v1.zip").is_file() and (out / "models" / "ppo_v1_obs_norm.npz").is_file()
    assert not list(out.rglob("*.tmp*"))


def test_residual_agent_with_zero_correction_is_its_baseline() -> None:
    """Training wrapper and evaluation policy compose the same way: r = 0 reproduces the baseline exactly."""
    from agents.policies.residual import ResidualAgentPolicy
    from agents.training.residual_env import ResidualEnv

    params = {"threshold": 0.85, "idle_time_s": 600, "a_spm": 0.8, "a_stroke": 1.0}

    class Zero:
        def predict(self, obs, state=None, episode_start=None, deterministic=True):
            assert obs.shape[-1] == len(NAMES) + 2  # the baseline's action is part of what it sees
            return np.zeros(2, np.float32), state

    env = make_env(FAKE, scenario="train")
    base = run_episode(env, PumpOffPolicy(NAMES, **params), seed=4)
    res = run_episode(env, ResidualAgentPolicy(Zero(), "pump_off", params, 0.3), seed=4)
    assert res["reward"] == pytest.approx(base["reward"]) and base["mean_duty"] < 1.0  # it did pump off
    wrapped = ResidualEnv(make_env(FAKE, scenario="train"), "pump_off", params, 0.3)
    obs, _ = wrapped.reset(seed=4)
    total, done = 0.0, False
    while not done:
        obs, r, term, trunc, _ = wrapped.step(np.zeros(2, np.float32))
        total, done = total + r, term or trunc
    assert total == pytest.approx(base["reward"])
    # a full-scale residual moves the action off the baseline
    obs, _ = wrapped.reset(seed=4)
    b = obs[-2:]
    wrapped.step(np.ones(2, np.float32))
    assert wrapped.env.unwrapped.last_a0 == pytest.approx(min(1.0, b[0] + 0.3), abs=1e-6)


def test_idle_scale_gives_the_agent_the_rate_only_where_the_base_idles() -> None:
    from agents.policies.residual import compose

    base = np.array([[-1.0, 0.5], [0.1, 0.5]], np.float32)  # an idle interval, a pumping one
    full = np.ones((2, 2), np.float32)
    assert compose(base, full, 0.5, 2.0) == pytest.approx(np.array([[1.0, 1.0], [0.6, 1.0]]))
    assert compose(base, full, 0.5) == pytest.approx(np.array([[-0.5, 1.0], [0.6, 1.0]]))
    # r0 <= 0 keeps the stop; the stroke entry always keeps the plain scale; r = 0 is the baseline
    assert compose(base[0], np.array([-0.4, -1.0]), 0.5, 2.0) == pytest.approx([-1.0, 0.0])
    assert compose(base, np.zeros((2, 2)), 0.5, 2.0) == pytest.approx(base)
    assert compose(base[0], np.array([0.25, 0.0]), 0.5, 2.0) == pytest.approx([-0.5, 0.5])


def test_residual_env_and_policy_compose_the_idle_override_alike() -> None:
    """Training wrapper and evaluation policy give the same episode when the agent overrides every stop."""
    from agents.policies.residual import ResidualAgentPolicy
    from agents.training.residual_env import ResidualEnv

    params = {"threshold": 0.85, "idle_time_s": 600, "a_spm": 0.8, "a_stroke": 1.0}

    class Pump:
        def predict(self, obs, state=None, episode_start=None, deterministic=True):
            return np.array([0.25 if obs[-2] <= -1.0 else 0.0, 0.0], np.float32), state

    env = make_env(FAKE, scenario="train")
    base = run_episode(env, PumpOffPolicy(NAMES, **params), seed=4)
    ev = run_episode(env, ResidualAgentPolicy(Pump(), "pump_off", params, 0.3, idle_scale=2.0), seed=4)
    wrapped = ResidualEnv(make_env(FAKE, scenario="train"), "pump_off", params, 0.3, idle_scale=2.0)
    obs, _ = wrapped.reset(seed=4)
    total, done, a0s = 0.0, False, []
    while not done:
        obs, r, term, trunc, _ = wrapped.step(Pump().predict(obs)[0])
        a0s.append(wrapped.env.unwrapped.last_a0)
        total, done = total + r, term or trunc
    assert total == pytest.approx(ev["reward"]) and base["mean_duty"] < 1.0
    assert -0.5 in [round(a, 6) for a in a0s] and -1.0 not in a0s  # every stop became a slow interval
    assert ev["mean_duty"] > base["mean_duty"]


@pytest.mark.parametrize("residual, match", [
    ({"base": "pump_off", "scale": 0.0}, "residual.scale"),
    ({"base": "pump_off", "scale": 2.5}, "residual.scale"),
    ({"base": "pump_off", "scale": "wide"}, "residual.scale"),
    ({"base": "pump_off", "scale": True}, "residual.scale"),
    ({"base": "pump_off", "scale": 0.5, "idle_scale": -1}, "residual.idle_scale"),
    ({"base": "pump_off", "scale": 0.5, "idle_scale": 3.0}, "residual.idle_scale"),
    ({"base": "pump_off", "scale": 0.5, "idle_scale": [2]}, "residual.idle_scale"),
    ({"base": "pump_off", "scale": 0.5, "idle": 2.0}, "unknown key"),
], ids=["scale-zero", "scale-big", "scale-str", "scale-bool", "idle-neg", "idle-big", "idle-list", "unknown-key"])
def test_benchmark_config_refuses_a_residual_out_of_its_box(tmp_path, residual, match) -> None:
    cfg = _quick_cfg(tmp_path, env_id="srenv/SuckerRod-v1")  # training YAMLs the loader accepts
    cfg["agents"]["runs"]["ppo_residual"]["residual"] = residual
    p = tmp_path / "bad.yaml"
    p.write_text(yaml.safe_dump(cfg))
    with pytest.raises(ValueError, match=match):
        load_benchmark_config(p)


@pytest.mark.parametrize("history", ["one line", [1, 2], {"run": 1}])
def test_benchmark_config_refuses_a_history_that_is_not_lines(tmp_path, history) -> None:
    cfg = _quick_cfg(tmp_path)
    cfg["history"] = history
    p = tmp_path / "bad.yaml"
    p.write_text(yaml.safe_dump(cfg))
    with pytest.raises(ValueError, match="history"):
        load_benchmark_config(p)


@pytest.mark.parametrize("per_well", [1, 2])
def test_paired_ci_counts_each_well_once_when_wells_repeat(per_well) -> None:
    """Two episodes of one well are not independent: the report adds the interval over per-well means."""
    from agents.benchmark.report import build_report, markdown_tables, mean_ci, verdict

    rng = np.random.default_rng(1)
    wells = [f"test-{w:03d}" for w in range(6) for _ in range(per_well)]
    seeds = list(range(100, 100 + len(wells)))

    def eps(shift):
        return [{"well_id": w, "seed": s, "reward": float(shift + 10 * (i % per_well) + rng.normal()), "cost": 0.0,
                 "reward_rate_usd_h": 0.0, "steps": 144} for i, (w, s) in enumerate(zip(wells, seeds))]

    pols = {"installed": {"kind": "baseline", "episodes": eps(0.0)}, "oracle": {"kind": "baseline", "episodes": eps(9.0)},
            "ppo": {"kind": "agent", "episodes": eps(3.0)}}
    rep = build_report({"source": "x", "env_id": "e", "env_kwargs": {}}, pols, {}, {}, {}, {})
    p = rep["paired"]["ppo"]["installed"]
    d = np.array([a["reward"] - b["reward"] for a, b in zip(pols["ppo"]["episodes"], pols["installed"]["episodes"])])
    assert p["ci95"] == pytest.approx(list(mean_ci(d)[1:]))
    if per_well == 1:
        assert "ci95_by_well" not in p and "each well once" not in verdict(rep)
    else:
        assert p["n_wells"] == 6
        by_well = mean_ci(d.reshape(6, 2).mean(axis=1))
        assert p["ci95_by_well"] == pytest.approx(list(by_well[1:]))
        assert "over the 6 wells' means" in verdict(rep)
    assert ("; wells [" in markdown_tables(rep)) == (per_well > 1)
    # significance is judged on the per-well interval when wells repeat, else on the episodes
    assert p["significant_positive"] == ((by_well if per_well > 1 else mean_ci(d))[1] > 0)


def test_a_lead_only_the_repeated_episodes_make_significant_is_called_within_noise() -> None:
    from agents.benchmark.report import build_report, verdict

    # 4 wells x 2 identical episodes: the per-episode CI halves in width, the per-well one does not
    diffs = [5.0, -1.0, 4.0, 0.5]
    wells = [f"test-{w:03d}" for w in range(4) for _ in range(2)]

    def eps(d):
        return [{"well_id": w, "seed": 100 + i, "reward": float(d[i // 2]), "cost": 0.0, "reward_rate_usd_h": 0.0,
                 "steps": 1} for i, w in enumerate(wells)]

    pols = {"installed": {"kind": "baseline", "episodes": eps([0.0] * 4)},
            "oracle": {"kind": "baseline", "episodes": eps([9.0] * 4)},
            "ppo": {"kind": "agent", "episodes": eps(diffs)}}
    rep = build_report({"source": "x", "env_id": "e", "env_kwargs": {}}, pols, {}, {}, {}, {})
    p = rep["paired"]["ppo"]["installed"]
    assert p["ci95"][0] > 0 > p["ci95_by_well"][0] and not p["significant_positive"]
    assert "within noise" in verdict(rep)


def test_one_episode_gives_no_ci_and_the_verdict_says_so() -> None:
    from agents.benchmark.report import build_report, verdict

    def eps(r):
        return [{"well_id": "test-000", "seed": 100, "reward": r, "cost": 0.0, "reward_rate_usd_h": 0.0, "steps": 1}]

    pols = {"installed": {"kind": "baseline", "episodes": eps(0.0)}, "oracle": {"kind": "baseline", "episodes": eps(9.0)},
            "ppo": {"kind": "agent", "episodes": eps(3.0)}}
    rep = build_report({"source": "x", "env_id": "e", "env_kwargs": {}}, pols, {}, {}, {}, {})
    line = verdict(rep)
    assert "no 95 % CI" in line and "within noise" not in line and "significant (95" not in line
