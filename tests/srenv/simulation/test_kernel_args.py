"""The kernel's arguments with their shared part kept between runs (srenv.simulation.kernel_args, docs/speed.md
§2f): every run's results are those of arguments built afresh for it (the builder as it was, copied here), bit
for bit, through QP steps, gas, an unanchored tubing, damping per direction, a condition that switches the
config and a solver switch changed between runs; and a simulator built at a fluid level is the simulator built
and then reset to it."""

from __future__ import annotations

import numpy as np
import pytest

from srenv.config import load_config
from srenv.numerics import kernel_layout as L
from srenv.simulation.simulator import Simulator

CASES = {
    "fig4": ("paper_fig4_deviated", []),
    "fig4_qp": ("paper_fig4_deviated", ["simulation.max_corrections=0"]),
    "gas": ("default", ["inflow.model=none", "pump.intake_gas_fraction=0.2"]),
    "tubing": ("paper_fig3_vertical", ["tubing.anchored=false"]),
    "split": ("paper_fig3_vertical", ["damping.upstroke_factor=3", "damping.downstroke_factor=0.5"]),
    "pound": ("default", ["inflow.max_rate_m3_day=8", "inflow.initial_fluid_level_m=1", "surface.spm=9"]),
}


def _fresh_stepper(self: Simulator, dt: float, n_steps: int, record: bool) -> L.Stepper:
    """Simulator._stepper before the shared part was kept: every argument built for the run."""
    s = self.cfg.simulation
    state = L.State(self.u, self.v, self.a, self.uav, self.status, self.prev_lam, self.prev_v, self.prev_stuck)
    return L.build(
        dt_s=dt, beta=s.newmark_beta, gamma=s.newmark_gamma, stiffness=self._k, mass=self._m,
        damping=self._c, load_n=self._f_all, ea_len_n_m=self._ea_len, side=self.side_force,
        rod_friction=self._friction_record(), valve=self._valve_record(), state=state, scratch=self._work,
        energy=self.energy, n_steps=n_steps, record=record, max_corrections=s.max_corrections,
        dc_max_iterations=s.dc_max_iterations, dc_tolerance_m_s=s.dc_tolerance_m_s,
        always_qp=self.always_qp, nonsmooth=not self.linear_reference,
        pump_pressure_force_n=self.p_pump_pa * self.area_bottom_m2,
        top_pressure_force_n=self.p_top_pa * self.area_top_m2, plunger_dir=self.pl_dir,
        ub_extremes_m=(self._ub_max, self._ub_min), kv_tau_s=self.cfg.damping.stiffness_proportional_s,
        damping_factors=(self.cfg.damping.upstroke_factor, self.cfg.damping.downstroke_factor),
        damping_now=self._damp_s)


def _runs(sim: Simulator) -> list:
    """Recorded and unrecorded strokes at two SPMs and a pull-out stretch: the shared part is kept, then built
    again for another step count, record flag and time step."""
    out = [sim.run_stroke(record=True), sim.run_stroke(record=True), sim.run_stroke(record=False)]
    spm = sim.cfg.surface.spm
    out.append(sim.run_stroke(spm * 0.8, record=True))
    out.append(sim.run_velocity(np.full(40, -0.1), 0.004, record=True))
    out.append(sim.run_stroke(spm, record=True))
    return out


def _same(a, b) -> None:
    for x, y in zip(a, b, strict=True):
        assert (x.n_steps, x.certified_steps, x.corrected_steps, x.qp_steps, x.qp_calls, x.dc_iterations) == \
            (y.n_steps, y.certified_steps, y.corrected_steps, y.qp_steps, y.qp_calls, y.dc_iterations)
        assert x.fillage == y.fillage and x.pumped_m3 == y.pumped_m3 and x.energy_j == y.energy_j
        for name in ("element_force_max_eq_n", "element_force_min_eq_n", "rod_stick_episodes"):
            np.testing.assert_array_equal(getattr(x, name), getattr(y, name))
        assert (x.trace is None) == (y.trace is None)
        if x.trace is not None:
            assert x.trace.keys() == y.trace.keys()
            for k in x.trace:
                np.testing.assert_array_equal(x.trace[k], y.trace[k])
        assert len(x.events) == len(y.events)


