"""RLlib backend: PPO through ``python -m agents train`` with the plain env id and two env runners, its
checkpoint evaluated next to a baseline, resume; the observation normaliser (its statistics saved, applied
by evaluate, restored on resume, merged exactly over runners); the three registration patterns of
:mod:`agents.training.rllib.registry`.

Smoke-sized (64-step iterations, 8-stroke episodes): plumbing, not learning.
"""

from __future__ import annotations

import json
import math
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import yaml

pytest.importorskip("ray.rllib")

from agents.envs import ENV_ID_V0, make_env
from agents.evaluation.evaluate import evaluate, make_policy
from agents.evaluation.rllib_model import POLICY_JSON, RLlibPolicy
from agents.training.config import TrainConfigError
from agents.training.rllib.backend import start_ray
from agents.training.rllib.config import parse_rllib_config

ROOT = Path(__file__).resolve().parents[2]
SHIPPED = ROOT / "configs" / "train" / "ppo_rllib.yaml"
SHORT = {"control__max_episode_steps": 8}


def _agents(*args: str, cwd: Path) -> subprocess.CompletedProcess:
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")])}
    return subprocess.run([sys.executable, "-m", "agents", *args], cwd=cwd, env=env, capture_output=True,
                          text=True, timeout=300, check=False)


def _summary(p: subprocess.CompletedProcess) -> dict:
    assert p.returncode == 0, p.stderr[-3000:]
    return json.loads(p.stdout.strip().splitlines()[-1])


@pytest.fixture(scope="module")
def run(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path, dict]:
    tmp = tmp_path_factory.mktemp("rllib")
    cfg = yaml.safe_load(SHIPPED.read_text())
    assert cfg["backend"] == "rllib" and cfg["env_id"] == "srenv/SuckerRod-v0"  # the plain id
    assert cfg["normalize"] == {"clip_std": 10}  # the shipped config normalises observations
    cfg["env_kwargs"] = {**cfg["env_kwargs"], **SHORT}
    cfg["training"].update(train_batch_size_per_learner=64, minibatch_size=32, num_epochs=1)
    cfg["checkpoint_freq"] = 64
    path = tmp / "tiny_rllib.yaml"
    path.write_text(yaml.safe_dump(cfg))
    out = tmp / "out"
    return path, out, _summary(_agents("train", str(path), "--total-timesteps", "64", "--out", str(out), cwd=tmp))


def test_one_iteration_two_runners_plain_id(run: tuple[Path, Path, dict]) -> None:
    _, out, s = run
    assert (s["backend"], s["algo"], s["num_env_runners"], s["iterations"]) == ("rllib", "ppo", 2, 1)
    assert s["num_timesteps"] >= 64
    assert s["last_episode_return_mean"] is not None and math.isfinite(s["last_episode_return_mean"])
    assert Path(s["model"]) == out / "checkpoint"
    progress = json.loads((out / "checkpoint" / "srenv_progress.json").read_text())
    assert progress == {"num_timesteps": s["num_timesteps"], "iterations": 1}
    assert (out / "checkpoints" / f"step_{s['num_timesteps']}").is_dir()


def test_checkpoint_evaluates_next_to_a_baseline(run: tuple[Path, Path, dict]) -> None:
    _, out, _ = run
    env = make_env(ENV_ID_V0, config="default", **SHORT)
    policy = make_policy(str(out / "checkpoint"), env)
    assert isinstance(policy, RLlibPolicy)
    # the data route (JSON + weights_only tensors) acts exactly as RLlib's own pickled module (trusted)
    trusted = make_policy(str(out / "checkpoint"), env, trust=True)
    obs, _ = env.reset(seed=3)
    for _ in range(3):
        a1, _ = policy.predict(obs)
        a2, _ = policy.predict(obs)
        assert a1.shape == env.action_space.shape and env.action_space.contains(a1)
        np.testing.assert_array_equal(a1, a2)  # deterministic: the distribution's mode
        np.testing.assert_array_equal(a1, trusted.predict(obs)[0])
        obs, *_ = env.step(a1)
    env.close()
    results = evaluate([str(out / "checkpoint"), "rocking"], 1, 1000, env_kwargs=SHORT)
    assert list(results) == ["out/checkpoint", "rocking"]
    assert all(math.isfinite(r["mean_reward"]) and r["mean_steps"] == 8 for r in results.values())


def _normalizer(checkpoint: Path) -> dict:
    return json.loads((checkpoint / POLICY_JSON).read_text())["obs_normalizer"]


