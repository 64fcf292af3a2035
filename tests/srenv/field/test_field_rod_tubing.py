"""Rod and tubing: unanchored tubing, fiberglass and sinker-bar tapers, stuffing-box friction."""

from __future__ import annotations

import math

import numpy as np
import pytest

from srenv.analysis.diagnose import diagnose_card
from srenv.analysis.pump_card import analyse_pump_card
from srenv.analysis.stroke_summary import summarize
from srenv.config import load_config
from srenv.physics.rod import GRAVITY_M_S2
from srenv.simulation.simulator import Simulator

FIG3 = "paper_fig3_vertical"


def _last(cfg, strokes: int = 4):
    sim = Simulator(cfg)
    runs = sim.run_strokes(strokes)
    return sim, runs


def _transfer_travel(x, f, fraction: float = 0.98) -> float:
    """Plunger travel from the bottom until the load has risen through `fraction` of the fluid load."""
    a = analyse_pump_card(x, f)
    i_b = int(np.argmin(x))
    xr, fr = np.roll(x, -i_b), np.roll(f, -i_b)
    j = int(np.argmax(fr >= a["downstroke_load_n"] + fraction * a["fluid_load_n"]))
    return float(xr[j] - xr[0])


def test_unanchored_tubing_shortens_the_pump_stroke_by_its_stretch():
    cfg_a = load_config(FIG3)
    cfg_u = load_config(FIG3, ["tubing.anchored=false"])
    sim_a, runs_a = _last(cfg_a)
    sim_u, runs_u = _last(cfg_u)
    tb = cfg_u.tubing
    area = math.pi / 4 * ((tb.outer_diameter_mm * 1e-3) ** 2 - (tb.inner_diameter_mm * 1e-3) ** 2)
    fluid = cfg_u.pump.upstroke_load_n - cfg_u.pump.downstroke_load_n  # P- - P+ = 11.7 kN
    stretch = fluid * cfg_u.rod_length_m / (tb.youngs_modulus_pa * area)  # the hand formula, ~52 mm
    assert sim_u.tubing_stiffness_n_m == pytest.approx(tb.youngs_modulus_pa * area / cfg_u.rod_length_m)
    ta, tu = runs_a[-1].trace, runs_u[-1].trace
    # anchored: the load transfers with the plunger at rest; unanchored: the plunger rises by the stretch
    assert _transfer_travel(ta["pump_position_m"], ta["pump_load_n"]) < 1e-3
    assert _transfer_travel(tu["pump_position_m"], tu["pump_load_n"]) == pytest.approx(0.98 * stretch, rel=0.03)
    # net stroke (plunger travel with the barrel still): shorter by the stretch
    net_a = np.ptp(ta["pump_position_m"]) - _transfer_travel(ta["pump_position_m"], ta["pump_load_n"], 1.0)
    net_u = np.ptp(tu["pump_position_m"]) - _transfer_travel(tu["pump_position_m"], tu["pump_load_n"], 1.0)
    assert net_a - net_u == pytest.approx(stretch, rel=0.05)
    # and so is the production
    pa, pu = summarize(sim_a, runs_a[-1:]), summarize(sim_u, runs_u[-1:])
    assert pu["production_m3_day"] / pa["production_m3_day"] == pytest.approx(
        1 - stretch / pa["pump_stroke_m"], rel=0.01)


def test_anchor_depth_shortens_the_free_tubing():
    cfg = load_config(FIG3, ["tubing.anchored=false", "tubing.anchor_depth_m=564"])
    sim = Simulator(cfg)
    free = load_config(FIG3, ["tubing.anchored=false"])
    assert sim.tubing_stiffness_n_m == pytest.approx(Simulator(free).tubing_stiffness_n_m * 1064 / 500)


def test_fiberglass_taper_takes_the_material_defaults_and_its_wave_speed():
    cfg = load_config(FIG3, {"rod.tapers": [{"diameter_mm": 22.0, "length_m": 624.0, "material": "fiberglass"},
                                            {"diameter_mm": 22.0, "length_m": 440.0, "material": "fiberglass"}],
                             "simulation.element_length_m": 10.0})
    t = cfg.rod.tapers[0]
    assert (t.youngs_modulus_pa, t.density_kg_m3, t.tensile_strength_pa) == (4.8e10, 2000.0, 6.9e8)
    sim = Simulator(cfg)
    a = math.sqrt(4.8e10 / 2000.0)
    assert sim.f1_hz == pytest.approx(a / (4 * cfg.rod_length_m), rel=2e-3)  # uniform fixed-free rod
    s = summarize(sim, [sim.run_stroke()])
    assert np.all(np.isfinite(s["goodman_pct"]))


def test_fiberglass_over_sinker_bars_static_stretch():
    """Hanging string in liquid, plunger holding P+: bottom displacement = sum over tapers of
    int N_eq / (E A) dx, the integral taken bottom-up with each taper's own E and buoyed weight."""
    cfg = load_config(FIG3, {"rod.tapers": [{"diameter_mm": 25.4, "length_m": 924.0, "material": "fiberglass"},
                                            {"diameter_mm": 38.1, "length_m": 140.0, "material": "sinker_bar"}],
                             "simulation.element_length_m": 10.0})
    assert cfg.rod.tapers[0].youngs_modulus_pa == 4.8e10 and cfg.rod.tapers[1].youngs_modulus_pa == 2.0e11
    sim = Simulator(cfg)
    rho_f = cfg.fluid.density_kg_m3
    a_bottom = math.pi / 4 * (cfg.rod.tapers[-1].diameter_mm * 1e-3) ** 2
    n_eq = cfg.pump.downstroke_load_n + rho_f * GRAVITY_M_S2 * cfg.rod_length_m * a_bottom
    stretch = 0.0
    for t in reversed(cfg.rod.tapers):
        area = math.pi / 4 * (t.diameter_mm * 1e-3) ** 2
        w_b = (t.density_kg_m3 - rho_f) * GRAVITY_M_S2 * area
        stretch += (n_eq * t.length_m + 0.5 * w_b * t.length_m ** 2) / (t.youngs_modulus_pa * area)
        n_eq += w_b * t.length_m
    assert sim.u[-1] == pytest.approx(stretch, rel=5e-3)


def test_stuffing_box_friction_shifts_the_surface_card_only():
    base = _last(load_config(FIG3), 2)[1][-1].trace
    cfg = load_config(FIG3, ["surface.stuffing_box_friction_n=800"])
    tr = _last(cfg, 2)[1][-1].trace
    up = base["polished_rod_velocity_m_s"] > 0
    down = base["polished_rod_velocity_m_s"] < 0
    d = tr["polished_rod_load_n"] - base["polished_rod_load_n"]
    assert np.allclose(d[up], 800.0) and np.allclose(d[down], -800.0)
    assert np.array_equal(tr["pump_load_n"], base["pump_load_n"])
    # diagnose removes it again (the round trip stays as tight as without it)
    card = diagnose_card(cfg, tr["t_s"], tr["polished_rod_position_m"], tr["polished_rod_load_n"])
    rms = np.sqrt(np.mean((card.pump_load_n - tr["pump_load_n"]) ** 2)) / tr["polished_rod_load_n"].max()
    assert rms < 0.01
