"""``srenv diagnose RECORD.json`` (issue 23 on real records): a dynacard record's stored card, forward in time as
``srenv validate`` reads it, diagnosed on the well the record describes (srenv.tools.record_well) without
``--config``; the same JSON figures and pump card as ``diagnose CARD.csv --config WELL`` with the motion CSV and
config written by hand; ``--damping``, ``--load-convention`` and ``--set`` as for a CSV card; a CSV card without
``--config`` and every bad record in one line, exit 2, nothing written or left behind (docs/field.md)."""

from __future__ import annotations

import json
import os
import shutil
import tempfile

import pytest
from conftest import FIELD_DATA, assert_cli_refuses, record_by_hand

from srenv.tools.cli import main


def _run(capsys, *args: str) -> dict:
    assert main(["diagnose", *args]) == 0
    (line,) = capsys.readouterr().out.splitlines()
    return json.loads(line)


# the energy balance needs a pump state apart from the card: 11708328 has no analysis of its own (refused, BAD)
@pytest.mark.parametrize("well, damping", [("11708328", "fixed"), ("7699227", "fixed"), ("7699227", "energy-balance")])
def test_the_record_route_equals_the_manual_route(well, damping, tmp_path, capsys, monkeypatch) -> None:
    """``diagnose RECORD.json`` = ``diagnose CARD.csv --config WELL --spm SPM`` with the well written by hand: the
    same summary and the same pump card CSV, byte for byte, plus ``well`` saying it came from the record; the
    described well's temporary directory is gone afterwards."""
    (tmp_path / "tmp").mkdir()
    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path / "tmp"))
    rec, cfg, card, _ = record_by_hand(FIELD_DATA / f"{well}.json", tmp_path)
    manual = _run(capsys, str(card), "--config", str(cfg), "--spm", repr(rec.spm), "--out", str(tmp_path / "m.csv"),
                  "--damping", damping)
    record = _run(capsys, str(FIELD_DATA / f"{well}.json"), "--out", str(tmp_path / "r.csv"), "--damping", damping)
    w = record.pop("well")
    assert record == manual
    assert (tmp_path / "r.csv").read_bytes() == (tmp_path / "m.csv").read_bytes()
    assert w["source"] == "record" and w["fillage"] == 1.0 and w["card_time_reversed"] is (well == "7699227")
    assert record["damping"]["rule"] == damping
    assert not list((tmp_path / "tmp").iterdir())


def test_load_convention_plot_and_set_work_on_a_record(tmp_path, capsys) -> None:
    rec = str(FIELD_DATA / "7699227.json")
    true = _run(capsys, rec, "--out", str(tmp_path / "t.csv"))
    eff = _run(capsys, rec, "--out", str(tmp_path / "e.csv"), "--load-convention", "effective", "--plot",
               str(tmp_path / "e.png"))
    assert (tmp_path / "e.csv").read_text().splitlines()[0] == "t_s,pump_position_m,pump_effective_load_n"
    assert eff["load_convention"] == "effective" and (tmp_path / "e.png").stat().st_size > 1000
    shift = eff["rod_end_pressure_pa"] * eff["rod_end_area_m2"]
    assert eff["upstroke_load_n"] == pytest.approx(true["upstroke_load_n"] + shift, rel=1e-9)
    damped = _run(capsys, rec, "--out", str(tmp_path / "s.csv"), "--set", "damping.damping_factor=0.05")
    assert damped["damping"] == {"rule": "fixed", "damping_factor": 0.05}
    assert true["damping"]["damping_factor"] != 0.05


# ---------------------------------------------------------------------------------------------- bad input
def _csv_card(d):
    shutil.copy(FIELD_DATA / "7699227.json", d / "r.json")  # the manual route's card: a CSV needs its --config
    record_by_hand(d / "r.json", d)
    for name in ("r.json", "well.yaml", "motion.csv", "surface.csv"):
        os.remove(d / name)
    return d / "card.csv"


def _text(name: str, text: str):
    def make(d):
        (d / name).write_text(text)
        return d / name
    return make


def _no_pump_depth(d):
    data = json.loads((FIELD_DATA / "7699227.json").read_text())
    del data["equipmentData"]["Pump"]["Depth"]
    (d / "nodepth.json").write_text(json.dumps(data))
    return d / "nodepth.json"


def _symlink(d):
    os.symlink(FIELD_DATA / "7699227.json", d / "link.json")
    return d / "link.json"


BAD = {
    "a CSV card without --config": (_csv_card, [], ("--config", "missing", "CSV card")),
    "--config with a record": (lambda d: FIELD_DATA / "7699227.json", ["--config", "paper_fig3_vertical"],
                               ("--config", "describes its well")),
    "a record that does not parse": (_text("cut.json", '{"cardData": '), [], ("RECORD", "readable JSON")),
    "a record missing the pump depth": (_no_pump_depth, [], ("equipmentData.Pump.Depth", "missing")),
    "a forward card with --reverse": (lambda d: FIELD_DATA / "11708328.json", ["--reverse"],
                                      ("--reverse", "already runs forward")),
    "a symlinked record": (_symlink, [], ("link.json", "symbolic link")),
    "energy balance without the record's own analysis": (lambda d: FIELD_DATA / "11708328.json",
                                                          ["--damping", "energy-balance"],
                                                          ("--damping", "degenerate")),
}


@pytest.mark.parametrize("case", sorted(BAD))
def test_bad_input_is_one_line_exit_2_nothing_written_or_left_behind(case, tmp_path) -> None:
    make, flags, needles = BAD[case]
    (tmp_path / "tmp").mkdir()
    card = make(tmp_path)
    out = tmp_path / "pump.csv"
    assert_cli_refuses(["diagnose", str(card), "--out", str(out), *flags], out, *needles, tmpdir=tmp_path / "tmp")


def test_an_output_through_a_symlink_is_refused_and_its_target_kept(tmp_path) -> None:
    (tmp_path / "tmp").mkdir()
    (tmp_path / "target.csv").write_text("keep me")
    os.symlink(tmp_path / "target.csv", tmp_path / "link.csv")
    assert_cli_refuses(["diagnose", str(FIELD_DATA / "7699227.json"), "--out", str(tmp_path / "link.csv")],
                       tmp_path / "none.csv", "--out", "symbolic link", tmpdir=tmp_path / "tmp")
    assert (tmp_path / "target.csv").read_text() == "keep me" and (tmp_path / "link.csv").is_symlink()
