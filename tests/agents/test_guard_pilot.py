"""The guard pilot (scripts/guard_pilot.py, issue 24) composes the shipped students on the base their report records
(``residual_on``), by the function replay and ``--evaluate-only --report`` use, not on a hard-coded one; its guarded
variants are the spec the benchmark builds from a ``guarded:`` block; its gate passes and refuses what it says."""

from __future__ import annotations

import importlib.util
import json
from pathlib import Path

import pytest

from agents.benchmark.stages import design_guarded
from agents.evaluation.replay import load_report, policy_specs

REPO = Path(__file__).resolve().parents[2]
REPORT = REPO / "docs/v2/benchmark.json"


@pytest.fixture(scope="module")
def pilot():
    spec = importlib.util.spec_from_file_location("guard_pilot", REPO / "scripts" / "guard_pilot.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def test_the_students_are_composed_on_their_recorded_base(pilot):
    ens, tuned = pilot.shipped()
    rec = load_report(REPORT)["policies"]["oracle_distilled_ensemble"]
    assert rec["residual_on"]["base"] == "pump_off"  # what they were trained on (the first pilot used fillage_pi)
    assert ens["kind"] == "ensemble" and ens["residual"] == {**rec["residual_on"], "scale": 0.5}
    assert ens["residual"]["params"] == tuned["pump_off"]
    assert [Path(m["path"]).name for m in ens["members"]] == [Path(m).name for m in rec["models"]]
    assert ens == policy_specs(load_report(REPORT), "oracle_distilled_ensemble", REPORT.parent)[0]


def test_the_base_is_read_not_hard_coded(pilot, tmp_path):
    rep = json.loads(REPORT.read_text())
    rec = rep["policies"]["oracle_distilled_ensemble"]
    rec["residual_on"] = {"base": "fillage_pi", "params": rep["tuned"]["fillage_pi"]["params"], "scale": 0.25}
    path = tmp_path / "benchmark.json"
    path.write_text(json.dumps(rep))
    ens, _ = pilot.shipped(path)  # the models are found in models/ (MODELS_HOME), as replay finds them
    assert ens["residual"] == {"base": "fillage_pi", "params": rep["tuned"]["fillage_pi"]["params"], "scale": 0.25}


def test_a_variant_is_the_benchmarks_guarded_spec(pilot):
    ens, tuned = pilot.shipped()
    specs = pilot.variant_specs(ens, tuned, pilot.VARIANTS)
    assert specs["ensemble_unguarded"] is ens
    g = pilot.VARIANTS["guard_load95"]
    cfg = {"guarded": {"fallback": "alarm_pump_off", "guard": g, "scale": None}}
    bench = design_guarded(cfg, {k: {"params": v} for k, v in tuned.items()}, ens, "oracle_distilled")
    assert {k: v for k, v in bench.items() if k != "of"} == specs["guard_load95"]
    assert specs["guard_load95"]["inner"]["residual"]["base"] == "pump_off"
    assert specs["guard_load95"]["fallback"] == {"name": "alarm_pump_off", "params": tuned["alarm_pump_off"]}


@pytest.mark.parametrize("mean, lo, cost, ok", [
    (+5.0, +0.5, 2.0, True),     # CI above zero, lower cost
    (+9.0, -3.0, 2.17, True),    # >= 10 % of 89.81 USD/h (8.98), CI across zero, equal cost
    (+8.9, -3.0, 2.0, False),    # under 10 %, CI across zero
    (+12.0, +1.0, 2.18, False),  # both reward conditions, but a higher cost
])
def test_the_gate(pilot, mean, lo, cost, ok):
    base = {"usd_h": 89.81, "cost": 2.17}
    row = {"cost": cost, "vs_alarm_pump_off": {"mean": mean, "ci95": [lo, 2 * mean - lo]}}
    assert pilot.gate(row, base) is ok