@pytest.mark.parametrize("case", sorted(CASES))
def test_kept_arguments_give_the_fresh_arguments_results(case: str, monkeypatch) -> None:
    name, over = CASES[case]
    kept = Simulator(load_config(name, over))
    runs = _runs(kept)
    with monkeypatch.context() as m:
        m.setattr(Simulator, "_stepper", _fresh_stepper)
        fresh = Simulator(load_config(name, over))
        ref = _runs(fresh)
    _same(runs, ref)
    for a, b in ((kept.u, fresh.u), (kept.v, fresh.v), (kept.a, fresh.a), (kept.energy, fresh.energy)):
        np.testing.assert_array_equal(a, b)
    if case == "fig4_qp":
        assert sum(r.qp_steps for r in ref) > 0  # the QP path was taken


def test_a_switched_config_and_a_solver_switch_rebuild_the_shared_part(monkeypatch) -> None:
    """A condition swaps the config between strokes (switch_config assembles new arrays) and a caller turns the
    linear reference on: the kept part must follow both, as arguments built afresh do."""
    base = load_config("default", ["inflow.model=none"])
    other = load_config("default", ["inflow.model=none", "friction.coefficient=0.3"])

    def story(sim: Simulator) -> list:
        out = [sim.run_stroke(), sim.run_stroke()]
        sim.switch_config(other)
        out += [sim.run_stroke()]
        sim.linear_reference = True
        out += [sim.run_stroke()]
        sim.linear_reference = False
        sim.switch_config(base)
        out += [sim.run_stroke()]
        return out

    kept = story(Simulator(base))
    with monkeypatch.context() as m:
        m.setattr(Simulator, "_stepper", _fresh_stepper)
        ref = story(Simulator(base))
    _same(kept, ref)
    assert not np.array_equal(kept[1].trace["polished_rod_load_n"], kept[2].trace["polished_rod_load_n"])


def test_the_shared_part_is_kept_at_one_setpoint() -> None:
    sim = Simulator(load_config("paper_fig4_deviated"))
    sim.run_stroke()
    shared = sim._kernel_args._shared
    sim.run_stroke()
    assert sim._kernel_args._shared is shared
    sim.run_stroke(record=False)
    assert sim._kernel_args._shared is not shared


def test_a_simulator_built_at_a_level_is_the_simulator_reset_to_it() -> None:
    cfg = load_config("default")
    a = Simulator(cfg, fluid_level_m=321.0)
    b = Simulator(cfg)
    b.reset(fluid_level_m=321.0)
    for name in ("u", "v", "a", "uav", "energy", "prev_lam"):
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name))
    assert a.annulus.level_m == b.annulus.level_m == pytest.approx(321.0)
    assert (a.void, a.void_until, a.e0, a.fillage) == (b.void, b.void_until, b.e0, b.fillage)
    _same([a.run_stroke(), a.run_stroke()], [b.run_stroke(), b.run_stroke()])


def test_each_run_gets_its_own_kstar() -> None:
    """The kernel adds the gas spring and the direction's damping to K*'s diagonal in place: a run's K* must
    not be the kept one, or the next run would start from what this one left."""
    sim = Simulator(load_config("paper_fig3_vertical", ["damping.upstroke_factor=3", "damping.downstroke_factor=0.5"]))
    a = sim._stepper(0.005, 10, True)
    a.model.ksd[:] += 1.0
    b = sim._stepper(0.005, 10, True)
    assert a.model.ksd is not b.model.ksd and a.model.kso is not b.model.kso
    np.testing.assert_array_equal(b.model.ksd + 1.0, a.model.ksd)
    sim._damp_s = 3.0  # a run that ended on an upstroke: K* of that factor, kept apart from factor 1's
    c = sim._stepper(0.005, 10, True)
    assert not np.array_equal(c.model.ksd, b.model.ksd)
    np.testing.assert_array_equal(c.model.ksd, L.build(
        dt_s=0.005, beta=sim.cfg.simulation.newmark_beta, gamma=sim.cfg.simulation.newmark_gamma,
        stiffness=sim._k, mass=sim._m, damping=sim._c, load_n=sim._f_all, ea_len_n_m=sim._ea_len,
        side=sim.side_force, rod_friction=sim._friction_record(), valve=sim._valve_record(),
        state=c.state, scratch=sim._work, energy=sim.energy, n_steps=10, record=True, max_corrections=1,
        dc_max_iterations=1, dc_tolerance_m_s=1.0, damping_factors=(3.0, 0.5), damping_now=3.0).model.ksd)
