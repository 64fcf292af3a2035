"""Well descriptions in field units (issue 27, build item 5): a top-level ``units:`` block, converted to SI once
when the file is read (srenv/config_units.py). Twins in field units load the same configs as the SI files and
simulate the same; bad blocks and out-of-range values are refused in one line naming the key or field, the value
as written and what is expected, in the file's unit too. Cases are generated from the fields' declarations."""

from __future__ import annotations

import copy
import dataclasses
import math
import os
import typing
from pathlib import Path
from typing import Any

import pytest
import yaml
from declared_helpers import nothing_left, one_line, run_srenv

from srenv import field_units
from srenv.config import (
    CONFIG_DIR,
    apply_overrides,
    config_from_dict,
    load_config,
    read_raw,
    shipped_configs,
    to_dict,
)
from srenv.config_units import declared_units, field_mapping, unit_keys, units_doc
from srenv.errors import ConfigError, short_repr

ROOT = Path(__file__).resolve().parents[2]
# every key in a field unit other than its SI one (the first that is not the key itself)
ALL_FIELD = {k: next(u for u in allowed if u not in (k, "m", "mm", "Pa", "N", "kg/m", "kg/m^3", "m^3/day", "s"))
             for k, allowed in unit_keys().items()}


def _close(a: Any, b: Any, path: str = "") -> None:
    """Equal configs, numbers to 1e-12 relative."""
    if isinstance(a, dict):
        assert a.keys() == b.keys(), path
        for k in a:
            _close(a[k], b[k], f"{path}.{k}")
    elif isinstance(a, list):
        assert len(a) == len(b), path
        for i, (x, y) in enumerate(zip(a, b)):
            _close(x, y, f"{path}[{i}]")
    elif isinstance(a, float) and not isinstance(b, bool):
        assert math.isclose(a, b, rel_tol=1e-12, abs_tol=0.0), (path, a, b)
    else:
        assert a == b, (path, a, b)


def test_the_block_converts_every_declared_unit_and_only_those() -> None:
    assert set(ALL_FIELD) == {"m", "mm", "Pa", "N", "kg/m", "kg/m^3", "m^3/day", "s"}
    assert ALL_FIELD["m"] == "in" and ALL_FIELD["N"] == "kN"
    # a field whose unit is a key is a float field (an int field would be left unconverted)
    from srenv.config_sections import WellConfig

    def walk(cls: type) -> None:
        for f in dataclasses.fields(cls):
            tp = typing.get_type_hints(cls)[f.name]
            inner = [a for a in typing.get_args(tp) if a is not type(None)] or [tp]
            tp = typing.get_args(inner[0])[0] if typing.get_origin(inner[0]) is tuple else inner[0]
            if dataclasses.is_dataclass(tp):
                walk(tp)
            else:
                assert not (tp is int and f.metadata.get("unit") in unit_keys()), f.name

    walk(WellConfig)


@pytest.mark.parametrize("name", [n for n in shipped_configs() if not n.endswith("_field_units")])
@pytest.mark.parametrize("units", [ALL_FIELD, {"m": "ft", "mm": "in", "Pa": "psi", "N": "lbf", "kg/m": "lb/ft",
                                               "m^3/day": "bbl/d"}], ids=["all", "oilfield"])
def test_every_shipped_well_in_field_units_loads_the_same_config(name: str, units: dict, tmp_path: Path) -> None:
    raw = read_raw(name)
    twin = field_mapping(raw, units)
    assert twin["units"] == units
    path = tmp_path / "twin.yaml"
    path.write_text(yaml.safe_dump(twin, sort_keys=False))
    _close(to_dict(load_config(path)), to_dict(load_config(name)))
    _close(to_dict(config_from_dict(twin)), to_dict(config_from_dict(raw)))  # a mapping handed in directly too


