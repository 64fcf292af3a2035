"""Teacher-student distillation (agents/training/distill.py) and its benchmark config, on the fake v1 env.

The teacher is a residual PPO model on the fake env's privileged observation whose action head is set so that
its correction is clearly not the student's; distillation must move the student's correction towards it,
change nothing in the zip but the weights, give the same student twice, and refuse the test split.
"""

from __future__ import annotations

import copy
import zipfile
from pathlib import Path

import numpy as np
import pytest
import torch
import yaml
from conftest import FAKE_ENV, FIELD_OBS_NAMES

from agents.benchmark.config import load_benchmark_config
from agents.envs import make_env
from agents.evaluation.agent import AgentPolicy
from agents.training.distill import distill
from agents.training.residual_env import ResidualEnv

FAKE = FAKE_ENV
PARAMS = {"threshold": 0.85, "idle_time_s": 600, "a_spm": 0.5, "a_stroke": 1.0}
RESIDUAL = {"base": "pump_off", "params": PARAMS, "scale": 0.5}


def _model(tmp_path: Path, name: str, observation: str, bias: tuple[float, float]) -> dict:
    from stable_baselines3 import PPO

    env = ResidualEnv(make_env(FAKE, scenario="train", observation=observation), "pump_off", PARAMS, 0.5)
    model = PPO("MlpPolicy", env, seed=0, device="cpu", policy_kwargs={"net_arch": [8, 8]})
    with torch.no_grad():
        model.policy.action_net.bias.copy_(torch.tensor(bias))
    path = tmp_path / f"{name}.zip"
    model.save(path)
    return {"path": str(path), "obs_norm": None}


@pytest.fixture()
def models(tmp_path):
    return _model(tmp_path, "teacher", "privileged", (0.6, -0.4)), _model(tmp_path, "student", "field", (-0.5, 0.5))


def _gap(spec: dict, teacher: dict, seeds) -> float:
    """Mean squared gap between the student's and the teacher's corrections along the student's episodes."""
    from agents.policies.residual import _Base, augment, compose

    s, t = AgentPolicy(spec["path"]), AgentPolicy(teacher["path"])
    env = make_env(FAKE, scenario="train", observation="privileged")
    gaps = []
    for seed in seeds:
        obs, _ = env.reset(seed=seed)
        base = _Base("pump_off", PARAMS, env)
        base.reset(env)
        done = False
        while not done:
            b = base.act(obs)
            rs = s.predict(augment(obs[:len(FIELD_OBS_NAMES)], b))[0]
            rt = np.clip(t.predict(augment(obs, b))[0], -1, 1)
            gaps.append(float(np.mean((rs - rt) ** 2)))
            obs, _, term, trunc, _ = env.step(compose(b, rs, 0.5))
            done = term or trunc
    return float(np.mean(gaps))


def test_distillation_moves_the_student_to_the_teacher_and_only_its_weights(tmp_path, models) -> None:
    teacher, init = models
    out = distill([teacher], init, RESIDUAL, FAKE, {"scenario": "train"}, list(range(40, 46)), 2, 0,
                  tmp_path / "out" / "student.zip")
    before, after = _gap(init, teacher, [7, 8]), _gap(out, teacher, [7, 8])  # episodes it did not see
    assert before > 0.5 and after < 0.2 * before
    assert [h["iteration"] for h in out["distill"]] == [0, 1] and out["distill"][1]["labels"] == 6 * 48
    with zipfile.ZipFile(init["path"]) as a, zipfile.ZipFile(out["path"]) as b:
        assert a.namelist() == b.namelist()
        changed = [n for n in a.namelist() if a.read(n) != b.read(n)]
    assert changed == ["policy.pth"]
    assert AgentPolicy(out["path"]).observation_space.shape == (len(FIELD_OBS_NAMES) + 2,)


