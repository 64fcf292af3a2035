"""Seed ensembles (agents/policies/ensemble.py): the mean action of several models, plain and residual."""

from __future__ import annotations

import copy

import numpy as np
import pytest
import yaml
from conftest import FAKE_ENV
from test_benchmark import _quick_cfg

from agents.benchmark.config import load_benchmark_config
from agents.envs import make_env
from agents.evaluation.agent import AgentPolicy, build_policy
from agents.policies.ensemble import EnsemblePolicy, ensemble_spec
from agents.policies.residual import augment, compose

FAKE = FAKE_ENV


class Const:
    def __init__(self, a):
        self.a = np.asarray(a, np.float32)

    def predict(self, obs, state=None, episode_start=None, deterministic=True):
        return self.a, state


def test_the_ensemble_acts_with_the_mean_of_its_members() -> None:
    obs = np.zeros(4, np.float32)
    a, _ = EnsemblePolicy([Const([0.2, -1.0]), Const([0.6, 0.0]), Const([-0.2, 0.4])]).predict(obs)
    assert a == pytest.approx([0.2, -0.2])
    same, _ = EnsemblePolicy([Const([0.3, 0.7])] * 3).predict(obs)
    assert same == pytest.approx([0.3, 0.7])  # identical members: the member itself


def _models(tmp_path, env, n):
    from stable_baselines3 import PPO

    paths = []
    for s in range(n):
        m = PPO("MlpPolicy", env, seed=s, policy_kwargs={"net_arch": [8]}, n_steps=16, batch_size=8)
        p = tmp_path / f"m{s}.zip"
        m.save(p)
        paths.append({"kind": "agent", "path": str(p), "obs_norm": None})
    return paths


@pytest.mark.parametrize("residual", [None, {"base": "pump_off", "params": {"threshold": 0.85, "idle_time_s": 600,
                                                                          "a_spm": 0.2, "a_stroke": 1.0},
                                             "scale": 0.5}], ids=["plain", "residual"])
def test_a_built_ensemble_composes_the_mean_correction_once(tmp_path, residual) -> None:
    from agents.training.residual_env import ResidualEnv

    env = make_env(FAKE, scenario="train")
    train_env = ResidualEnv(make_env(FAKE, scenario="train"), "pump_off", residual["params"], 0.5) if residual else env
    specs = [{**s, **({"residual": residual} if residual else {})} for s in _models(tmp_path, train_env, 2)]
    pol = build_policy(ensemble_spec(specs), env)
    members = [AgentPolicy(s["path"]) for s in specs]
    obs, _ = env.reset(seed=3)
    if residual:
        pol.reset(env)
        base = build_policy({"kind": "baseline", "name": "pump_off", "params": residual["params"]}, env)
        base.reset(env)
        b, _ = base.predict(obs, episode_start=np.array([True]))
        want = compose(b, np.mean([m.predict(augment(obs, b))[0] for m in members], axis=0), 0.5)
    else:
        want = np.mean([m.predict(obs)[0] for m in members], axis=0)
    got, _ = pol.predict(obs, episode_start=np.array([True]))
    assert np.asarray(got) == pytest.approx(want, abs=1e-6)
    one = [np.asarray(m.predict(augment(obs, b) if residual else obs)[0]) for m in members]
    assert np.abs(one[0] - one[1]).max() > 1e-3  # the members differ, so the mean is a real test


def test_ensemble_members_must_share_one_residual() -> None:
    a = {"kind": "agent", "path": "a.zip", "residual": {"base": "pump_off", "params": {}, "scale": 0.5}}
    b = copy.deepcopy(a)
    b["residual"]["scale"] = 0.3
    with pytest.raises(ValueError, match="share one residual"):
        ensemble_spec([a, b])
    with pytest.raises(ValueError, match="at least one"):
        ensemble_spec([])


@pytest.mark.parametrize("ensemble,seeds", [("yes", [0, 1]), (1, [0, 1]), (True, [0])],
                         ids=["string", "number", "one-seed"])
def test_benchmark_config_refuses_a_bad_ensemble_flag(tmp_path, ensemble, seeds) -> None:
    cfg = _quick_cfg(tmp_path)
    cfg["agents"]["runs"]["ppo"].update(ensemble=ensemble, seeds=seeds)
    p = tmp_path / "bad.yaml"
    p.write_text(yaml.safe_dump(cfg))
    with pytest.raises(ValueError, match=r"agents\.runs\.ppo\.ensemble"):
        load_benchmark_config(p)


def test_the_members_disagreement_is_the_largest_std_over_the_entries() -> None:
    from agents.policies.ensemble import disagreement

    obs = np.zeros(4, np.float32)
    pol = EnsemblePolicy([Const([0.2, -1.0]), Const([0.6, 0.0]), Const([-0.2, 0.4])])
    acts = pol.member_actions(obs)
    assert acts.shape == (3, 2) and acts[1] == pytest.approx([0.6, 0.0])
    pol.predict(obs)
    assert pol.last_disagreement == pytest.approx(np.std([-1.0, 0.0, 0.4]))  # the rate entry's 0.327 < 0.589
    assert disagreement(np.array([[[0.0, 1.0], [0.5, 0.5]], [[0.0, -1.0], [0.5, 0.5]]])) == pytest.approx([1.0, 0.0])
