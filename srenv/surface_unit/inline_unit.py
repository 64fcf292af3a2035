"""A beam unit given by its nameplate (``surface.beam_unit``, :class:`srenv.config_sections.BeamUnitConfig`):
the cross-field checks that name the fields (a four-bar that cannot close over a crank turn is refused here,
before any work), the unit object the surface motion drives, its counterbalance, and the mapping of a field
record's ``SurfaceUnit`` onto the same block. docs/surface_unit.md gives the equations and conventions.
"""

from __future__ import annotations

import dataclasses
import functools
import math
from typing import TYPE_CHECKING, Any

import numpy as np

from ..errors import ConfigError
from .beam_unit import BeamUnitGeometry, ConventionalUnit, _wrap_pi
from .unit_catalogue import parse_designation

if TYPE_CHECKING:
    from ..config_sections import BeamUnitConfig, SurfaceConfig

WHERE = "surface.beam_unit"
UNRATED = 1.0e12  # max stroke / load of a unit named without a designation: not rated, never binding


def check_surface(s: SurfaceConfig) -> None:
    """Cross-field checks of the inline unit (each refusal names the field, the value and what is expected)."""
    if getattr(s, "motor", None) is not None and s.motion not in ("conventional", "beam_unit"):
        raise ConfigError("surface.motor", "a motor", "null unless surface.motion is 'conventional' or 'beam_unit' "
                          "(the motor drives a unit's cranks)")
    if s.motion != "beam_unit":
        if s.beam_unit is not None:
            raise ConfigError(WHERE, "a unit", "null unless surface.motion is 'beam_unit' (it drives the well)")
        return
    u = s.beam_unit
    if u is None:
        raise ConfigError(WHERE, None, "the unit's nameplate (geometry, rotation, a_m, c_m, i_m, k_m, p_m, r_m) "
                          "when surface.motion is 'beam_unit'")
    if s.counterbalance_moment_nm != 0.0 or s.counterbalance_offset_deg != 0.0:
        raise ConfigError("surface.counterbalance_moment_nm", s.counterbalance_moment_nm,
                          f"0 with surface.motion 'beam_unit' (give it as {WHERE}.counterbalance_moment_nm)")
    _check_counterbalance(u)
    _check_rating(u)
    check_linkage(u.i_m, u.k_m, u.c_m, u.p_m, u.r_m)


def _check_counterbalance(u: BeamUnitConfig) -> None:
    air = (u.air_pressure_pa, u.air_piston_area_m2, u.air_arm_m)
    if u.geometry == "air_balanced":
        if u.counterbalance_moment_nm > 0:
            raise ConfigError(f"{WHERE}.counterbalance_moment_nm", u.counterbalance_moment_nm,
                              "0 on an air_balanced unit (its counterbalance is air_pressure_pa x air_piston_area_m2)")
        if any(v > 0 for v in air) and not all(v > 0 for v in air):
            name = ("air_pressure_pa", "air_piston_area_m2", "air_arm_m")[min(i for i, v in enumerate(air) if v == 0)]
            raise ConfigError(f"{WHERE}.{name}", 0.0, "a positive value: the air counterbalance needs the pressure, "
                              "the piston area and the cylinder's arm")
    elif any(v > 0 for v in air):
        raise ConfigError(f"{WHERE}.air_pressure_pa", u.air_pressure_pa,
                          f"0 unless {WHERE}.geometry is air_balanced (a {u.geometry} unit has crank weights)")


def _check_rating(u: BeamUnitConfig) -> None:
    if u.designation:
        try:
            parse_designation(u.designation)
        except ConfigError as exc:
            raise ConfigError(f"{WHERE}.designation", u.designation, exc.expected) from None
    elif u.torque_rating_nm <= 0:
        raise ConfigError(f"{WHERE}.torque_rating_nm", u.torque_rating_nm,
                          f"a positive gearbox rating in N*m (or {WHERE}.designation, e.g. M-228D-213-86)")


