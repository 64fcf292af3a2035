"""Start-up of the prescribed top: the top node's velocity and acceleration come from the motion.

Started at rest (a = 0) while the harmonic motion starts at -(S/2)w^2, the Newmark recursion of the top's
acceleration kept the error forever, alternating sign each step: a Nyquist sawtooth of ~17 N in the
polished-rod load of the fig3 well that did not shrink with dt.
"""

from __future__ import annotations

import numpy as np
import pytest

from srenv.analysis.stroke_summary import summarize
from srenv.config import load_config
from srenv.simulation.simulator import Simulator

FIG3 = "paper_fig3_vertical"


def nyquist_amplitude_n(load: np.ndarray) -> float:
    """Amplitude A of an A(-1)^k component of a per-step series, from its second difference (4A(-1)^k for
    the sawtooth; a smooth series leaves only its end slopes / N)."""
    d2 = load[2:] - 2 * load[1:-1] + load[:-2]
    return float(abs(np.mean((-1.0) ** np.arange(len(d2)) * d2)) / 4)


def test_no_nyquist_sawtooth_on_the_paper_well():
    sim = Simulator(load_config(FIG3))
    runs = sim.run_strokes(2)
    for r in runs:
        assert nyquist_amplitude_n(r.trace["polished_rod_load_n"]) < 0.1  # was 17.5 N


def test_no_sawtooth_when_the_spm_changes_between_strokes():
    sim = Simulator(load_config(FIG3))
    sim.run_stroke()
    r = sim.run_stroke(spm=8.0)  # the bottom acceleration jumps from -(S/2)w6^2 to -(S/2)w8^2
    assert nyquist_amplitude_n(r.trace["polished_rod_load_n"]) < 0.1  # ~14 N without the restart
    # the top's acceleration at the start of the stroke is the motion's (not the previous stroke's)
    sim2 = Simulator(load_config(FIG3))
    sim2.run_stroke()
    sim2.run_stroke(spm=8.0, record=False)
    omega = 2 * np.pi * 8.0 / 60.0
    assert sim2.uav[2] == pytest.approx(-1.2 * omega**2, rel=1e-3)


def test_conventional_unit_starts_from_its_own_acceleration():
    cfg = load_config(FIG3, ["surface.motion=conventional"])
    sim = Simulator(cfg)
    v0, a0 = sim.surface.stroke_start_state(6.0, sim.surface.stroke_length_m(2.4))
    assert abs(v0) < 1e-9 and a0 < 0  # at the bottom: at rest, accelerating upward (u positive down)
    r = sim.run_stroke()
    assert nyquist_amplitude_n(r.trace["polished_rod_load_n"]) < 0.1


def _smooth_case_prl(dt: float) -> np.ndarray:
    """A smooth problem (no valve law, no fluid: the static start is exact) with strong damping so that the
    start-up transient is gone by the second stroke; PRL of the second stroke on a 4 ms grid."""
    cfg = load_config(FIG3, [f"simulation.time_step_s={dt}", "fluid.density_kg_m3=0", "pump.downstroke_load_n=0",
                             "damping.damping_factor=0.5"])
    sim = Simulator(cfg, linear_reference=True)
    load = sim.run_strokes(2)[-1].trace["polished_rod_load_n"]
    k = round(0.004 / dt)
    return load[k - 1::k]


def test_polished_rod_load_converges_at_second_order_in_dt():
    prl = {dt: _smooth_case_prl(dt) for dt in (0.004, 0.002, 0.001, 0.0005)}
    ref = prl[0.0005]
    err = {dt: float(np.sqrt(np.mean((prl[dt] - ref) ** 2))) for dt in (0.004, 0.002, 0.001)}
    # second order: halving dt divides the error by ~4 (a little more against the finite reference)
    assert err[0.004] / err[0.002] > 3.5
    assert err[0.002] / err[0.001] > 3.5
    pprl = {dt: float(p.max()) for dt, p in prl.items()}
    d1, d2 = abs(pprl[0.004] - pprl[0.002]), abs(pprl[0.002] - pprl[0.001])
    assert d2 < d1 / 3
    assert err[0.004] < 0.01  # N: nothing of the 17 N sawtooth is left


def test_summary_has_last_stroke_peaks():
    sim = Simulator(load_config(FIG3))
    runs = sim.run_strokes(3)
    s = summarize(sim, runs)
    last = runs[-1].trace["polished_rod_load_n"]
    assert s["last_stroke_pprl_n"] == last.max() and s["last_stroke_mprl_n"] == last.min()
    allp = np.concatenate([r.trace["polished_rod_load_n"] for r in runs])
    assert s["pprl_n"] == allp.max() and s["mprl_n"] == allp.min()
