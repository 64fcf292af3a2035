"""The record commands survive the held-out records (issues 27 and 23): every layout variation of a vendor dynacard
export derived from the two public records (tests/srenv/field/record_variants.py) either runs - exit 0, one JSON
line, every default it took said in its ``record_notes`` - or is refused in one stderr line naming the field,
exit 2, no traceback, nothing written; never anything else. ``srenv validate``, ``srenv diagnose RECORD.json``
and ``srenv classify RECORD.json`` run in-process on each (a few as subprocesses). docs/field.md lists the
record's fields, which are required, their bounds and the defaults.
"""

from __future__ import annotations

import contextlib
import io
import json
import math
import subprocess
import sys
from pathlib import Path

import pytest
from record_variants import Variant, all_variants, base

from srenv.tools.cli import main

NEGATIVE_OK = ("StructuralImbalance", "CounterbalanceMoment", "Azimuth", "Fluid Load", "PhaseAngle")
# an absent field whose consequence the output states elsewhere than in record_notes (the intake pressure's
# source is pump_state.source; without a fluid density the liquid is made of the water cut and gravities); and
# fields not used when another is given (the gravities beside a fluid density, the TVD column but for
# --survey-weight tvd, Count and IndividualLength beside a TotalLength)
SAID_ELSEWHERE = ("Pump Intake Pressure", "FluidDensity", "TVD")
UNUSED_BESIDE = {"OilApi": ("InputParameters", "FluidDensity"), "WaterGravity": ("InputParameters", "FluidDensity")}
VARIANTS = all_variants()


def _no_nan(text: str):
    raise ValueError(f"{text} in a JSON line")


def run(args: list[str]) -> tuple[int, str, str]:
    """``srenv ARGS`` in-process: (exit code, stdout, stderr); an exception escaping main is a traceback."""
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        try:
            rc = main(args)
        except SystemExit as e:  # argparse
            rc = e.code
    return rc, out.getvalue(), err.getvalue()


def outcome(v: Variant, args: list[str], written: Path | None = None) -> tuple[str, dict | str]:
    """('ran', the JSON line) or ('refused', the stderr line), asserting the contract of either."""
    rc, out, err = run(args)
    if rc == 2:
        lines = err.strip().splitlines()
        assert len(lines) == 1 and out == "", (v.name, args, err)
        assert "Traceback" not in err and (not v.field or v.field.split(".")[-1] in lines[0]), (v.name, lines)
        assert written is None or not written.exists(), v.name
        return "refused", lines[0]
    assert rc == 0, (v.name, args, rc, err)
    (line,) = out.splitlines()
    return "ran", json.loads(line, parse_constant=_no_nan)


def _notes(cmd: str, js: dict) -> list[str]:
    return js["record_notes"] if cmd == "validate" else js["well"]["record_notes"]


def check_variant(v: Variant, tmp: Path) -> None:
    path = tmp / f"{v.name}.json"
    path.write_text(json.dumps(v.record))
    out_csv = tmp / f"{v.name}-pump.csv"
    results = {"validate": outcome(v, ["validate", str(path)]),
               "diagnose": outcome(v, ["diagnose", str(path), "--out", str(out_csv)], out_csv),
               "classify": outcome(v, ["classify", str(path), "--json"])}
    kinds = {k for k, _ in results.values()}
    assert len(kinds) == 1, (v.name, results)  # one reader: the three commands agree on the record
    key = v.field.split(".")[-1] if v.field else ""
    kind = v.kind
    if kind == "text" or kind.startswith("bad") or (kind == "negative" and key not in NEGATIVE_OK):
        assert kinds == {"refused"}, (v.name, "an invalid value ran", results["validate"])
    if kinds == {"ran"}:
        for cmd, (_, js) in results.items():
            notes = " | ".join(_notes(cmd, js))
            if v.note:
                assert v.note in notes, (v.name, cmd, notes)
            beside = UNUSED_BESIDE.get(key)
            unused = beside is not None and v.record.get(beside[0], {}).get(beside[1]) is not None
            if kind in ("null", "absent", "empty-text") and key not in SAID_ELSEWHERE and not unused:
                assert key in notes, (v.name, cmd, "a default taken without a note", notes)
        if v.same_as_base:
            assert _figures(results["validate"][1]) == _figures(_base_validate(v.name.split("-")[0], tmp))


def _figures(js: dict) -> dict:
    return {k: v for k, v in js.items() if k not in ("record", "record_notes", "card_time_reversed")}


_BASE: dict[str, dict] = {}


def _base_validate(well: str, tmp: Path) -> dict:
    if well not in _BASE:
        p = tmp / f"{well}-base.json"
        p.write_text(json.dumps(base(well)))
        _BASE[well] = outcome(Variant("base", {}, ""), ["validate", str(p)])[1]
    return _BASE[well]


@pytest.mark.parametrize("v", VARIANTS, ids=[v.name for v in VARIANTS])
def test_each_variant_runs_or_is_refused_in_one_line(v: Variant, tmp_path: Path) -> None:
    check_variant(v, tmp_path)


SUBPROCESS = ("7699227-card-reversed", "11708328-equipmentData.Pump.Diameter-text", "7699227-tapers-5")


@pytest.mark.parametrize("name", SUBPROCESS)
def test_as_a_command(name: str, tmp_path: Path) -> None:
    """A few variants as the command itself: the same outcome, and a refusal carries no traceback."""
    (v,) = [x for x in VARIANTS if x.name == name]
    path = tmp_path / "record.json"
    path.write_text(json.dumps(v.record))
    p = subprocess.run([sys.executable, "-m", "srenv.tools.cli", "validate", str(path)], capture_output=True,
                       text=True, check=False)
    kind, _ = outcome(v, ["validate", str(path)])
    assert p.returncode == (0 if kind == "ran" else 2), p.stderr
    assert "Traceback" not in p.stderr and len(p.stderr.strip().splitlines()) == (0 if kind == "ran" else 1)
    if kind == "ran":
        assert math.isfinite(json.loads(p.stdout)["pprl_error_pct"])
