"""A card's time column must give a stroke period a pumping unit can have (0.1-60 strokes/min): a 20-sample card
spanning 1e5 s or samples 1e298 s apart is refused in one line before any work (issue 28's two card cases)."""

from __future__ import annotations

import numpy as np
import pytest
from conftest import assert_cli_refuses


def _card(path, t_s: np.ndarray) -> None:
    ph = 2 * np.pi * np.arange(len(t_s)) / len(t_s)
    np.savetxt(path, np.c_[t_s, 1.2 * (1 - np.cos(ph)), 40e3 + 8e3 * np.sin(ph)], delimiter=",",
               header="t_s,polished_rod_position_m,polished_rod_load_n", comments="")


@pytest.mark.parametrize(("name", "t_s"), [("20 samples over 1e5 s", np.arange(20) * 5e3),
                                           ("samples 1e298 s apart", np.arange(200) * 1e298),
                                           ("a 0.2 s stroke", np.arange(200) * 1e-3)])
def test_a_card_with_an_impossible_stroke_period_is_refused(tmp_path, name, t_s) -> None:
    _card(tmp_path / "card.csv", t_s)
    out = tmp_path / "pump.csv"
    assert_cli_refuses(["diagnose", str(tmp_path / "card.csv"), "--config", "paper_fig3_vertical", "--out", str(out)],
                       out, "stroke period", "1 to 600 s")
