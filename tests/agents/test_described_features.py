"""The described features (agents/policies/described_features.py, issue 24, helper d42): 13 scalars of the operator's
well file, each scaled by its declared range; the ranges hold every training and validation well of the v2 family, a
value outside reads as the nearest bound, a non-finite one is refused, a bad well file is refused in one line."""

from __future__ import annotations

import copy
import math

import gymnasium as gym
import numpy as np
import pytest

import agents.policies.described_features as df
import srenv  # noqa: F401
from srenv.task.well_file import well_file


@pytest.fixture(scope="module")
def files():
    """Every training and validation well's file, as ``well_file(env)`` hands it over (v2's per-well physics)."""
    out = {}
    for split, n in (("train", 200), ("validation", 50)):
        env = gym.make("srenv/SuckerRod-v2", scenario=split, observation="field")
        out.update({(split, i): well_file(env.unwrapped._split_well(i)) for i in range(n)})
        env.close()
    return out


def test_the_ranges_hold_every_training_and_validation_well(files):
    raw = np.array([[df.raw_features(f)[k] for k in df.FEATURES] for f in files.values()])
    lo, hi = np.array([v[:2] for v in df.FEATURES.values()]).T
    assert np.all(raw >= lo) and np.all(raw <= hi), [k for k, a, b in zip(df.FEATURES, raw.min(0), raw.max(0))]
    x = np.stack([df.features(f) for f in files.values()])
    assert x.dtype == np.float32 and x.shape == (250, len(df.FEATURES)) == (250, 13)
    assert np.allclose(x, (raw - lo) / (hi - lo), atol=1e-6)
    # they tell wells apart: no two wells alike, and the geometry takes its three codes
    assert len({tuple(np.round(r, 5)) for r in x}) == 250
    assert set(x[:, list(df.FEATURES).index("unit_geometry_code")]) == {0.0, 0.5, 1.0}


def test_the_physics_of_one_well(files):
    f = files[("train", 5)]
    r = df.raw_features(f)
    area = math.pi / 4 * (f["pump"]["plunger_diameter_mm"] * 1e-3) ** 2
    assert r["pump_depth_m"] == pytest.approx(sum(t["length_m"] for t in f["rod"]["tapers"]))
    assert r["plunger_diameter_m"] == pytest.approx(f["pump"]["plunger_diameter_mm"] / 1000)
    air = sum(7850 * 9.80665 * math.pi / 4 * (t["diameter_mm"] / 1000) ** 2 * t["length_m"] for t in f["rod"]["tapers"])
    rho = f["fluid"]["density_kg_m3"]
    assert r["rod_weight_buoyant_n"] == pytest.approx(air * (1 - rho / 7850), rel=2e-3)
    assert r["fluid_load_n"] == pytest.approx((rho * 9.80665 * r["pump_depth_m"] + 5e5) * area, rel=2e-2)  # ~TVD
    assert r["fluid_to_rod_weight_ratio"] == pytest.approx(r["fluid_load_n"] / r["rod_weight_buoyant_n"])
    assert r["pump_capacity_m3_s"] == pytest.approx(area * f["control"]["stroke_max_m"] * f["control"]["spm_max"] / 60)
    assert r["gearbox_torque_rating_nm"] == f["surface"]["beam_unit"]["torque_rating_nm"] > 0
    assert r["pprl_headroom_ratio"] == pytest.approx(f["economics"]["pprl_rating_n"] / (air + r["fluid_load_n"]),
                                                     rel=2e-3)
    harmonic = copy.deepcopy(f)
    harmonic["surface"].update(motion="harmonic", beam_unit=None)
    hr = df.raw_features(harmonic)
    assert hr["gearbox_torque_rating_nm"] == 0.0 and hr["unit_geometry_code"] == 0.0


@pytest.mark.parametrize("name", list(df.FEATURES))
def test_each_feature_is_scaled_by_its_declared_range_and_clipped(files, name, monkeypatch):
    lo, hi, _ = df.FEATURES[name]
    i = list(df.FEATURES).index(name)
    raw = df.raw_features(files[("train", 0)])
    for v, want in ((lo, 0.0), (hi, 1.0), (0.25 * lo + 0.75 * hi, 0.75), (lo - abs(hi - lo), 0.0),
                    (hi + 10 * abs(hi - lo), 1.0)):
        monkeypatch.setattr(df, "raw_features", lambda f, v=v: {**raw, name: v})
        assert df.features({})[i] == pytest.approx(want, abs=1e-6)
    for bad in (float("nan"), float("inf"), -float("inf")):
        monkeypatch.setattr(df, "raw_features", lambda f, bad=bad: {**raw, name: bad})
        with pytest.raises(ValueError, match=f"well file feature {name} = .*expected a finite number"):
            df.features({})


def test_a_bad_well_file_is_refused_in_one_line(files):
    good = files[("train", 0)]
    bad = []
    for mutate, field in ((lambda f: f.pop("pump"), "pump"),
                          (lambda f: f["pump"].update(secret=1), "pump.secret"),
                          (lambda f: f.update(inflow_reservoir={}), "inflow_reservoir"),
                          (lambda f: f["fluid"].update(density_kg_m3=-5.0), "density_kg_m3"),
                          (lambda f: f["control"].update(spm_max="fast"), "spm_max")):
        f = copy.deepcopy(good)
        mutate(f)
        bad.append((f, field))
    bad.append(([1, 2], "well file"))
    for f, field in bad:
        with pytest.raises(ValueError) as e:
            df.features(f)
        assert field in str(e.value) and "\n" not in str(e.value)


def test_the_acting_student_is_the_fitted_model_on_its_described_input(described_student):
    from agents.evaluation.agent import AgentPolicy, build_policy
    from agents.policies.residual import augment, bound_correction, compose

    base = {"threshold": 0.95, "idle_time_s": 1800, "a_spm": 0.1, "a_stroke": 0.0}
    res = {"base": "pump_off", "params": base, "scale": 0.5, "cap": {"spm_cap": 0.0}}
    spec = {"kind": "ensemble", "members": [described_student] * 2, "residual": res, "described": True}
    env = gym.make("srenv/SuckerRod-v2", scenario="validation", observation="field", episode_hours=1.0)
    policy = build_policy(spec, env)
    plain = build_policy({"kind": "baseline", "name": "pump_off", "params": base}, env)
    model = AgentPolicy(described_student["path"], described_student["obs_norm"])
    with pytest.raises(RuntimeError, match="reset"):
        policy.model.predict(np.zeros(91, np.float32))
    seen = []
    for seed in (3, 4):
        obs, _ = env.reset(seed=seed)
        policy.reset(env)
        extra = df.features(well_file(env))  # the played well's file, read once at reset
        seen.append(extra)
        for _ in range(3):
            a, _ = policy.predict(obs)
            b = np.asarray(plain.predict(obs)[0], np.float32)
            r = model.predict(np.concatenate([augment(obs, b), extra]), deterministic=True)[0]
            np.testing.assert_allclose(a, compose(b, bound_correction(r, res["cap"]), 0.5), atol=1e-6)
            obs = env.step(a)[0]
    assert not np.array_equal(*seen)  # another well, other features
    with pytest.raises(ValueError, match="described = 'yes': expected true or false"):
        build_policy({**spec, "described": "yes"}, env)
