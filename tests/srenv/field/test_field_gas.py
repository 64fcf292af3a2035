"""Gas interference: free gas in the pump chamber delays the travelling valve on the downstroke by the
plunger travel that compresses it to the discharge pressure (ideal gas, polytropic)."""

from __future__ import annotations

import numpy as np
import pytest

from srenv.analysis.pump_card import analyse_pump_card
from srenv.analysis.stroke_summary import summarize
from srenv.config import ConfigError, load_config
from srenv.simulation.simulator import Simulator

BASE = ["inflow.model=none"]  # the default well's 1.75 in pump at a fixed 1 MPa intake pressure


def _downstroke(x: np.ndarray, f: np.ndarray):
    i_top = int(np.argmax(x))
    xr, fr = np.roll(x, -i_top), np.roll(f, -i_top)
    i_bot = int(np.argmin(xr))
    return xr[: i_bot + 1], fr[: i_bot + 1]


def _travel_to(xd, fd, level) -> float:
    """Plunger travel from the top until the load first falls to `level`."""
    j = int(np.flatnonzero(fd <= level)[0])
    return float(xd[0] - xd[j])


def _gas_run(phi: float, *extra: str):
    cfg = load_config("default", [*BASE, f"pump.intake_gas_fraction={phi}", *extra])
    sim = Simulator(cfg)
    runs = sim.run_strokes(3)
    return cfg, sim, runs[-1]


def _transfer(phi: float, *extra: str) -> tuple[float, float, float, float, str]:
    """(measured travel to 98 % of the transfer, its ideal-gas estimate, travel to the middle, estimate, class)"""
    cfg, sim, r = _gas_run(phi, *extra)
    x, f = r.trace["pump_position_m"], r.trace["pump_load_n"]
    card = analyse_pump_card(x, f)
    xd, fd = _downstroke(x, f)
    lo, fl = card["downstroke_load_n"], card["fluid_load_n"]
    p_in, p_d = cfg.pump.intake_pressure_pa, sim.p_pump_pa + cfg.pump.discharge_overpressure_pa
    upstroke = float(np.ptp(x))
    if sim.gas is None:
        est_end = est_mid = 0.0
    else:
        est_end = sim.gas.compression_travel_m(p_in, p_d, upstroke)
        est_mid = sim.gas.compression_travel_m(p_in, p_d, upstroke, 0.5 * (p_in + p_d))
    return _travel_to(xd, fd, lo + 0.02 * fl), est_end, _travel_to(xd, fd, lo + 0.5 * fl), est_mid, \
        summarize(sim, [r])["card_class"]


def test_transfer_interval_grows_with_gas_and_matches_the_ideal_gas_estimate():
    ends = []
    for phi in (0.05, 0.2, 0.4):
        end, est_end, mid, est_mid, _ = _transfer(phi)
        assert end == pytest.approx(est_end, rel=0.03), phi
        assert mid == pytest.approx(est_mid, rel=0.05), phi
        ends.append(end)
    assert ends[0] < ends[1] < ends[2]


def test_no_gas_no_transfer_interval():
    end, est_end, mid, _, cls = _transfer(0.0)
    assert est_end == 0.0 and end < 0.002 and mid < 0.002
    assert cls == "full"


def test_adiabatic_compression_is_shorter_than_isothermal():
    iso, est_iso, *_ = _transfer(0.3)
    adi, est_adi, *_ = _transfer(0.3, "pump.gas_polytropic_exponent=1.3")
    assert adi == pytest.approx(est_adi, rel=0.03)
    assert adi < 0.95 * iso  # 1 - (p_in/p_d)^(1/k): 0.80 against 0.88 at p_d / p_in = 8.3
    assert adi / iso == pytest.approx(est_adi / est_iso, rel=0.02)


def test_glr_gives_the_same_card_as_its_gas_fraction():
    # G = GLR p_std / p_in; phi = G / (1 + G): at 1 MPa, GLR 2.5 -> phi = 0.2021
    *_, r1 = _gas_run(0.0, "pump.intake_gas_fraction=0", "pump.intake_glr_m3_m3=2.5")
    g = 2.5 * 101325.0 / 1.0e6
    _, _, r2 = _gas_run(g / (1 + g))
    assert np.max(np.abs(r1.trace["pump_load_n"] - r2.trace["pump_load_n"])) < 1e-6 * 1e4


def test_gas_card_class_and_liquid_fraction():
    _, _, _, _, cls = _transfer(0.4)
    assert cls == "gas_interference"
    _cfg, sim, r = _gas_run(0.4)
    # the gas takes its share of the displacement: fillage ~ 1 - phi (less what the clearance re-expands)
    assert 0.5 < r.fillage < 0.62
    s = summarize(sim, [r])
    assert s["card_class"] == "gas_interference" and s["card_fillage"] < 0.75


def test_gas_needs_pressures():
    with pytest.raises(ConfigError, match="pump.load_source"):
        load_config("paper_fig3_vertical", ["pump.intake_gas_fraction=0.2"])
    with pytest.raises(ConfigError, match="pump.intake_glr_m3_m3"):
        load_config("default", ["pump.intake_gas_fraction=0.2", "pump.intake_glr_m3_m3=10"])
