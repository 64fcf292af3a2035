"""Agents: baselines, SB3 training (save / reload / resume), evaluation and the CLI's JSON contract.

Training runs are smoke-sized (a few hundred steps on 8-stroke episodes): they check the plumbing, not
learning; the learning result is in docs/agents.md.
"""

from __future__ import annotations

import json
import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from agents.envs import ENV_ID_V0, make_env
from agents.evaluation.evaluate import (
    evaluate,
    evaluate_episode,
    fillage_index,
    load_model,
    make_policy,
    policy_label,
    well_config,
)
from agents.policies.v0 import (
    FillagePolicy,
    RockingMachinePolicy,
    action_from_setpoints,
    setpoints_from_action,
)
from agents.training.config import parse_train_config
from agents.training.sb3.checkpoints import checkpoints
from agents.training.sb3.train import train
from srenv.config import load_config

SHORT = {"control__max_episode_steps": 8}  # env override: 8-stroke episodes keep the tests fast


def smoke_config(**over: object) -> dict:
    cfg = {"algo": "ppo", "env_kwargs": {"config": "default", **SHORT}, "n_envs": 1, "vec_env": "dummy",
           "n_timesteps": 128, "policy_kwargs": {"net_arch": [16, 16], "activation_fn": "tanh"},
           "normalize": {"norm_obs": True, "norm_reward": True}, "checkpoint_freq": 64, "eval_freq": 64,
           "n_eval_episodes": 1, "n_steps": 32, "batch_size": 32, "n_epochs": 2, "learning_rate": "lin_3e-4"}
    return {**cfg, **over}


@pytest.fixture(scope="module")
def env():
    e = make_env(ENV_ID_V0, config="default", **SHORT)
    yield e
    e.close()


# ------------------------------------------------------------------------------------------- baselines
def test_action_map_round_trip() -> None:
    control = load_config("default").control
    a = action_from_setpoints([control.spm_min, 6.0, control.spm_max], [control.stroke_min_m, 1.6, 2.0], control)
    assert a.dtype == np.float32 and a.shape == (3, 2)
    assert np.allclose(a[0], -1) and np.allclose(a[2], [1, 1])
    spm, stroke = setpoints_from_action(a, control)
    assert np.allclose(spm, [control.spm_min, 6.0, control.spm_max], atol=1e-5)
    assert np.allclose(stroke, [control.stroke_min_m, 1.6, 2.0], atol=1e-6)


def test_rocking_machine_is_the_configured_unit(env) -> None:
    cfg = load_config("default")
    policy = RockingMachinePolicy(cfg)
    obs, _ = env.reset(seed=0)
    action, state = policy.predict(obs)
    spm, stroke = setpoints_from_action(action, cfg.control)
    assert state is None and action.shape == env.action_space.shape
    assert spm == pytest.approx(cfg.surface.spm, abs=1e-5)
    assert stroke == pytest.approx(cfg.surface.stroke_length_m, abs=1e-6)
    batch, _ = policy.predict(np.stack([obs, obs]))
    assert batch.shape == (2, 2)


def test_fillage_pi_lowers_spm_below_setpoint_and_raises_above() -> None:
    cfg = load_config("default")
    pol = FillagePolicy(cfg, fillage_index=2, setpoint=0.85, kp=4.0, ki=2.0)
    obs = np.zeros((2, 5), np.float32)
    obs[:, 2] = [0.5, 1.0]  # env 0 pumped off, env 1 full barrel
    action, state = pol.predict(obs, episode_start=np.array([True, True]))
    spm, stroke = setpoints_from_action(action, cfg.control)
    assert spm[0] < cfg.surface.spm < spm[1]
    assert np.allclose(stroke, cfg.surface.stroke_length_m, atol=1e-6)  # the stroke is not a control here
    # keeps integrating while the error persists, never past the speed range
    for _ in range(50):
        action, state = pol.predict(obs, state=state, episode_start=np.array([False, False]))
    spm, _ = setpoints_from_action(action, cfg.control)
    assert spm == pytest.approx([cfg.control.spm_min, cfg.control.spm_max], abs=1e-5)
    # a new episode restarts from the configured speed
    _, state = pol.predict(obs, state=state, episode_start=np.array([True, False]))
    assert state[0, 0] < cfg.surface.spm and state[1, 0] == pytest.approx(cfg.control.spm_max)


