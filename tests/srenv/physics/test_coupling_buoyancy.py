"""The couplings' buoyancy: all the string's steel displaces liquid, the couplings' too (srenv/physics/rod.py
``coupling_buoyancy_n_m``; docs/realism.md, "The static load budget")."""

from __future__ import annotations

import math

import numpy as np
import pytest

from srenv.analysis.diagnose import segments
from srenv.physics.rod import GRAVITY_M_S2
from srenv.simulation.simulator import Simulator


def _archimedes_n(cfg) -> float:
    """Air weight (body + couplings) times (1 - rho_f / rho_steel): all the steel displaces liquid."""
    w = 0.0
    for t in cfg.rod.tapers:
        mass = t.density_kg_m3 * math.pi / 4 * (t.diameter_mm * 1e-3) ** 2 + t.coupling_mass_kg_per_m
        w += mass * GRAVITY_M_S2 * t.length_m * (1.0 - cfg.fluid.density_kg_m3 / t.density_kg_m3)
    return w


def test_couplings_are_buoyed_like_the_rod_body(with_couplings):
    """A vertical string with couplings hangs with its air weight times (1 - rho_f / rho_s), in the simulator's
    static state and in the diagnosis's weight per length. Before the fix the couplings' mass had no buoyancy:
    rho_f / rho_s of their weight too heavy (341 N on this string)."""
    cfg = with_couplings("paper_fig3_vertical")
    sim = Simulator(cfg)
    expected = _archimedes_n(cfg)
    # the static string's top (effective) load is its buoyed weight plus the plunger's P+ (equivalent force)
    assert sim.uav[3] - sim.law.down_eq_n == pytest.approx(expected, rel=1e-9)
    sg = segments(cfg)
    assert float(np.sum(sg.w_n_m * sg.h_m)) == pytest.approx(expected, rel=1e-9)
    couplings = sum(t.coupling_mass_kg_per_m * t.length_m for t in cfg.rod.tapers) * GRAVITY_M_S2
    assert couplings * cfg.fluid.density_kg_m3 / 7800.0 > 300.0  # what the test would miss without the fix


def test_couplings_leave_a_string_without_them_unchanged(with_couplings):
    """No coupling mass: the mesh has no coupling volume and the weight is the body's (the envs' strings)."""
    cfg = with_couplings("paper_fig4_deviated", coupling_kg_m=0.0)
    sim = Simulator(cfg)
    assert sim.mesh.coupling_area_m2 is None
