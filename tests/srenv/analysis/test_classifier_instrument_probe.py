"""scripts/classifier_instrument_probe.py (issue 23, reported only): on a small simulated set it prints one line per
perturbation with the accuracy the shipped surface model reaches, and the perturbations change the cards they read."""

from __future__ import annotations

import importlib.util
import re
import subprocess
import sys
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[3]
SCRIPT = REPO / "scripts" / "classifier_instrument_probe.py"


def _module():
    spec = importlib.util.spec_from_file_location("classifier_instrument_probe", SCRIPT)
    m = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(m)
    return m


def test_each_perturbation_changes_the_card_as_named() -> None:
    m = _module()
    t = np.linspace(0.0, 1.0, 256, endpoint=False)
    x, y = 1.0 - np.cos(2 * np.pi * t), 5e4 + 1e4 * np.sign(np.sin(2 * np.pi * t))
    for tag, f in m.PERTURBATIONS.items():
        px, py = f(x, y)
        if tag == "clean":
            assert px is x and py is y
        elif tag.startswith("zero offset"):
            assert np.allclose(py - y, float(tag.split()[2]) * 6e4) and px is x
        elif tag.startswith("resampled"):
            assert len(px) == len(py) == 200
        else:  # a low-pass smooths the square load
            assert np.abs(np.diff(py)).max() < np.abs(np.diff(y)).max()


def test_a_small_set_prints_an_accuracy_line_per_perturbation(tmp_path: Path) -> None:
    cards = tmp_path / "cards"
    subprocess.run([sys.executable, "-m", "srenv.tools.cli", "cards", "--n", "24", "--seed", "41", "--surface", "v2",
                    "--out", str(cards), "--workers", "1", "--no-progress"], check=True, capture_output=True)
    p = subprocess.run([sys.executable, str(SCRIPT), "--cards", str(cards)], check=False, capture_output=True,
                       text=True, cwd=REPO)
    assert p.returncode == 0, p.stderr
    lines = p.stdout.strip().splitlines()
    assert len(lines) == len(_module().PERTURBATIONS)
    for line in lines:
        acc = float(re.search(r"accuracy (\d\.\d+) \((\d+) / 24\)", line).group(1))
        assert 0.0 <= acc <= 1.0


def test_a_missing_set_a_set_without_cards_and_a_model_that_is_not_data_are_one_line_exit_2(tmp_path: Path) -> None:
    np.savez(tmp_path / "cards.npz", label=np.zeros(2, int))  # a set without its card columns
    (tmp_path / "model.npz").write_text("import os  # code, not data\n")
    for args in (["--cards", str(tmp_path / "nowhere")], ["--cards", str(tmp_path)]):
        p = subprocess.run([sys.executable, str(SCRIPT), *args], check=False, capture_output=True, text=True, cwd=REPO)
        assert p.returncode == 2 and p.stdout == "" and len(p.stderr.strip().splitlines()) == 1, p.stderr
        assert "--cards" in p.stderr and "Traceback" not in p.stderr
    subprocess.run([sys.executable, "-m", "srenv.tools.cli", "cards", "--n", "2", "--seed", "41", "--out",
                    str(tmp_path / "set"), "--workers", "1", "--no-progress"], check=True, capture_output=True)
    p = subprocess.run([sys.executable, str(SCRIPT), "--cards", str(tmp_path / "set"), "--model",
                        str(tmp_path / "model.npz")], check=False, capture_output=True, text=True, cwd=REPO)
    assert p.returncode == 2 and len(p.stderr.strip().splitlines()) == 1 and "--model" in p.stderr, p.stderr
