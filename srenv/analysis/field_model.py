"""The well model of a field record: a srenv config (as a dict, SI) built from the record's description, and
the pump's state read off a diagnosis (the vendor's analysis where the record has one, srenv's own diagnosis
of the measured card otherwise). No field is fitted to the surface card here.

What follows from the description (docs/realism.md):
- each taper's mass per length is the record's weight in lb/ft (rod body plus couplings): the steel body's
  share is the body density times the area, the rest is ``coupling_mass_kg_per_m``;
- the liquid's density is the well test's water cut mixing the water's specific gravity and the oil's API
  gravity (or the record's fluid density);
- the pump sits at its own depth, below the listed rods where the record says so: ``pump.depth_m``
  (physics.pump_inputs: the liquid column between the rod string's end and the pump enters the valve law as
  an intake pressure lower by its weight; the rod end's true load keeps the pressure at the rod end);
- a pump that does not fill (fillage f < 1) is ``pump.fillage``: free gas in the intake whose compression
  takes (1 - f) of the stroke (``physics.pump.gas_fraction_for_fillage``).
"""

from __future__ import annotations

import math

import numpy as np

from ..errors import ConfigError
from ..physics.rod import GRAVITY_M_S2
from .field_record import FieldRecord

STEEL_DENSITY_KG_M3 = 7850.0
DEFAULT_DAMPING_FACTOR = 0.02        # the vendor's own range on 11708328 (0.009-0.038; docs/realism.md)
DEFAULT_KV_TAU_S = 0.03              # Kelvin-Voigt retardation time of the string (docs/realism.md)
MIN_INTAKE_PA = 101325.0       # a pump intake below atmospheric is read as pumped off at one atmosphere
CLEARANCE_FRACTION = 0.05
TUBING_ID_M = 0.062            # 2 7/8-in tubing (srenv's tubing default) where the record names none
# isothermal compressibilities of produced water and of crude oil (3e-6 and 10e-6 1/psi, the textbook values
# of reservoir-engineering tables; the records give neither): the chamber's liquid as a spring (docs/realism.md)
WATER_COMPRESSIBILITY_PER_PA = 3e-6 / 6894.757293168
OIL_COMPRESSIBILITY_PER_PA = 10e-6 / 6894.757293168


def _qp_solver() -> str:
    """The project's default backend where installed (proxqp), else the first installed one."""
    try:
        import qpsolvers

        avail = list(qpsolvers.available_solvers)
    except ImportError:
        return "proxqp"
    return "proxqp" if "proxqp" in avail or not avail else min(avail)


def tapers(rec: FieldRecord) -> list[dict]:
    """The record's tapers as config tapers: a steel body plus couplings making up the record's weight; a taper
    lighter than a steel bar of its diameter (fiberglass) is a body of its own density (weight / area)."""
    out = []
    for t in rec.tapers:
        area = math.pi / 4 * t["diameter_m"] ** 2
        density = min(STEEL_DENSITY_KG_M3, t["weight_kg_m"] / area)
        out.append({"diameter_mm": 1e3 * t["diameter_m"], "length_m": t["length_m"],
                    "youngs_modulus_pa": t["youngs_modulus_pa"], "density_kg_m3": density,
                    "coupling_mass_kg_per_m": max(t["weight_kg_m"] - density * area, 0.0),
                    "grade": t["grade"] if t["grade"] in ("C", "K", "D") else "D"})
    return out


def fluid_column_kg(rec: FieldRecord, tubing_inner_diameter_m: float = TUBING_ID_M) -> float:
    """The liquid column lifted with the plunger as a mass at the plunger, summed over the tapers' annuli
    (and the gap below the rods at the bottom taper's area); the records give no tubing: 2 7/8-in by default."""
    from ..physics.pump import fluid_column_mass_kg

    a_t = math.pi / 4 * tubing_inner_diameter_m ** 2
    a_pl = math.pi / 4 * rec.plunger_diameter_m ** 2
    lengths = [t["length_m"] for t in rec.tapers]
    lengths[-1] += max(rec.pump_depth_m - rec.rod_length_m, 0.0)
    return float(sum(fluid_column_mass_kg(rec.fluid_density_kg_m3, h, a_pl, a_t, math.pi / 4 * t["diameter_m"] ** 2)
                     for h, t in zip(lengths, rec.tapers)))


