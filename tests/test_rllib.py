"""RLlib backend: PPO through ``python -m agents train`` with the plain env id and two env runners, its
checkpoint evaluated next to a baseline, resume; the three registration patterns of :mod:`srenv.rllib`.

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

from agents.evaluate import evaluate, make_policy
from agents.rllib_backend import start_ray
from agents.rllib_config import parse_rllib_config
from agents.rllib_policy import RLlibPolicy
from agents.train import TrainConfigError, make_env

ROOT = Path(__file__).resolve().parents[1]
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
    env = make_env(config="default", **SHORT)
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


def test_resume_continues_the_step_count(run: tuple[Path, Path, dict]) -> None:
    path, out, first = run
    s = _summary(_agents("train", str(path), "--total-timesteps", "128", "--out", str(out), "--resume",
                         cwd=out.parent))
    assert s["resumed_from"] == str(out / "checkpoints" / f"step_{first['num_timesteps']}")
    assert s["iterations"] == 2 and s["num_timesteps"] >= 128


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


def test_registration_patterns() -> None:
    """srenv.rllib.register() + plain id, ``module:id`` and the creator: each makes srenv envs in a runner."""
    import ray
    from ray.rllib.algorithms.ppo import PPOConfig
    from ray.tune.registry import register_env

    import srenv.rllib

    srenv.rllib.register()
    register_env("any-name", srenv.rllib.env_creator)
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
        srenv.rllib.register(["CartPole-v1"])


def test_pickle_only_checkpoint_needs_trust(run: tuple[Path, Path, dict], tmp_path: Path) -> None:
    import shutil

    from agents.rllib_checkpoints import POLICY_JSON

    _, out, _ = run
    bare = tmp_path / "bare"
    shutil.copytree(out / "checkpoint", bare)
    (bare / POLICY_JSON).unlink()  # as written by RLlib itself: pickles only
    env = make_env(config="default", **SHORT)
    with pytest.raises(ValueError, match="--trust-model"):
        make_policy(str(bare), env)
    assert isinstance(make_policy(str(bare), env, trust=True), RLlibPolicy)
    env.close()

