"""`srenv simulate` end to end: CSV contract, JSON summary, plot, and the docs that are generated."""

from __future__ import annotations

import csv
import json
from pathlib import Path

import pytest

from srenv.config import config_doc
from srenv.tools.cli import main

COLUMNS = ["t_s", "polished_rod_position_m", "polished_rod_load_n", "pump_position_m", "pump_velocity_m_s",
           "pump_load_n"]


def test_simulate_writes_csv_plot_and_summary(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    out, png = tmp_path / "f3.csv", tmp_path / "f3.png"
    rc = main(["simulate", "paper_fig3_vertical", "--strokes", "2", "--out", str(out), "--plot", str(png)])
    assert rc == 0
    summary = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
    for key in ("pprl_n", "mprl_n", "pump_stroke_m", "plunger_stick_episodes", "solver_calls",
                "certified_steps"):
        assert key in summary
    assert summary["steps"] == summary["certified_steps"] + summary["corrected_steps"] + summary["qp_steps"]
    with open(out) as fh:
        rows = list(csv.DictReader(fh))
    assert set(COLUMNS) <= set(rows[0])
    assert len(rows) == summary["steps"] == 4000
    assert max(float(r["polished_rod_load_n"]) for r in rows) == pytest.approx(summary["pprl_n"], rel=1e-9)
    assert png.stat().st_size > 10_000 and png.read_bytes()[:4] == b"\x89PNG"


def test_strokes_follow_spm_and_always_qp_counts(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    out = tmp_path / "a.csv"
    assert main(["simulate", "paper_fig3_vertical", "--strokes", "1", "--spm", "12", "--always-qp",
                 "--out", str(out)]) == 0
    s = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
    assert s["steps"] == 1000  # 5 s stroke at 5 ms
    assert s["qp_steps"] == s["steps"] and s["solver_calls"] >= s["steps"]


def test_config_doc_is_current() -> None:
    doc = Path(__file__).resolve().parents[3] / "docs" / "config.md"
    assert config_doc() in doc.read_text(), "regenerate docs/config.md with `srenv config-doc`"
