"""RLlib backend with ``vec_env: native``: an env runner steps its wells through srenv's vector entry point and
samples the episodes the default ``sync`` mode samples (same seed, same weights, the normaliser on, through an
autoreset; threads and worker processes); ``python -m agents train`` runs one iteration with it; a bad
``vec_env`` / ``vec_processes`` / env id is one line, exit 2.

Smoke-sized (3-interval episodes, 64-step iteration): plumbing, not learning.
"""

from __future__ import annotations

import json
import subprocess
from pathlib import Path

import numpy as np
import pytest
import yaml

pytest.importorskip("ray.rllib")

from test_rllib import SHIPPED, _agents, _summary

from agents.training.config import TrainConfigError
from agents.training.residual_env import RESIDUAL_ENV_ID
from agents.training.rllib.config import build_algorithm_config, parse_rllib_config

SHORT = {"episode_hours": 0.25}  # 3 five-minute intervals: episodes end (and autoreset) inside the samples


def _yaml(**over: object) -> dict:
    cfg = yaml.safe_load(SHIPPED.read_text())
    cfg.update({"env_id": "srenv/SuckerRod-v1", "env_kwargs": dict(SHORT), **over})
    return cfg


def _runner(vec_env: str, **over: object):
    """A local env runner (no Ray) built from the training YAML as ``python -m agents train`` builds it."""
    from ray.rllib.env.single_agent_env_runner import SingleAgentEnvRunner

    data = _yaml(num_env_runners=0, num_envs_per_env_runner=3, vec_env=vec_env, seed=7,
                 model_config={"fcnet_hiddens": [8]}, **over)
    return SingleAgentEnvRunner(config=build_algorithm_config(parse_rllib_config(data)))


def _episodes(runner, steps: int) -> list[tuple]:
    out = []
    for e in runner.sample(num_timesteps=steps, explore=False):
        out.append((np.asarray(e.get_observations()), np.asarray(e.get_actions()), np.asarray(e.get_rewards()),
                    e.is_terminated, e.is_truncated))
    return out


@pytest.mark.parametrize("vec_processes", [1, 2])  # 1: threads in the runner; 2: two worker processes
def test_native_runner_samples_the_sync_episodes(vec_processes: int) -> None:
    sync = _runner("sync")
    native = _runner("native", vec_processes=vec_processes)
    try:
        assert type(sync.env.unwrapped).__name__ == "SyncVectorEnv"
        venv = native.env.unwrapped
        assert type(venv).__name__ == "KernelVectorEnv" and venv.num_envs == 3
        assert venv.processes == (2 if vec_processes == 2 else 1)
        native.module.set_state(sync.module.get_state())  # the same weights (deterministic actions: the mode)
        done = 0
        for _ in range(3):  # 3 x 12 steps over 3 wells: every well's episode ends and autoresets
            a, b = _episodes(sync, 12), _episodes(native, 12)
            assert len(a) == len(b) > 0
            for x, y in zip(a, b, strict=True):
                for u, v in zip(x, y, strict=True):
                    np.testing.assert_array_equal(u, v)
            done += sum(bool(x[3] or x[4]) for x in a)
        assert done >= 3
        # the normaliser (the shipped config's) ran in both runners on the same observations
        from ray.rllib.utils.filter import RunningStat

        sa, sb = (RunningStat.from_state(
            r.get_state()["env_to_module_connector"]["ObsMeanStdFilter"][None]["running_stats"][0])
            for r in (sync, native))
        assert sa.n == sb.n > 0
        np.testing.assert_array_equal(sa.mean, sb.mean)
        np.testing.assert_array_equal(sa.std, sb.std)
    finally:
        sync.stop()
        native.stop()


def test_train_one_iteration_native(tmp_path: Path) -> None:
    cfg = _yaml(env_id="srenv/SuckerRod-v2", num_env_runners=1, num_envs_per_env_runner=2, vec_env="native",
                vec_processes=1, checkpoint_freq=64)
    cfg["training"].update(train_batch_size_per_learner=64, minibatch_size=32, num_epochs=1)
    (tmp_path / "c.yaml").write_text(yaml.safe_dump(cfg))
    s = _summary(_agents("train", "c.yaml", "--total-timesteps", "64", "--out", "out", cwd=tmp_path))
    assert (s["backend"], s["iterations"], s["num_envs_per_env_runner"]) == ("rllib", 1, 2)
    assert s["num_timesteps"] >= 64 and (tmp_path / s["model"]).is_dir()
    written = json.loads((tmp_path / "out" / "train_config.json").read_text())
    assert (written["vec_env"], written["vec_processes"]) == ("native", 1)


