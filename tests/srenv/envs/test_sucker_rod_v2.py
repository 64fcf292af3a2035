"""srenv/SuckerRod-v2: condition events at their documented rates, their effect on the physics and the reward,
family and validation wells, and the reward / cost bookkeeping."""

import itertools
import math

import gymnasium as gym
import numpy as np
import pytest

import srenv  # noqa: F401
from srenv.envs.sucker_rod_v2 import FIELD_OBS_NAMES, PRIVILEGED_OBS_NAMES
from srenv.task import events as ev
from srenv.task import well_family as wf

ID = "srenv/SuckerRod-v2"


def test_events_occur_at_their_documented_rates():
    rng = np.random.default_rng(0)
    counts = dict.fromkeys(ev.EVENTS, 0)
    exposure_h = 0.0  # hours of normal running, when every clock ticks
    horizon = 12.0
    for _ in range(4000):
        sched = ev.draw_schedule(rng, horizon)
        t = 0.0
        for e in sched.events:
            exposure_h += e.start_h - t
            counts[e.label] += 1
            t = e.end_h
        if math.isfinite(t):
            exposure_h += max(0.0, horizon - t)
    for name, spec in ev.EVENTS.items():
        expected = spec.rate_per_h * exposure_h
        assert abs(counts[name] - expected) < 4.0 * math.sqrt(expected) + 1, (name, counts[name], expected)


def test_rods_part_at_the_documented_rate_scaled_by_the_loading():
    rng = np.random.default_rng(1)
    t_mean = 1.0 / ev.PARTING_RATE_PER_H
    # pumping t_mean hours at the reference loading parts 1 - 1/e of the strings (exponential with that rate)
    parted = [ev.PartingClock.draw(rng).advance(t_mean, 1.0, ev.PARTING_REFERENCE_GOODMAN_PCT) for _ in range(4000)]
    assert np.mean(parted) == pytest.approx(1.0 - math.exp(-1.0), abs=0.025)
    clock = ev.PartingClock(budget=1.0)
    clock.advance(1.0, 1.0, 2 * ev.PARTING_REFERENCE_GOODMAN_PCT)
    assert clock.used == pytest.approx(16 * ev.PARTING_RATE_PER_H)  # twice the loading, 2^4 the hazard
    idle = ev.PartingClock(budget=1e-12)
    assert not idle.advance(1.0, 0.0, 90.0)  # a well that does not pump does not part its rods


def test_parting_clock_ends_a_v2_episode():
    env = gym.make(ID, scenario="train", episode_hours=0.5).unwrapped
    env.reset(seed=3)
    env._parting = ev.PartingClock(budget=0.0)
    _, _, term, _, info = env.step(np.array([0.5, 1.0], np.float32))
    assert term and info["condition"] == "parted_rods" and info["reward_workover"] < 0
    assert info["reward_lost_production"] == 0.0  # they parted at the end of the interval


def test_schedule_severity_develops_and_one_condition_at_a_time():
    e = ev.Event("travelling_valve_leak", 1.0, math.inf, 0.4, ramp_h=4.0)
    assert e.severity_at(0.5) == 0.0 and e.severity_at(3.0) == pytest.approx(0.2) and e.severity_at(9.0) == 0.4
    sched = ev.draw_schedule(np.random.default_rng(3), 500.0)
    ends = [(x.start_h, x.end_h) for x in sched.events]
    assert all(b[0] >= a[1] for a, b in itertools.pairwise(ends))  # no overlap


def _forced(label, severity, hours=0.5, **kw):
    env = gym.make(ID, scenario="train", episode_hours=hours, **kw).unwrapped
    env.reset(seed=3)
    env._schedule = ev.Schedule([ev.Event(label, 0.0, math.inf, severity)])
    return env


def test_gas_slug_changes_the_card_and_is_reported():
    a = np.array([0.5, 1.0], np.float32)
    clean = gym.make(ID, scenario="train", episode_hours=0.5, event_rate_scale=0.0).unwrapped
    clean.reset(seed=3)
    o_clean, _, _, _, i_clean = clean.step(a)
    gas = _forced("gas_interference", 1.0)
    o_gas, r, _, _, info = gas.step(a)
    assert info["condition"] == "gas_interference" and info["condition_severity"] == 1.0
    assert gas.sim.cfg.pump.intake_gas_fraction > 0
    # the gas takes pump volume (the fillage and the production drop) and shows on the surface card: the chamber
    # law acts in the exact strokes (a slug switched on mid-episode once left the transfer rigid while only the
    # bookkeeping counted the gas: the card moved by 5e-3 of the rating), and the fast-forward draws what the
    # gas leaves of the displacement, as the exact strokes do
    assert info["fillage"] < i_clean["fillage"] - 0.05
    assert info["production_m3_day"] < 0.95 * i_clean["production_m3_day"]
    assert info["fillage"] == pytest.approx(gas._last.fillage, abs=0.02)
    assert np.abs(o_gas[:64] - o_clean[:64]).max() > 0.05
    up = gas._last.trace["pump_load_n"] > 0.5 * (gas._last.trace["pump_load_n"].max() + gas._last.trace["pump_load_n"].min())
    up_clean = clean._last.trace["pump_load_n"] > 0.5 * (clean._last.trace["pump_load_n"].max()
                                                            + clean._last.trace["pump_load_n"].min())
    assert up.mean() > up_clean.mean() + 0.05  # the plunger carries the fluid load into the downstroke
    # the slug ends: the well is back on its own config
    gas._schedule = ev.Schedule([])
    gas.step(a)
    assert gas.sim.cfg is gas.cfg and gas.sim.gas is None
    assert r == pytest.approx(sum(v for k, v in info.items() if k.startswith("reward_")), rel=1e-12, abs=1e-9)


