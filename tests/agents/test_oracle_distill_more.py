"""More DAgger for the shipped v2 students (scripts/oracle_distill_more.py, issue 24, helper d24): the gate's seeds are
training wells no earlier design, tuning or test played, THE GATE follows its pre-registered rule, the ensembles are
the shipped and the continued students on the shipped residual, and bad arguments are refused in one line (exit 2)."""

from __future__ import annotations

import importlib
import json
import subprocess
import sys
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]
SCRIPT = REPO / "scripts" / "oracle_distill_more.py"


@pytest.fixture(scope="module")
def more():
    sys.path.insert(0, str(SCRIPT.parent))  # the script and the pilots it imports, as when it runs
    return importlib.import_module(SCRIPT.stem)


def test_gate_seeds_are_unplayed_training_wells_0_to_15(more):
    assert [s % 200 for s in more.GATE_SEEDS] == list(range(16))
    earlier = set(range(20000, 20248)) | set(range(20400, 20416)) | set(range(20600, 20616))  # docs/agents.md's
    assert not set(more.GATE_SEEDS) & earlier and not set(more.GATE_SEEDS) & set(range(100000, 100100))
    assert "20800..20815" in " ".join(more.load_benchmark_config(str(more.CONFIG))["history"])


def _summ(lo: float, cost: float, base_cost: float = 2.0) -> dict:
    return {"alarm_pump_off": {"cost": base_cost},
            "continued_ensemble": {"cost": cost, "vs_alarm_pump_off": {"mean": 5.0, "ci95": [lo, 9.0]}}}


@pytest.mark.parametrize("lo, cost, passed", [(0.1, 2.0, True), (0.1, 1.0, True), (0.0, 1.0, False),
                                              (-2.0, 1.0, False), (0.1, 2.01, False)])
def test_the_gate_rule(more, lo, cost, passed):
    assert more.gate(_summ(lo, cost)) is passed


def test_ensembles_are_the_students_on_the_shipped_residual(more, monkeypatch):
    monkeypatch.chdir(REPO)
    _, name, run, tuned, res = more.setup()
    assert name == "oracle_distilled" and run["seeds"] == [0, 1, 2]
    assert res == {"base": "pump_off", "params": tuned["pump_off"]["params"], "scale": 0.5}
    shipped = json.loads((REPO / "docs/v2/benchmark.json").read_text())["policies"]["oracle_distilled_ensemble"]
    assert shipped["residual_on"]["base"] == "pump_off" and shipped["residual_on"]["params"] == res["params"]
    st = more.students(more.SHIPPED, name, run["seeds"], res)
    assert [Path(s["path"]).name for s in st] == [f"oracle_distilled_v2_seed{k}.zip" for k in (0, 1, 2)]
    assert all(Path(s["path"]).is_file() and Path(s["obs_norm"]).is_file() for s in st)


@pytest.mark.parametrize("args, match", [
    (["--stage", "gate", "--workers", "3"], "--workers 3"),
    (["--stage", "gate", "--workers", "0"], "--workers 0"),
])
def test_bad_arguments_refused_in_one_line(tmp_path, args, match):
    r = subprocess.run([sys.executable, str(SCRIPT), *args, "--out", str(tmp_path / "o")], check=False,
                       capture_output=True, text=True, cwd=REPO, timeout=120, env={"PYTHONPATH": str(REPO),
                                                                                   **_env()})
    assert r.returncode == 2 and "Traceback" not in r.stderr
    assert match in r.stderr.strip().splitlines()[-1] and not (tmp_path / "o").exists()


def test_gate_refuses_missing_students_in_one_line(tmp_path):
    r = subprocess.run([sys.executable, str(SCRIPT), "--stage", "gate", "--out", str(tmp_path / "o")], check=False,
                       capture_output=True, text=True, cwd=REPO, timeout=120, env={"PYTHONPATH": str(REPO), **_env()})
    assert r.returncode == 2 and "Traceback" not in r.stderr
    assert "no such student (run --stage dagger first)" in r.stderr.strip().splitlines()[-1]


def _env() -> dict:
    import os

    return {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
