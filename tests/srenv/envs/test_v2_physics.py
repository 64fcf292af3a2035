"""v2's per-well physics (srenv.task.v2_physics via sucker_rod_v2.physics_overrides): a beam unit of a drawn
geometry sized to the well, the stroke action on its crank, and Kelvin-Voigt damping with one damping ratio on
every well's fundamental."""

import math

import gymnasium as gym
import numpy as np
import pytest

import srenv  # noqa: F401
from srenv.config import load_config
from srenv.config_sections import BeamUnitConfig
from srenv.simulation.simulator import Simulator
from srenv.surface_unit.inline_unit import inline_unit, unit_for_stroke
from srenv.task import v2_physics as vp
from srenv.task import well_family as wf

ID = "srenv/SuckerRod-v2"
GEOMETRIES = [g for g, _ in vp.GEOMETRY_SHARES]


def _first_train_well(geometry: str) -> int:
    return next(k for k in range(wf.N_TRAIN) if vp.draw_geometry(wf.build_spec("train", k).params) == geometry)


def test_v2_well_config_carries_its_unit_and_tau_and_keeps_the_familys_damping():
    env = gym.make(ID, scenario="train", episode_hours=0.5).unwrapped
    _, info = env.reset(seed=5)
    spec = wf.build_spec("train", 5)
    assert info["well_id"] == spec.well_id == "train-005"  # the physics leaves the id alone
    cfg = env.cfg
    assert cfg.surface.motion == "beam_unit" and cfg.surface.beam_unit.crank_follows_stroke
    assert cfg.surface.beam_unit.geometry == vp.draw_geometry(spec.params)
    assert cfg.damping.stiffness_proportional_s == vp.kv_tau_s(spec) > 0.0
    # dotted keys: the family's viscous factor survives (a nested damping dict would have reset it)
    assert cfg.damping.damping_factor == spec.params.damping_factor
    assert cfg.damping.model == spec.cfg.damping.model


def test_the_same_well_gets_the_same_unit_in_every_episode_and_split():
    env = gym.make(ID, scenario="train", episode_hours=0.5).unwrapped
    env.reset(seed=7)
    first = env.cfg.surface.beam_unit
    env.reset(seed=7 + wf.N_TRAIN)  # another episode of the same well (seed mod N)
    assert env.cfg.surface.beam_unit == first
    val = gym.make(ID, scenario="validation", episode_hours=0.5).unwrapped
    val.reset(seed=3)
    assert val.cfg.surface.beam_unit == load_config(wf.build_spec("validation", 3).cfg,
                                                    vp.overrides(wf.build_spec("validation", 3))).surface.beam_unit
    fam = [gym.make(ID, scenario="family:4242", episode_hours=0.5).unwrapped for _ in range(2)]
    for e, seed in zip(fam, (0, 99)):
        e.reset(seed=seed)
    assert fam[0].cfg.surface.beam_unit == fam[1].cfg.surface.beam_unit
    assert fam[0].cfg.damping == fam[1].cfg.damping


def test_every_geometry_appears_over_the_train_split_at_its_share():
    drawn = [vp.draw_geometry(wf.draw_params(wf.well_seed("train", k))) for k in range(wf.N_TRAIN)]
    for geometry, share in vp.GEOMETRY_SHARES:
        n = drawn.count(geometry)
        sd = math.sqrt(wf.N_TRAIN * share * (1 - share))
        assert abs(n - wf.N_TRAIN * share) < 3.5 * sd, (geometry, n)


@pytest.mark.parametrize("geometry", GEOMETRIES)
def test_scaled_unit_strokes_the_wells_unit_stroke_and_its_crank_follows_the_request(geometry):
    spec = wf.build_spec("train", _first_train_well(geometry))
    block = BeamUnitConfig(**vp.unit_block(spec, geometry))
    assert block.geometry == geometry
    assert inline_unit(block).stroke_m == pytest.approx(spec.params.unit_stroke_m, abs=1e-5)
    for s in (spec.cfg.control.stroke_min_m, spec.cfg.surface.stroke_length_m):
        unit = unit_for_stroke(block, s)
        assert unit.stroke_m == pytest.approx(s, abs=1e-8) and unit.crank_radius_m < block.r_m
    cfg = load_config(spec.cfg, vp.overrides(spec))
    surface = Simulator(cfg).surface
    # the request up to the unit's stroke, capped there; applying it twice changes nothing (the runner does)
    assert surface.stroke_length_m(2.0 * spec.params.unit_stroke_m) == pytest.approx(spec.params.unit_stroke_m,
                                                                                    abs=1e-5)
    s = surface.stroke_length_m(spec.cfg.control.stroke_min_m)
    assert s == spec.cfg.control.stroke_min_m == surface.stroke_length_m(s)