def test_fillage_pi_info_fed_route() -> None:
    cfg = load_config("default")
    pol = FillagePolicy(cfg, fillage_index=None, setpoint=0.9)
    obs = np.zeros(4, np.float32)
    action, state = pol.predict(obs, episode_start=np.array([True]))
    assert state[0, 0] == pytest.approx(cfg.surface.spm)  # nothing measured yet: hold the speed
    pol.observe({"fillage": 0.6})
    action, state = pol.predict(obs, state=state, episode_start=np.array([False]))
    assert setpoints_from_action(action, cfg.control)[0] < cfg.surface.spm


def test_fillage_index_matches_info(env) -> None:
    idx = fillage_index(env)
    env.reset(seed=1)
    obs, *_, info = env.step(action_from_setpoints(10.0, 2.0, load_config("default").control))
    assert obs[idx] == pytest.approx(info["fillage"], rel=1e-6)


def test_the_episode_loop_feeds_info_to_a_policy_that_needs_it(env) -> None:
    """The one episode loop (rollout.play) calls observe(info) for a pump-off controller without a fillage index:
    it steers the SPM as the observation-fed one does (same direction, same total move within a step's rate),
    where without the info it would hold its first SPM for the whole episode."""
    cfg = well_config(env)
    fed = evaluate_episode(env, FillagePolicy(cfg, fillage_index=None, setpoint=0.95), seed=3).steps["spm"]
    read = evaluate_episode(env, FillagePolicy(cfg, fillage_index=fillage_index(env), setpoint=0.95), seed=3).steps["spm"]
    assert len(set(np.round(fed, 6))) > 1 and len(set(np.round(read, 6))) > 1
    assert np.sign(fed[-1] - fed[0]) == np.sign(read[-1] - read[0])


@pytest.mark.parametrize("name", ["rocking", "fillage"])
def test_baselines_give_finite_metrics(env, name: str) -> None:
    ep = evaluate_episode(env, make_policy(name, env), seed=3)
    m = ep.metrics()
    assert m["steps"] == SHORT["control__max_episode_steps"]
    for key in ("reward", "production_m3_day", "pprl_n", "goodman_max_pct", "stick_slip_index"):
        assert math.isfinite(m[key]), key
    assert m["production_m3_day"] > 0 and m["pprl_max_n"] > 0


# -------------------------------------------------------------------------------------------- training
def test_train_save_reload_evaluate(tmp_path: Path) -> None:
    cfg = parse_train_config(smoke_config(n_envs=2, vec_env="subproc"))
    summary = train(cfg, tmp_path)
    assert summary["num_timesteps"] >= 128 and summary["n_envs"] == 2
    assert Path(summary["model"]).is_file() and Path(summary["vecnormalize"]).is_file()
    assert list((tmp_path / "tb").iterdir()), "no TensorBoard run written"
    res = evaluate([summary["model"], "rocking"], episodes=2, seed=500, env_kwargs=SHORT,
                   plot=tmp_path / "cards.png")
    model = res[policy_label(summary["model"])]
    assert math.isfinite(model["mean_reward"]) and math.isfinite(model["mean_production_m3_day"])
    assert (tmp_path / "cards.png").stat().st_size > 10_000


def test_resume_continues_step_count(tmp_path: Path) -> None:
    cfg = parse_train_config(smoke_config())
    first = train(cfg, tmp_path, total_timesteps=64)
    at_checkpoint = checkpoints(tmp_path)[0][0]
    assert at_checkpoint == first["num_timesteps"] == 64
    resumed = train(cfg, tmp_path, total_timesteps=160, resume=True)
    assert resumed["resumed_from"] is not None and resumed["resumed_from"].endswith("rl_model_64_steps.zip")
    assert resumed["num_timesteps"] > at_checkpoint and resumed["num_timesteps"] >= 160
    assert checkpoints(tmp_path)[0][0] > at_checkpoint


