"""Field records: a measured card with the well it came from, read from the public vendor dynacard JSON layout
(``docs/realism.md``; e.g. the exports in github.com/vamseeachanta/digitalmodel, MIT) or from srenv's own
card CSV plus well YAML. Field units are converted once, by ``srenv.field_units``; the record holds SI.

The JSON is read as data (``json``, bounded size); every number used is checked finite and in range, and a
missing or malformed item is one ConfigError naming its key. The card passes ``card_checks`` (a record
stored in reverse time needs ``reverse=True``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .. import field_units as fu
from ..errors import ConfigError
from ..input_files import read_json
from ..surface_unit.card_checks import check_card, check_magnitude, loop_work
from .record_extras import card_type, coefficients, ideal_card, pump_card
from .record_fields import FIELDS, absent_notes, number, raw, series, spelling_notes

MAX_RECORD_BYTES = 20_000_000


@dataclass
class FieldRecord:
    source: str
    t_s: np.ndarray                      # the surface card, forward time, one stroke
    position_m: np.ndarray               # polished-rod position, upward from the bottom
    load_n: np.ndarray                   # polished-rod load (load cell: true load), N
    spm: float
    tapers: list[dict]                   # top-down: diameter_m, length_m, youngs_modulus_pa, weight_kg_m, grade
    pump_depth_m: float
    plunger_diameter_m: float
    tubing_pressure_pa: float
    fluid_density_kg_m3: float
    survey: list[dict] = field(default_factory=list)   # md_m, inclination_deg, azimuth_deg, tvd_m (or None)
    water_cut: float | None = None
    intake_pressure_pa: float | None = None            # the vendor's analysis, where it has one
    fillage: float | None = None
    fluid_load_n: float | None = None
    pump_position_m: np.ndarray | None = None          # the vendor's pump card (effective loads)
    pump_load_n: np.ndarray | None = None
    damping_coefficients: list[float] = field(default_factory=list)
    unit: dict = field(default_factory=dict)           # API 11E dimensions (m) and names, as given
    time_reversed: bool = False                        # the stored card ran in reverse time
    config: dict | None = None                         # srenv's own record: the well YAML (its model)
    notes: list[str] = field(default_factory=list)     # what the reader filled in or found doubtful
    motion_from_unit: bool = False                     # positions are the record's unit's (validate), not stored
    card_type: str | None = None                       # the vendor's card type (Startup, Shutdown, ...)
    # the vendor's own prediction of the record's full-pump surface card (its "ideal card"): PPRL, MPRL (N)
    reference_prediction: dict | None = None
    motor: dict = field(default_factory=dict)          # equipmentData.RodPumpMotor as given (field_model.record_motor)

    @property
    def period_s(self) -> float:
        return 60.0 / self.spm

    @property
    def rod_length_m(self) -> float:
        return float(sum(t["length_m"] for t in self.tapers))


def _section(d: dict, key: str, where: str, required: bool = True) -> dict:
    """A JSON object of the record ({} when optional and absent); anything else is one ConfigError."""
    v = raw(d, key, where)
    if v is None and not required:
        return {}
    if not isinstance(v, dict):
        raise ConfigError(f"{where}.{key}", "missing" if v is None else type(v).__name__, "a JSON object")
    return v


# API RP 11L (5th ed., 1988), Table 4.1 "Rod and pump data", column w_r: steel sucker rods with their couplings,
# lb/ft by rod size in inches; used when a record gives a taper no weight
API_ROD_WEIGHT_LB_FT = {0.5: 0.726, 0.625: 1.135, 0.75: 1.634, 0.875: 2.224, 1.0: 2.904, 1.125: 3.676}
STEEL_LB_FT_PER_IN2 = 3.40  # 490 lb/ft^3 steel: a bar's body weight per square inch of section (sinker bars)


def rod_weight_lb_ft(diameter_in: float) -> tuple[float, str]:
    """A taper's weight per length when the record has none: the API table for API rod sizes, else a plain steel
    bar (sinker bars, whose couplings add a few percent); and where the figure came from."""
    for size, w in API_ROD_WEIGHT_LB_FT.items():
        if abs(diameter_in - size) < 0.01:
            return w, "API RP 11L Table 4.1 (rod with couplings)"
    return STEEL_LB_FT_PER_IN2 * math.pi / 4 * diameter_in ** 2, "steel bar body (3.40 lb/ft per in^2)"


NOT_STEEL = 0.6      # a taper lighter than this share of a steel bar of its diameter is not steel (fiberglass)


def _taper(r, w: str, notes: list[str]) -> dict:
    if not isinstance(r, dict):
        raise ConfigError(w, r, "a JSON object (Diameter, TotalLength, ModulusOfElasticity, Weight, Grade)")
    d_m = number(r, "Diameter", w)
    weight = number(r, "Weight", w)
    if weight is None:
        lb_ft, how = rod_weight_lb_ft(d_m / fu.factor("in"))
        weight = fu.to_si(lb_ft, "lb/ft")
        notes.append(f"{w}.Weight missing: {lb_ft:.3f} lb/ft from {how}")
    length = number(r, "TotalLength", w)
    if length is None:
        count, each = number(r, "Count", w), number(r, "IndividualLength", w)
        if count is None or each is None:
            raise ConfigError(f"{w}.TotalLength", "missing", "a number in ft (or Count and IndividualLength)")
        length = count * each
        notes.append(f"{w}.TotalLength missing: Count x IndividualLength = {fu.from_si(length, 'ft'):g} ft")
    steel_bar = fu.to_si(STEEL_LB_FT_PER_IN2 * math.pi / 4 * (d_m / fu.factor("in")) ** 2, "lb/ft")
    if raw(r, "ModulusOfElasticity", w) is None and weight < NOT_STEEL * steel_bar:
        raise ConfigError(f"{w}.ModulusOfElasticity", "missing", "a number in psi: the taper weighs "
                          f"{fu.from_si(weight, 'lb/ft'):.3g} lb/ft, lighter than steel (fiberglass?), so no default")
    grade = raw(r, "Grade", w)
    if grade is None:
        notes.append(f"{w}.Grade missing: D (its tensile strength enters the Goodman loading only)")
    return {"diameter_m": d_m, "length_m": length, "youngs_modulus_pa": number(r, "ModulusOfElasticity", w, notes),
            "weight_kg_m": weight, "grade": str(grade or "D")}


def _tapers(rods: list, where: str, notes: list[str]) -> list[dict]:
    if not isinstance(rods, list) or not rods:
        raise ConfigError(where, "missing" if not rods else type(rods).__name__, "a list of rod tapers (top-down)")
    return [_taper(r, f"{where}[{i}]", notes) for i, r in enumerate(rods)]


def _depth_notes(rec: FieldRecord) -> list[str]:
    """A pump far below (or above) the listed rods usually means a taper missing from the record: said, not
    refused (the model then hangs the listed rods and takes the liquid column between them and the pump)."""
    gap = rec.pump_depth_m - rec.rod_length_m
    if gap < -0.01 * rec.pump_depth_m or gap > 0.1 * rec.pump_depth_m:
        return [(f"the rod tapers sum to {fu.from_si(rec.rod_length_m, 'ft'):.0f} ft against a pump depth of "
                 f"{fu.from_si(rec.pump_depth_m, 'ft'):.0f} ft: check the record's rod string (a taper missing?)")]
    return []


UNIT_DIMENSIONS = ("DimensionalA", "DimensionalC", "DimensionalI", "DimensionalK", "DimensionalP", "Radius")
UNIT_KEYS = {k: k[-1] if k != "Radius" else "R" for k in UNIT_DIMENSIONS}  # the record's key -> API letter


def _unit(su: dict, where: str, notes: list[str]) -> dict:
    from ..surface_unit.inline_unit import record_geometry, record_rotation_known

    if not su:
        notes.append(f"{where} missing: no unit kinematics")
        return {}
    out = {letter: number(su, k, where) for k, letter in UNIT_KEYS.items()}
    out["geometry"] = raw(su, "PumpingUnitGeometry", where)
    out["rotation"] = raw(su, "Rotation", where)
    missing = [k for k, letter in UNIT_KEYS.items() if out[letter] is None]
    if record_geometry(out["geometry"]) is None:
        notes.append(f"{where}.PumpingUnitGeometry = {out['geometry']!r}: not a known API geometry (C, M, A): "
                     "no unit kinematics")
    elif missing:
        notes.append(f"{where}.{missing[0]} missing: no unit kinematics")
    elif not record_rotation_known(out["rotation"]):
        notes.append(f"{where}.Rotation = {out['rotation']!r}: not a known rotation: clockwise (the API default)")
    out["structural_unbalance_n"] = number(su, "StructuralImbalance", where, notes)
    # the layout gives the gearbox rating and the counterbalance moment in thousands of in-lb, the phase angle
    # (a Mark II's crank offset) in degrees; srenv.surface_unit.inline_unit maps them onto surface.beam_unit
    rating, moment = number(su, "GearBoxRating", where), number(su, "CounterbalanceMoment", where)
    notes += absent_notes(where, {"GearBoxRating": rating, "CounterbalanceMoment": moment})
    out["torque_rating_nm"] = None if rating is None else fu.to_si(1e3 * rating, "in") * fu.to_si(1.0, "lbf")
    out["counterbalance_moment_nm"] = None if moment is None else fu.to_si(1e3 * moment, "in") * fu.to_si(1.0, "lbf")
    out["phase_angle_deg"] = number(su, "PhaseAngle", where, notes)
    return out


def load_record_json(path: str | Path):
    """The parsed JSON of a record file (data only: ``json``, at most MAX_RECORD_BYTES), any JSON value."""
    p = Path(path)
    if not p.is_file():
        raise ConfigError("RECORD", str(path), "an existing field record file (.json, or .csv with --config)")
    return read_json(p, "RECORD", "record", MAX_RECORD_BYTES)


def _card(d: dict, source: str, reverse: bool, auto_orient: bool) -> tuple[np.ndarray, np.ndarray, bool]:
    """The surface card (m, N) forward in time, checked (``card_checks``), and whether it was stored reversed."""
    cd = _section(d, "cardData", "record")
    x_in, f_lbf = series(cd, "Position", "cardData"), series(cd, "Load", "cardData")
    for what, values in (("positions", x_in), ("loads", f_lbf)):  # as read: the unit conversion would overflow
        check_magnitude(values, "cardData", source, what)
    if len(x_in) != len(f_lbf):
        raise ConfigError("cardData", f"{len(x_in)} positions, {len(f_lbf)} loads", "one load per position")
    x_m, f_n = fu.to_si(x_in, "in"), fu.to_si(f_lbf, "lbf")
    if auto_orient and len(x_m) == len(f_n) and np.all(np.isfinite(x_m)) and np.all(np.isfinite(f_n)):
        reverse = reverse or loop_work(x_m, f_n) < 0
    x, f = check_card(x_m, f_n, "cardData", source, reverse)
    return x, f, reverse


EQUIPMENT = ("Pump", "Rods", "SurfaceUnit", "WellBore", "RodPumpMotor")


def _equipment(d: dict, notes: list[str]) -> dict:
    """``equipmentData``; the layout's ``dynaoutputData`` copy where the record has no equipmentData (said), and a
    copy that disagrees with it is said (equipmentData is read)."""
    eq = raw(d, "equipmentData", "record")
    dyn = _section(d, "dynaoutputData", "record", required=False)
    if eq is None and any(k in dyn for k in EQUIPMENT):
        notes.append("record.equipmentData missing: the equipment is read from dynaoutputData (the vendor's copy)")
        return dyn
    eq = _section(d, "equipmentData", "record")
    notes += [f"dynaoutputData.{k} differs from equipmentData.{k}: equipmentData is read" for k in EQUIPMENT
              if dyn.get(k) is not None and eq.get(k) is not None and dyn[k] != eq[k]]
    return eq


def _fluid(d: dict, eq: dict, ip: dict, notes: list[str]) -> tuple[float | None, float]:
    """The well test's water cut (fraction, None without one) and the liquid's density (kg/m^3)."""
    wb = _section(eq, "WellBore", "equipmentData", required=False)
    wt = _section(d, "WellTestData", "record", required=False)
    wcut = number(wt, "WaterCut", "WellTestData")
    if wcut is None:
        notes.append("WellTestData.WaterCut missing: 0 % (all oil) for the liquid's density and compressibility")
    rho_given = number(ip, "FluidDensity", "InputParameters")
    where = "equipmentData.WellBore"
    taken: list[str] = []  # the gravities' defaults, said where the density is made of them
    api, sgw = number(wb, "OilApi", where, taken), number(wb, "WaterGravity", where, taken)
    if rho_given is not None:
        return wcut, rho_given
    notes += taken
    return wcut, fu.liquid_density_kg_m3(wcut if wcut is not None else 0.0, sgw, api)


def _analysis(d: dict, notes: list[str]) -> dict:
    """The vendor's diagnosis (intake pressure, fillage, fluid load; SI), where the record has one."""
    an = _section(d, "downholeCardAnalysis", "record", required=False)
    where = "downholeCardAnalysis"
    out = {"intake_pressure_pa": number(an, "Pump Intake Pressure", where),
           "fillage": number(an, "Pump Fillage", where), "fluid_load_n": number(an, "Fluid Load", where)}
    if out["intake_pressure_pa"] is not None:
        notes += absent_notes(where, {"Pump Fillage": out["fillage"], "Fluid Load": out["fluid_load_n"]})
    return out


