"""Potential-based reward shaping (agents/training/shaping.py) on the real ``srenv/SuckerRod-v1``: the shaped return
telescopes to the true return minus the first state's potential (so no policy ranking changes), the potential
is the value of the present inflow for the time left, and the residual env imports only the two inner envs."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import yaml

from agents.benchmark.config import load_benchmark_config
from agents.envs import make_env
from agents.policies.factory import make_baseline
from agents.policies.field import obs_names_of
from agents.training.residual_env import make_residual_env
from agents.training.shaping import SHAPED_ENV_ID, potential

REPO = Path(__file__).resolve().parents[2]
PUMP_OFF = {"threshold": 0.95, "idle_time_s": 3600, "a_spm": 0.1, "a_stroke": 1.0}


@pytest.fixture(scope="module")
def shaped():
    env = make_env(SHAPED_ENV_ID, scenario="train", observation="field")
    yield env
    env.close()


@pytest.mark.parametrize("seed", [20001, 20004])
def test_shaped_return_is_the_true_return_minus_the_first_potential(shaped, seed) -> None:
    pol = make_baseline("pump_off", PUMP_OFF, obs_names_of(shaped))
    obs, _ = shaped.reset(seed=seed)
    pol.reset(shaped)
    phi0 = potential(shaped)
    state, start, shaped_ret, true_ret, terms = None, True, 0.0, 0.0, []
    while True:
        a, state = pol.predict(obs, state=state, episode_start=np.array([start]))
        start = False
        obs, r, term, trunc, info = shaped.step(a)
        shaped_ret += r
        true_ret += r - info["shaping"]
        terms.append(info["shaping"])
        if term or trunc:
            break
    assert phi0 > 0.0
    assert shaped_ret == pytest.approx(true_ret - phi0, rel=1e-9, abs=1e-6)
    # the shaping is not a constant offset: it moves with what each interval did to the inflow
    assert np.std(terms) > 1.0


def test_potential_falls_faster_than_time_when_the_level_rises(shaped) -> None:
    """Idle: the annulus fills, the intake pressure rises and the inflow falls (the IPR), so the value of the
    present inflow for the time left falls by more than the time left does."""
    shaped.reset(seed=20001)
    u = shaped.unwrapped
    t0, phi0, level0 = u.horizon_s - u._elapsed(), potential(shaped), u.sim.annulus.level_m
    for _ in range(3):
        shaped.step(np.array([-1.0, -1.0], np.float32))  # idle
    t1, phi1, level1 = u.horizon_s - u._elapsed(), potential(shaped), u.sim.annulus.level_m
    assert level1 > level0
    assert phi1 / phi0 < t1 / t0 - 1e-6


@pytest.mark.parametrize("inner", ["os:system", "srenv/SuckerRod-v0", "agents.training.shaping:Other-v1"])
def test_residual_env_refuses_other_inner_envs(inner) -> None:
    with pytest.raises(ValueError, match="inner_env_id"):
        make_residual_env(inner_env_id=inner, base="pump_off", base_params=PUMP_OFF, scale=0.5)


@pytest.mark.parametrize("inner", ["os:system", "srenv/SuckerRod-v0"])
def test_shaped_env_refuses_other_inner_envs(inner) -> None:
    from agents.training.shaping import make_shaped_env

    with pytest.raises(ValueError, match="inner_env_id"):
        make_shaped_env(inner_env_id=inner)


@pytest.mark.parametrize("shaping", ["bogus", 1, "reward"])
def test_benchmark_config_refuses_unknown_shaping(tmp_path, shaping) -> None:
    cfg = yaml.safe_load((REPO / "configs/benchmark/v1.yaml").read_text())
    cfg["agents"]["runs"]["ppo_residual_shaped"]["residual"]["shaping"] = shaping
    p = tmp_path / "bad.yaml"
    p.write_text(yaml.safe_dump(cfg))
    with pytest.raises(ValueError, match="shaping"):
        load_benchmark_config(p)