def test_mismatched_model_is_one_clear_error(tmp_path: Path, env) -> None:
    import gymnasium as gym
    from stable_baselines3 import PPO

    other = gym.make("Pendulum-v1")
    path = tmp_path / "pendulum.zip"
    PPO("MlpPolicy", other, n_steps=32, batch_size=32, device="cpu").save(path)
    with pytest.raises(ValueError) as err:
        load_model(path, env)
    msg = str(err.value)  # read as data: the spaces are compared by shape (nothing unpickled)
    assert str(other.observation_space.shape) in msg and str(env.observation_space.shape) in msg
    assert str(other.action_space.shape) in msg and str(env.action_space.shape) in msg
    with pytest.raises(ValueError) as err:  # the trusted SB3 route names the full spaces
        load_model(path, env, trust=True)
    assert str(other.observation_space) in str(err.value)


def test_train_config_errors_name_the_key() -> None:
    with pytest.raises(ValueError, match="algo"):
        parse_train_config(smoke_config(algo="dqn"))
    with pytest.raises(ValueError, match="n_stepz"):
        parse_train_config(smoke_config(n_stepz=8))
    with pytest.raises(ValueError, match="policy_kwargs"):
        parse_train_config(smoke_config(policy_kwargs="dict(net_arch=[8])"))


def test_shipped_train_configs_parse() -> None:
    root = Path(__file__).resolve().parents[2] / "configs" / "train"
    from agents.training.config import load_train_config

    for name in ("ppo_default.yaml", "sac_default.yaml", "ppo_quick.yaml"):
        cfg = load_train_config(root / name)
        assert cfg.n_timesteps > 0 and cfg.algo in ("ppo", "sac")


# ------------------------------------------------------------------------------------------------- CLI
def test_cli_evaluate_last_line_is_json_with_reward() -> None:
    cmd = [sys.executable, "-m", "agents", "evaluate", "--policy", "rocking", "--policy", "fillage",
           "--episodes", "1", "--seed", "0", "--env-kwarg", "control__max_episode_steps=4"]
    p = subprocess.run(cmd, check=False, capture_output=True, text=True, timeout=300)
    assert p.returncode == 0, p.stderr
    lines = p.stdout.strip().splitlines()
    assert lines[0].startswith("| policy |")  # the markdown comparison table comes first
    out = json.loads(lines[-1])
    assert set(out["policies"]) == {"rocking", "fillage"}
    assert all(math.isfinite(r["mean_reward"]) for r in out["policies"].values())


def test_cli_bad_model_path_exits_2() -> None:
    cmd = [sys.executable, "-m", "agents", "evaluate", "--policy", "no/such/model.zip", "--episodes", "1"]
    p = subprocess.run(cmd, check=False, capture_output=True, text=True, timeout=300)
    assert p.returncode == 2 and "no such model file" in p.stderr


def test_episode_production_is_time_weighted() -> None:
    from agents.evaluation.evaluate import Episode

    ep = Episode(seed=0, rewards=[1.0, 1.0])
    ep.steps.update(production_m3_day=[10.0, 0.0], spm=[10.0, 5.0], pprl_n=[40e3, 50e3],
                    goodman_max_pct=[30.0, 40.0], stick_slip_index=[1.0, 3.0])
    m = ep.metrics()
    # 6 s at 10 m3/day then 12 s at 0: a third of the time producing
    assert m["production_m3_day"] == pytest.approx(10.0 / 3.0)
    assert m["pprl_max_n"] == 50e3 and m["goodman_max_pct"] == 40.0 and m["stick_slip_index"] == 2.0
    assert m["production_per_peak_load"] == pytest.approx(10.0 / 3.0 / 50.0)