def _spm(d: dict, ip: dict, notes: list[str]) -> float:
    """The record's stroke rate: ``InputParameters.StrokesPerMinute``, else the vendor analysis's own reading
    (``downholeCardAnalysis.SPM``, two decimals), said; else one ConfigError."""
    spm = number(ip, "StrokesPerMinute", "InputParameters")
    if spm is not None:
        return spm
    spm = number(_section(d, "downholeCardAnalysis", "record", required=False), "SPM", "downholeCardAnalysis")
    if spm is None:
        raise ConfigError("InputParameters.StrokesPerMinute", "missing",
                          FIELDS["InputParameters.StrokesPerMinute"].number.expected() + " (or downholeCardAnalysis.SPM)")
    notes.append(f"InputParameters.StrokesPerMinute missing: downholeCardAnalysis.SPM = {spm:g} (the vendor's reading)")
    return spm


def read_dynacard_json(path: str | Path, reverse: bool = False, auto_orient: bool = False) -> FieldRecord:
    """A vendor dynacard export (``cardData``, ``equipmentData``, ``InputParameters``, ...). The layout stores
    cards in either time direction: with `auto_orient` a reversed card is turned forward (and the record says
    so, ``time_reversed``); otherwise it is refused unless `reverse`. The fields read, their bounds and the
    defaults taken are declared once (``record_fields``); every default taken is said in ``notes``."""
    d = load_record_json(path)
    if not isinstance(d, dict):
        raise ConfigError("RECORD", str(path), "a JSON object (the dynacard layout)")
    notes: list[str] = []
    with spelling_notes(notes):  # a key the record spells its own way is read, and said
        eq = _equipment(d, notes)
        x, f, reverse = _card(d, str(path), reverse, auto_orient)
        ip = _section(d, "InputParameters", "record")
        spm = _spm(d, ip, notes)
        pump = _section(eq, "Pump", "equipmentData")
        tapers = _tapers(raw(eq, "Rods", "equipmentData"), "equipmentData.Rods", notes)
        wcut, rho = _fluid(d, eq, ip, notes)
        rec = FieldRecord(
            notes=notes, source=str(path), time_reversed=reverse, t_s=np.arange(len(x)) * (60.0 / spm / len(x)),
            position_m=x - x.min(), load_n=f, spm=spm, tapers=tapers,
            pump_depth_m=number(pump, "Depth", "equipmentData.Pump"),
            plunger_diameter_m=number(pump, "Diameter", "equipmentData.Pump"),
            tubing_pressure_pa=number(ip, "TubingPressure", "InputParameters", notes),
            fluid_density_kg_m3=rho, survey=_survey(raw(d, "surveyData", "record"), notes), water_cut=wcut,
            **_analysis(d, notes),
            damping_coefficients=coefficients(eq.get("DampingCoefficient") or _section(
                d, "dynaoutputData", "record", required=False).get("DampingCoefficient")),
            unit=_unit(_section(eq, "SurfaceUnit", "equipmentData", required=False), "equipmentData.SurfaceUnit", notes))
        rec.notes += _depth_notes(rec)
        rec.card_type = card_type(d.get("CardDetails"))
        motor = eq.get("RodPumpMotor")
        rec.motor = motor if isinstance(motor, dict) else {}
        rec.reference_prediction = ideal_card(d.get("Performance"), float(np.ptp(rec.position_m)), notes)
        rec.pump_position_m, rec.pump_load_n = pump_card(d.get("downholeCard"), notes)
        return rec


