"""Layout variations of a vendor dynacard record, derived programmatically from the two public records
(tests/data/field/): what a held-out export of the same source may hold instead (a block or field missing or
null, values as strings, negative, NaN or out of range, a different taper count, a fiberglass taper, a unit
geometry code not met, no survey or one station, a reversed card, a repeated closing point, a disagreeing
``dynaoutputData`` copy). Each variant is (name, record dict, the field a refusal must name, what an output
must say) for tests/srenv/field/test_record_variants.py.
"""

from __future__ import annotations

import copy
import json
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path

DATA = Path(__file__).resolve().parents[2] / "data" / "field"
WELLS = ("11708328", "7699227")


@dataclass(frozen=True)
class Variant:
    name: str
    record: dict
    field: str           # the field a refusal must name (in its one line)
    note: str = ""       # a text the run's record_notes must hold (a default used, a copy that disagrees)
    same_as_base: bool = False  # the figures must be the unchanged record's (the variant only respells it)
    kind: str = ""       # a field's mutation (null, absent, text, ...; record_variants._field_variants)


def base(well: str) -> dict:
    return json.loads((DATA / f"{well}.json").read_text())


def _at(d, path: tuple):
    for k in path[:-1]:
        d = d[k]
    return d


def _set(path: tuple, value) -> Callable[[dict], None]:
    def go(d: dict) -> None:
        _at(d, path)[path[-1]] = value
    return go


def _drop(path: tuple) -> Callable[[dict], None]:
    def go(d: dict) -> None:
        _at(d, path).pop(path[-1], None)
    return go


def _name(path: tuple) -> str:
    out = ""
    for k in path:
        out += f"[{k}]" if isinstance(k, int) else (f".{k}" if out else k)
    return out


# the list item a declared field is mutated at ('[]' in its declared path): a taper, a station below the surface
ITEM = {"Rods": 0, "surveyData": 1}
# fields read only in another's absence: their variants drop that one (a path from the list item's or block's parent)
ONLY_WITHOUT = {"Count": ("TotalLength",), "IndividualLength": ("TotalLength",),
                "SPM": ("..", "InputParameters", "StrokesPerMinute")}


def declared_paths() -> dict[tuple, object]:
    """Every numeric field the reader takes (srenv.analysis.record_fields.FIELDS, its declaration) as a path from
    the record's top, lists at one item: the variants are generated from the declarations."""
    from srenv.analysis.record_fields import FIELDS

    out = {}
    for name, decl in FIELDS.items():
        path: list = []
        for part in name.split("."):
            if part.endswith("[]"):
                path += [part[:-2], ITEM[part[:-2]]]
            else:
                path.append(part)
        out[tuple(path)] = decl
    return out


# blocks a record may lack (True) or must hold (False)
BLOCKS = {("WellTestData",): True, ("downholeCardAnalysis",): True, ("downholeCard",): True, ("surveyData",): True,
          ("dynaoutputData",): True, ("Performance",): True, ("CardDetails",): True,
          ("equipmentData", "SurfaceUnit"): True, ("equipmentData", "WellBore"): True,
          ("equipmentData", "RodPumpMotor"): True, ("equipmentData", "Rods"): False,
          ("equipmentData", "Pump"): False, ("cardData",): False, ("InputParameters",): False}


def _has(d: dict, path: tuple) -> bool:
    try:
        v = _at(d, path)
        return (path[-1] in v) if isinstance(v, dict) else (isinstance(path[-1], int) and path[-1] < len(v))
    except (KeyError, IndexError, TypeError):
        return False


