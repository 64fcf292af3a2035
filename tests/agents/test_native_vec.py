"""``vec_env: native`` (issue 25 item 3): SB3 training on srenv's native vector env trains the same policy as
``vec_env: dummy`` for the same seed and ``n_envs`` (both backends, the residual wrapper inside each slot, autoresets
inside the run), runs end to end from ``python -m agents train``, and its keys refuse bad values in one line."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import torch

from agents.training.config import TrainConfigError, parse_train_config
from agents.training.residual_env import RESIDUAL_ENV_ID
from agents.training.sb3.train import train

# residual PPO on v2 (the v2 benchmark's arrangement), 6 intervals an episode: episodes end and reset in the run
RESIDUAL_V2 = {"algo": "ppo", "env_id": RESIDUAL_ENV_ID, "n_envs": 2, "n_timesteps": 128, "seed": 3,
               "env_kwargs": {"inner_env_id": "srenv/SuckerRod-v2", "scenario": "train", "observation": "field",
                              "episode_hours": 0.5, "base": "fillage_pi", "scale": 0.5},
               "policy_kwargs": {"net_arch": [16, 16], "activation_fn": "tanh"},
               "normalize": {"norm_obs": True, "norm_reward": True, "gamma": 0.9}, "checkpoint_freq": 10**9,
               "eval_freq": 10**9, "n_eval_episodes": 1, "n_steps": 32, "batch_size": 32, "n_epochs": 2}


def _trained(tmp_path: Path, name: str, **over: object) -> tuple[np.ndarray, ...]:
    from stable_baselines3 import PPO

    from agents.evaluation.model_io import stats_path

    s = train(parse_train_config({**RESIDUAL_V2, **over}), tmp_path / name, log=lambda m: None)
    params = torch.cat([p.detach().flatten() for p in PPO.load(s["model"], device="cpu").policy.parameters()])
    stats = json.loads(stats_path(s["model"]).read_text())  # VecNormalize's statistics
    assert s["num_timesteps"] == 128 and s["n_envs"] == 2
    return params.numpy(), *(np.asarray(stats[k][m]) for k in ("obs_rms", "ret_rms") for m in ("mean", "var"))


def test_native_trains_the_same_policy_as_dummy(tmp_path: Path) -> None:
    ref = _trained(tmp_path, "dummy", vec_env="dummy")
    for name, procs in (("threads", 1), ("processes", 2)):
        got = _trained(tmp_path, name, vec_env="native", vec_processes=procs)
        for a, b in zip(ref, got):
            np.testing.assert_array_equal(a, b, err_msg=name)
    other = _trained(tmp_path, "seed4", vec_env="native", vec_processes=1, seed=4)
    assert not np.array_equal(ref[0], other[0])  # the comparison can fail: another seed trains another policy


def test_cli_trains_with_the_native_vector_env(tmp_path: Path) -> None:
    cfg = {**RESIDUAL_V2, "env_id": "srenv/SuckerRod-v1", "env_kwargs": {"task__episode_hours": 0.25},
           "n_timesteps": 64, "vec_env": "native", "vec_processes": 2}
    (tmp_path / "c.yaml").write_text(json.dumps(cfg))  # JSON is YAML
    cmd = [sys.executable, "-m", "agents", "train", str(tmp_path / "c.yaml"), "--out", str(tmp_path / "o")]
    p = subprocess.run(cmd, check=False, capture_output=True, text=True, timeout=600)
    assert p.returncode == 0, p.stderr
    out = json.loads(p.stdout.strip().splitlines()[-1])
    assert out["num_timesteps"] == 64 and Path(out["model"]).is_file()
    assert json.loads((tmp_path / "o" / "train_config.json").read_text())["vec_env"] == "native"


@pytest.mark.parametrize(("over", "needle"), [
    ({"vec_env": "dummy", "vec_processes": 2}, "vec_processes = 2: expected no value unless vec_env: native"),
    ({"vec_env": "native", "vec_processes": -1}, "vec_processes = -1"),
    ({"vec_env": "native", "vec_processes": 10**6}, "vec_processes = 1000000"),
    ({"vec_env": "native", "env_id": "srenv/SuckerRod-v0", "env_kwargs": {}}, "native vector env"),
    ({"vec_env": "native", "env_kwargs": {"inner_env_id": "srenv/SuckerRod-v0"}}, "native vector env"),
    ({"vec_env": "vectorised"}, "subproc, dummy or native")])
def test_native_keys_refuse_bad_values(over: dict, needle: str) -> None:
    with pytest.raises(TrainConfigError) as ex:
        parse_train_config({**RESIDUAL_V2, **over})
    assert needle in str(ex.value) and len(str(ex.value).splitlines()) == 1


def test_cli_bad_native_key_exits_2_in_one_line(tmp_path: Path) -> None:
    (tmp_path / "c.yaml").write_text(json.dumps({**RESIDUAL_V2, "vec_env": "native", "vec_processes": "all"}))
    p = subprocess.run([sys.executable, "-m", "agents", "train", str(tmp_path / "c.yaml"), "--out",
                        str(tmp_path / "o")], check=False, capture_output=True, text=True, timeout=300)
    assert p.returncode == 2 and "vec_processes" in p.stderr and len(p.stderr.strip().splitlines()) == 1
    assert not (tmp_path / "o").exists()
