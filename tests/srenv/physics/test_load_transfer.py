"""The gradual load transfer at the pump's valves (issue 27, pump.liquid_compressibility_per_pa): the chamber's
liquid (with its free gas, and the tubing when unanchored) is a spring in series with the valve law, so the
fluid load moves between tubing and rods over a plunger travel (fluid load) / k instead of at once."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest

from srenv.analysis.field_model import _qp_solver
from srenv.config import load_config
from srenv.errors import ConfigError
from srenv.physics.laws import gas_spring
from srenv.physics.laws import valve as valve_record
from srenv.physics.pump import ValveLaw, liquid_stiffness_n_m, plunger_area_m2, series_stiffness_n_m
from srenv.simulation.simulator import Simulator


def _last_stroke(extra: list[str]):
    cfg = load_config("default", ["inflow.model=none", f"simulation.qp_solver={_qp_solver()}", *extra])
    sim = Simulator(cfg)
    return cfg, sim, sim.run_strokes(3)[-1].trace


def _transfer(trace) -> tuple[float, float]:
    """(fluid load moved, slope dF/du_B while it moves) of the pump card's upstroke transfer (loads strictly
    inside the range, before the load first reaches the top of it; the stroke starts at the bottom)."""
    f, u = trace["pump_load_n"], trace["pump_position_m"]
    lo, hi = f.min(), f.max()
    before_top = np.arange(len(f)) < np.argmax(f > hi - 0.05 * (hi - lo))
    inside = (f > lo + 0.1 * (hi - lo)) & (f < hi - 0.1 * (hi - lo)) & before_top
    return hi - lo, abs(np.polyfit(u[inside], f[inside], 1)[0])


def _transfers(trace) -> list[tuple[float, float]]:
    """(plunger position, slope dF/du_B) of each stretch of the pump card strictly inside its load range:
    the upstroke's transfer at the bottom and the downstroke's at the top."""
    f, u = trace["pump_load_n"], trace["pump_position_m"]
    lo, hi = f.min(), f.max()
    idx = np.flatnonzero((f > lo + 0.02 * (hi - lo)) & (f < hi - 0.02 * (hi - lo)))
    runs = [r for r in np.split(idx, np.flatnonzero(np.diff(idx) > 1) + 1) if len(r) >= 3]
    return [(float(u[r].mean()), abs(np.polyfit(u[r], f[r], 1)[0])) for r in runs]


def test_transfer_travel_grows_with_compliance_and_fluid_load():
    """No gas: the liquid-full chamber is the spring A^2 / (c V), V the clearance at the bottom (the upstroke's
    transfer) and clearance + swept at the top (the downstroke's); the pump card's transfers follow them
    exactly, so the travel (fluid load) / k doubles with c and grows with the fluid load (a lower intake)."""
    travel = {}
    for c, p_in in ((2.5e-9, 1e6), (5e-9, 1e6), (5e-9, 3e6)):
        cfg, sim, trace = _last_stroke([f"pump.liquid_compressibility_per_pa={c}", f"pump.intake_pressure_pa={p_in}"])
        a, stroke, clear = plunger_area_m2(cfg.pump), cfg.surface.stroke_length_m, cfg.pump.clearance_volume_fraction
        k_up, k_down = a / (c * clear * stroke), a / (c * (1 + clear) * stroke)
        assert sim.tubing_stiffness_n_m == pytest.approx(k_up, rel=1e-12)
        assert sim.tubing_top_stiffness_n_m == pytest.approx(k_down, rel=1e-12)
        (x_up, s_up), (x_down, s_down) = _transfers(trace)
        assert x_up < x_down  # the first at the bottom (positions positive down: the top's u_B is larger)
        assert s_up == pytest.approx(k_up, rel=1e-3) and s_down == pytest.approx(k_down, rel=1e-3)
        load, slope = _transfer(trace)
        travel[c, p_in] = load / slope
        assert abs(sim.energy_balance()["residual_j"]) < 1e-6
    assert travel[5e-9, 1e6] == pytest.approx(2 * travel[2.5e-9, 1e6], rel=1e-3)
    assert travel[5e-9, 1e6] > 1.2 * travel[5e-9, 3e6]


def test_each_transfer_compresses_its_own_chamber_volume():
    """The upstroke's transfer decompresses the clearance's liquid alone from p_d to p_in, V_d c dp / A_pl; the
    downstroke's compresses the top's chamber, (V_d + V_swept) c dp / A_pl (plunger friction and the
    travelling valve's loss 0, so the load step is dp A_pl exactly). The earlier law (``top_of_stroke``)
    gave both the top's travel: it fails the first equality by a factor (1 + V_swept / V_d) = 21."""
    c = 5e-9
    for law in ("per_transfer", "top_of_stroke"):
        cfg, sim, trace = _last_stroke([f"pump.liquid_compressibility_per_pa={c}", "pump.plunger_friction_n=0",
                                        "pump.discharge_overpressure_pa=0", f"pump.liquid_chamber_volume={law}"])
        a, swept = plunger_area_m2(cfg.pump), plunger_area_m2(cfg.pump) * cfg.surface.stroke_length_m
        dp = sim.p_pump_pa - cfg.pump.intake_pressure_pa
        load = trace["pump_load_n"].max() - trace["pump_load_n"].min()
        assert load == pytest.approx(dp * a, rel=1e-9)
        (_, k_up), (_, k_down) = _transfers(trace)
        clear = cfg.pump.clearance_volume_fraction * swept
        assert load / k_down == pytest.approx((clear + swept) * c * dp / a, rel=1e-3)
        if law == "per_transfer":
            assert load / k_up == pytest.approx(clear * c * dp / a, rel=1e-3)
        else:
            assert load / k_up == pytest.approx((clear + swept) * c * dp / a, rel=1e-3)
    with pytest.raises(ConfigError, match="pump.clearance_volume_fraction"):
        load_config("default", ["pump.liquid_compressibility_per_pa=1e-9", "pump.clearance_volume_fraction=0",
                                "pump.load_source=pressures"])


def test_zero_compressibility_is_the_rigid_law_and_series_with_tubing():
    """c = 0 is today's rigid valve law (the same card bit for bit); the liquid and unanchored tubing are two
    springs in series; the field is refused out of range and with the nonmonotone law."""
    _, _, t0 = _last_stroke([])
    _, sim, t1 = _last_stroke(["pump.liquid_compressibility_per_pa=0"])
    assert sim.tubing_stiffness_n_m == 0.0
    assert np.array_equal(t0["polished_rod_load_n"], t1["polished_rod_load_n"])
    assert np.array_equal(t0["pump_load_n"], t1["pump_load_n"])
    assert series_stiffness_n_m(2.0, 2.0) == 1.0 and series_stiffness_n_m(0.0, math.inf) == 0.0
    assert series_stiffness_n_m(3.0, math.inf) == 3.0
    cfg = load_config("default", ["inflow.model=none", "pump.liquid_compressibility_per_pa=1e-9"])
    assert liquid_stiffness_n_m(cfg.pump, 2.0) == pytest.approx(plunger_area_m2(cfg.pump) / (1e-9 * 1.05 * 2.0))
    with pytest.raises(ConfigError, match="pump.liquid_compressibility_per_pa"):
        load_config("default", ["pump.liquid_compressibility_per_pa=-1e-9"])
    with pytest.raises(ConfigError, match="pump.liquid_compressibility_per_pa"):
        load_config("default", ["pump.liquid_compressibility_per_pa=1e-9", "pump.load_source=loads",
                                "pump.law=nonmonotone"])


def _chamber(gas_m3: float, liquid_m3: float, c: float) -> np.ndarray:
    p = valve_record.make(ValveLaw(1e4, -1e3))
    p["gas_mode"], p["u0_m"], p["gas_m3"], p["p0"], p["liquid_m3"] = 1, 0.0, gas_m3, 1e6, liquid_m3
    p["k"], p["area_m2"], p["p_in_pa"], p["p_d_pa"], p["p_out_pa"] = 1.0, 1.5e-3, 1e6, 15e6, 15e6
    p["liq_c"] = c
    return p


def test_gas_and_liquid_in_series_in_the_chamber():
    """Free gas and compressible liquid: the chamber pressure solves A (u - u0) = gas squeeze + V_l c dp; the
    stiffness is the two in series (the finite difference of the force), below the gas alone's and the
    liquid alone's; a liquid-full chamber is the linear spring A^2 / (V_l c)."""
    a, vl, c = 1.5e-3, 2e-3, 5e-10
    p = _chamber(1e-4, vl, c)
    gas_only = _chamber(1e-4, vl, 0.0)
    for u in (0.02, 0.05, 0.06):
        f, k = gas_spring.spring(p, u)
        pc = f / a + 15e6
        assert gas_spring.squeeze_m3(p, pc) == pytest.approx(a * u, rel=1e-9)
        df = (gas_spring.spring(p, u + 1e-7)[0] - gas_spring.spring(p, u - 1e-7)[0]) / 2e-7
        assert k == pytest.approx(df, rel=1e-4)
        k_gas = a * a * pc / (1e-4 * 1e6 / pc)  # the gas alone at the same pressure: A^2 k p / V_g
        assert 1 / k == pytest.approx(1 / k_gas + vl * c / a ** 2, rel=1e-9)
        assert gas_spring.spring(gas_only, u)[0] >= f  # the liquid's give delays the transfer
    full = _chamber(0.0, vl, c)
    f, k = gas_spring.spring(full, 0.005)
    assert k == pytest.approx(a * a / (vl * c), rel=1e-9)
    assert f == pytest.approx((1e6 + a * 0.005 / (vl * c) - 15e6) * a, rel=1e-9)
    assert gas_spring.spring(full, 1.0)[0] == pytest.approx(0.0)  # at p_d the travelling valve opens


def test_unanchored_tubing_adds_its_compliance_to_the_chamber():
    """Unanchored tubing with gas: the barrel's travel A^2 (pc - p0) / k_t adds to the chamber's squeeze, so
    the three compliances add; the config accepts gas with free tubing only with this chamber law."""
    a, vl, c, kt = 1.5e-3, 2e-3, 5e-10, 2e5
    p = _chamber(1e-4, vl, c)
    p["tub_c"] = a * a / kt
    for u in (0.02, 0.1):
        f, k = gas_spring.spring(p, u)
        pc = f / a + 15e6
        assert gas_spring.squeeze_m3(p, pc) == pytest.approx(a * u, rel=1e-9)
        k_gas = a * a * pc / (1e-4 * 1e6 / pc)
        assert 1 / k == pytest.approx(1 / k_gas + vl * c / a ** 2 + 1 / kt, rel=1e-9)
    load_config("default", ["inflow.model=none", "pump.fillage=0.8", "tubing.anchored=false",
                            "pump.liquid_compressibility_per_pa=5e-10"])
    with pytest.raises(ConfigError, match="tubing.anchored"):
        load_config("default", ["inflow.model=none", "pump.fillage=0.8", "tubing.anchored=false"])


def test_gas_chamber_with_compressible_liquid_closes_the_energy_balance():
    """The field wells' case (fillage < 1): gas and compressible liquid together (and free tubing); the
    balance closes and a softer transfer lowers the peak (the load arrives over a longer travel)."""
    peaks, fills = [], []
    for extra in ([], ["pump.liquid_compressibility_per_pa=5e-9"],
                  ["pump.liquid_compressibility_per_pa=5e-10", "tubing.anchored=false"]):
        _, sim, t = _last_stroke(["pump.fillage=0.8", *extra])
        assert abs(sim.energy_balance()["residual_j"]) < 1e-6
        peaks.append(t["polished_rod_load_n"].max())
        fills.append(sim.fillage)
    assert peaks[1] < peaks[0] and peaks[2] < peaks[0]
    # free tubing: the barrel's travel is lost stroke, the gas still takes its share of what is left
    assert fills[2] == pytest.approx(fills[0], abs=0.05)


@pytest.mark.parametrize("chamber", [["pump.fillage=0.8"], ["pump.liquid_compressibility_per_pa=5e-9"]])
def test_tagging_adds_its_contact_to_the_chamber_spring(chamber):
    """Tagging is a contact between the plunger and the pump's end, whatever the chamber holds: with free gas or
    a compressible liquid its impact load still grows strictly with the overtravel (top: the peak, bottom: the
    lowest pump load), the balance closes, and the surface card differs from the spring's alone and from the
    tagging's alone (once refused: the spring mode dropped the contact)."""
    def run(extra):
        _, sim, t = _last_stroke([*extra])
        assert abs(sim.energy_balance()["residual_j"]) < 1e-6
        return t

    free = run(chamber)
    for end, pick in (("top", np.max), ("bottom", lambda y: -np.min(y))):
        impact = [pick(free["pump_load_n"])]
        for over in (0.05, 0.1, 0.2):
            impact.append(pick(run([*chamber, f"pump.tag_{end}_overtravel_m={over}"])["pump_load_n"]))
        assert all(a < b for a, b in itertools.pairwise(impact)), (end, impact)
    both = run([*chamber, "pump.tag_top_overtravel_m=0.1"])["polished_rod_load_n"]
    tag_only = run(["pump.tag_top_overtravel_m=0.1"])["polished_rod_load_n"]
    span = np.ptp(free["polished_rod_load_n"])
    n = min(len(both), len(tag_only), len(free["polished_rod_load_n"]))
    assert np.abs(both[:n] - free["polished_rod_load_n"][:n]).max() > 0.05 * span
    assert np.abs(both[:n] - tag_only[:n]).max() > 0.05 * span


def _late_upstroke(trace):
    """(xi, pump load) over the rising plunger's upper half (xi in the stroke's pump travel, 0 at the bottom),
    after the load transfer, short of the top."""
    x, y = trace["pump_position_m"], trace["pump_load_n"]
    xi = (x - x.min()) / np.ptp(x)
    sel = np.r_[False, np.diff(x) > 0] & (xi > 0.5) & (xi < 0.9)
    return xi[sel], y[sel]


@pytest.mark.parametrize("chamber", [["pump.fillage=0.8"], ["pump.liquid_compressibility_per_pa=5e-9"],
                                     ["tubing.anchored=false"]])
def test_a_tubing_leak_drains_the_column_the_chamber_spring_pushes_on(chamber):
    """A tubing leak with a chamber spring: the column's pressure on the plunger falls over the upstroke as in
    the rigid law, P-_eff = P+ + dP (1 - f (1 + xi) / 2). The liquid / tubing spring meets it as its fluid-load
    clamp: after the transfer the card is the rigid leak's (within 1 % of dP). The gas chamber meets it as the
    discharge pressure and the pressure above the plunger, lowered by f (1 + xi) / 2 (p_d - p_in): the
    plunger friction F is not drained, so the load sits F f (1 + xi) above the rigid law's (which drains dP
    with its 2F). The upstroke load falls strictly with the leak and the balance closes."""
    cfg, _, rigid = _last_stroke(["pump.tubing_leak_fraction=0.5"])
    loads, late, last = [], None, None
    for f in (0.0, 0.3, 0.5):
        _, sim, t = _last_stroke([*chamber, f"pump.tubing_leak_fraction={f}"])
        assert abs(sim.energy_balance()["residual_j"]) < 1e-6
        x, y = t["pump_position_m"], t["pump_load_n"]
        loads.append(float(np.median(y[1:][np.diff(x) > 0])))
        late, last = _late_upstroke(t), t["pump_load_n"]
    assert loads[0] > loads[1] > loads[2], loads
    n = min(len(last), len(rigid["pump_load_n"]))  # the spring's transfer still shapes the card
    assert np.abs(last[:n] - rigid["pump_load_n"][:n]).max() > 0.05 * np.ptp(rigid["pump_load_n"])
    xr, yr = _late_upstroke(rigid)
    order = np.argsort(xr)
    xi, y = late
    expected = np.interp(xi, xr[order], yr[order])
    if chamber[0].startswith("pump.fillage"):
        expected = expected + cfg.pump.plunger_friction_n * 0.5 * (1 + xi)
    dp = np.ptp(rigid["pump_load_n"])
    assert len(xi) > 50 and np.abs(y - expected).max() < 0.01 * dp, np.abs(y - expected).max() / dp