SURVEY_WEIGHTS = ("inclination", "tvd")


def survey_stations(rec: FieldRecord, survey_weight: str = "inclination") -> list[dict]:
    """The survey the model takes from the record (md_m, inclination_deg, azimuth_deg; [] = vertical).

    ``inclination`` (the physics, the default): the record's inclinations. ``tvd``: the record's own TVD
    column, each interval's inclination arccos(dTVD / dMD) - the convention of a record whose TVD column was
    written vertical (7699227: TVD = MD at every station while the inclination reaches 40 deg; the vendor's
    diagnosis follows it, docs/realism.md "The static load budget"). A station without a TVD is refused."""
    if survey_weight not in SURVEY_WEIGHTS:
        raise ConfigError("--survey-weight", survey_weight, f"one of {', '.join(SURVEY_WEIGHTS)}")
    rows = [s for s in rec.survey if s["md_m"] > 0.0]
    if not rows:
        return []
    if survey_weight == "inclination":
        incl = [s["inclination_deg"] for s in rows]
    else:
        missing = [i for i, s in enumerate(rec.survey) if s.get("tvd_m") is None]
        if missing:
            raise ConfigError(f"surveyData[{missing[0]}].TVD", "missing", "a TVD at every station for "
                              "--survey-weight tvd")
        prev = [{"md_m": 0.0, "tvd_m": 0.0}] + rows[:-1]
        incl = [math.degrees(math.acos(min(max((s["tvd_m"] - p["tvd_m"]) / (s["md_m"] - p["md_m"]), -1.0), 1.0)))
                if s["md_m"] > p["md_m"] else 0.0 for s, p in zip(rows, prev)]
    return [{"md_m": 0.0, "inclination_deg": 0.0, "azimuth_deg": 0.0}] + [
        {"md_m": s["md_m"], "inclination_deg": i, "azimuth_deg": s["azimuth_deg"]} for s, i in zip(rows, incl)]


def pump_tvd_m(rec: FieldRecord, survey_weight: str = "inclination") -> float:
    """True vertical depth of the pump from the record's survey (minimum curvature approximated by the
    trapezoidal rule on cos(inclination) every metre; vertical without a survey)."""
    stations = survey_stations(rec, survey_weight)
    if not stations:
        return rec.pump_depth_m
    md = np.array([s["md_m"] for s in stations])
    inc = np.radians([s["inclination_deg"] for s in stations])
    grid = np.linspace(0.0, rec.pump_depth_m, max(int(rec.pump_depth_m), 2))
    c = np.cos(np.interp(grid, md, inc))
    return float(np.sum(0.5 * (c[1:] + c[:-1]) * np.diff(grid)))


def discharge_pressure_pa(rec: FieldRecord, survey_weight: str = "inclination") -> float:
    """Hydrostatic tubing pressure at the pump: tubing-head pressure plus the liquid column."""
    return rec.tubing_pressure_pa + rec.fluid_density_kg_m3 * GRAVITY_M_S2 * pump_tvd_m(rec, survey_weight)


def pump_drag_n(rec: FieldRecord, fluid_load_n: float | None, intake_pressure_pa: float,
                survey_weight: str = "inclination") -> float:
    """The plunger's friction read off a diagnosed fluid load: the diagnosed load step between the upstroke
    and downstroke plateaus is (p_d - p_in) A_pl + 2 P_f, so P_f = (F_fluid - (p_d - p_in) A_pl) / 2 with the
    hydrostatic p_d (0 when the diagnosis carries no more than the pressures)."""
    if fluid_load_n is None:
        return 0.0
    a_pl = math.pi / 4 * rec.plunger_diameter_m ** 2
    return max(0.0, 0.5 * (fluid_load_n - (discharge_pressure_pa(rec, survey_weight) - intake_pressure_pa) * a_pl))


