"""srenv fit: least squares of named config fields to a measured card, driven by the card's motion."""

from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
import pytest

from srenv.analysis.fit import CardFit, fit_card
from srenv.config import load_config
from srenv.simulation.simulator import Simulator

BASE = ["inflow.model=none"]
TRUE = {"damping.damping_factor": 0.08, "friction.coefficient": 0.15, "pump.intake_pressure_pa": 1.5e6}


@pytest.fixture(scope="module")
def synthetic_card(tmp_path_factory):
    cfg = load_config("default", BASE + [f"{k}={v}" for k, v in TRUE.items()])
    tr = Simulator(cfg).run_strokes(4)[-1].trace
    path = tmp_path_factory.mktemp("fit") / "card.csv"
    np.savetxt(path, np.c_[tr["t_s"], tr["polished_rod_position_m"], tr["polished_rod_load_n"]], delimiter=",",
               header="t_s,polished_rod_position_m,polished_rod_load_n", comments="")
    return path, tr


def test_fit_recovers_known_parameters_from_a_synthetic_card(synthetic_card):
    path, _ = synthetic_card
    fit = CardFit(str(path), "default", list(TRUE), BASE)  # starts at 0.05, 0.1, 1.0 MPa
    r = fit_card(fit)
    assert r["initial_card_rms_pct_of_pprl"] > 1.0
    for k, v in TRUE.items():
        assert r["params"][k] == pytest.approx(v, rel=1e-3), k
    assert r["card_rms_pct_of_pprl"] < 0.01


def test_fit_on_a_noisy_card_is_within_its_uncertainty(synthetic_card, tmp_path):
    _path, tr = synthetic_card
    rng = np.random.default_rng(1)
    noise = 0.005 * tr["polished_rod_load_n"].max() * rng.standard_normal(len(tr["t_s"]))
    noisy = tmp_path / "noisy.csv"
    np.savetxt(noisy, np.c_[tr["t_s"], tr["polished_rod_position_m"], tr["polished_rod_load_n"] + noise],
               delimiter=",", header="t_s,polished_rod_position_m,polished_rod_load_n", comments="")
    r = fit_card(CardFit(str(noisy), "default", ["damping.damping_factor", "friction.coefficient"],
                         [*BASE, "pump.intake_pressure_pa=1.5e6"]))
    assert r["card_rms_pct_of_pprl"] == pytest.approx(0.5, rel=0.1)  # what is left is the noise
    for k in ("damping.damping_factor", "friction.coefficient"):
        err = abs(r["params"][k] - TRUE[k])
        assert 0 < r["uncertainty"][k] < 0.05 * TRUE[k]
        assert err < 5 * r["uncertainty"][k], (k, err, r["uncertainty"][k])


def test_cli_fit_writes_a_loadable_fitted_config(synthetic_card, tmp_path):
    path, _ = synthetic_card
    out = tmp_path / "fitted.yaml"
    p = subprocess.run([sys.executable, "-m", "srenv.tools.cli", "fit", str(path), "--config", "default", "--set",
                        "inflow.model=none", "--param", "damping.damping_factor", "--param", "friction.coefficient",
                        "--set", "pump.intake_pressure_pa=1.5e6", "--out", str(out)],
                       check=False, capture_output=True, text=True)
    assert p.returncode == 0, p.stderr
    lines = p.stdout.strip().splitlines()
    assert len(lines) == 1
    r = json.loads(lines[0])
    assert r["params"]["friction.coefficient"] == pytest.approx(0.15, rel=1e-3)
    cfg = load_config(out)
    assert cfg.friction.coefficient == pytest.approx(r["params"]["friction.coefficient"])
    assert cfg.surface.motion == "measured"
    assert list(tmp_path.iterdir()) == [out]  # nothing else left behind


@pytest.mark.parametrize("param, expect", [("friction.nope", "--param"), ("rod.tapers", "--param"),
                                           ("simulation.max_corrections", "real-valued")])
def test_cli_fit_bad_param_is_one_line_exit_2(synthetic_card, tmp_path, param, expect):
    path, _ = synthetic_card
    out = tmp_path / "fitted.yaml"
    p = subprocess.run([sys.executable, "-m", "srenv.tools.cli", "fit", str(path), "--config", "default", "--param", param,
                        "--out", str(out)], check=False, capture_output=True, text=True)
    assert p.returncode == 2
    lines = p.stderr.strip().splitlines()
    assert len(lines) == 1 and expect in lines[0], p.stderr
    assert not out.exists()