def _survey(rows, notes: list[str]) -> list[dict]:
    """The record's stations (SI, sorted by MD); [] for a vertical well. No survey, an empty one or one station
    is a vertical well, said; a station's missing inclination or azimuth is 0, said once per column; a station
    repeated is dropped, said; two stations at one MD that disagree are refused."""
    if rows is not None and not isinstance(rows, list):
        raise ConfigError("surveyData", rows, "a list of stations (MD, Inclination, Azimuth, TVD)")
    if not rows or len(rows) == 1:
        notes.append(f"surveyData {'missing' if not rows else 'has one station'}: a vertical well")
    out, taken = [], []
    for i, s in enumerate(rows or []):
        w = f"surveyData[{i}]"
        if not isinstance(s, dict):
            raise ConfigError(w, s, "a JSON object (MD, Inclination, Azimuth, TVD)")
        out.append({"md_m": number(s, "MD", w), "inclination_deg": number(s, "Inclination", w, taken),
                    "azimuth_deg": number(s, "Azimuth", w, taken),
                    # the record's own TVD column, read for `validate --survey-weight tvd` only (docs/realism.md)
                    "tvd_m": number(s, "TVD", w), "row": i})
    for key in ("Inclination", "Azimuth"):
        n = sum(f".{key} missing" in t for t in taken)
        if n:
            notes.append(f"surveyData[].{key} missing at {n} of {len(rows)} stations: 0 deg")
    out.sort(key=lambda s: s["md_m"])
    kept = [s for k, s in enumerate(out) if k == 0 or s["md_m"] != out[k - 1]["md_m"] or _disagree(out[k - 1], s)]
    if len(kept) < len(out):
        notes.append(f"surveyData: {len(out) - len(kept)} repeated station(s) dropped")
    for s in kept:
        s.pop("row")
    return kept if any(s["inclination_deg"] > 0 for s in kept) else []