def check_linkage(i_m: float, k_m: float, c_m: float, p_m: float, r_m: float, where: str = WHERE) -> None:
    """The four-bar must close, without a toggle, at every crank angle: the pin-to-saddle distance sweeps
    [K - R, K + R] and must stay strictly inside the triangle inequality |C - P| < d < C + P."""
    if not i_m < k_m:
        raise ConfigError(f"{where}.i_m", i_m, f"m, less than {where}.k_m = {k_m:g} (the saddle above the crank)")
    if not r_m < k_m:
        raise ConfigError(f"{where}.r_m", r_m, f"m, less than {where}.k_m = {k_m:g}")
    if not k_m + r_m < c_m + p_m:
        raise ConfigError(f"{where}.p_m", p_m, f"m with c_m + p_m > k_m + r_m = {k_m + r_m:.6g} (fields c_m, p_m, "
                          "k_m, r_m: the four-bar cannot close over a full crank turn)")
    if not k_m - r_m > abs(c_m - p_m):
        longer = "p_m" if p_m > c_m else "c_m"
        raise ConfigError(f"{where}.{longer}", max(p_m, c_m), f"m with |c_m - p_m| < k_m - r_m = {k_m - r_m:.6g} "
                          "(fields c_m, p_m, k_m, r_m: the four-bar cannot close over a full crank turn)")


def _ratings(u: BeamUnitConfig) -> tuple[float, float, float]:
    """(torque rating N*m, max load N, max stroke m): the designation's, the given rating winning."""
    torque, load, stroke = parse_designation(u.designation) if u.designation else (0.0, UNRATED, UNRATED)
    # a record's unit may carry no rating (the config loader refuses that, _check_rating)
    return (u.torque_rating_nm or torque or UNRATED), load, stroke


@functools.lru_cache(maxsize=16)
def inline_unit(u: BeamUnitConfig) -> ConventionalUnit:
    """The unit object of a checked block, cached: the env rebuilds simulators on every reset."""
    check_linkage(u.i_m, u.k_m, u.c_m, u.p_m, u.r_m)
    torque, load, stroke = _ratings(u)
    geometry = BeamUnitGeometry(
        designation=u.designation or f"inline {u.geometry}", a_m=u.a_m, c_m=u.c_m, i_m=u.i_m, k_m=u.k_m,
        p_m=u.p_m, crank_radii_m=(u.r_m,), rotation=u.rotation, torque_rating_nm=torque,
        structural_unbalance_n=u.structural_unbalance_n, max_stroke_m=stroke, max_load_n=load, kind=u.geometry)
    return ConventionalUnit(geometry)


def _stroke_on_radius(full: ConventionalUnit, radius_m: float) -> float:
    """The stroke_m of ``full``'s linkage on crank radius ``radius_m``: ConventionalUnit.__init__'s dead centres
    and arithmetic, so a unit built on that radius has this stroke to the bit (tests/srenv/simulation/
    test_fast_paths_rl.py), without building and checking one."""
    class_one = full._lever > 0
    bottom, top = full._dead_centre(class_one, radius_m)[1], full._dead_centre(not class_one, radius_m)[1]
    return full.geometry.a_m * float(_wrap_pi(np.asarray(top - bottom)))


@functools.lru_cache(maxsize=256)
def unit_for_stroke(u: BeamUnitConfig, stroke_m: float) -> ConventionalUnit:
    """The unit of ``u`` with its crank radius moved so that its stroke is ``stroke_m`` (<= the stroke of
    ``u.r_m``; ``crank_follows_stroke``): a shorter crank hole, as a crew sets one, made continuous. The stroke
    grows monotonically and nearly linearly with R (S ~ 2 R A / C), so a few secant steps on R hit it to 1e-9
    m. A smaller R only makes the four-bar easier to close (K + R < C + P, K - R > |C - P|)."""
    full = inline_unit(u)
    if stroke_m >= full.stroke_m:
        return full
    r0, s0 = u.r_m, full.stroke_m
    r1 = u.r_m * stroke_m / s0
    # the secant reads a radius's stroke off the full unit's linkage (the bits of a unit built on that radius,
    # without building and checking one per step: a new stroke every env step of an RL agent); only the unit
    # it returns is built, and checked
    s1 = _stroke_on_radius(full, r1)
    for _ in range(20):
        if abs(s1 - stroke_m) < 1e-10:
            break
        r0, s0, r1 = r1, s1, r1 + (stroke_m - s1) * (r1 - r0) / (s1 - s0)
        s1 = _stroke_on_radius(full, r1)
    return inline_unit.__wrapped__(dataclasses.replace(u, r_m=r1))


