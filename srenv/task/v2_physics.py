"""v2's per-well physics (``srenv.envs.sucker_rod_v2.physics_overrides``): a beam unit drawn per well and
sized to it, and the string's Kelvin-Voigt damping chosen per well. docs/task.md ("v2's per-well physics")
gives the reasons and the measured effect.

**Unit.** Each well gets a conventional (Class I), Mark II or air-balanced (Class III) unit with the shares
:data:`GEOMETRY_SHARES`, drawn from the well's own seed (``WellParams.dogleg_seed``, itself drawn from the well
seed), so a well has the same unit in every episode, split and ``family:`` call. The unit is a reference
nameplate of that geometry (:data:`REFERENCE_UNITS`) scaled geometrically: every length times
``unit_stroke_m / S_ref``. The stroke is A times the beam's swing, which a uniform scaling leaves unchanged,
so the scaled unit's longest stroke is the well's unit stroke exactly. The crank follows the stroke action
(``surface.beam_unit.crank_follows_stroke``: the crank radius of each requested stroke). Counterbalance and
gearbox rating are set at the installed point (the counterbalance that minimises the peak torque on Mills'
rectangular card, the rating :data:`GEARBOX_MARGIN` times that peak).

**Damping.** tau = 2 zeta_1 / omega_1 with omega_1 the string's fundamental (quarter-wave, ``n0_spm``) and
zeta_1 = :data:`KV_ZETA_1`: every well's mode k gets the damping ratio (2k - 1) zeta_1, the ratio that
``srenv validate``'s tau = 0.03 s gives the field well it was found on (11708328, fundamental 0.86 Hz).
"""

from __future__ import annotations

import functools
import math
from typing import Any

import numpy as np

from ..config_sections import BeamUnitConfig
from ..physics.rod import GRAVITY_M_S2
from ..surface_unit.gearbox import optimal_counterbalance_nm
from ..surface_unit.inline_unit import inline_unit, unit_for_stroke
from . import well_family as wf

# conventional units are most of the installed base, Mark II the common choice for heavier loads (a gearbox
# size smaller), air-balanced the large/portable minority; no census was found, the shares are stated ones
GEOMETRY_SHARES = (("conventional", 0.60), ("mark_ii", 0.25), ("air_balanced", 0.15))
UNIT_STREAM = 0xB0A  # the unit's own draw from the well's seed: the family's draws keep their meaning

# one nameplate per geometry (m): conventional = catalogue C-228D-213-86, hole 0 (86 in); mark_ii =
# configs/wells/mark_ii_fig4.yaml (64 in); air_balanced = the representative Class III proportions of
# tests/srenv/surface_unit/test_unit_geometry.py (97.2 in); rotations as their references
REFERENCE_UNITS: dict[str, dict[str, Any]] = {
    "conventional": {"a_m": 2.8194, "c_m": 2.4397, "i_m": 2.4384, "k_m": 3.8245, "p_m": 2.8956,
                     "r_m": 0.9177, "rotation": "clockwise", "crank_offset_deg": 0.0},
    "mark_ii": {"a_m": 2.032, "c_m": 1.166, "i_m": 1.161, "k_m": 1.732, "p_m": 1.437, "r_m": 0.4526,
                "rotation": "counterclockwise", "crank_offset_deg": 10.0},
    "air_balanced": {"a_m": 3.0, "c_m": 1.5, "i_m": 1.45, "k_m": 2.25, "p_m": 1.75, "r_m": 0.6,
                     "rotation": "clockwise", "crank_offset_deg": 0.0},
}
LINKS = ("a_m", "c_m", "i_m", "k_m", "p_m", "r_m")
AIR_PISTON_AREA_REF_M2 = 0.06  # of the reference air unit; scales with the square of the unit's size
AIR_ARM_FRACTION = 0.7  # the cylinder's arm about the saddle as a fraction of C (it sits under the back arm)
GEARBOX_MARGIN = 1.75  # the rectangular card misses the dynamic peaks (sim peak 1.0-1.6x it, 40 train wells)

KV_ZETA_1 = 0.08  # zeta_1 of srenv validate's tau = 0.03 s on 11708328 (fundamental 0.86 Hz; docs/realism.md)


def draw_geometry(params: wf.WellParams) -> str:
    """The well's unit geometry, deterministic per well (its own seed, not the episode's)."""
    rng = np.random.default_rng([params.dogleg_seed, UNIT_STREAM])
    names, shares = zip(*GEOMETRY_SHARES)
    return names[int(rng.choice(len(names), p=shares))]


@functools.cache
def reference_stroke_m(geometry: str) -> float:
    """The longest stroke of ``geometry``'s reference nameplate (a constant: computed once, not per well)."""
    return inline_unit(BeamUnitConfig(geometry=geometry, torque_rating_nm=1.0, **REFERENCE_UNITS[geometry])).stroke_m


def installed_point(spec: wf.WellSpec) -> tuple[float, float, float]:
    """(fluid density kg/m^3, installed stroke m, installed SPM) of the well's config, or of its mapping when it is
    not parsed yet (``spec.cfg`` None: the same numbers, which the parse takes as they are)."""
    if spec.cfg is not None:
        cfg = spec.cfg
        return cfg.fluid.density_kg_m3, cfg.surface.stroke_length_m, cfg.surface.spm
    raw = spec.raw
    return raw["fluid"]["density_kg_m3"], raw["surface"]["stroke_length_m"], raw["surface"]["spm"]


