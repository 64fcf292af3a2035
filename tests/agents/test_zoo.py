"""rl-zoo3 reads configs/train/zoo_ppo.yml: keyed by env id, its hyperparameters reach the trained model.

A tiny run (-n 64: one PPO rollout of 2 x 256 steps); the zoo's saved config and the model's stored
hyperparameters are compared with the file, so a key the zoo ignored or renamed fails here.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import zipfile
from pathlib import Path

import pytest
import yaml

ROOT = Path(__file__).resolve().parents[2]
ZOO_FILE = ROOT / "configs" / "train" / "zoo_ppo.yml"
ENV_ID = "srenv/SuckerRod-v0"

pytest.importorskip("rl_zoo3")


def test_zoo_file_is_keyed_by_env_id() -> None:
    data = yaml.safe_load(ZOO_FILE.read_text())
    assert ENV_ID in data and "srenv/SuckerRod-v1" in data
    v0, v1 = data[ENV_ID], data["srenv/SuckerRod-v1"]
    # the v1 entry inherits the v0 model (YAML merge key) and differs only in its env kwargs
    assert {k: v for k, v in v1.items() if k != "env_kwargs"} == {k: v for k, v in v0.items() if k != "env_kwargs"}
    assert v1["env_kwargs"] != v0["env_kwargs"]


def test_rl_zoo3_trains_with_the_file(tmp_path: Path) -> None:
    logs = tmp_path / "logs"
    cmd = [sys.executable, "-m", "rl_zoo3.train", "--algo", "ppo", "--env", ENV_ID, "--gym-packages", "srenv",
           "-conf", str(ZOO_FILE), "-n", "64", "-f", str(logs), "--seed", "0", "--eval-freq", "-1",
           "--device", "cpu"]
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")])}
    p = subprocess.run(cmd, cwd=tmp_path, env=env, capture_output=True, text=True, timeout=300, check=False)
    assert p.returncode == 0, p.stderr[-2000:]
    assert f"Loading hyperparameters from: {ZOO_FILE}" in p.stdout
    run = logs / "ppo" / "srenv-SuckerRod-v0_1"
    expected = yaml.safe_load(ZOO_FILE.read_text())[ENV_ID]
    # the zoo saves what it used as a python-tagged OrderedDict: our own file, read back in this test only
    saved = yaml.load((run / "srenv-SuckerRod-v0" / "config.yml").read_text(), Loader=yaml.UnsafeLoader)
    # the zoo gives VecNormalize the algorithm's gamma, and saves the normalize mapping with it
    assert dict(saved) == {**expected, "normalize": {**expected["normalize"], "gamma": expected["gamma"]}}
    with zipfile.ZipFile(run / "srenv-SuckerRod-v0.zip") as zf:
        data = json.loads(zf.read("data"))
    for key in ("n_steps", "batch_size", "n_epochs", "gamma", "gae_lambda", "ent_coef"):
        assert data[key] == expected[key], key
    assert data["n_envs"] == expected["n_envs"]
    assert data["num_timesteps"] == expected["n_envs"] * expected["n_steps"]  # one full rollout
    pk = data["policy_kwargs"]
    assert (pk["net_arch"], pk["log_std_init"], pk["activation_fn"]) == ([64, 64], -1.0,
                                                                          "<class 'torch.nn.modules.activation.Tanh'>")
    assert (run / "srenv-SuckerRod-v0" / "vecnormalize.pkl").is_file()  # normalize: from the file
