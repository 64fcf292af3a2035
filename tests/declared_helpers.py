"""Shared by the tests generated from the declarations (tests/test_declared_inputs.py, test_declared_files.py):
the in-process runners of ``srenv`` and ``python -m agents`` and the one-line refusal check."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pytest

from srenv.tools.cli import main

FIG3 = "paper_fig3_vertical"
FIG7 = "paper_fig7_pullout"
CARD_HEADER = "t_s,polished_rod_position_m,polished_rod_load_n"
# the smallest valid command line of each command, flags and outputs added by the cases
BASE_ARGV = {
    "simulate": ["simulate", FIG3, "--out", "o.csv"],
    "bench": ["bench"],
    "sweep": ["sweep", FIG7, "--param", "surface.pull_velocity_m_s", "--values", "0.5", "--out", "o.csv"],
    "diagnose": ["diagnose", "card.csv", "--config", FIG3, "--out", "o.csv"],
    "fit": ["fit", "card.csv", "--config", FIG3, "--param", "damping.damping_factor", "--out", "f.yaml"],
    "validate": ["validate", "card.csv", "--config", FIG3],
    "cards": ["cards", "--n", "1", "--out", "cards_out"],
}


def run_srenv(argv: list[str], capsys: pytest.CaptureFixture) -> tuple[int, str]:
    try:
        rc = main(argv)
    except SystemExit as ex:  # argparse-level refusals exit from inside main
        rc = ex.code
    return rc, capsys.readouterr().err


def run_agents(argv: list[str], capsys: pytest.CaptureFixture) -> tuple[int, str]:
    from agents.cli import main as agents_main

    try:
        rc = agents_main(argv)
    except SystemExit as ex:
        rc = ex.code
    return rc, capsys.readouterr().err


def one_line(rc: int, err: str, *needles: str, code: int = 2) -> str:
    lines = [ln for ln in err.splitlines() if ln.strip()]
    assert rc == code, err[-2000:]
    assert len(lines) == 1 and "Traceback" not in err, err[-2000:]
    assert len(lines[0]) < 600
    for n in needles:
        assert n in lines[0], (n, lines[0])
    return lines[0]


def nothing_left(d: Path, before: set[str]) -> None:
    assert sorted(set(os.listdir(d)) - before) == []


def write_card(path: Path, n: int = 200, period_s: float = 10.0) -> None:
    t = np.arange(n) * period_s / n
    x = 1.2 * (1 - np.cos(2 * np.pi * t / period_s))
    f = 40e3 + 8e3 * np.sin(2 * np.pi * t / period_s)
    np.savetxt(path, np.c_[t, x, f], delimiter=",", header=CARD_HEADER, comments="")