def _field_variants(d: dict, path: tuple, decl) -> Iterator[tuple[str, Callable, bool]]:
    """(kind, mutation, same_as_base) for one declared field present in the record: absent, null, empty, every
    value its declaration refuses (Number.bad_values: not numbers, not finite, just out of range either side),
    negative, and its own value written as text."""
    value = _at(d, path)[path[-1]]
    yield "null", _set(path, None), False
    yield "absent", _drop(path), False
    yield "empty-text", _set(path, ""), False
    yield "text", _set(path, "abc"), False
    for i, bad in enumerate(decl.number.bad_values()):
        if bad is not None:
            yield f"bad{i}", _set(path, bad), False
    try:
        x = float(str(value).rstrip("%"))
    except ValueError:
        return
    if x > 0:
        yield "negative", _set(path, -x), False
    yield "as-text", _set(path, str(value)), True


def variants(well: str) -> Iterator[Variant]:
    d0 = base(well)

    def make(name: str, *muts: Callable, field: str = "", note: str = "", same: bool = False,
             kind: str = "") -> Variant:
        d = copy.deepcopy(d0)
        for m in muts:
            m(d)
        return Variant(f"{well}-{name}", d, field, note, same, kind)

    for path, decl in declared_paths().items():
        if not _has(d0, path):
            continue
        other = ONLY_WITHOUT.get(path[-1])
        first = [] if other is None else [_drop(other[1:] if other[0] == ".." else (*path[:-1], *other))]
        for kind, mut, same in _field_variants(d0, path, decl):
            yield make(f"{_name(path)}-{kind}", *first, mut, field=_name(path), same=same and not first, kind=kind)
    for path in BLOCKS:
        if _has(d0, path):
            yield make(f"drop-{_name(path)}", _drop(path), field=_name(path))
            yield make(f"null-{_name(path)}", _set(path, None), field=_name(path))
            yield make(f"text-{_name(path)}", _set(path, "abc"), field=_name(path))
    yield from _structural(well, d0, make)


def _tapers(n: int, fiberglass: bool = False) -> Callable[[dict], None]:
    """The listed rod string as n tapers (API sizes 1 in down to 5/8 in, top-down, the same total length); with
    `fiberglass` the top taper is a 1-in fiberglass rod (E 7.2e6 psi, 0.8 lb/ft)."""
    def go(d: dict) -> None:
        rods = d["equipmentData"]["Rods"]
        total = sum(float(r["TotalLength"]) for r in rods)
        sizes = [1.0, 0.875, 0.75, 0.625, 0.625, 0.625][:n]
        proto = rods[-1]
        out = []
        for i, s in enumerate(sizes):
            r = dict(proto, Diameter=s, TotalLength=round(total / n, 2), Weight={1.0: 2.904, 0.875: 2.224,
                     0.75: 1.634, 0.625: 1.135}[s], ModulusOfElasticity=30500000, Grade="D")
            if fiberglass and i == 0:
                r.update(ModulusOfElasticity=7200000, Weight=0.8, Grade="FG")
            out.append(r)
        d["equipmentData"]["Rods"] = out
    return go


def _reverse_card(d: dict) -> None:
    for k in ("Position", "Load"):
        d["cardData"][k] = d["cardData"][k][::-1]


def _close_card(d: dict) -> None:
    for k in ("Position", "Load"):
        d["cardData"][k] = d["cardData"][k] + d["cardData"][k][:1]


def _dyna_disagrees(d: dict) -> None:
    dyn = d.setdefault("dynaoutputData", {})
    dyn["Pump"] = dict(d["equipmentData"]["Pump"], Diameter=2.25)


def _equipment_in_dyna_only(d: dict) -> None:
    dyn = d.setdefault("dynaoutputData", {})
    for k in ("Pump", "Rods", "SurfaceUnit", "WellBore", "RodPumpMotor"):
        if k in d["equipmentData"]:
            dyn[k] = d["equipmentData"][k]
    d.pop("equipmentData")


