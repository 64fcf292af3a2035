"""The numeric fields srenv reads from a vendor dynacard record, declared once: each field's path in the record,
the field unit its value is in, its physical range (in that unit), whether the record is refused without it,
and what is taken when it is absent, null or an empty string (docs/field.md has the same table, written from
this one; tests/test_declared_record.py generates its refusal cases from it).

A value may be a JSON number or a number written as text (the layout writes its analysis as strings: '239',
'95.4%'); anything else - another text, a boolean, a list, NaN, infinity, or a number out of range - is one
``ConfigError`` naming the field, the value and what is expected. A key that is absent while a key spelt
the same but for case, spaces or underscores is present is read under that spelling (said in the notes): a
default is never taken for a field the record holds under another spelling, and an export that spells its keys
its own way still runs.
"""

from __future__ import annotations

import contextlib
import math
import re
from collections.abc import Iterator
from contextvars import ContextVar
from dataclasses import dataclass

import numpy as np

from .. import field_units as fu
from ..declarations import Number
from ..errors import ConfigError


@dataclass(frozen=True)
class RecordField:
    number: Number      # name: the field's path ('[]' for a list's items), unit as shown, range in the field unit
    unit: str           # the field unit the record writes it in (srenv.field_units); '-' dimensionless
    required: bool
    default: float | None = None   # the value taken when absent, in the field unit (None: see `absent`)
    absent: str = ""    # what the reader does without it (docs/field.md; said in the record's notes)


def _f(path: str, unit: str, lo: float, hi: float, *, shown: str | None = None, required: bool = False,
       default: float | None = None, absent: str = "") -> tuple[str, RecordField]:
    shown = unit if shown is None else shown
    return path, RecordField(Number(path, float, shown, lo, hi, lo_open=False), unit, required, default, absent)


FIELDS: dict[str, RecordField] = dict([
    _f("InputParameters.StrokesPerMinute", "-", 0.5, 20.0, shown="strokes/min",
       absent="downholeCardAnalysis.SPM (the vendor's reading), else refused"),
    _f("downholeCardAnalysis.SPM", "-", 0.5, 20.0, shown="strokes/min", absent="read only without a StrokesPerMinute"),
    _f("InputParameters.TubingPressure", "psi", 0.0, 5000.0, default=0.0, absent="0 psi (tubing open to the flowline)"),
    _f("InputParameters.FluidDensity", "kg/m^3", 500.0, 1500.0,
       absent="from the well test's water cut, the water's gravity and the oil's API gravity"),
    _f("equipmentData.Pump.Depth", "ft", 100.0, 17000.0, required=True),
    _f("equipmentData.Pump.Diameter", "in", 0.5, 6.0, required=True),
    _f("equipmentData.Rods[].Diameter", "in", 0.3, 2.5, required=True),
    _f("equipmentData.Rods[].TotalLength", "ft", 1.0, 20000.0, absent="Count x IndividualLength (both given)"),
    _f("equipmentData.Rods[].Count", "-", 1.0, 1000.0, shown="rods", absent="read only without a TotalLength"),
    _f("equipmentData.Rods[].IndividualLength", "ft", 1.0, 50.0, absent="read only without a TotalLength"),
    _f("equipmentData.Rods[].ModulusOfElasticity", "psi", 1e6, 4e7, default=30.5e6,
       absent="30.5e6 psi (steel) unless the taper's weight is below a steel bar's: then refused"),
    _f("equipmentData.Rods[].Weight", "lb/ft", 0.1, 15.0,
       absent="API RP 11L Table 4.1 for API rod sizes, else a steel bar's body (3.40 lb/ft per in^2)"),
    _f("equipmentData.WellBore.OilApi", "-", 5.0, 80.0, shown="deg API", default=35.0, absent="35 deg API"),
    _f("equipmentData.WellBore.WaterGravity", "-", 0.9, 1.4, shown="(specific gravity)", default=1.0, absent="1.0"),
    _f("WellTestData.WaterCut", "%", 0.0, 100.0, absent="0 % (all oil) for the liquid's density and compressibility"),
    _f("downholeCardAnalysis.Pump Intake Pressure", "psi", 0.0, 10000.0,
       absent="srenv's diagnosis of the measured card (pump_state.source 'srenv diagnose')"),
    _f("downholeCardAnalysis.Pump Fillage", "%", 0.0, 100.0, absent="100 % (a full pump) beside a given intake pressure"),
    _f("downholeCardAnalysis.Fluid Load", "lbf", -1e5, 1e5, absent="no plunger friction beside a given intake pressure"),
    _f("surveyData[].MD", "ft", 0.0, 40000.0, required=True),
    _f("surveyData[].Inclination", "-", 0.0, 180.0, shown="deg", default=0.0, absent="0 deg"),
    _f("surveyData[].Azimuth", "-", -360.0, 360.0, shown="deg", default=0.0, absent="0 deg"),
    _f("surveyData[].TVD", "ft", 0.0, 40000.0, absent="none (validate --survey-weight tvd refuses the record)"),
    *(_f(f"equipmentData.SurfaceUnit.Dimensional{k}", "in", 1.0, 1000.0, absent="no unit kinematics") for k in "ACIKP"),
    _f("equipmentData.SurfaceUnit.Radius", "in", 1.0, 500.0, absent="no unit kinematics"),
    _f("equipmentData.SurfaceUnit.StructuralImbalance", "lbf", -1e5, 1e5, default=0.0, absent="0 lbf"),
    _f("equipmentData.SurfaceUnit.GearBoxRating", "-", 0.0, 1e6, shown="thousand in-lb",
       absent="no rating (the gearbox loading is not reported against one)"),
    _f("equipmentData.SurfaceUnit.CounterbalanceMoment", "-", -1e6, 1e6, shown="thousand in-lb",
       absent="srenv's optimal counterbalance where one is needed"),
    _f("equipmentData.SurfaceUnit.PhaseAngle", "-", -360.0, 360.0, shown="deg", default=0.0, absent="0 deg"),
])