def test_distillation_is_reproducible(tmp_path, models) -> None:
    teacher, init = models
    runs = [distill([teacher], init, RESIDUAL, FAKE, {"scenario": "train"}, [40, 41], 1, 3,
                    tmp_path / f"o{k}" / "student.zip") for k in (0, 1)]
    with zipfile.ZipFile(runs[0]["path"]) as a, zipfile.ZipFile(runs[1]["path"]) as b:
        assert a.read("policy.pth") == b.read("policy.pth")


def test_distillation_refuses_the_test_split(tmp_path, models) -> None:
    teacher, init = models
    with pytest.raises(ValueError, match="test"):
        distill([teacher], init, RESIDUAL, FAKE, {"scenario": "test"}, [40], 1, 0, tmp_path / "s.zip")
    assert not (tmp_path / "s.zip").exists()


# ---------------------------------------------------------------------------------------- config
def _cfg(tmp_path: Path) -> dict:
    from test_benchmark import _quick_cfg

    cfg = _quick_cfg(tmp_path, env_id="srenv/SuckerRod-v1")
    runs = cfg["agents"]["runs"]
    runs["ppo_residual_shaped"]["seeds"] = [0, 1]
    runs["distilled"] = {"config": runs["ppo_residual_shaped"]["config"], "seeds": [0, 1],
                         "residual": copy.deepcopy(runs["ppo_residual_shaped"]["residual"]),
                         "teacher": {"students_from": "ppo_residual_shaped", "iterations": 2, "episodes": 3,
                                     "seed_start": 40000, "idle_scale": 1.0}}
    return cfg


def test_benchmark_config_accepts_a_teacher_student_run(tmp_path) -> None:
    p = tmp_path / "ok.yaml"
    p.write_text(yaml.safe_dump(_cfg(tmp_path)))
    assert load_benchmark_config(p)["agents"]["runs"]["distilled"]["teacher"]["iterations"] == 2


@pytest.mark.parametrize("change, match", [
    (lambda r: r.update(teacher="yes"), "teacher = "),
    (lambda r: r["teacher"].update(extra=1), "teacher = "),
    (lambda r: r["teacher"].pop("episodes"), "teacher = "),
    (lambda r: r["teacher"].update(students_from="nope"), "students_from = 'nope'"),
    (lambda r: r["teacher"].update(students_from="distilled"), "students_from = 'distilled'"),
    (lambda r: r["teacher"].update(students_from="ppo"), "base, scale and idle_scale"),
    (lambda r: r["residual"].update(scale=0.3), "base, scale and idle_scale"),
    (lambda r: r.update(seeds=[0, 2]), "seeds"),
    (lambda r: r["teacher"].update(iterations=0), r"iterations = 0: expected an integer in \[1, 20\]"),
    (lambda r: r["teacher"].update(iterations=True), "iterations = True"),
    (lambda r: r["teacher"].update(episodes=2.5), "episodes = 2.5"),
    (lambda r: r["teacher"].update(seed_start=-1), "seed_start = -1"),
    (lambda r: r["teacher"].update(iterations=20, episodes=60), "iterations x episodes = 1200"),
    (lambda r: r["teacher"].update(idle_scale=3.0), "idle_scale = 3.0"),
    (lambda r: r["teacher"].update(seed_start=499), "share seeds"),
], ids=["not-a-map", "unknown-key", "missing-key", "unknown-run", "itself", "no-residual", "other-scale",
        "other-seeds", "iterations-zero", "iterations-bool", "episodes-float", "start-negative",
        "too-many-episodes", "idle-big", "validation-overlap"])
def test_benchmark_config_refuses_a_bad_teacher(tmp_path, change, match) -> None:
    cfg = _cfg(tmp_path)
    change(cfg["agents"]["runs"]["distilled"])
    p = tmp_path / "bad.yaml"
    p.write_text(yaml.safe_dump(cfg))
    with pytest.raises(ValueError, match=match):
        load_benchmark_config(p)