def test_normaliser_statistics_are_saved_and_applied_by_evaluate(run: tuple[Path, Path, dict]) -> None:
    """evaluate's action is the module's mode on the normalised observation (computed here from the JSON
    statistics), not on the raw one; the data route's normaliser is RLlib's own pickled filter's twin."""
    import torch

    _, out, s = run
    stats = _normalizer(out / "checkpoint")
    mean, std = np.asarray(stats["mean"]), np.asarray(stats["std"], dtype=np.float32)
    # every sampled step and every episode's first observation went through the filter of one of the runners
    assert s["num_timesteps"] <= stats["count"] <= 2 * s["num_timesteps"]
    assert stats["clip_std"] == 10.0 and np.all(std >= 0) and np.count_nonzero(std > 1e-6) > len(std) // 2
    assert np.max(np.abs(mean)) > 0.1  # non-trivial: the observation is not already centred
    env = make_env(ENV_ID_V0, config="default", **SHORT)
    policy = make_policy(str(out / "checkpoint"), env)
    trusted = make_policy(str(out / "checkpoint"), env, trust=True)
    assert type(trusted.obs_filter).__name__ == "RLlibObsFilter"  # RLlib's MeanStdFilter from the pickles
    assert trusted.obs_filter.observation_space == policy.module.observation_space

    def mode(x: np.ndarray) -> np.ndarray:
        with torch.no_grad():
            logits = policy.module.forward_inference({"obs": torch.as_tensor(x[None])})["action_dist_inputs"]
            a = policy.module.get_inference_action_dist_cls().from_logits(logits).to_deterministic().sample()
        return np.clip(a[0].numpy(), env.action_space.low, env.action_space.high)

    obs, _ = env.reset(seed=5)
    for _ in range(3):
        normalised = np.clip((obs - mean) / (std + 1e-6), -10, 10).astype(np.float32)
        np.testing.assert_array_equal(policy.obs_filter(obs), normalised)
        np.testing.assert_array_equal(trusted.obs_filter(obs), normalised)
        action = policy.predict(obs)[0]
        np.testing.assert_allclose(action, mode(normalised), rtol=0, atol=1e-6)
        assert np.max(np.abs(action - mode(obs.astype(np.float32)))) > 1e-4  # the raw obs: another action
        obs, *_ = env.step(action)
    env.close()


def test_resume_continues_the_step_count(run: tuple[Path, Path, dict]) -> None:
    path, out, first = run
    before = _normalizer(out / "checkpoints" / f"step_{first['num_timesteps']}")
    s = _summary(_agents("train", str(path), "--total-timesteps", "128", "--out", str(out), "--resume",
                         cwd=out.parent))
    assert s["resumed_from"] == str(out / "checkpoints" / f"step_{first['num_timesteps']}")
    assert s["iterations"] == 2 and s["num_timesteps"] >= 128
    # the normaliser went on from the checkpoint's statistics: a fresh one would count one iteration only
    after = _normalizer(out / "checkpoint")
    assert after["count"] >= before["count"] + (s["num_timesteps"] - first["num_timesteps"])
    np.testing.assert_allclose(after["mean"], before["mean"], rtol=0.5, atol=0.05)


def test_runner_statistics_merge_exactly_over_iterations() -> None:
    """Two env runners' filters synced as EnvRunnerGroup.sync_env_runner_states does (the runners' states
    merged into the local runner's, the result broadcast back) for four rounds: the merged count, mean and
    std are those of every observation. RLlib 2.60's own MeanStdFilter fails this from the second round."""
    import gymnasium as gym
    from ray.rllib.connectors.env_to_module import MeanStdFilter
    from ray.rllib.env.single_agent_episode import SingleAgentEpisode
    from ray.rllib.utils.filter import RunningStat

    from agents.training.rllib.obs_filter import ObsMeanStdFilter

    space = gym.spaces.Box(-100, 100, (3,), np.float32)
    rng = np.random.default_rng(0)
    batches = [rng.normal([5, -3, 1], [1, 2, 0.5], (2, 50, 3)).astype(np.float32) for _ in range(4)]

    def merged_after_rounds(cls: type) -> list[RunningStat]:
        filters = []
        for _ in range(3):
            f = cls(clip_by_value=1e6)
            f.input_action_space, f.input_observation_space = space, space
            filters.append(f)
        local, runners, out = filters[0], filters[1:], []
        for batch in batches:
            for runner, xs in zip(runners, batch, strict=True):
                for x in xs:  # as an env runner calls it: on the episodes' newest observation
                    runner(rl_module=None, batch={}, episodes=[SingleAgentEpisode(observations=[x])])
            merged = local.merge_states([r.get_state() for r in runners])
            for f in filters:
                f.set_state(merged)
            out.append(RunningStat.from_state(merged[None]["running_stats"][0]))
        return out

    seen = [np.concatenate([b.reshape(-1, 3) for b in batches[: k + 1]]).astype(np.float64)
            for k in range(len(batches))]
    for stats, xs in zip(merged_after_rounds(ObsMeanStdFilter), seen, strict=True):
        assert stats.n == len(xs)
        np.testing.assert_allclose(stats.mean, xs.mean(axis=0), rtol=1e-9)
        np.testing.assert_allclose(stats.std, xs.std(axis=0, ddof=1), rtol=1e-5)
    stock = merged_after_rounds(MeanStdFilter)[-1]
    # if this fails, RLlib fixed its merge upstream and ObsMeanStdFilter can go
    assert np.max(np.abs(stock.mean - seen[-1].mean(axis=0))) > 1.0


