"""Students on the field pump-off with alarms (scripts/alarm_base_pilot.py, issue 24 design w24): the base-controller
choice builds the right spec (alarm base: the shut-in alarms followed, no cost limit; pump-off base: the plain
ensemble, as the shipped students were trained and tested), and the guard's ``follow_shut_in`` alone plays the
student until an alarm shuts the well in, then idles for the rest of the episode whatever the student wants."""

from __future__ import annotations

import importlib.util
from pathlib import Path

import numpy as np
import pytest

import srenv  # noqa: F401
from agents.envs import make_env
from agents.evaluation.agent import build_policy
from agents.evaluation.rollout import run_episode
from agents.policies.field import IDLE, obs_names_of
from agents.policies.guarded import GuardedPolicy

REPO = Path(__file__).resolve().parents[2]
KW = {"observation": "field", "episode_hours": 0.5, "event_rate_scale": 0.0}
APO = {"threshold": 0.5, "idle_time_s": 900, "a_spm": 0.3, "a_stroke": 1.0, "load_drop": 0.5, "alarm_prob": 0.6,
       "gas_slowdown": 0.3}
PUMP = np.array([0.77, -0.33], np.float32)


def _pilot():
    spec = importlib.util.spec_from_file_location("alarm_base_pilot", REPO / "scripts" / "alarm_base_pilot.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


class _Pump:
    def predict(self, observation, state=None, episode_start=None, deterministic=True):
        return PUMP.copy(), None


@pytest.fixture(scope="module")
def env():
    e = make_env("srenv/SuckerRod-v2", **KW)
    yield e
    e.close()


def test_the_base_choice_builds_the_design_spec():
    pilot = _pilot()
    tuned = pilot.tuned_params()
    specs = pilot.variants(tuned, [])
    plain, alarm = specs["shipped_ensemble_on_pump_off"], specs["shipped_ensemble_on_alarm_pump_off"]
    assert plain["kind"] == "ensemble" and plain["residual"]["base"] == "pump_off"
    assert plain["residual"]["params"] == tuned["pump_off"] and plain["residual"]["scale"] == 0.5
    assert len(plain["members"]) == 3 and all(Path(m["path"]).exists() for m in plain["members"])
    assert alarm["kind"] == "guarded" and alarm["guard"] == {"follow_shut_in": True}  # no cost limit
    assert alarm["inner"]["residual"]["base"] == "alarm_pump_off"
    assert alarm["fallback"] == {"name": "alarm_pump_off", "params": tuned["alarm_pump_off"]}
    assert alarm["inner"]["members"] == plain["members"]


def test_following_the_shut_in_alone_idles_the_well_after_an_alarm(env):
    names = obs_names_of(env)
    pol = GuardedPolicy(_Pump(), "alarm_pump_off", APO, {"follow_shut_in": True}, names)
    obs, _ = env.reset(seed=0)
    pol.reset(env)
    card = np.array(obs, np.float32)
    card[names.index("fillage_est")], card[names.index("pprl")], card[names.index("mprl")] = 0.95, 0.8, 0.4
    assert not pol.fires(card)  # no limit: only the shut-in hands the well over
    np.testing.assert_array_equal(pol.predict(card)[0], PUMP)
    np.testing.assert_array_equal(pol.predict(card)[0], PUMP)
    parted = card.copy()
    parted[names.index("pprl")] = 0.45  # the load range collapsed: 0.05 < (1 - 0.5) x 0.4
    for o in (parted, card, card):  # shut in, and it stays shut in whatever the card shows
        assert pol.predict(o)[0][0] == IDLE
    assert pol.fired == 3


def test_with_no_alarm_the_followed_base_is_the_plain_residual(env):
    pilot = _pilot()
    tuned = pilot.tuned_params()
    members = [pilot.member(pilot.SHIPPED[0])]
    ens = {"kind": "ensemble", "members": members,
           "residual": {"base": "alarm_pump_off", "params": tuned["alarm_pump_off"], "scale": 0.5}}
    plain = run_episode(env, build_policy(ens, env), 3)
    pol = build_policy(pilot.on_base(members, "alarm_pump_off", tuned), env)
    followed = run_episode(env, pol, 3)
    assert pol.fired == 0  # no alarm on this well: the premise
    assert followed["reward"] == plain["reward"] and followed["cost"] == plain["cost"]