def counterbalance(u: BeamUnitConfig) -> tuple[float, float]:
    """(counterbalance, lead τ of the counterweight arm in rad) for the gearbox: the crank moment M in N*m,
    or an air-balanced unit's cylinder force at the polished rod in N (p·A_piston·arm / A, the pressure
    taken constant over the stroke). A Mark II's API offset angle is a lag: lead = -τ."""
    if u.geometry == "air_balanced":
        return u.air_pressure_pa * u.air_piston_area_m2 * u.air_arm_m / u.a_m, 0.0
    sign = -1.0 if u.geometry == "mark_ii" else 1.0
    return u.counterbalance_moment_nm, sign * math.radians(u.crank_offset_deg)


# ----------------------------------------------------------------------------------- field records
# the dynacard layout's PumpingUnitGeometry codes (vendor exports spell them several ways)
_RECORD_GEOMETRIES = {"C": "conventional", "CONVENTIONAL": "conventional", "M": "mark_ii", "MARKII": "mark_ii",
                      "MII": "mark_ii", "MARK2": "mark_ii", "A": "air_balanced", "AIR": "air_balanced",
                      "AIRBALANCED": "air_balanced", "AB": "air_balanced"}


def record_geometry(code: Any) -> str | None:
    """The API geometry of a record's geometry string ('C', 'M', 'Mark II', 'A', 'Air Balanced'...), or None."""
    key = "".join(ch for ch in str(code or "").upper() if ch.isalnum())
    return _RECORD_GEOMETRIES.get(key)


_CCW = ("c.clock", "counter", "ccw", "cclock")


def _rotation_key(text: Any) -> str:
    return str(text or "").lower().replace(" ", "").replace("-", "")


def record_rotation(text: Any) -> str:
    """'C. Clockwise', 'CCW', 'Counterclockwise' -> counterclockwise; anything else clockwise (API default)."""
    return "counterclockwise" if _rotation_key(text).startswith(_CCW) else "clockwise"


def record_rotation_known(text: Any) -> bool:
    """Whether a record's rotation names one (either way round); an unknown one is read clockwise, said so."""
    return _rotation_key(text).startswith((*_CCW, "clock", "cw"))


def record_unit_config(unit: dict) -> dict | None:
    """A record's ``SurfaceUnit`` (SI, as read by ``srenv.analysis.field_record``) as a ``surface.beam_unit``
    block, or None when its geometry is unknown or a dimension is missing. Ratings are the record's when given."""
    geometry = record_geometry(unit.get("geometry"))
    if geometry is None or any(unit.get(k) is None for k in "ACIKPR"):
        return None
    block = {"geometry": geometry, "rotation": record_rotation(unit.get("rotation")),
             **{f"{k.lower()}_m": float(unit[k]) for k in "ACIKPR"},
             "structural_unbalance_n": float(unit.get("structural_unbalance_n") or 0.0),
             "torque_rating_nm": float(unit.get("torque_rating_nm") or 0.0),
             # the record's moment only feeds the gearbox report: a negative one (a vendor's sign) is no moment
             "counterbalance_moment_nm": max(float(unit.get("counterbalance_moment_nm") or 0.0), 0.0),
             "crank_offset_deg": float(unit.get("phase_angle_deg") or 0.0)}
    if geometry == "air_balanced":
        block["counterbalance_moment_nm"] = 0.0  # the record's moment is no crank moment on an air unit
    return block