def liquid_compressibility_per_pa(rec: FieldRecord) -> float:
    """The produced liquid's compressibility from the well test's water cut (all oil without one)."""
    wc = (rec.water_cut or 0.0) / 100.0
    return wc * WATER_COMPRESSIBILITY_PER_PA + (1.0 - wc) * OIL_COMPRESSIBILITY_PER_PA


def well_config(rec: FieldRecord, card_csv: str, intake_pressure_pa: float, fillage: float = 1.0,
                plunger_friction_n: float = 0.0, damping_factor: float = DEFAULT_DAMPING_FACTOR,
                friction_coefficient: float = 0.0, survey_weight: str = "inclination") -> dict:
    """The config dict of the record's well, driven by the measured motion in `card_csv` (t_s, position)."""
    stations = survey_stations(rec, survey_weight)
    # a pump below the listed rods is pump.depth_m; the intake at the pump is read as one atmosphere at least
    depth = rec.pump_depth_m if rec.pump_depth_m > rec.rod_length_m else None
    return {
        "name": "field-record",
        "description": f"built from {rec.source} by srenv validate",
        "rod": {"tapers": tapers(rec)},
        "fluid": {"density_kg_m3": rec.fluid_density_kg_m3, "wellhead_pressure_pa": rec.tubing_pressure_pa},
        "pump": {"load_source": "pressures", "plunger_diameter_mm": 1e3 * rec.plunger_diameter_m,
                 "intake_pressure_pa": max(intake_pressure_pa, MIN_INTAKE_PA), "depth_m": depth,
                 "plunger_friction_n": plunger_friction_n,
                 "fillage": min(max(fillage, 0.05), 1.0), "clearance_volume_fraction": CLEARANCE_FRACTION,
                 "liquid_compressibility_per_pa": liquid_compressibility_per_pa(rec)},
        "damping": {"model": "dimensionless", "damping_factor": damping_factor,
                    "stiffness_proportional_s": DEFAULT_KV_TAU_S},
        "survey": {"stations": stations},
        "friction": {"coefficient": friction_coefficient},
        "surface": {"motion": "measured", "measured_card_csv": card_csv, "measured_spm": rec.spm,
                    "stroke_length_m": float(rec.position_m.max() - rec.position_m.min())},
        "simulation": {"qp_solver": _qp_solver()},
    }


def unit_from_record(rec: FieldRecord):
    """The record's unit from its inline API dimensions (A, C, I, K, P, R, geometry, rotation, unbalance) as
    a ``surface.beam_unit`` block (conventional, Mark II or air-balanced), or None when the record names a
    geometry srenv does not know or lacks a dimension."""
    from ..config import _parse
    from ..config_sections import BeamUnitConfig
    from ..surface_unit.inline_unit import inline_unit, record_unit_config

    block = record_unit_config(rec.unit)
    if block is None:
        return None
    try:
        return inline_unit(_parse(BeamUnitConfig, block, "equipmentData.SurfaceUnit"))
    except ConfigError:  # a nameplate that cannot close (or out of range): no unit, the record stays usable
        return None


# a polished-rod position whose samples are one harmonic of time to within this share of the stroke was not
# measured: every beam unit's four-bar puts 2-8 % of the first harmonic's amplitude in the second
SYNTHETIC_POSITION_RMS = 0.002


def position_is_synthesised(position_m: np.ndarray) -> bool:
    """True when the card's position samples (one stroke, equal times) are a pure first harmonic of time: a
    controller that measures load only and writes x = S (1 - cos ωt)/2 (docs/realism.md, 11708328)."""
    x = np.asarray(position_m, dtype=float)
    c = np.fft.rfft(x - x.mean())
    c[2:] = 0.0
    fit = np.fft.irfft(c, len(x)) + x.mean()
    return bool(np.sqrt(np.mean((fit - x) ** 2)) < SYNTHETIC_POSITION_RMS * np.ptp(x))


