"""The ``surface.beam_unit`` section: a pumping unit by its nameplate (kept apart from the other sections for
size; its fields are declared like theirs, ``srenv.config_fields``)."""

from __future__ import annotations

from dataclasses import dataclass, field

from .config_fields import num, opt

# ------------------------------------------------------------ the unit by its nameplate (surface.beam_unit)
# API Spec 11E dimensions, rotation, unbalance and counterbalance of a conventional, Mark II or air-balanced
# unit instead of a catalogue designation; checked and built by srenv.surface_unit.inline_unit
# (docs/surface_unit.md).
GEOMETRIES = ("conventional", "mark_ii", "air_balanced")
ROTATIONS = ("clockwise", "counterclockwise")
MAX_UNIT_LINK_M = 30.0  # the largest API 11E units (A ~ 5 m, P ~ 5 m); 30 m is no pumping unit
MAX_UNIT_FORCE_N = 1.0e6  # 225 000 lbf: above any API 11E structure rating (the largest ~ 47 000 lbf)


def _link(doc: str) -> float:
    return num(unit="m", lo=0.01, hi=MAX_UNIT_LINK_M, doc=doc)


@dataclass(frozen=True)
class BeamUnitConfig:
    """One pumping unit's nameplate, SI. Required: geometry, rotation and the six API dimensions."""

    geometry: str = field(metadata={"options": GEOMETRIES, "doc": (
        "API geometry: conventional (Class I), mark_ii (Class III, front-mounted, phased cranks), "
        "air_balanced (Class III, air-cylinder counterbalance)")})
    rotation: str = field(metadata={"options": ROTATIONS, "doc": (
        "crank rotation seen with the wellhead to the right (API)")})
    a_m: float = _link("API A: saddle bearing to the horsehead's arc (front arm)")
    c_m: float = _link("API C: saddle bearing to the equalizer bearing")
    i_m: float = _link("API I: horizontal distance saddle bearing to crank shaft")
    k_m: float = _link("API K: distance saddle bearing to crank shaft")
    p_m: float = _link("API P: pitman, crank pin to equalizer bearing")
    r_m: float = _link("API R: crank radius of the hole in use")
    designation: str = opt("", doc="API designation, e.g. M-228D-213-86: its gearbox rating is used when "
                           "torque_rating_nm is 0")
    torque_rating_nm: float = num(0.0, unit="N*m", check="nonneg", hi=1.0e8,
                                  doc="gearbox torque rating; 0 = from the designation")
    structural_unbalance_n: float = num(0.0, unit="N", check="any", lo=-MAX_UNIT_FORCE_N, hi=MAX_UNIT_FORCE_N,
                                        doc="API SU: force at the polished rod holding the beam level with the "
                                        "pitmans off, + downward (pitman side heavy)")
    counterbalance_moment_nm: float = num(0.0, unit="N*m", check="nonneg", hi=1.0e8,
                                          doc="crank-balanced units: max moment M of counterweights and cranks")
    crank_offset_deg: float = num(0.0, unit="deg", check="any", lo=-180.0, hi=180.0,
                                  doc="API offset angle tau of the counterweight arm: lead over the pin "
                                  "(conventional), lag behind the side opposite the pin (mark_ii)")
    air_pressure_pa: float = num(0.0, unit="Pa", check="nonneg", hi=1.0e8,
                                 doc="air_balanced: gauge pressure in the counterbalance cylinder")
    air_piston_area_m2: float = num(0.0, unit="m^2", check="nonneg", hi=10.0,
                                    doc="air_balanced: effective piston area of the cylinder")
    air_arm_m: float = num(0.0, unit="m", check="nonneg", hi=MAX_UNIT_LINK_M,
                           doc="air_balanced: moment arm of the cylinder's force about the saddle bearing")
    crank_follows_stroke: bool = opt(False, doc=(
        "true: each stroke's crank radius is the one (<= r_m) that gives the requested "
        "surface.stroke_length_m / control stroke, capped at r_m's stroke (a continuously adjustable crank "
        "pin, for the env's stroke action), counterbalance_moment_nm (given for r_m) scaled with the stroke as a "
        "crew rebalances on a hole change; false: the stroke is r_m's whatever is requested"))


# ------------------------------------------------------------------------ the unit's motor (surface.motor)
# opt-in: without it the crank turns at constant speed (srenv.surface_unit.motor, docs/surface_unit.md)
NEMA_LETTERS = ("B", "C", "D")


@dataclass(frozen=True)
class MotorConfig:
    """The prime mover of a linkage motion: a NEMA induction motor whose slip lets the crank speed follow the net
    gearbox torque through the stroke (the mean speed stays the SPM's)."""

    rated_power_w: float = num(unit="W", lo=100.0, hi=1.0e6, doc="the motor's nameplate power (20 hp = 14914 W)")
    nema_design: str = field(default="D", metadata={"options": NEMA_LETTERS, "doc": (
        "NEMA MG-1 design letter: its nominal rated slip (B 0.03, C 0.04, D 0.065) and largest torque (2.0, 1.9, "
        "2.75 x rated) when rated_slip is not given")})
    rated_slip: float | None = num(None, unit="-", lo=0.001, hi=0.5,
                                   doc="slip at rated torque, 1 - speed / synchronous speed; null = the design's")
    inertia_kg_m2: float = num(0.0, unit="kg*m^2", check="nonneg", hi=1.0e7,
                               doc="rotating inertia referred to the crank shaft (motor rotor and sheaves x the "
                                   "squared speed ratio, gearbox, cranks and counterweights); 0 = the quasi-static "
                                   "slip line")
