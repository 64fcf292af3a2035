"""Gas the travelling valve leaves in the clearance (issue 27, pump.clearance_gas_fraction): kept at p_d at the
bottom of the stroke, it re-expands on every upstroke before the standing valve opens, so the upstroke's load
transfer takes a plunger travel while the downstroke's (the fillage's gas) stays as it was."""

from __future__ import annotations

import pytest

from srenv.analysis.field_model import _qp_solver
from srenv.analysis.transfer_reading import clearance_gas_fraction, transfer_travel_m
from srenv.config import load_config
from srenv.errors import ConfigError
from srenv.physics.laws.gas_spring import expel_keeping
from srenv.simulation.simulator import Simulator


def _stroke(psi: float):
    """The fourth stroke's transfer travels, and the chamber's gas at p_d at its start (the bottom)."""
    cfg = load_config("default", ["inflow.model=none", f"simulation.qp_solver={_qp_solver()}", "pump.fillage=0.8",
                                  "pump.plunger_friction_n=0", f"pump.clearance_gas_fraction={psi}"])
    sim = Simulator(cfg)
    sim.run_strokes(3)
    gas_m3, p0 = float(sim._gas[2]), float(sim._gas[3])
    res = sim.run_stroke()
    tr = res.trace
    return sim, res, transfer_travel_m(tr["pump_position_m"], tr["pump_load_n"]), gas_m3, p0


def test_the_clearance_gas_lengthens_the_upstroke_transfer_and_keeps_the_downstroke():
    """With psi of the clearance kept as gas at p_d (plus the mixed remainder's little gas) the upstroke's
    10-90 % transfer is the isothermal re-expansion V_g ((p_d / p_90) - (p_d / p_10)) / A_pl (friction 0: the
    load's shares are the chamber pressure's); the reading rule gives the clearance's gas share back; the
    downstroke's transfer (the fillage's gas) moves < 5 %, and so does the fillage."""
    _, res0, t0, _, _ = _stroke(0.0)
    assert t0["up"] < 1e-3
    for psi in (0.1, 0.2):
        sim, res, t, gas_m3, p0 = _stroke(psi)
        a, clear_m = sim.gas.area_m2, sim.gas.clearance_m3 / sim.gas.area_m2
        p_in, p_d = sim.cfg.pump.intake_pressure_pa, sim.p_pump_pa + sim.cfg.pump.discharge_overpressure_pa
        assert p0 == p_d and psi * clear_m * a <= gas_m3 < 1.2 * psi * clear_m * a  # kept + the remainder's
        dp = p_d - p_in
        expected = gas_m3 / a * (p_d / (p_in + 0.1 * dp) - p_d / (p_d - 0.1 * dp))
        assert t["up"] == pytest.approx(expected, rel=0.03)
        read = clearance_gas_fraction(t["up"], p_in, p_d, clear_m)
        assert read == pytest.approx(gas_m3 / (clear_m * a), rel=0.03)
        assert t["down"] == pytest.approx(t0["down"], rel=0.05)
        assert res.fillage == pytest.approx(res0.fillage, rel=0.05)
        assert abs(sim.energy_balance()["residual_j"]) < 1e-6


def test_expel_keeping_keeps_the_gas_then_lets_it_go():
    """keep 0 is the mixed outflow; a kept volume stays while liquid and free gas leave; past them it goes too."""
    g, liq = expel_keeping(0.0, 1.0, 3.0, 2.0)
    assert (g, liq) == pytest.approx((0.5, 1.5))
    g, liq = expel_keeping(0.6, 1.0, 3.0, 2.0)  # free gas 0.4 of a 3.4 mixture
    assert g == pytest.approx(0.6 + 0.4 * (1 - 2.0 / 3.4)) and liq == pytest.approx(3.0 * (1 - 2.0 / 3.4))
    assert expel_keeping(0.6, 1.0, 3.0, 3.7) == pytest.approx((0.3, 0.0))


def test_clearance_gas_needs_free_gas_and_a_share():
    with pytest.raises(ConfigError, match="pump.clearance_gas_fraction"):
        load_config("default", ["pump.clearance_gas_fraction=0.1"])
    with pytest.raises(ConfigError, match="pump.clearance_gas_fraction"):
        load_config("default", ["pump.fillage=0.8", "pump.clearance_gas_fraction=1.5"])
    assert clearance_gas_fraction(0.0, 1e6, 1e7, 0.1) == 0.0