def unit_position_for_card(rec: FieldRecord, crank=None) -> np.ndarray | None:
    """The polished-rod position of the record's own unit (its API dimensions and rotation) at each card sample,
    at constant crank speed from the card's bottom sample (or on a motor's crank profile,
    ``surface_unit.motor.CrankProfile``), scaled to the card's stroke; None without a unit."""
    cu = unit_from_record(rec)
    if cu is None:
        return None
    n = len(rec.position_m)
    k0 = int(np.argmin(rec.position_m))
    if crank is None:
        past_bottom = 2 * np.pi * (np.arange(n) - k0) / n
    else:
        past_bottom = crank.angle_and_speed((np.arange(n) - k0) * (rec.period_s / n))[0]
    p = np.asarray(cu.position_m(cu.theta_bottom + past_bottom), dtype=float)
    return (p - p[k0]) * (float(np.ptp(rec.position_m)) / cu.stroke_m)


HP_W = 745.6998715822702  # one mechanical horsepower, W


def record_motor(rec: FieldRecord) -> dict | None:
    """The record's ``equipmentData.RodPumpMotor`` as a ``surface.motor`` block plus where each item came from:
    rated power from ``HP``, the NEMA design letter from ``Model`` ('Nema D'); the rated slip is the design's
    nominal (the record's ``SlipTorque`` is not a slip: 3 on a NEMA B and a NEMA D motor alike, its meaning is
    not documented), the inertia not given (0: the quasi-static slip line, docs/realism.md). None when the
    record names no motor, no power or no NEMA design B, C or D."""
    import re

    from ..surface_unit.motor import NEMA_DESIGNS

    motor = rec.motor  # read with the record (field_record.read_dynacard_json), not from its file again
    hp, model = motor.get("HP"), str(motor.get("Model") or "")
    letter = re.fullmatch(r"\s*(?:nema)?\s*(?:design)?\s*([a-z])\s*", model, flags=re.IGNORECASE)
    if not isinstance(hp, (int, float)) or isinstance(hp, bool) or not 0 < hp < 1e4 or letter is None:
        return None
    design = letter.group(1).upper()
    if design not in NEMA_DESIGNS:
        return None
    return {"block": {"nema_design": design, "rated_power_w": float(hp) * HP_W, "rated_slip": None,
                      "inertia_kg_m2": 0.0},
            "source": {"rated_power_w": f"equipmentData.RodPumpMotor.HP = {hp}",
                       "nema_design": f"equipmentData.RodPumpMotor.Model = {model!r}",
                       "rated_slip": f"NEMA {design} nominal {NEMA_DESIGNS[design][0]:g} (the record's SlipTorque = "
                                     f"{motor.get('SlipTorque')!r} is not read: its meaning is not documented)",
                       "inertia_kg_m2": "not in the record: 0, the quasi-static slip line"}}


def unit_kinematics_check(rec: FieldRecord) -> dict | None:
    """The record's unit at constant crank speed against its measured polished-rod position: stroke error and
    the RMS position difference (best time alignment over the card's samples), in % of the measured stroke."""
    cu = unit_from_record(rec)
    if cu is None:
        return None
    n = len(rec.position_m)
    stroke = float(np.ptp(rec.position_m))
    base = cu.theta_bottom + 2 * np.pi * np.arange(n) / n
    best = min(float(np.sqrt(np.mean((np.asarray(cu.position_m(base - 2 * np.pi * k / n)) - rec.position_m) ** 2)))
               for k in range(n))
    return {"unit_stroke_error_pct": 100.0 * (cu.stroke_m / stroke - 1.0),
            "unit_position_rms_pct_of_stroke": 100.0 * best / stroke,
            "unit_rotation": cu.geometry.rotation, "unit_geometry": cu.geometry.kind}