def test_tubing_leak_prices_the_lost_production():
    env = _forced("tubing_leak", 0.4)
    _, r, _, _, info = env.step(np.array([0.5, 1.0], np.float32))
    v = env.econ.net_value_usd_m3
    assert info["reward_lost_production"] == pytest.approx(-0.4 * info["reward_revenue"], rel=1e-9)
    assert info["reward_lost_production"] < 0 and v > 0
    assert r == pytest.approx(sum(v for k, v in info.items() if k.startswith("reward_")), rel=1e-12, abs=1e-9)


def test_parted_rods_end_the_episode_with_a_workover():
    env = _forced("parted_rods", 1.0)
    _, _, term, trunc, info = env.step(np.array([0.5, 1.0], np.float32))
    h = env.cfg.task.interval_s / 3600.0
    assert term and not trunc and info["condition"] == "parted_rods"
    assert info["reward_workover"] == pytest.approx(-env.cfg.economics.workover_usd / h)
    assert info["cost_parted_rods"] == 1.0 and info["cost"] >= 1.0
    assert info["reward_revenue"] + info["reward_lost_production"] == pytest.approx(0.0, abs=1e-9)


def test_tagging_costs_and_privileged_truth():
    env = _forced("tagging_down", 0.5, observation="privileged")
    o, _, _, _, info = env.step(np.array([0.5, 1.0], np.float32))
    assert info["reward_tagging"] < 0 and info["cost_tagging"] == pytest.approx(0.5 * info["duty"])
    names = PRIVILEGED_OBS_NAMES
    assert o[names.index("true_tagging_down")] == 1.0 and o[names.index("true_severity")] == 0.5
    assert len(o) == len(names) and len(FIELD_OBS_NAMES) == 77 + 12


def test_family_wells_are_deterministic_and_outside_the_splits():
    a, b = wf.family_spec(12), wf.family_spec(12)
    assert a.params == b.params and a.well_id == "family-12"
    split_params = {wf.draw_params(wf.well_seed(s, k)) for s in wf.V2_SPLITS for k in range(3)}
    assert a.params not in split_params
    assert wf.draw_params(0) != wf.family_spec(0).params  # the same seed, another stream
    env = gym.make(ID, scenario="family:12", episode_hours=0.25)
    o1, i1 = env.reset(seed=4)
    o2, _ = env.reset(seed=4)
    assert np.array_equal(o1, o2) and i1["well_id"] == "family-12"
    with pytest.raises(ValueError, match="family:SEED"):
        gym.make(ID, scenario="family:x")


def test_validation_split_is_for_selection_only():
    assert gym.make(ID, scenario="validation").reset(seed=7)[1]["well_id"] == "validation-007"
    wf.check_split("validation", "select")
    for split, purpose in (("validation", "tune"), ("validation", "train"), ("family", "select"),
                           ("test", "train")):
        with pytest.raises(ValueError, match="refused"):
            wf.check_split(split, purpose)


@pytest.mark.parametrize("label", ["travelling_valve_leak", "standing_valve_leak", "tubing_leak", "tagging_down",
                                   "heavy_oil", "flowing", "gas_interference"])
def test_a_condition_leaves_its_signature_and_the_classifier_sees_it(label):
    env = _forced(label, 0.8)
    i = FIELD_OBS_NAMES.index("prob_full")
    for _ in range(2):
        o, *_ = env.step(np.array([0.5, 1.0], np.float32))
    probs = o[i:i + 12]
    # free gas at this well's intake (1 MPa against 22 MPa) compresses so steeply that the card is a "gas pound":
    # an incomplete-fillage card either label may name
    seen = {"gas_interference", "fluid_pound"} if label == "gas_interference" else {label}
    assert ev.LABELS[int(np.argmax(probs))] in seen and probs.sum() == pytest.approx(1.0, abs=1e-5)
    clean = gym.make(ID, scenario="train", episode_hours=0.5, event_rate_scale=0.0).unwrapped
    clean.reset(seed=3)
    oc, *_ = clean.step(np.array([0.5, 1.0], np.float32))
    assert ev.LABELS[int(np.argmax(oc[i:i + 12]))] == "full"
