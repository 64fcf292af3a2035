"""The constraint guard (agents/policies/guarded.py) on a tiny v2 env (30 min episodes of 5 min intervals, no events):
it fires on a constructed cost signal and holds for its intervals, passes the inner policy through when it does not
fire, plays the fallback when it always does, scale 0 is the residual's base, its spec survives JSON and replay, its
bad parameters are refused in one line, and the design's config keeps v2's splits, baselines and protocol."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

import srenv  # noqa: F401
from agents.benchmark.config import load_benchmark_config
from agents.envs import make_env
from agents.evaluation.agent import build_policy
from agents.evaluation.rollout import run_episode
from agents.policies.field import obs_names_of
from agents.policies.guarded import GuardedPolicy, check_guard, guarded_spec

REPO = Path(__file__).resolve().parents[2]
ENV = "srenv/SuckerRod-v2"
KW = {"observation": "field", "episode_hours": 0.5, "event_rate_scale": 0.0}
FPI = {"setpoint": 0.95, "kp": 0.5, "ki": 0.2, "a_stroke": 0.0}
APO = {"threshold": 0.9, "idle_time_s": 900, "a_spm": 0.3, "a_stroke": 1.0, "load_drop": 0.5, "alarm_prob": 0.6,
       "gas_slowdown": 0.3}
NEVER = {"above": {"pprl": 1e9}, "hold_intervals": 1}
ALWAYS = {"below": {"pprl": 1e9}, "hold_intervals": 1}
CONFIG = REPO / "configs/benchmark/v2_oracle_distilled_guarded.yaml"


INNER = np.array([0.77, -0.33], np.float32)


class _Const:
    """An inner policy that always pumps at one action (far from any baseline's), so a switch shows."""

    def predict(self, observation, state=None, episode_start=None, deterministic=True):
        return INNER.copy(), None


@pytest.fixture(scope="module")
def env():
    e = make_env(ENV, **KW)
    yield e
    e.close()


@pytest.fixture(scope="module")
def student(tmp_path_factory):
    from agents.training.oracle_distill import fresh_student

    path = tmp_path_factory.mktemp("student") / "student.zip"
    fresh_student(91, {"net_arch": [8, 8]}, 0, path)  # v2's field observation (89) + the base action
    return {"kind": "ensemble", "members": [{"path": str(path), "obs_norm": None}],
            "residual": {"base": "fillage_pi", "params": FPI, "scale": 0.5}}


def test_fires_on_the_cost_signal_and_holds(env):
    names = obs_names_of(env)
    guard = {"above": {"pprl": 0.95}, "below": {"fillage_est": 0.5}, "hold_intervals": 3}
    pol = GuardedPolicy(_Const(), "alarm_pump_off", APO, guard, names)
    obs, _ = env.reset(seed=0)
    pol.reset(env)
    quiet = np.array(obs, np.float32)
    quiet[names.index("pprl")], quiet[names.index("fillage_est")] = 0.8, 0.9
    assert not pol.fires(quiet)
    np.testing.assert_array_equal(pol.predict(quiet)[0], INNER)
    loud = quiet.copy()
    loud[names.index("pprl")] = 1.1  # the peak load above the rating
    assert pol.fires(loud)
    acts = [pol.predict(o)[0] for o in (loud, quiet, quiet, quiet)]
    for a in acts[:3]:  # the firing interval and the two after it: the fallback's action
        assert not np.allclose(a, INNER)
    np.testing.assert_array_equal(acts[3], INNER)
    assert pol.fired == 3
    empty = quiet.copy()
    empty[names.index("fillage_est")] = 0.3  # a pounding card: the lower limit
    assert pol.fires(empty)


def test_never_firing_is_the_inner_policy_and_always_firing_the_fallback(env, student):
    inner = run_episode(env, build_policy(student, env), 1)
    quiet = run_episode(env, build_policy(guarded_spec(student, "alarm_pump_off", APO, NEVER), env), 1)
    assert quiet["reward"] == inner["reward"] and quiet["cost"] == inner["cost"]
    fb = run_episode(env, build_policy({"kind": "baseline", "name": "alarm_pump_off", "params": APO}, env), 1)
    loud = run_episode(env, build_policy(guarded_spec(student, "alarm_pump_off", APO, ALWAYS), env), 1)
    assert loud["reward"] == fb["reward"] and loud["cost"] == fb["cost"]
    assert fb["reward"] != inner["reward"]  # the two are different controllers on this well


def test_scale_zero_is_the_base_and_the_scale_replaces_the_trained_one(env, student):
    base = run_episode(env, build_policy({"kind": "baseline", "name": "fillage_pi", "params": FPI}, env), 2)
    zero = run_episode(env, build_policy(guarded_spec(student, "alarm_pump_off", APO, NEVER, scale=0.0), env), 2)
    assert zero["reward"] == base["reward"]
    pol = build_policy(guarded_spec(student, "alarm_pump_off", APO, NEVER, scale=0.25), env)
    assert pol.inner.scale == 0.25 and student["residual"]["scale"] == 0.5


def test_spec_round_trips_through_json(env, student):
    spec = guarded_spec(student, "alarm_pump_off", APO, {"below": {"fillage_est": 0.85}, "above": {"pprl": 0.95},
                                                         "hold_intervals": 3, "follow_shut_in": True}, scale=0.35)
    back = json.loads(json.dumps(spec))
    assert back == spec
    a = run_episode(env, build_policy(spec, env), 3)
    b = run_episode(env, build_policy(back, env), 3)
    assert a["reward"] == b["reward"]


@pytest.mark.parametrize("guard, match", [
    ({"hold_intervals": 0}, r"guard.hold_intervals = 0: expected an integer in \[1, 144\]"),
    ({"above": {"pprl": "high"}}, r"guard.above.pprl = 'high': expected a finite number"),
    ({"after": 3}, r"guard.after: unknown key, expected a mapping with keys above"),
    ({"follow_shut_in": 1}, r"guard.follow_shut_in = 1: expected true or false"),
])
def test_bad_guard_is_refused_in_one_line(guard, match):
    with pytest.raises(ValueError, match=match):
        check_guard(guard)


def test_unknown_observation_name_is_refused(env):
    with pytest.raises(ValueError, match="observation has no 'pprl_kn'"):
        GuardedPolicy(_Const(), "alarm_pump_off", APO, {"above": {"pprl_kn": 1.0}}, obs_names_of(env))


def test_scale_out_of_range_is_refused(student):
    with pytest.raises(ValueError, match=r"guarded.scale = 2.5: expected a number in \[0, 2\]"):
        guarded_spec(student, "alarm_pump_off", APO, NEVER, scale=2.5)


def test_design_config_keeps_v2s_splits_baselines_and_protocol():
    for quick in (False, True):
        ours = load_benchmark_config(CONFIG, quick=quick)
        for ref in ("v2.yaml", "v2_oracle_distilled.yaml"):
            v2 = load_benchmark_config(REPO / "configs/benchmark" / ref, quick=quick)
            for k in ("env_id", "env_kwargs", "workers", "tuning", "validation", "test", "baselines",
                      "figure_episode"):
                assert ours[k] == v2[k], (ref, k)
        od = load_benchmark_config(REPO / "configs/benchmark/v2_oracle_distilled.yaml", quick=quick)
        assert ours["agents"]["runs"] == od["agents"]["runs"]  # the same students, not retrained
    cfg = load_benchmark_config(CONFIG)
    g = cfg["guarded"]
    check_guard(g["guard"])
    assert g["fallback"] == "alarm_pump_off" and 0.0 <= g["scale"] <= 2.0


def test_test_stage_plays_the_named_baselines_and_a_guarded_design(student):
    """stages.run_test_episodes(policies=...): only the baselines a look's judge reads, beside the design."""
    from agents.benchmark.stages import run_test_episodes
    from agents.evaluation.rollout import Runner

    cfg = {"env_id": ENV, "env_kwargs": KW, "test": {"scenario": "validation", "seeds": [0, 1]}}
    tuned = {"fillage_pi": {"params": FPI}, "alarm_pump_off": {"params": APO}, "pump_off": {"params": {}}}
    design = {**guarded_spec(student, "alarm_pump_off", APO, ALWAYS), "of": "oracle_distilled"}
    with Runner(1) as runner:
        by = run_test_episodes(cfg, runner, tuned, {"oracle_distilled_guarded": [design]}, -1,
                               policies=["alarm_pump_off"])
    assert set(by) == {("alarm_pump_off", -1), ("oracle_distilled_guarded", 0)}
    assert [e["reward"] for e in by[("oracle_distilled_guarded", 0)]] == [e["reward"] for e in by[("alarm_pump_off", -1)]]


@pytest.mark.parametrize("change, match", [
    ({"fallback": "oracle"}, r"guarded.fallback = 'oracle': expected a tuned field baseline"),
    ({"scale": -0.1}, r"guarded.scale = -0.1: expected a number in \[0, 2\]"),
    ({"guard": {"hold_intervals": 200}}, r"guarded.guard.hold_intervals = 200"),
    ({"limits": {}}, r"guarded = .*: expected \{fallback: BASELINE"),
])
def test_config_refuses_a_bad_guarded_block(tmp_path, change, match):
    import yaml

    from agents.benchmark.config import BenchmarkConfigError

    raw = yaml.safe_load(CONFIG.read_text())
    raw["guarded"] = {**raw["guarded"], **change}
    bad = tmp_path / "bad.yaml"
    bad.write_text(yaml.safe_dump(raw))
    with pytest.raises(BenchmarkConfigError, match=match):
        load_benchmark_config(bad)


def test_a_guarded_ensemble_is_named_as_guarded_in_the_report_header():
    from agents.benchmark.report import _runs_text

    tr = {"runs": {}, "ensembles": {"g": {"of": "s", "models": ["a.zip", "b.zip"]}, "e": {"of": "s", "models": ["a.zip"]}}}
    text = _runs_text(tr, {"g": {"guarded": {"guard": {}}}, "e": {"kind": "agent"}})
    assert "g: the mean action of s's 2 seed models, under the constraint guard" in text
    assert text.endswith("e: the mean action of s's 1 seed models")


# issue 24, u44: the members' agreement, alarms first, pump-off's idle, and the stale-card fix


class _Member:
    def __init__(self, a):
        self.a = np.asarray(a, np.float32)

    def predict(self, observation, state=None, episode_start=None, deterministic=True):
        return self.a.copy(), None


SPLIT = [[0.2, -1.0], [0.6, 0.0]]  # std per entry (0.2, 0.5): disagreement 0.5, mean (0.4, -0.5)
POF = {"threshold": 0.9, "idle_time_s": 900, "a_spm": 0.3, "a_stroke": 1.0}


def _quiet(env, names, **entries):
    obs, _ = env.reset(seed=0)
    x = np.array(obs, np.float32)
    x[names.index("fillage_est")], x[names.index("duty")] = 0.99, 1.0
    for k, v in entries.items():
        x[names.index(k)] = v
    return x


@pytest.mark.parametrize("tau, inner", [(0.4, False), (0.5, True), (0.6, True)])
def test_the_members_disagreement_gates_the_ensemble(env, tau, inner):
    """Above tau the interval is the fallback's (no hold), at or below it the ensemble's mean action."""
    from agents.policies.ensemble import EnsemblePolicy

    names = obs_names_of(env)
    pol = GuardedPolicy(EnsemblePolicy([_Member(a) for a in SPLIT]), "pump_off", POF, {"disagreement_above": tau},
                        names)
    quiet = _quiet(env, names)
    pol.reset(env)
    a = pol.predict(quiet)[0]
    assert pol.ensemble.last_disagreement == pytest.approx(0.5)
    if inner:
        np.testing.assert_allclose(a, [0.4, -0.5])
    else:
        np.testing.assert_allclose(a, [POF["a_spm"], POF["a_stroke"]])
    assert pol.fired == (0 if inner else 1)
    agree = GuardedPolicy(EnsemblePolicy([_Member(SPLIT[0])] * 3), "pump_off", POF, {"disagreement_above": 0.0},
                          names)
    agree.reset(env)
    np.testing.assert_allclose(agree.predict(quiet)[0], SPLIT[0])  # members that agree: never gated


def test_the_gate_needs_an_ensemble_inside(env):
    with pytest.raises(ValueError, match="guard.disagreement_above: the inner policy is not a seed ensemble"):
        GuardedPolicy(_Const(), "pump_off", POF, {"disagreement_above": 0.3}, obs_names_of(env))


def test_alarms_first_plays_alarm_pump_off_where_its_alarms_act(env):
    names = obs_names_of(env)
    pol = GuardedPolicy(_Const(), "alarm_pump_off", APO, {"follow_alarms": True}, names)
    pol.reset(env)
    np.testing.assert_array_equal(pol.predict(_quiet(env, names, prob_gas_interference=0.1))[0], INNER)
    gas = pol.predict(_quiet(env, names, prob_gas_interference=0.9))[0]  # the gas alarm: the slow-down
    np.testing.assert_allclose(gas, [APO["a_spm"] - APO["gas_slowdown"], APO["a_stroke"]], atol=1e-6)
    shut = pol.predict(_quiet(env, names, prob_parted_rods=0.9))[0]  # the shut-in, and every interval after it
    assert shut[0] == -1.0 and pol.predict(_quiet(env, names))[0][0] == -1.0
    with pytest.raises(ValueError, match="guard.follow_alarms: the fallback 'pump_off' has no alarms"):
        GuardedPolicy(_Const(), "pump_off", POF, {"follow_alarms": True}, names)


def test_respecting_the_fallbacks_idle(env):
    names = obs_names_of(env)
    pol = GuardedPolicy(_Const(), "pump_off", POF, {"follow_idle": True}, names)
    pol.reset(env)
    np.testing.assert_array_equal(pol.predict(_quiet(env, names))[0], INNER)  # pump-off pumps: the inner's
    low = _quiet(env, names, fillage_est=0.5)  # the pumped card shows pump-off: the fallback idles 3 intervals
    acts = [pol.predict(low)[0] for _ in range(4)]
    assert [a[0] for a in acts[:3]] == [-1.0] * 3 and pol.fired == 3


@pytest.mark.parametrize("fresh", [False, True])
def test_a_stale_card_refires_only_without_fresh_card_only(env, fresh):
    """b43's finding: after the well idled (duty 0) the last card is the stale one that fired; with
    ``fresh_card_only`` the limits do not fire on it again, without it (every archived guard) they do."""
    names = obs_names_of(env)
    guard = {"above": {"prob_tagging_down": 0.5}, "fresh_card_only": fresh}
    pol = GuardedPolicy(_Const(), "pump_off", {**POF, "a_spm": -1.0}, guard, names)
    pol.reset(env)
    card = _quiet(env, names, prob_tagging_down=0.9)
    stale = card.copy()
    stale[names.index("duty")] = 0.0
    assert not np.allclose(pol.predict(card)[0], INNER)  # a pumped tagging card fires
    assert np.allclose(pol.predict(stale)[0], INNER) == fresh
    assert not np.allclose(pol.predict(card)[0], INNER)  # a new pumped tagging card fires again


@pytest.mark.parametrize("guard, match", [
    ({"disagreement_above": -0.1}, r"guard.disagreement_above = -0.1: expected a number in \[0, 1\]"),
    ({"disagreement_above": "half"}, r"guard.disagreement_above = 'half': expected a number in \[0, 1\]"),
    ({"disagreement_above": True}, r"guard.disagreement_above = True: expected a number"),
    ({"follow_alarms": "yes"}, r"guard.follow_alarms = 'yes': expected true or false"),
    ({"follow_idle": 0}, r"guard.follow_idle = 0: expected true or false"),
    ({"fresh_card_only": None}, r"guard.fresh_card_only = None: expected true or false"),
])
def test_bad_new_guard_keys_are_refused_in_one_line(guard, match):
    with pytest.raises(ValueError, match=match):
        check_guard(guard)
