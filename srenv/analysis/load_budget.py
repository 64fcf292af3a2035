"""The static load budget of a well model, term by term, and the load plateaus of a card (docs/realism.md,
"The static load budget").

The polished-rod load of a string at rest, in the two bookkeepings that must agree:

- true loads: the polished rod carries the air weight of every taper along the survey (w L cos), less the
  couplings' buoyancy, plus the pressure on every taper step (p (A_below - A_above), pushing down where the
  string thickens downward), plus the rod end's true load, which is the pump's effective load less the
  pressure on the rod end's area (p_end A_end pushes the string up);
- effective loads: the buoyed weight of every taper along the survey, less the wellhead pressure on the top
  area (it pushes the rod out through the stuffing box), plus the pump's effective load.

The pump's effective load is the valve law's: upstroke (p_d - p_in) A_pl + P_f, downstroke -P_f - dp_valve A_pl.
Rod-tubing friction adds on the upstroke and subtracts on the downstroke; at rest it is the side-force law's
bound at the static node forces (``physics.laws.rod_friction``), an estimate: the moving string's forces differ.
"""

from __future__ import annotations

import numpy as np

from ..physics.fluid import tubing_pressure_pa
from ..physics.pump import plunger_area_m2
from ..physics.rod import GRAVITY_M_S2, coupling_buoyancy_n_m


def card_plateaus(position_m: np.ndarray, load_n: np.ndarray, lo: float = 0.25, hi: float = 0.75) -> dict:
    """Mean load over the middle of the stroke (lo..hi of the travel from the bottom), upstroke and downstroke
    apart: a card's static levels, its dynamics averaged over half a stroke. The direction is the position's
    periodic gradient (one stroke, equal times)."""
    x, f = np.asarray(position_m, dtype=float), np.asarray(load_n, dtype=float)
    v = np.roll(x, -1) - np.roll(x, 1)
    band = (x >= x.min() + lo * np.ptp(x)) & (x <= x.min() + hi * np.ptp(x))
    return {"upstroke_n": float(f[band & (v > 0)].mean()), "downstroke_n": float(f[band & (v < 0)].mean())}


def _static_node_forces(sim, plunger_eq_n: float) -> np.ndarray:
    """Effective axial force per free node of the string at rest holding `plunger_eq_n` at its end."""
    elem = plunger_eq_n + np.cumsum(sim._f_all[1:][::-1])[::-1]
    return np.r_[0.5 * (elem[:-1] + elem[1:]), elem[-1]]


def static_friction_n(sim, plunger_eq_n: float) -> float:
    """Sum of the rod-tubing friction bounds at the static node forces (N; 0 with friction.coefficient 0)."""
    sf = sim.side_force
    n = _static_node_forces(sim, plunger_eq_n)
    f = np.hypot(sf.weight_n - sf.axial * n, sf.turn * n)
    return float(f[:-1].sum())


def static_budget(sim) -> dict:
    """The static polished-rod load of `sim`'s well (a built ``Simulator``) on the upstroke and the downstroke,
    term by term (N; loads positive = tension, forces pushing the string down positive)."""
    cfg, mesh = sim.cfg, sim.mesh
    rho_f = cfg.fluid.density_kg_m3
    x = mesh.x_m
    cos_mid = np.cos(sim.survey.inclination(0.5 * (x[1:] + x[:-1])))
    w_c = coupling_buoyancy_n_m(mesh, rho_f)
    tvd = sim.survey.tvd(x)
    tapers = []
    for k in range(int(mesh.taper.max()) + 1):
        e = mesh.taper == k
        air = mesh.rho_a_kg_m[e] * GRAVITY_M_S2 * mesh.length_m[e]
        body = rho_f * GRAVITY_M_S2 * mesh.area_m2[e] * mesh.length_m[e]
        tapers.append({"length_m": float(mesh.length_m[e].sum()), "area_m2": float(mesh.area_m2[e][0]),
                       "air_weight_n": float(air.sum()), "air_weight_along_survey_n": float((air * cos_mid[e]).sum()),
                       "coupling_buoyancy_n": float((w_c[e] * cos_mid[e] * mesh.length_m[e]).sum()),
                       "body_buoyancy_n": float((body * cos_mid[e]).sum()),
                       "mean_cos": float((cos_mid[e] * mesh.length_m[e]).sum() / mesh.length_m[e].sum())})
    steps = []
    for j in np.flatnonzero(np.diff(mesh.taper) != 0):  # element j is the last of its taper
        p = float(tubing_pressure_pa(cfg.fluid, tvd[j + 1]))
        steps.append({"md_m": float(x[j + 1]), "pressure_pa": p,
                      "force_n": p * float(mesh.area_m2[j + 1] - mesh.area_m2[j])})
    law, a_pl = sim.law, plunger_area_m2(cfg.pump)
    rod_end = -sim.p_pump_pa * sim.area_bottom_m2
    wellhead = -sim.p_top_pa * sim.area_top_m2
    weight_true = sum(t["air_weight_along_survey_n"] - t["coupling_buoyancy_n"] for t in tapers)
    buoyed = sum(t["air_weight_along_survey_n"] - t["coupling_buoyancy_n"] - t["body_buoyancy_n"] for t in tapers)
    pressures = sum(s["force_n"] for s in steps) + rod_end
    out = {"tapers": tapers, "steps": steps, "rod_end_pressure_force_n": rod_end,
           "wellhead_pressure_force_n": wellhead, "buoyed_weight_n": buoyed,
           "pump": {"upstroke_effective_n": law.up_eq_n, "downstroke_effective_n": law.down_eq_n,
                    "plunger_friction_n": cfg.pump.plunger_friction_n if cfg.pump.load_source == "pressures" else None,
                    "fluid_load_n": (law.up_eq_n - law.down_eq_n), "plunger_area_m2": a_pl}}
    for name, eq in (("upstroke", law.up_eq_n), ("downstroke", law.down_eq_n)):
        fr = static_friction_n(sim, eq) * (1.0 if name == "upstroke" else -1.0)
        out[name] = {"true_bookkeeping_n": weight_true + pressures + eq + fr,
                     "effective_bookkeeping_n": buoyed + wellhead + eq + fr, "rod_tubing_friction_n": fr}
    return out
