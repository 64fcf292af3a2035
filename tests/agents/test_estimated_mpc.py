"""estimated_mpc (agents/policies/estimated_mpc.py): the causal oracle's planner on a twin of the nearest training
well. It must never read the played well's hidden parameters or state, play the same actions for the same
observations, refuse bad parameters, and its shipped library must hold training wells only, none of the
validation episodes' wells."""

from __future__ import annotations

import numpy as np
import pytest

from agents.envs import make_env
from agents.policies.estimated_mpc import LIBRARY, EstimatedMPCPolicy, WellLibrary
from agents.policies.factory import make_baseline

ENV = "srenv/SuckerRod-v2"
KW = {"observation": "field", "episode_hours": 0.5, "interval_s": 300.0}  # 6 intervals, conditions on
PARAMS = {"horizon": 2, "replan_every": 2,
          "policies": [["pump_off", {"threshold": 0.99, "idle_time_s": 3600, "a_spm": 0.4, "a_stroke": 0.0}]]}
SEED = 20003  # a validation episode's seed on the training split (well 3)


def _play(env, pol, seed: int, obs_list: list | None = None) -> tuple[list, list]:
    """Actions of ``pol`` on ``env``'s episode ``seed``, or on the given observations (then env is not stepped)."""
    obs, _ = env.reset(seed=seed)
    pol.reset(env)
    acts, seen = [], []
    for k in range(6):
        o = obs if obs_list is None else obs_list[k]
        a, _ = pol.predict(o, episode_start=np.array([k == 0]))
        acts.append(np.asarray(a).copy())
        seen.append(np.asarray(o).copy())
        if obs_list is None:
            obs, _, term, trunc, _ = env.step(a)
            if term or trunc:
                break
    return acts, seen


def test_never_reads_the_hidden_well_or_state():
    """The same observations give the same actions when everything hidden of the env is taken away after reset:
    the well (its parameters and config), the simulator (annulus, reservoir), the condition schedule."""
    env = make_env(ENV, scenario="train", **KW)
    acts, seen = _play(env, EstimatedMPCPolicy(**PARAMS), SEED)
    blind = make_env(ENV, scenario="train", **KW)
    pol = EstimatedMPCPolicy(**PARAMS)
    blind.reset(seed=SEED)
    pol.reset(blind)
    u = blind.unwrapped
    for name in ("well", "sim", "cfg", "_schedule", "_condition", "_parting", "runner", "inflow_multiplier"):
        setattr(u, name, None)  # any read of these raises
    again = []
    for k, o in enumerate(seen):
        a, _ = pol.predict(o, episode_start=np.array([k == 0]))
        again.append(np.asarray(a))
    np.testing.assert_array_equal(np.array(acts), np.array(again))
    assert pol.sim_steps > len(seen)  # it did plan (rollouts on its twin), not only follow


def test_deterministic_and_another_well_other_model():
    env = make_env(ENV, scenario="train", **KW)
    a1, _ = _play(env, EstimatedMPCPolicy(**PARAMS), SEED)
    p2 = EstimatedMPCPolicy(**PARAMS)
    a2, _ = _play(env, p2, SEED)
    np.testing.assert_array_equal(np.array(a1), np.array(a2))
    first = p2.model_well
    p3 = EstimatedMPCPolicy(**PARAMS)
    _play(env, p3, 20011)
    assert first >= 16 and p3.model_well >= 16 and first != p3.model_well


@pytest.mark.parametrize("bad", [{"horizon": 0}, {"horizon": -1}, {"horizon": 1.5}, {"horizon": True},
                                 {"horizon": 145}, {"replan_every": 0}, {"library": "/nonexistent/lib.npz"}])
def test_bad_params_refused(bad):
    with pytest.raises(ValueError) as exc:
        EstimatedMPCPolicy(**{**PARAMS, **bad})
    key = next(iter(bad))
    assert key in str(exc.value) and "\n" not in str(exc.value)


