"""The record's fields declared once (srenv.analysis.record_fields): the generated variants cover every
declaration, docs/field.md lists every one, and the defaults and refusals that used to be silent wrong figures
(a fiberglass taper weighed as steel, a fillage of 0 read as a full pump, an optional key spelt otherwise taken
as absent). ``srenv validate`` on the two public records prints the same JSON as before these changes, byte for
byte (pinned on numpy's AVX2 kernels, conftest.run_on_avx2_numpy)."""

from __future__ import annotations

import copy
import json
import math
from pathlib import Path

import pytest
from conftest import run_on_avx2_numpy
from record_variants import ITEM, all_variants, base

from srenv import field_units as fu
from srenv.analysis.field_model import tapers
from srenv.analysis.field_record import read_dynacard_json
from srenv.analysis.record_fields import FIELDS, declared_path, number
from srenv.errors import ConfigError

ROOT = Path(__file__).resolve().parents[3]


def _read(d: dict, tmp_path: Path, name: str = "r.json"):
    p = tmp_path / name
    p.write_text(json.dumps(d))
    return read_dynacard_json(p, auto_orient=True)


def test_every_declared_field_has_generated_variants() -> None:
    """A field added to FIELDS is mutated by construction: it must be present in one of the two records (at
    the list item record_variants.ITEM names), so that its refusals and its default are run."""
    mutated = {declared_path(*v.field.rsplit(".", 1)) for v in all_variants() if v.kind}
    assert sorted(set(FIELDS) - mutated) == []
    assert set(ITEM) == {p.split("[]")[0].split(".")[-1] for p in FIELDS if "[]" in p}


def test_docs_list_every_declared_field() -> None:
    text = (ROOT / "docs" / "field.md").read_text()
    for name, decl in FIELDS.items():
        assert f"`{name}`" in text, name
        assert decl.number.expected().split(" within ")[-1] in text, name


@pytest.mark.parametrize("name", sorted(FIELDS))
def test_each_declaration_refuses_its_bad_values(name: str) -> None:
    decl = FIELDS[name]
    where, key = name.rsplit(".", 1)
    for bad in [*decl.number.bad_values(), "abc", "1e999"]:
        if bad is None:
            continue
        with pytest.raises(ConfigError) as e:
            number({key: bad}, key, where)
        assert name in str(e.value) and decl.number.expected() in str(e.value)
    if decl.required:
        with pytest.raises(ConfigError, match="missing"):
            number({}, key, where)
    else:
        notes: list[str] = []
        got = number({}, key, where, notes)
        assert (got is None) == (decl.default is None)
        assert bool(notes) == (decl.default is not None) and all(name in n for n in notes)


def test_a_fiberglass_taper_weighs_what_the_record_says(tmp_path: Path) -> None:
    """A 1-in fiberglass taper at 0.8 lb/ft is not a steel body (3.98 kg/m): its density follows from its weight,
    and a steel taper keeps its body and couplings as before."""
    d = base("7699227")
    top = dict(d["equipmentData"]["Rods"][0], Diameter=1.0, ModulusOfElasticity=7.2e6, Weight=0.8, Grade="FG")
    d["equipmentData"]["Rods"].insert(0, top)
    rec = _read(d, tmp_path)
    fg, steel = tapers(rec)[:2]
    area = math.pi / 4 * 0.0254 ** 2
    assert fg["density_kg_m3"] * area + fg["coupling_mass_kg_per_m"] == pytest.approx(fu.to_si(0.8, "lb/ft"))
    assert fg["density_kg_m3"] < 3000 and fg["coupling_mass_kg_per_m"] == 0.0
    assert steel["density_kg_m3"] == 7850.0 and steel["coupling_mass_kg_per_m"] > 0


