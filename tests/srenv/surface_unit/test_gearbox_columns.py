"""A well's gearbox report of one stroke with its setpoint's columns kept (gearbox.stroke_columns, docs/speed.md
§2f): the same report and summary as the columns computed for the stroke, on the three unit geometries; the kept
columns are read-only and follow the setpoint; the summary's figures are its report's properties."""

from __future__ import annotations

import numpy as np
import pytest

from srenv.config import load_config
from srenv.simulation.simulator import Simulator
from srenv.surface_unit import gearbox as G
from srenv.surface_unit.inline_unit import counterbalance
from srenv.task import v2_physics
from srenv.task import well_family as wf

ARRAYS = ("crank_angle_rad", "net_torque_nm", "polished_rod_power_w", "crank_power_w", "time_step_s")


def _sim(geometry: str) -> Simulator:
    spec = wf.build_spec("train", 11)
    over = {"surface.motion": "beam_unit", "surface.beam_unit": v2_physics.unit_block(spec, geometry)}
    return Simulator(load_config(spec.cfg, over))


def _plain(sim: Simulator, r) -> G.GearboxReport:
    """SurfaceMotion.gearbox_report without the kept columns."""
    surface = sim.surface
    unit = surface.unit_for(r.stroke_length_m)
    moment, offset = counterbalance(surface.cfg.beam_unit)
    if not unit.air_balanced:
        moment *= unit.stroke_m / surface.unit.stroke_m
    return G.analyse_runs(unit, [r], counterbalance_moment_nm=moment, counterbalance_offset_rad=offset,
                          motor_efficiency=surface.cfg.motor_efficiency)


def _equal(a: G.GearboxReport, b: G.GearboxReport) -> None:
    for name in ARRAYS:
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name))
    assert a.optimal_counterbalance_nm == b.optimal_counterbalance_nm
    assert list(a.summary().items()) == list(b.summary().items())


@pytest.mark.parametrize("geometry", ["conventional", "mark_ii", "air_balanced"])
def test_kept_columns_give_the_computed_report(geometry: str) -> None:
    sim = _sim(geometry)
    spm0 = sim.cfg.surface.spm
    for spm, stroke in ((spm0, 1.2), (spm0, 1.2), (6.0, 1.0), (spm0, 1.2)):
        r = sim.run_stroke(spm, stroke, record=True)
        kept = sim.surface.gearbox_report([r])
        _equal(kept, _plain(sim, r))
    assert len(sim.surface._columns) == 2  # two setpoints
    cols = next(iter(sim.surface._columns.values()))
    with pytest.raises(ValueError):
        cols.theta[0] = 0.0  # shared by every report of the setpoint


def test_the_summary_is_the_reports_properties() -> None:
    sim = _sim("conventional")
    rep = sim.surface.gearbox_report([sim.run_stroke(record=True)])
    m = rep.summary()
    assert m["peak_gearbox_torque_nm"] == rep.peak_torque_nm
    assert m["gearbox_loading_pct"] == rep.loading_pct
    assert m["polished_rod_power_w"] == rep.mean_polished_rod_power_w
    assert m["motor_power_w"] == rep.motor_power_w
    assert m["optimal_counterbalance_nm"] == rep.optimal_counterbalance_nm > 0


def test_two_strokes_in_one_report_keep_nothing() -> None:
    """The columns are kept for a single stroke at constant speed; two strokes are concatenated as before."""
    sim = _sim("mark_ii")
    runs = [sim.run_stroke(record=True), sim.run_stroke(record=True)]
    rep = sim.surface.gearbox_report(runs)
    assert rep.net_torque_nm.size == sum(r.n_steps for r in runs)
    assert not sim.surface._columns


@pytest.mark.parametrize("geometry", ["conventional", "air_balanced"])
def test_a_deferred_summary_completes_to_the_full_one(geometry: str) -> None:
    """stroke_figures(defer=True) leaves the optimal counterbalance and the powers None, in their places;
    completed() gives the summary of stroke_figures without defer, key for key and in order."""
    from srenv.task.interval import IntervalRunner, completed

    sim = _sim(geometry)
    runner = IntervalRunner(sim)
    r = sim.run_stroke(record=True)
    full = runner._figures(r)
    later = runner._figures(r, defer=True)
    assert full.gearbox is None and later.gearbox is not None
    lazy = [k for k, v in later.summary.items() if v is None]
    key = "optimal_counterbalance_force_n" if geometry == "air_balanced" else "optimal_counterbalance_nm"
    assert sorted(lazy) == sorted([key, "polished_rod_power_w", "motor_power_w"])
    assert list(later.summary) == list(full.summary)
    assert completed(later) is later and later.gearbox is None
    assert list(later.summary.items()) == list(full.summary.items())
    assert sim.surface._deferring is None  # the surface reports in full again


def test_an_intervals_last_stroke_is_complete() -> None:
    """Every exact stroke of an interval is summarised with its gearbox figures deferred; the one the interval
    keeps (its last, the env's observation and the reused stroke) is completed."""
    from srenv.task.interval import IntervalRunner

    sim = _sim("mark_ii")
    runner = IntervalRunner(sim, reuse_periodic=True, carry=True, draw_at_top=True)
    for avg, stroke in ((sim.cfg.surface.spm, 1.2), (sim.cfg.surface.spm, 1.2), (5.0, 1.0)):
        res = runner.run(avg, stroke, 300.0)
        assert res.exact_strokes >= 1 or res.last is not None
        assert res.last.gearbox is None
        assert all(v is not None for v in res.last.summary.values())
    for f, _, _ in runner._periodic.values():
        assert f.gearbox is None and all(v is not None for v in f.summary.values())