def test_kv_tau_gives_every_well_the_same_damping_ratio_on_its_fundamental():
    specs = [wf.build_spec("train", k) for k in range(40)]
    zeta = [vp.kv_tau_s(s) * 2 * math.pi * s.design["n0_spm"] / 60.0 / 2 for s in specs]
    assert np.allclose(zeta, vp.KV_ZETA_1, rtol=2e-3)
    # so tau grows with the depth: the fixed 0.03 s of srenv validate sits inside the family's range
    depth = np.array([s.params.depth_m for s in specs])
    tau = np.array([vp.kv_tau_s(s) for s in specs])
    assert tau[depth.argmin()] < 0.015 and tau[depth.argmax()] > 0.045


@pytest.mark.parametrize("geometry", GEOMETRIES)
def test_a_v2_episode_runs_on_a_well_of_each_geometry(geometry):
    k = _first_train_well(geometry)
    env = gym.make(ID, scenario="train", episode_hours=1.0, event_rate_scale=0.0).unwrapped
    env.reset(seed=k)
    assert env.cfg.surface.beam_unit.geometry == geometry
    lo, hi = env.cfg.control.stroke_min_m, env.cfg.control.stroke_max_m
    strokes, spms = [], []
    for a in ([0.0, -1.0], [0.6, 1.0], [0.2, 0.0]):
        _, reward, term, _, info = env.step(np.array(a, np.float32))
        assert np.isfinite(reward) and not term, info.get("failure")
        strokes.append(env._stroke)
        spms.append(env._avg_spm)
        # a unit sized and balanced at the installed point: its gearbox is loaded, not overloaded
        assert 20.0 < env._last.summary["gearbox_loading_pct"] < 150.0
    assert strokes[0] == pytest.approx(lo, abs=1e-6) and strokes[1] == pytest.approx(hi, abs=1e-5)
    assert spms[1] > spms[2] > spms[0]  # the VSD still sets the rate


def test_installed_gearbox_loading_is_where_units_run():
    loads = []
    for k in range(12):
        spec = wf.build_spec("train", k)
        sim = Simulator(load_config(spec.cfg, vp.overrides(spec)))
        runs = [sim.run_stroke(record=True) for _ in range(3)]
        loads.append(sim.surface.gearbox_report(runs[1:]).loading_pct)
    assert 55.0 < float(np.median(loads)) < 90.0 and max(loads) < 130.0, loads


def test_a_well_given_by_its_config_and_the_callers_overrides_keep_their_physics():
    shipped = gym.make(ID, scenario="default", episode_hours=0.5).unwrapped
    shipped.reset(seed=0)  # a well given by its file keeps its own (harmonic, no Kelvin-Voigt) physics
    assert shipped.cfg.surface.motion == "harmonic" and shipped.cfg.damping.stiffness_proportional_s == 0.0
    env = gym.make(ID, scenario="train", episode_hours=0.5,
                   overrides={"surface.motion": "harmonic", "damping.stiffness_proportional_s": 0.0}).unwrapped
    env.reset(seed=5)
    assert env.cfg.surface.motion == "harmonic" and env.cfg.surface.beam_unit is None
    assert env.cfg.damping.stiffness_proportional_s == 0.0
    env = gym.make(ID, scenario="train", episode_hours=0.5, overrides={"damping.damping_factor": 0.05}).unwrapped
    env.reset(seed=5)
    assert env.cfg.surface.motion == "beam_unit" and env.cfg.damping.damping_factor == 0.05
    assert env.cfg.damping.stiffness_proportional_s == vp.kv_tau_s(wf.build_spec("train", 5))


@pytest.mark.parametrize("observation", ["field", "privileged"])
def test_v2_with_its_physics_passes_the_gymnasium_and_sb3_checkers(observation):
    import warnings

    from gymnasium.utils.env_checker import check_env
    from stable_baselines3.common.env_checker import check_env as sb3_check_env

    def make():
        return gym.make(ID, scenario="train", observation=observation, episode_hours=0.5).unwrapped

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        env = make()
        check_env(env, skip_render_check=True)
        sb3_check_env(make(), warn=True)
    assert env.cfg.surface.motion == "beam_unit"  # the checkers ran the per-well physics


def test_a_crank_that_follows_the_stroke_strokes_the_request_and_keeps_the_counterbalance_effect():
    base = load_config("mark_ii_fig4")
    fixed = Simulator(load_config("mark_ii_fig4", {"surface.stroke_length_m": 1.2}))
    follow = Simulator(load_config("mark_ii_fig4", {"surface.stroke_length_m": 1.2,
                                                    "surface.beam_unit.crank_follows_stroke": True}))
    full = fixed.run_stroke(record=True)
    assert np.ptp(full.trace["polished_rod_position_m"]) == pytest.approx(1.6248, abs=2e-3)  # the hole's, not 1.2
    runs = [follow.run_stroke(record=True) for _ in range(2)]
    assert np.ptp(runs[-1].trace["polished_rod_position_m"]) == pytest.approx(1.2, abs=2e-3)
    report = follow.surface.gearbox_report(runs[-1:])
    m = base.surface.beam_unit.counterbalance_moment_nm
    assert report.summary()["counterbalance_moment_nm"] == pytest.approx(m * 1.2 / full.stroke_length_m, rel=1e-6)