def test_a_light_taper_without_a_modulus_is_refused_a_steel_one_takes_steel(tmp_path: Path) -> None:
    d = base("7699227")
    d["equipmentData"]["Rods"][0].pop("ModulusOfElasticity")
    rec = _read(d, tmp_path)
    assert rec.tapers[0]["youngs_modulus_pa"] == fu.to_si(30.5e6, "psi")
    assert any("Rods[0].ModulusOfElasticity missing" in n for n in rec.notes)
    d["equipmentData"]["Rods"][0]["Weight"] = 0.8
    with pytest.raises(ConfigError, match=r"Rods\[0\]\.ModulusOfElasticity.*lighter than steel"):
        _read(d, tmp_path)


def test_a_taper_length_from_its_rods(tmp_path: Path) -> None:
    d = base("11708328")
    rods = d["equipmentData"]["Rods"]
    rods[0].pop("TotalLength")
    rec = _read(d, tmp_path)
    assert rec.tapers[0]["length_m"] == pytest.approx(fu.to_si(rods[0]["Count"] * rods[0]["IndividualLength"], "ft"))
    assert any("Count x IndividualLength" in n for n in rec.notes)
    rods[0].pop("Count")
    with pytest.raises(ConfigError, match=r"Rods\[0\]\.TotalLength"):
        _read(d, tmp_path)


def test_a_fillage_of_zero_is_not_a_full_pump(tmp_path: Path) -> None:
    from srenv.tools.validate import pump_state

    d = base("7699227")
    d["downholeCardAnalysis"]["Pump Fillage"] = "0%"
    rec = _read(d, tmp_path)
    assert rec.fillage == 0.0
    assert pump_state(rec, str(tmp_path))["fillage"] == 0.0


@pytest.mark.parametrize("section, key, other", [("InputParameters", "TubingPressure", "tubing_pressure"),
                                                 ("WellTestData", "WaterCut", "watercut"),
                                                 ("downholeCardAnalysis", "Pump Fillage", "PumpFillage")])
def test_a_key_spelt_otherwise_is_read_and_said_not_defaulted(section, key, other, tmp_path: Path) -> None:
    """An export that spells a key its own way (case, spaces, underscores) still runs, on the value it holds."""
    d = base("7699227")
    ref = _read(copy.deepcopy(d), tmp_path, "ref.json")
    d[section][other] = d[section].pop(key)
    rec = _read(d, tmp_path)
    assert f"{section}.{key} read from the record's key {other!r}" in rec.notes
    assert (rec.tubing_pressure_pa, rec.water_cut, rec.fillage) == (ref.tubing_pressure_pa, ref.water_cut, ref.fillage)


def test_equipment_from_the_vendor_copy_and_a_copy_that_disagrees(tmp_path: Path) -> None:
    d = base("11708328")
    ref = _read(d, tmp_path, "ref.json")
    only = copy.deepcopy(d)
    only.pop("equipmentData")
    rec = _read(only, tmp_path)
    assert rec.tapers == ref.tapers and rec.plunger_diameter_m == ref.plunger_diameter_m
    assert any("read from dynaoutputData" in n for n in rec.notes)
    d["dynaoutputData"]["Pump"]["Diameter"] = 2.25
    rec = _read(d, tmp_path)
    assert rec.plunger_diameter_m == ref.plunger_diameter_m
    assert any("dynaoutputData.Pump differs" in n for n in rec.notes)


# sha256 of `srenv validate tests/data/field/<id>.json`'s stdout before the record fields were declared (main at
# 9172aed): the two records' figures do not move
VALIDATE_SHA256 = {"11708328": "05056fb132f3f292feb806c22ba31aae22b329c67b8e5b2e02556e87e4a03fe0",
                   "7699227": "35304343ca63b256d25d8920f919424f3e5c689acb89e866bcfbc03efd818acf"}
PIN = """
import contextlib, hashlib, io
from srenv.tools.cli import main
for r in ("11708328", "7699227"):
    buf = io.StringIO()
    with contextlib.redirect_stdout(buf):
        assert main(["validate", f"tests/data/field/{r}.json"]) == 0
    print(r, hashlib.sha256(buf.getvalue().encode()).hexdigest())
"""


def test_validate_prints_the_same_json_on_the_two_records() -> None:
    got = dict(line.split() for line in run_on_avx2_numpy(PIN).splitlines())
    assert got == VALIDATE_SHA256
