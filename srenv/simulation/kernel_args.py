"""The kernel's arguments of a simulator's runs, their shared part kept from run to run (docs/speed.md §2f).

Every stroke at one setpoint and physics asks for the same constants, friction record, side-force arrays and
K* (``kernel_layout.shared``: ~25 record fields and five passes over the nodes, ~0.02 ms of a ~1.3 ms stroke);
a run's own arguments (state, valve record, progress, counters, output, a fresh K*) are built for every run
(``kernel_layout.for_run``). The shared part is built again when anything it is made of changed: the config,
the model's arrays (a condition's ``switch_config`` assembles new ones), the time step, the record flag or the
simulator's solver switches.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from ..numerics import kernel_layout as L

if TYPE_CHECKING:
    from .simulator import Simulator


class KernelArgs:
    """One simulator's kept :class:`~srenv.numerics.kernel_layout.Shared` and what it was built from."""

    def __init__(self) -> None:
        self._made_of: tuple = ()
        self._values: tuple = ()
        self._shared: L.Shared | None = None

    def stepper(self, sim: Simulator, dt: float, n_steps: int, record: bool) -> L.Stepper:
        """The arguments of a run of ``n_steps`` steps of ``dt`` from the simulator's state now."""
        s = sim.cfg.simulation
        made_of = (sim.cfg, sim._k, sim._m, sim._c, sim._f_all, sim._ea_len, sim.side_force)
        values = (dt, bool(record), sim.always_qp, sim.linear_reference, sim.p_pump_pa, sim.area_bottom_m2,
                  sim.p_top_pa, sim.area_top_m2)
        if (self._shared is None or values != self._values or len(made_of) != len(self._made_of)
                or any(a is not b for a, b in zip(made_of, self._made_of))):
            self._shared = L.shared(
                dt_s=dt, beta=s.newmark_beta, gamma=s.newmark_gamma, stiffness=sim._k, mass=sim._m,
                damping=sim._c, load_n=sim._f_all, ea_len_n_m=sim._ea_len, side=sim.side_force,
                rod_friction=sim._friction_record(), record=record, max_corrections=s.max_corrections,
                dc_max_iterations=s.dc_max_iterations, dc_tolerance_m_s=s.dc_tolerance_m_s,
                always_qp=sim.always_qp, nonsmooth=not sim.linear_reference,
                pump_pressure_force_n=sim.p_pump_pa * sim.area_bottom_m2,
                top_pressure_force_n=sim.p_top_pa * sim.area_top_m2, kv_tau_s=sim.cfg.damping.stiffness_proportional_s,
                damping_factors=(sim.cfg.damping.upstroke_factor, sim.cfg.damping.downstroke_factor))
            self._made_of, self._values = made_of, values
        state = L.State(sim.u, sim.v, sim.a, sim.uav, sim.status, sim.prev_lam, sim.prev_v, sim.prev_stuck)
        return L.for_run(self._shared, valve=sim._valve_record(), state=state, scratch=sim._work, energy=sim.energy,
                         n_steps=n_steps, plunger_dir=sim.pl_dir, ub_extremes_m=(sim._ub_max, sim._ub_min),
                         damping_now=sim._damp_s)