@pytest.mark.parametrize(("over", "needle"), [
    ({"vec_env": "native", "env_id": "srenv/SuckerRod-v0", "env_kwargs": {}},
     "vec_env = 'native' with env_id 'srenv/SuckerRod-v0': expected an env with a native vector env"),
    ({"vec_env": "native", "env_id": RESIDUAL_ENV_ID, "env_kwargs": {}},
     (f"env_id = '{RESIDUAL_ENV_ID}': expected srenv/SuckerRod-v1 or srenv/SuckerRod-v2 or srenv/SuckerRod-v3 "
      "with vec_env: native")),
    ({"vec_env": "subproc"}, "vec_env = 'subproc': expected sync or native"),
    ({"vec_env": "sync", "vec_processes": 2}, "vec_processes = 2: expected no value unless vec_env: native"),
    ({"vec_env": "native", "vec_processes": 10**6}, "vec_processes = 1000000: expected an integer within"),
])
def test_bad_native_keys_are_one_line(over: dict, needle: str) -> None:
    with pytest.raises(TrainConfigError) as ex:
        parse_rllib_config(_yaml(**over))
    assert needle in str(ex.value) and len(str(ex.value).splitlines()) == 1


def test_cli_refuses_native_without_a_vector_env(tmp_path: Path) -> None:
    (tmp_path / "c.yaml").write_text(yaml.safe_dump(_yaml(env_id="srenv/SuckerRod-v0", vec_env="native")))
    p: subprocess.CompletedProcess = _agents("train", "c.yaml", "--out", "o", cwd=tmp_path)
    assert p.returncode == 2
    assert p.stderr.strip().splitlines() == [
        ("agents: error: train config: vec_env = 'native' with env_id 'srenv/SuckerRod-v0': expected an env with a "
         "native vector env (srenv/SuckerRod-v1, srenv/SuckerRod-v2, srenv/SuckerRod-v3, or the residual / shaped env "
         "on one)")]
    assert not (tmp_path / "o").exists()


def test_rate_script_measures_the_same_episodes_in_every_mode(tmp_path: Path) -> None:
    """scripts/rllib_vector_rate.py (the docs' figures): each mode is the vector env it names, every mode samples
    the same episodes (so the rates compare the same work), the JSON is written; a bad flag is one line, exit 2."""
    import importlib.util
    import sys

    spec = importlib.util.spec_from_file_location("rllib_vector_rate", SHIPPED.parents[2] / "scripts" /
                                                  "rllib_vector_rate.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    out = tmp_path / "rate.json"
    assert mod.main(["--env-id", "srenv/SuckerRod-v1", "--n", "2", "--steps-per-env", "2", "--rounds", "1",
                     "--json", str(out)]) == 0
    res = json.loads(out.read_text())["results"]["srenv/SuckerRod-v1 N=2"]
    assert res["same_episodes"] is True
    got = {m: (res[m]["vector_env"], res[m]["threads"], res[m]["processes"]) for m in mod.MODES}
    assert got == {"sync": ("SyncVectorEnv", 1, 1), "native_t1": ("KernelVectorEnv", 1, 1),
                   "native_t2": ("KernelVectorEnv", 2, 1), "native_p2": ("KernelVectorEnv", 1, 2)}
    assert all(res[m]["env_steps_per_s_best"] > 0 and res[m]["env_steps"] == [4] for m in mod.MODES)
    assert all(0 < res[m]["env_step_share"] < 1 for m in mod.MODES)
    p = subprocess.run([sys.executable, str(SHIPPED.parents[2] / "scripts" / "rllib_vector_rate.py"), "--n", "0"],
                       capture_output=True, text=True, check=False, timeout=120)
    assert p.returncode == 2 and p.stderr.strip().splitlines() == [
        "rllib_vector_rate.py: error: argument --n: --n = '0': expected a positive integer at most 256"]


def test_shipped_native_config_reads() -> None:
    from agents.training.rllib.config import load_rllib_config

    cfg = load_rllib_config(SHIPPED.parent / "ppo_rllib_native_v2.yaml")
    assert (cfg.env_id, cfg.vec_env, cfg.vec_processes, cfg.num_envs_per_env_runner) == (
        "srenv/SuckerRod-v2", "native", 1, 8)
    runners = build_algorithm_config(cfg)
    assert runners.gym_env_vectorize_mode == "vector_entry_point" and set(runners.env_config) == {"threads"}
