"""``srenv diagnose --load-convention true|effective``: effective = true load + p A at the rod end (the vendors'
buoyant pump cards), converted by the one function validate uses too (analysis.diagnose.load_in_convention);
the JSON carries the rod end's pressure and area so a user can convert."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from srenv.analysis.diagnose import load_in_convention
from srenv.config import load_config
from srenv.physics.rod import GRAVITY_M_S2
from srenv.physics.survey import Survey
from srenv.simulation.simulator import Simulator
from srenv.tools.cli import main

WELL = "default"
SETS = ["inflow.model=none", "pump.intake_pressure_pa=2e6"]


@pytest.fixture(scope="module")
def card_csv(tmp_path_factory: pytest.TempPathFactory) -> Path:
    tr = Simulator(load_config(WELL, SETS)).run_strokes(2)[-1].trace
    path = tmp_path_factory.mktemp("conv") / "card.csv"
    np.savetxt(path, np.c_[tr["t_s"], tr["polished_rod_position_m"], tr["polished_rod_load_n"]], delimiter=",",
               header="t_s,polished_rod_position_m,polished_rod_load_n", comments="")
    return path


def _diagnose(card: Path, out: Path, convention: str | None, capsys: pytest.CaptureFixture) -> tuple[dict, dict]:
    argv = ["diagnose", str(card), "--config", WELL, "--out", str(out)]
    for s in SETS:
        argv += ["--set", s]
    if convention:
        argv += ["--load-convention", convention]
    assert main(argv) == 0
    summary = json.loads(capsys.readouterr().out)
    return summary, np.genfromtxt(out, delimiter=",", names=True)


def test_effective_and_true_pump_cards_differ_by_exactly_p_a_at_the_rod_end(card_csv: Path, tmp_path: Path,
                                                                            capsys: pytest.CaptureFixture) -> None:
    s_true, c_true = _diagnose(card_csv, tmp_path / "t.csv", None, capsys)  # true is the default
    s_eff, c_eff = _diagnose(card_csv, tmp_path / "e.csv", "effective", capsys)
    assert s_true["load_convention"] == "true" and s_eff["load_convention"] == "effective"
    assert c_true.dtype.names == ("t_s", "pump_position_m", "pump_load_n")
    assert c_eff.dtype.names == ("t_s", "pump_position_m", "pump_effective_load_n")
    # the rod end's pressure and area, checked independently: p = rho g TVD(992 m), A of the 19-mm rod
    cfg = load_config(WELL, SETS)
    tvd = Survey.from_config(cfg.survey, cfg.rod_length_m).tvd(cfg.rod_length_m)
    assert s_eff["rod_end_pressure_pa"] == pytest.approx(850.0 * GRAVITY_M_S2 * tvd, rel=1e-12)
    assert s_eff["rod_end_area_m2"] == pytest.approx(math.pi / 4 * 0.019 ** 2, rel=1e-12)
    pa = s_eff["rod_end_pressure_pa"] * s_eff["rod_end_area_m2"]  # 2.0 kN here
    assert pa > 1000.0
    np.testing.assert_allclose(c_eff["pump_effective_load_n"] - c_true["pump_load_n"], pa, rtol=0, atol=1e-6)
    for key in ("upstroke_load_n", "downstroke_load_n"):
        assert s_eff[key] - s_true[key] == pytest.approx(pa, abs=1e-6)
    # what does not depend on the convention stays
    for key in ("fluid_load_n", "fillage", "card_class", "intake_pressure_pa"):
        assert s_eff[key] == s_true[key]


def test_one_conversion_serves_validate_and_diagnose() -> None:
    from srenv.tools import diagnose_cli, validate

    assert validate.load_in_convention is load_in_convention is diagnose_cli.load_in_convention
    assert load_in_convention(np.array([1.0, -2.0]), "effective", 1e6, 2e-4).tolist() == [201.0, 198.0]
    assert load_in_convention(5.0, "true", 1e6, 2e-4) == 5.0
    with pytest.raises(ValueError, match="load convention"):
        load_in_convention(5.0, "buoyant", 1e6, 2e-4)


def test_a_bad_load_convention_is_one_line_exit_2(card_csv: Path, tmp_path: Path,
                                                  capsys: pytest.CaptureFixture) -> None:
    with pytest.raises(SystemExit) as ex:
        main(["diagnose", str(card_csv), "--config", WELL, "--out", str(tmp_path / "o.csv"),
              "--load-convention", "buoyant"])
    assert ex.value.code == 2
    err = [ln for ln in capsys.readouterr().err.splitlines() if ln.strip()]
    assert len(err) == 1 and "--load-convention" in err[0] and "buoyant" in err[0]
    assert not (tmp_path / "o.csv").exists()