def _disagree(a: dict, b: dict) -> bool:
    """Two stations at one MD: the same (a repeat, False) or one ConfigError naming the second."""
    if (a["inclination_deg"], a["azimuth_deg"]) == (b["inclination_deg"], b["azimuth_deg"]):
        return False
    raise ConfigError(f"surveyData[{b['row']}].MD", fu.from_si(b["md_m"], "ft"), f"a depth of its own (surveyData["
                      f"{a['row']}] is at the same MD with another inclination or azimuth)")


def read_record_csv(path: str | Path, config: str, reverse: bool = False) -> FieldRecord:
    """srenv's own record: a card CSV (``t_s, polished_rod_position_m, polished_rod_load_n``, SI or a unit row;
    the last stroke is used) with the well YAML it came from (the tapers, fluid, pump and survey of the config;
    the pump's state from srenv's diagnosis)."""
    from ..config import config_from_dict, read_raw
    from ..surface_unit.measured_motion import last_stroke, read_card_csv, stroke_period_s

    raw = read_raw(config)
    cfg = config_from_dict(raw)
    cols = read_card_csv(path, "RECORD", ("t_s", "polished_rod_position_m", "polished_rod_load_n"),
                         reverse=reverse)
    t, x, f = cols["t_s"], cols["polished_rod_position_m"], cols["polished_rod_load_n"]
    period = 60.0 / cfg.surface.measured_spm if cfg.surface.measured_spm > 0 else stroke_period_s(t, x)
    keep = last_stroke(t, period)
    t, x, f = t[keep] - t[keep][0], x[keep], f[keep]
    tp = [{"diameter_m": 1e-3 * tp.diameter_mm, "length_m": tp.length_m, "youngs_modulus_pa": tp.youngs_modulus_pa,
           "weight_kg_m": tp.density_kg_m3 * math.pi / 4 * (1e-3 * tp.diameter_mm) ** 2 + tp.coupling_mass_kg_per_m,
           "grade": tp.grade} for tp in cfg.rod.tapers]
    return FieldRecord(
        source=str(path), t_s=t, position_m=x - x.min(), load_n=f, spm=60.0 / period, tapers=tp,
        pump_depth_m=cfg.rod_length_m, plunger_diameter_m=1e-3 * cfg.pump.plunger_diameter_mm,
        tubing_pressure_pa=cfg.fluid.wellhead_pressure_pa, fluid_density_kg_m3=cfg.fluid.density_kg_m3,
        survey=[{"md_m": s.md_m, "inclination_deg": s.inclination_deg, "azimuth_deg": s.azimuth_deg}
                for s in cfg.survey.stations], config=raw)