def test_bad_library_refused(tmp_path):
    p = tmp_path / "lib.npz"
    np.savez(p, wells=np.arange(3), features=np.ones((2, 4)), names=np.array(["a", "b", "c", "d"]))
    with pytest.raises(ValueError, match="library"):
        EstimatedMPCPolicy(**PARAMS, library=str(p))


def test_shipped_library_is_training_wells_16_up_and_matches_itself():
    lib = WellLibrary.load(LIBRARY)
    assert lib.wells.min() >= 16 and lib.wells.max() < 200  # no tuning or validation well (0..15)
    assert len(set(lib.wells.tolist())) == 184
    row = lib._z[10] / lib.weight * lib.scale + lib.mean  # a library row is nearest to itself
    names = lib.names
    assert lib.nearest(row, names) == lib.wells[10]


def test_built_by_name_as_a_baseline():
    env = make_env(ENV, scenario="train", **KW)
    pol = make_baseline("estimated_mpc", PARAMS, env.unwrapped.obs_names)
    assert isinstance(pol, EstimatedMPCPolicy) and pol.params()["horizon"] == 2


ALARM = {"threshold": 0.99, "idle_time_s": 3600, "a_spm": 0.4, "a_stroke": 0.0, "load_drop": 0.5, "alarm_prob": 0.6,
         "gas_slowdown": 0.6}
GUARD = {"fallback": ["alarm_pump_off", ALARM], "pound_below": 0.9, "load_above": 0.95, "condition_prob": 0.6}


@pytest.mark.parametrize("bad", [{"pound_below": 0.9}, {**GUARD, "extra": 1}, {**GUARD, "fallback": "pump_off"},
                                 {**GUARD, "load_above": -0.1}, {**GUARD, "condition_prob": True},
                                 {**GUARD, "pound_below": "0.9"}])
def test_bad_guard_refused(bad):
    with pytest.raises(ValueError, match="estimated_mpc guard") as exc:
        EstimatedMPCPolicy(**PARAMS, guard=bad)
    assert "\n" not in str(exc.value)


def test_an_always_firing_guard_plays_the_fallback():
    """With every threshold past its reach the guard fires each interval: the actions are alarm_pump_off's own."""
    env = make_env(ENV, scenario="train", **KW)
    always = {**GUARD, "pound_below": 1.5}  # fillage_est < 1.5 on every card
    pol = EstimatedMPCPolicy(**PARAMS, guard=always)
    acts, seen = _play(env, pol, SEED)
    fb = make_baseline("alarm_pump_off", ALARM, env.unwrapped.obs_names)
    env.reset(seed=SEED)
    ref, state = [], None
    for k, o in enumerate(seen):
        a, state = fb.predict(o, state=state, episode_start=np.array([k == 0]))
        ref.append(np.asarray(a))
    np.testing.assert_allclose(np.array(acts), np.array(ref), atol=1e-6)
    assert pol.guarded_intervals == len(seen)


def test_the_shipped_library_is_what_its_script_builds():
    """The data shipped is reproducible from the training wells by scripts/estimated_mpc_library.py's build."""
    import sys
    from pathlib import Path

    sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "scripts"))
    from estimated_mpc_library import build

    lib = WellLibrary.load(LIBRARY)
    wells, feats, names = build(4, range(16, 20))
    np.testing.assert_array_equal(wells, lib.wells[:16])
    assert names == lib.names
    np.testing.assert_allclose(feats, (lib._z[:16] / lib.weight) * lib.scale + lib.mean, rtol=1e-9, atol=1e-9)


# ---------------------------------------------------------------- twin: described (t24b), guard pound_prob
DESCRIBED = {**PARAMS, "twin": "described"}