def test_the_shipped_field_units_example_is_defaults_twin_and_simulates_the_same(
        tmp_path: Path, capsys: pytest.CaptureFixture, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(tmp_path)
    raw = yaml.safe_load((CONFIG_DIR / "default_field_units.yaml").read_text())
    assert raw["units"] == {"m": "ft", "mm": "in", "Pa": "psi", "N": "lbf", "kg/m^3": "g/cm^3", "m^3/day": "bbl/d"}
    assert raw["pump"]["plunger_diameter_mm"] == 1.75 and raw["rod"]["tapers"][0]["length_m"] > 1000  # field numbers
    field, si = load_config("default_field_units"), load_config("default")
    assert field.pump.plunger_diameter_mm == 44.45  # 1.75 in, as if 44.45 had been written
    _close(to_dict(dataclasses.replace(field, name=si.name)), to_dict(si))
    outs = []
    for cfg, out in (("default", "si.csv"), (str(CONFIG_DIR / "default_field_units.yaml"), "fu.csv")):
        assert run_srenv(["simulate", cfg, "--strokes", "1", "--out", out], capsys)[0] == 0
        outs.append((Path(out).read_bytes(), capsys.readouterr().out))
    assert outs[0] == outs[1] and len(outs[0][0]) > 1000


def test_overrides_on_a_field_units_file_are_si_and_its_units_are_not_overridden() -> None:
    cfg = load_config("default_field_units", ["surface.stroke_length_m=1.2"])
    assert cfg.surface.stroke_length_m == 1.2  # a --set value is SI, as the name says
    assert cfg.rod.tapers[0].length_m == pytest.approx(328.0, rel=1e-12)
    with pytest.raises(ConfigError) as ex:
        load_config("default", ["units.m=ft"])
    assert ex.value.field == "units.m"


# ------------------------------------------------------------------------------ bad blocks, by class
def _bad_blocks() -> list[Any]:
    keys = unit_keys()
    other = {k: next(u for u, (d, _) in field_units.UNITS.items() if d not in ("-", field_units.UNITS[k][0]))
             for k in keys}
    unused = [u for u, (d, _) in field_units.UNITS.items() if d != "-" and u not in keys]
    cases = []
    for k in keys:
        cases.append(pytest.param({k: other[k]}, f"units.{k}", other[k], "same quantity", id=f"dimension-{k}"))
        cases.append(pytest.param({k: "furlong"}, f"units.{k}", "furlong", keys[k][-1], id=f"unknown-unit-{k}"))
        cases.append(pytest.param({k: 3}, f"units.{k}", "3", "a unit of", id=f"non-string-unit-{k}"))
        bad_key = k.lower().replace("/", "_per_") + "x"
        cases.append(pytest.param({bad_key: keys[k][-1]}, f"units.{bad_key}", keys[k][-1], "declared SI unit",
                                  id=f"unknown-key-{k}"))
    cases.append(pytest.param({"pa": "psi"}, "units.pa", "psi", "did you mean Pa", id="unknown-key-pa"))
    cases.append(pytest.param({"deg": "rad"}, "units.deg", "rad", "declared SI unit", id="unknown-key-deg"))
    cases += [pytest.param({u: u}, f"units.{u}", u, "a key some field uses", id=f"unused-key-{u}") for u in unused]
    cases += [pytest.param(v, "units", repr(v)[:5], "a mapping", id=f"non-mapping-{type(v).__name__}")
              for v in (["m", "ft"], "m: ft", None, 3.0)]
    return cases


@pytest.mark.parametrize(("block", "field", "value", "expected"), _bad_blocks())
def test_a_bad_units_block_is_one_line_exit_2_and_writes_nothing(block: Any, field: str, value: str, expected: str,
                                                                  tmp_path: Path, capsys: pytest.CaptureFixture,
                                                                  monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(tmp_path)
    Path("w.yaml").write_text(yaml.safe_dump({"units": block, **read_raw("paper_fig3_vertical")}))
    rc, err = run_srenv(["simulate", "w.yaml", "--strokes", "1", "--out", "o.csv"], capsys)
    one_line(rc, err, f"'{field}'", value, expected)
    nothing_left(tmp_path, {"w.yaml"})


def test_every_command_reading_a_config_reads_field_units(tmp_path: Path, capsys: pytest.CaptureFixture,
                                                          monkeypatch: pytest.MonkeyPatch) -> None:
    """simulate, diagnose, fit, validate --config and sweep read a config through read_raw / load_config: a bad
    block is refused by each (so each converts), and the env takes a field-units file by name."""
    from declared_helpers import write_card

    monkeypatch.chdir(tmp_path)
    write_card(tmp_path / "card.csv")
    Path("w.yaml").write_text(yaml.safe_dump({"units": {"m": "lbf"}, **read_raw("paper_fig3_vertical")}))
    for argv in (["simulate", "w.yaml", "--out", "o.csv"], ["diagnose", "card.csv", "--config", "w.yaml", "--out",
                 "o.csv"], ["fit", "card.csv", "--config", "w.yaml", "--param", "damping.damping_factor", "--out",
                 "f.yaml"], ["validate", "card.csv", "--config", "w.yaml"],
                 ["sweep", "w.yaml", "--param", "surface.spm", "--values", "5", "--out", "o.csv"]):
        rc, err = run_srenv(argv, capsys)
        one_line(rc, err, "'units.m'", "lbf", "same quantity")
    nothing_left(tmp_path, {"w.yaml", "card.csv"})
    import gymnasium as gym

    env = gym.make("srenv:srenv/SuckerRod-v0", config="default_field_units")
    assert env.unwrapped.base_cfg.pump.plunger_diameter_mm == 44.45
    env.close()


# ------------------------------------------------------------------------------ bounds, in the file's unit
def _bound_cases() -> list[Any]:
    from srenv.declarations import config_fields

    out = []
    for key, (decl, _optional) in config_fields().items():
        if decl.unit in unit_keys() and decl.kind is float:
            out.append(pytest.param(key, decl, ALL_FIELD[decl.unit], id=key))
    return out


@pytest.mark.parametrize(("key", "decl", "unit"), _bound_cases())
def test_an_out_of_range_field_unit_value_is_named_as_written(key: str, decl: Any, unit: str) -> None:
    """Generated from the declarations (declarations.config_fields): each SI bad number of a field, written in
    the field unit, is refused naming the field, the value as written with its unit and the range in that unit."""
    from test_declared_files import _raw_with_section_of

    si_unit = decl.unit
    twin = field_mapping(_raw_with_section_of(key), {si_unit: unit})
    config_from_dict(twin)  # valid as it is
    ratio = field_units.factor(unit) / field_units.factor(si_unit)
    bad = [v for v in decl.bad_values() if isinstance(v, (int, float)) and not isinstance(v, bool)]
    assert bad
    for v in bad:
        written = v / ratio if isinstance(v, float) and math.isfinite(v) else v
        raw = copy.deepcopy(twin)
        raw = apply_overrides(raw, {key: written}, owned=True)
        with pytest.raises(ConfigError) as ex:
            config_from_dict(raw)
        assert ex.value.field == key.replace(".0.", "[0].")
        assert ex.value.value == f"{short_repr(written)} {unit}", str(ex.value)
        assert f"in {unit}: a number within" in ex.value.expected and f"units.{si_unit}: {unit}" in ex.value.expected
        assert "\n" not in str(ex.value)
    if decl.hi is not None and math.isfinite(decl.hi):  # the range shown in the file's unit is the SI one
        assert f"{decl.hi / ratio:.6g}]" in ex.value.expected


def test_the_units_table_in_the_docs_is_current() -> None:
    doc = (ROOT / "docs" / "config.md").read_text()
    assert units_doc() in doc, "regenerate the units table in docs/config.md (srenv.config_units.units_doc)"
    assert "default_field_units" in doc and "default_field_units" in (ROOT / "README.md").read_text()
    assert sum(len(v) for v in declared_units().values()) > 50
    assert os.path.exists(CONFIG_DIR / "default_field_units.yaml")


# ------------------------------------------------------------------------------ simulate --out-units field
def test_simulate_writes_a_field_unit_card_the_card_readers_read_back(tmp_path: Path, capsys: pytest.CaptureFixture,
                                                                     monkeypatch: pytest.MonkeyPatch) -> None:
    import numpy as np

    from srenv.surface_unit.measured_motion import read_card_csv

    monkeypatch.chdir(tmp_path)
    for out, units in (("si.csv", "si"), ("field.csv", "field")):
        assert run_srenv(["simulate", "paper_fig3_vertical", "--strokes", "1", "--out", out, "--out-units", units],
                         capsys)[0] == 0
    lines = Path("field.csv").read_text().splitlines()
    assert lines[1] == "s,in,,lbf,in,,lbf,"  # the unit row; velocities stay m/s (empty cell: the name's unit)
    cols = ("t_s", "polished_rod_position_m", "polished_rod_load_n")
    pump = ("pump_position_m", "pump_load_n", "pump_velocity_m_s")
    si, field = (read_card_csv(p, "CARD.csv", cols, pump) for p in ("si.csv", "field.csv"))
    raw_field = np.loadtxt("field.csv", delimiter=",", skiprows=2)
    assert raw_field[:, 3].max() == pytest.approx(si["polished_rod_load_n"].max() / 4.4482216152605, rel=1e-11)
    for c in cols + pump:
        scale = float(np.abs(si[c]).max())
        np.testing.assert_allclose(field[c], si[c], rtol=1e-11, atol=1e-11 * scale, err_msg=c)
    rc, err = run_srenv(["simulate", "paper_fig3_vertical", "--out", "x.csv", "--out-units", "imperial"], capsys)
    assert rc == 2 and "--out-units" in err and "field" in err and not Path("x.csv").exists()