def _rod_loads_n(spec: wf.WellSpec, rho_f: float) -> tuple[float, float, float]:
    """(rod weight in air, buoyed rod weight, fluid load) of the well's design, N."""
    rod_w = sum(wf.STEEL_RHO * GRAVITY_M_S2 * math.pi / 4 * (d * 1e-3) ** 2 * length
                for d, length in spec.design["tapers_bottom_up"])
    return rod_w, rod_w * (1.0 - rho_f / wf.STEEL_RHO), spec.design["fluid_load_n"]


def unit_block(spec: wf.WellSpec, geometry: str) -> dict[str, Any]:
    """The ``surface.beam_unit`` block of ``geometry`` sized to the well (see the module docstring)."""
    ref = REFERENCE_UNITS[geometry]
    f = spec.params.unit_stroke_m / reference_stroke_m(geometry)
    block: dict[str, Any] = {"geometry": geometry, "rotation": ref["rotation"],
                             **{k: round(ref[k] * f, 6) for k in LINKS}, "crank_follows_stroke": True}
    # counterbalance and gearbox at the installed point (the crew balances the unit where it runs), on the
    # classical rectangular card: Mills' PPRL on the upstroke, his MPRL on the downstroke
    rho_f, stroke_m, spm = installed_point(spec)
    rod_w, rod_wb, fluid = _rod_loads_n(spec, rho_f)
    pprl, mprl = wf.mills_loads_n(rod_w, rod_wb, fluid, stroke_m, spm)
    offset = math.radians(ref["crank_offset_deg"]) * (-1.0 if geometry == "mark_ii" else 1.0)  # API lag: -lead
    probe = unit_for_stroke(BeamUnitConfig(**{**block, "torque_rating_nm": 1.0}), stroke_m)
    theta = probe.theta_bottom + np.linspace(0.0, 2 * np.pi, 721)[:-1]
    card = np.where(np.asarray(probe.torque_factor_m(theta)) > 0.0, pprl, mprl)
    m = optimal_counterbalance_nm(probe, theta, card, offset)
    peak = float(np.max(np.abs(probe.net_torque_nm(theta, card, 0.0 if probe.air_balanced else m, offset,
                                                     m if probe.air_balanced else 0.0))))
    block["torque_rating_nm"] = 1000.0 * math.ceil(GEARBOX_MARGIN * peak / 1000.0)
    if geometry == "air_balanced":
        area = AIR_PISTON_AREA_REF_M2 * f * f
        arm = AIR_ARM_FRACTION * block["c_m"]
        block.update(air_piston_area_m2=round(area, 6), air_arm_m=round(arm, 6),
                     air_pressure_pa=round(m * block["a_m"] / (area * arm), 1))
    else:
        # given for the full crank radius: the surface scales it with the stroke (crank_follows_stroke)
        full = m * spec.params.unit_stroke_m / probe.stroke_m
        block.update(counterbalance_moment_nm=round(full, 1), crank_offset_deg=ref["crank_offset_deg"])
    return block


def kv_tau_s(spec: wf.WellSpec) -> float:
    """Kelvin-Voigt retardation time giving the well's fundamental the damping ratio KV_ZETA_1."""
    return kv_tau_of(spec.design["n0_spm"])


def kv_tau_of(n0_spm: float) -> float:
    """Kelvin-Voigt retardation time giving a string of fundamental ``n0_spm`` (strokes/min) zeta_1 = KV_ZETA_1."""
    omega_1 = 2 * math.pi * n0_spm / 60.0
    return round(2.0 * KV_ZETA_1 / omega_1, 5)


# keys that only make sense together: a caller who sets one of them chooses the surface motion
GROUPS = (("surface.motion", "surface.beam_unit"),)


def yield_to(physics: dict[str, Any], caller: dict[str, Any] | None) -> dict[str, Any]:
    """``physics`` without what the caller's own overrides set (the same key, a field under it or its section,
    or any key of its :data:`GROUPS`): a user who asks for ``surface.motion: harmonic`` or a damping keeps it."""
    if not caller:
        return physics

    def touched(key: str) -> bool:
        return any(u == key or u.startswith(key + ".") or key.startswith(u + ".") for u in caller)

    out = dict(physics)
    for key in physics:
        group = next((g for g in GROUPS if key in g), (key,))
        if any(touched(k) for k in group):
            out.pop(key)
    return out


def overrides(spec: wf.WellSpec) -> dict[str, Any]:
    """The dotted-key overrides of v2's per-well physics (dotted: a nested section would replace the whole
    section and drop the family's ``damping.damping_factor``); none for a well given by its config (a shipped
    well or YAML path: its file says its unit and damping)."""
    if spec.params is None:
        return {}
    return {"surface.motion": "beam_unit",
            "surface.beam_unit": unit_block(spec, draw_geometry(spec.params)),
            "damping.stiffness_proportional_s": kv_tau_s(spec)}