def test_described_twin_reads_only_the_operator_file():
    """twin: described - the same observations give the same actions when, BEFORE the policy's reset, the env's
    well is swapped for one with the same equipment and another reservoir, friction, damping and decline (the file
    is the same), and when after reset everything hidden is taken away."""
    import dataclasses

    from srenv.config import load_config
    from srenv.task.well_file import well_file

    env = make_env(ENV, scenario="train", **KW)
    pol = EstimatedMPCPolicy(**DESCRIBED)
    acts, seen = _play(env, pol, SEED)
    assert pol.sim_steps > len(seen) and pol.model_well == -1 and pol.params()["twin"] == "described"
    blind = make_env(ENV, scenario="train", **KW)
    blind.reset(seed=SEED)
    u = blind.unwrapped
    other = load_config(u.well.cfg, {"inflow.max_rate_m3_day": 3.0 * u.well.cfg.inflow.max_rate_m3_day,
                                     "friction.coefficient": 0.01, "damping.damping_factor": 0.11,
                                     "task.inflow_decline_per_day": 0.29})
    u.well = dataclasses.replace(u.well, cfg=other, params=None)
    assert well_file(u.well) == well_file(env)
    pol2 = EstimatedMPCPolicy(**DESCRIBED)
    pol2.reset(blind)
    for name in ("well", "sim", "cfg", "_schedule", "_condition", "_parting", "runner", "inflow_multiplier"):
        setattr(u, name, None)
    again = [np.asarray(pol2.predict(o, episode_start=np.array([k == 0]))[0]) for k, o in enumerate(seen)]
    np.testing.assert_array_equal(np.array(acts), np.array(again))


def test_described_twin_is_the_played_wells_equipment():
    from srenv.config import to_dict
    from srenv.task.well_file import WHITELIST

    env = make_env(ENV, scenario="train", **KW)
    pol = EstimatedMPCPolicy(**DESCRIBED)
    _play(env, pol, 20011)
    twin, well = to_dict(pol._twin.well.cfg), to_dict(env.unwrapped.well.cfg)
    assert all(twin[s][k] == well[s][k] for s, ks in WHITELIST.items() for k in ks)
    assert pol._twin.event_rate_scale == 0.0 and pol._twin._schedule.events == []


def test_default_twin_is_the_library_and_bad_twin_refused():
    assert "twin" not in EstimatedMPCPolicy(**PARAMS).params()
    for bad in ("true", None, 1, "Described"):
        with pytest.raises(ValueError, match="estimated_mpc twin") as exc:
            EstimatedMPCPolicy(**PARAMS, twin=bad)
        assert "\n" not in str(exc.value)


@pytest.mark.parametrize("bad", [0.0, -0.1, 1.01, True, "0.5", None])
def test_bad_pound_prob_refused(bad):
    with pytest.raises(ValueError, match="pound_prob") as exc:
        EstimatedMPCPolicy(**PARAMS, guard={**GUARD, "pound_prob": bad})
    assert "\n" not in str(exc.value)


def test_pound_prob_fires_on_the_classifiers_pound_only_when_set():
    """A card the fillage estimate calls full (0.92 > pound_below 0.9) but the classifier calls pounding: the guard
    fires with pound_prob at or below the probability, not without it (m24's guard unchanged)."""
    env = make_env(ENV, scenario="train", **KW)
    names = list(env.unwrapped.obs_names)
    obs = np.zeros(len(names))
    obs[names.index("fillage_est")], obs[names.index("prob_fluid_pound")] = 0.92, 0.7
    fired = {}
    for p in (None, 0.5, 0.7, 0.8):
        pol = EstimatedMPCPolicy(**PARAMS, guard=GUARD if p is None else {**GUARD, "pound_prob": p})
        pol._names = names
        fired[p] = pol._alarmed(obs)
    assert fired == {None: False, 0.5: True, 0.7: True, 0.8: False}
    assert "pound_prob" not in EstimatedMPCPolicy(**PARAMS, guard=GUARD).params()["guard"]
