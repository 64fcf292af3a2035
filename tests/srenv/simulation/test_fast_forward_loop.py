"""The interval's fast-forward compiled (srenv/task/fast_forward.py, docs/speed.md §2e) books the annulus and the
interval's sums to the bit as the Python loop it replaced (kept for wells with free gas): whole intervals run both
ways on copies of one simulator, v1's and v2's runners, linear and Vogel inflow, a fillage drift that calls exact
strokes back, compared with ``==``."""

from __future__ import annotations

import copy
import dataclasses

import pytest

from srenv.config import load_config
from srenv.simulation.simulator import Simulator
from srenv.task import interval
from srenv.task import well_family as wf
from srenv.task.interval import IntervalRunner

SCALARS = [f.name for f in dataclasses.fields(interval.IntervalResult) if f.name not in ("last", "solver")]


def _run(sim: Simulator, compiled: bool, monkeypatch, draw_at_top: bool, setpoints, tol: float | None):
    monkeypatch.setattr(interval, "compiled_applies", lambda s: compiled and s.gas is None)
    runner = IntervalRunner(sim, reuse_periodic=draw_at_top, carry=draw_at_top, draw_at_top=draw_at_top)
    if tol is not None:
        runner.task = dataclasses.replace(runner.task, fast_forward_fillage_tol=tol)
    out = []
    for spm, stroke in setpoints:
        r = runner.run(spm, stroke, 300.0, exact_strokes_max=6)
        out.append(([getattr(r, k) for k in SCALARS], sim.time_s, sim.annulus.volume_m3, sim.annulus.last_time_s))
    return out


def _sim(index: int, model: str) -> Simulator:
    cfg = wf.build_spec("train", index).cfg
    if cfg.inflow.model != model:
        cfg = load_config(cfg, {"inflow.model": model})
    sim = Simulator(cfg)
    sim.reset(fluid_level_m=0.0)  # an empty annulus: the pump draws what flows in, its fillage drifts
    sim.run_stroke(cfg.surface.spm, cfg.surface.stroke_length_m, record=True)
    return sim


@pytest.mark.parametrize(("index", "model", "draw_at_top", "tol"), [
    (11, "vogel", True, None), (12, "linear", False, None), (3, "vogel", False, 0.02), (5, "linear", True, 0.02), (40, "linear", False, None)])
def test_compiled_fast_forward_is_the_python_loop_to_the_bit(monkeypatch, index, model, draw_at_top, tol) -> None:
    sim = _sim(index, model)
    spm = sim.cfg.control.spm_max  # faster than the inflow: the well pumps off
    setpoints = [(spm, sim.cfg.surface.stroke_length_m), (spm, sim.cfg.surface.stroke_length_m),
                 (0.5 * spm, sim.cfg.surface.stroke_length_m), (0.2, sim.cfg.surface.stroke_length_m)]
    fast = _run(copy.deepcopy(sim), True, monkeypatch, draw_at_top, setpoints, tol)
    slow = _run(copy.deepcopy(sim), False, monkeypatch, draw_at_top, setpoints, tol)
    assert fast == slow
    assert sum(row[0][SCALARS.index("fast_forward_strokes")] for row in fast) > 10  # the loop ran


def test_compiled_fast_forward_applies_to_the_envs_wells_and_not_to_gas() -> None:
    sim = _sim(11, "vogel")
    assert interval.compiled_applies(sim)
    sim.gas = object()  # a chamber: the pump's liquid share follows its law stroke by stroke, in Python
    assert not interval.compiled_applies(sim)


@pytest.mark.parametrize("index", [3, 11, 40])
def test_compiled_tvd_and_inflow_are_the_annulus_methods_to_the_bit(index: int) -> None:
    """Each depth and each volume the loop can meet: Survey.tvd_at and Annulus.inflow_m3_s (both models, a
    rate multiplier that is not 1) against their compiled forms, compared with ``==`` (the interval's
    comparison above meets a reassociated form's different rounding too rarely to pin it)."""
    import numpy as np

    from srenv.task import fast_forward as ff

    sim = _sim(index, "vogel")
    grid, z = sim.survey._tvd_table
    xs = np.r_[np.random.default_rng(index).uniform(-10.0, grid[-1] + 10.0, 4000), grid[:50], grid[-3:],
               -0.0, np.nan]
    got = [ff._tvd_at(grid, z, float(x)) for x in xs]
    want = [sim.survey.tvd_at(float(x)) for x in xs]
    assert all(g == w or (np.isnan(g) and np.isnan(w)) for g, w in zip(got, want))
    ann = sim.annulus
    for model, multiplier in (("vogel", 0.73), ("linear", 1.31), ("linear", 1.0)):
        ann.cfg = dataclasses.replace(ann.cfg, model=model, productivity_index_m3_day_pa=3.7e-6)
        ann.rate_multiplier = multiplier
        a = ff.annulus_params(ann)
        for v in np.r_[np.random.default_rng(1).uniform(0.0, 1.2 * ann._full_m3, 3000), 0.0, ann._full_m3]:
            ann.volume_m3 = float(v)
            assert ff._inflow_m3_s(float(v), a, grid, z) == ann.inflow_m3_s()