def declared_path(where: str, key: str) -> str:
    """The declaration's path of `key` read in `where` ('equipmentData.Rods[2]' -> 'equipmentData.Rods[]')."""
    return re.sub(r"\[\d+\]", "[]", f"{where}.{key}")


def _spelling(key: str) -> str:
    return re.sub(r"[\s_\-]", "", key).lower()


def misspelt(d: dict, key: str) -> str | None:
    """A key of `d` spelt as `key` but for case, spaces, dashes or underscores (not `key` itself), or None."""
    want = _spelling(key)
    return next((k for k in d if isinstance(k, str) and k != key and _spelling(k) == want), None)


_SPELLING_NOTES: ContextVar[list[str] | None] = ContextVar("record_spelling_notes", default=None)


@contextlib.contextmanager
def spelling_notes(notes: list[str]) -> Iterator[None]:
    """Within the block, every key read under another spelling (``raw``) is said in `notes` (the record's)."""
    token = _SPELLING_NOTES.set(notes)
    try:
        yield
    finally:
        _SPELLING_NOTES.reset(token)


def raw(d, key: str, where: str):
    """The value of `key` in the record's object `d`, None when absent, null or an empty text; where `key` is
    absent and the record spells it otherwise (``misspelt``), that key's value, said in the notes of the
    enclosing ``spelling_notes`` block."""
    if not isinstance(d, dict):
        return None
    v = d.get(key)
    if key not in d:
        other = misspelt(d, key)
        if other is not None:
            v = d[other]
            notes = _SPELLING_NOTES.get()
            if notes is not None and (line := f"{where}.{key} read from the record's key {other!r}") not in notes:
                notes.append(line)
    return None if v is None or (isinstance(v, str) and not v.strip()) else v


def number(d, key: str, where: str, notes: list[str] | None = None):
    """The declared field `key` of `d` in SI: checked in its range (in its field unit) and converted; when absent,
    its default (said in `notes`) or None, or one ConfigError when the field is required."""
    decl = FIELDS[declared_path(where, key)]
    name = f"{where}.{key}"
    v = raw(d, key, where)
    if v is None:
        if decl.required:
            raise ConfigError(name, "missing", decl.number.expected())
        if decl.default is None:
            return None
        if notes is not None:
            notes.append(f"{name} missing: {decl.absent}")
        return fu.to_si(decl.default, decl.unit, name)
    x = v
    if isinstance(v, str):
        text = v.strip()
        text = text[:-1] if decl.unit == "%" and text.endswith("%") else text
        try:
            x = float(text)
        except ValueError:
            raise ConfigError(name, v, decl.number.expected()) from None
    if isinstance(x, float) and not math.isfinite(x):
        raise ConfigError(name, v, decl.number.expected())
    decl.number.check(x, name)
    return fu.to_si(float(x), decl.unit, name)


def absent_notes(where: str, values: dict) -> list[str]:
    """The notes of the declared fields of `where` read as None (absent, no default): what the reader does without
    each (the declaration's ``absent``)."""
    return [f"{where}.{k} missing: {FIELDS[declared_path(where, k)].absent}" for k, v in values.items() if v is None]


def series(d: dict, key: str, where: str) -> np.ndarray:
    """A list of numbers of the record (numbers written as text are read), flat; one ConfigError otherwise."""
    v = raw(d, key, where)
    if v is None:
        raise ConfigError(f"{where}.{key}", "missing", "a list of numbers")
    try:
        a = np.asarray(v, dtype=float)
    except (TypeError, ValueError):
        raise ConfigError(f"{where}.{key}", "a non-numeric list", "a list of numbers") from None
    if a.ndim != 1:
        raise ConfigError(f"{where}.{key}", f"shape {a.shape}", "a flat list of numbers")
    return a