def _structural(well: str, d0: dict, make) -> Iterator[Variant]:
    for n in range(1, 7):
        yield make(f"tapers-{n}", _tapers(n))
    yield make("tapers-0", _set(("equipmentData", "Rods"), []), field="equipmentData.Rods")
    yield make("taper-text", _set(("equipmentData", "Rods"), ["abc"]), field="equipmentData.Rods[0]")
    yield make("fiberglass-top", _tapers(3, fiberglass=True))
    yield make("geometry-unknown", _set(("equipmentData", "SurfaceUnit", "PumpingUnitGeometry"), "Z9"))
    yield make("geometry-mark-ii", _set(("equipmentData", "SurfaceUnit", "PumpingUnitGeometry"), "M"))
    yield make("geometry-null", _set(("equipmentData", "SurfaceUnit", "PumpingUnitGeometry"), None))
    yield make("rotation-unknown", _set(("equipmentData", "SurfaceUnit", "Rotation"), "sideways"))
    yield make("grade-null", _set(("equipmentData", "Rods", 0, "Grade"), None), note="Grade")
    yield make("survey-one-station", lambda d: d.__setitem__("surveyData", d["surveyData"][:1]), note="one station")
    yield make("survey-empty", _set(("surveyData",), []), note="surveyData missing")
    yield make("survey-unsorted", lambda d: d.__setitem__("surveyData", d["surveyData"][::-1]))
    yield make("survey-duplicate-md", lambda d: d.__setitem__("surveyData", d["surveyData"] + d["surveyData"][-1:]),
               note="" if well == "11708328" else "repeated station")
    yield make("survey-md-disagrees", lambda d: d.__setitem__("surveyData", d["surveyData"] + [
        dict(d["surveyData"][-1], Inclination=float(d["surveyData"][-1]["Inclination"] or 0) + 5.0)]),
        field="MD")
    yield make("survey-text", _set(("surveyData",), "abc"), field="surveyData")
    yield make("card-reversed", _reverse_card, same=True)
    yield make("card-closing-point", _close_card)
    yield make("card-short", lambda d: [d["cardData"].__setitem__(k, d["cardData"][k][:5]) for k in ("Position", "Load")],
               field="cardData")
    yield make("card-lengths-differ", lambda d: d["cardData"]["Load"].pop(), field="cardData")
    yield make("card-text-values", lambda d: d["cardData"].__setitem__("Load", [str(v) for v in d["cardData"]["Load"]]),
               same=True)
    yield make("card-flat", lambda d: d["cardData"].__setitem__("Position", [1.0] * len(d["cardData"]["Position"])),
               field="cardData")
    yield make("downhole-card-empty", _set(("downholeCard",), {"Position": [], "Load": []}))
    yield make("downhole-card-text", _set(("downholeCard",), "abc"), note="downholeCard")
    yield make("downhole-card-short", lambda d: [d["downholeCard"].__setitem__(k, d["downholeCard"][k][:5])
                                                 for k in ("Position", "Load")], note="downholeCard")
    yield make("analysis-fields-null", lambda d: d.__setitem__("downholeCardAnalysis", {
        k: None for k in d["downholeCardAnalysis"]}))
    yield make("analysis-intake-only", lambda d: d.__setitem__("downholeCardAnalysis", {
        "Pump Intake Pressure": "300"}), note="Pump Fillage")
    yield make("analysis-fillage-zero", _set(("downholeCardAnalysis", "Pump Fillage"), "0%"))
    yield make("well-test-empty", _set(("WellTestData",), {}), note="WaterCut")
    yield make("dynaoutput-disagrees", _dyna_disagrees, note="dynaoutputData.Pump")
    yield make("equipment-in-dynaoutput-only", _equipment_in_dyna_only, note="dynaoutputData")
    yield make("not-an-object", lambda d: (d.clear(), d.__setitem__("x", 1)), field="equipmentData")
    yield make("key-case", lambda d: d["InputParameters"].__setitem__(
        "strokesPerMinute", d["InputParameters"].pop("StrokesPerMinute")), field="StrokesPerMinute")


def all_variants() -> list[Variant]:
    return [v for w in WELLS for v in variants(w)]