def test_bad_rllib_config_is_one_line(tmp_path: Path) -> None:
    bad = yaml.safe_load(SHIPPED.read_text())
    bad["training"]["no_such_argument"] = 1
    (tmp_path / "bad.yaml").write_text(yaml.safe_dump(bad))
    p = _agents("train", str(tmp_path / "bad.yaml"), "--out", str(tmp_path / "o"), cwd=tmp_path)
    assert p.returncode == 2
    assert p.stderr.strip().splitlines() == [
        "agents: error: train config: training.no_such_argument = 1: expected an argument of RLlib's PPO training()"]
    with pytest.raises(TrainConfigError, match="num_env_runners"):
        parse_rllib_config({**bad, "training": {}, "num_env_runners": -1})
    ok = {**bad, "training": {}}
    assert parse_rllib_config({**ok, "normalize": True}).normalize == {"clip_std": 10.0}
    assert parse_rllib_config({**ok, "normalize": False}).normalize is None
    assert parse_rllib_config({**ok, "normalize": {"clip_std": 5}}).normalize == {"clip_std": 5.0}
    for value, key in (({"clip_std": 0}, "normalize.clip_std = 0"), ({"clip": 5}, "normalize = {'clip': 5}"),
                       ("yes", "normalize = 'yes'")):
        with pytest.raises(TrainConfigError, match=key.replace("{", r"\{").replace("}", r"\}")):
            parse_rllib_config({**ok, "normalize": value})


def test_registration_patterns() -> None:
    """registry.register() + plain id, ``module:id`` and the creator: each makes srenv envs in a runner."""
    import ray
    from ray.rllib.algorithms.ppo import PPOConfig
    from ray.tune.registry import register_env

    from agents.training.rllib import registry

    registry.register()
    register_env("any-name", registry.env_creator)
    started = start_ray(None, None, 1)
    try:
        # the plain id first: fresh runner processes, which never imported srenv (Ray reuses workers)
        for env, env_config in (("srenv/SuckerRod-v0", SHORT), ("srenv:srenv/SuckerRod-v0", SHORT),
                                ("any-name", {"env_id": "srenv/SuckerRod-v0", **SHORT})):
            algo = (PPOConfig().environment(env, env_config=env_config).env_runners(num_env_runners=1)
                    .rl_module(model_config={"fcnet_hiddens": [8]}).build_algo())
            try:
                names = algo.env_runner_group.foreach_env_runner(
                    lambda r: [type(e.unwrapped).__name__ for e in r.env.unwrapped.envs], local_env_runner=False)
            finally:
                algo.stop()
            assert names == [["SuckerRodEnv"]], env
    finally:
        if started:
            ray.shutdown()
    with pytest.raises(ValueError, match="CartPole-v1"):
        registry.register(["CartPole-v1"])


def test_pickle_only_checkpoint_needs_trust(run: tuple[Path, Path, dict], tmp_path: Path) -> None:
    import shutil

    _, out, _ = run
    bare = tmp_path / "bare"
    shutil.copytree(out / "checkpoint", bare)
    (bare / POLICY_JSON).unlink()  # as written by RLlib itself: pickles only
    env = make_env(ENV_ID_V0, config="default", **SHORT)
    with pytest.raises(ValueError, match="--trust-model"):
        make_policy(str(bare), env)
    assert isinstance(make_policy(str(bare), env, trust=True), RLlibPolicy)
    env.close()

