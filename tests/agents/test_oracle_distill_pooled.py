"""The pooled student's design (scripts/oracle_distill_pooled.py, configs/benchmark/v2_oracle_distilled_pooled.yaml,
issue 24, helper e24): its DAgger, pre-check and gate seeds are unused training seeds, the config keeps v2's splits,
baselines and protocol (tests/agents/test_oracle_distill.py also checks those and the CLI refusing a bad
``teacher.pool`` field in one line), an ensemble acts in a labelled episode as the mean of its members, and no gate is played without a passed pre-check."""

from __future__ import annotations

import importlib
import json
import os
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from agents.benchmark.config import distill_seeds, load_benchmark_config
from agents.evaluation.agent import AgentPolicy
from agents.training.oracle_distill import _student

REPO = Path(__file__).resolve().parents[2]
SCRIPT = REPO / "scripts" / "oracle_distill_pooled.py"
POOLED = REPO / "configs/benchmark/v2_oracle_distilled_pooled.yaml"
CAPPED = REPO / "configs/benchmark/v2_oracle_distilled_capped.yaml"  # f24: e24's agents block, copied
WELLS = REPO / "configs/benchmark/v2_oracle_distilled_wells.yaml"  # g40: f24's config, copied
DESCRIBED = REPO / "configs/benchmark/v2_oracle_distilled_described.yaml"  # d42: g40's config, copied
DESCRIBED_GUARDED = REPO / "configs/benchmark/v2_oracle_distilled_described_guarded.yaml"  # a43: d42's, copied
STROKE_GUARDED = REPO / "configs/benchmark/v2_oracle_distilled_stroke_guarded.yaml"  # b43: a43's, copied
AGREEMENT = REPO / "configs/benchmark/v2_oracle_distilled_agreement.yaml"  # u44: b43's, copied


@pytest.fixture(scope="module")
def pooled():
    sys.path.insert(0, str(SCRIPT.parent))  # the script and the pilots it imports, as when it runs
    return importlib.import_module(SCRIPT.stem)


def _env() -> dict:
    return {**{k: v for k, v in os.environ.items() if k != "PYTHONPATH"}, "PYTHONPATH": str(REPO)}


def test_seeds_are_unused_training_seeds(pooled, monkeypatch):
    monkeypatch.chdir(REPO)
    cfg = load_benchmark_config(POOLED)
    run = cfg["agents"]["runs"]["oracle_distilled"]
    t, p = run["teacher"], run["teacher"]["pool"]
    dagger = set(distill_seeds(t, run["seeds"][0]))
    pre = set(range(p["precheck_seed_start"], p["precheck_seed_start"] + p["precheck_episodes"]))
    assert dagger == set(range(56000, 56032)) and pre == set(range(57000, 57016)) and t["beta0"] == 0.0
    assert [s % 200 for s in pooled.GATE_SEEDS] == list(range(16)) and pooled.GATE_SEEDS[0] == 21000
    d24 = {s for k in (0, 1, 2) for s in range(53000 + 1000 * k, 53032 + 1000 * k)}
    earlier = set(range(20000, 20248)) | set(range(20400, 20416)) | set(range(20600, 20616)) | set(range(20800, 20816))
    assert not (dagger | pre) & (d24 | set(range(10)) | set(range(20000, 21000)) | set(range(50000, 53000)))
    assert not set(pooled.GATE_SEEDS) & (earlier | set(range(100000, 100100)))
    others = " ".join(f.read_text() for f in (REPO / "configs").rglob("*.yaml") if f not in (POOLED, CAPPED, WELLS, DESCRIBED,
                                                                                          DESCRIBED_GUARDED,
                                                                                          STROKE_GUARDED, AGREEMENT))
    assert not re.search(r"\b(560\d\d|570\d\d|210\d\d)\b", others)
    hist = " ".join(cfg["history"])
    assert all(s in hist for s in ("56000..56031", "57000..57015", "21000..21015", "0.6 x M_d24"))
    assert (p["fit_seeds"], p["precheck_ratio"], len(pooled.candidates(p))) == ([0, 1, 2], 0.6, 12)


def test_an_ensemble_acts_as_the_mean_of_its_members():
    members = [{"path": str(REPO / f"models/oracle_distilled_v2_seed{k}.zip"),
                "obs_norm": str(REPO / f"models/oracle_distilled_v2_seed{k}_obs_norm.npz")} for k in (0, 1)]
    ens = _student({"student": {"members": members}})
    x = np.random.default_rng(0).normal(size=(4, 91)).astype(np.float32)
    each = [AgentPolicy(m["path"], m["obs_norm"]).predict(x, deterministic=True)[0] for m in members]
    np.testing.assert_allclose(ens.predict(x)[0], np.mean(each, 0), atol=1e-6)


def test_the_gate_rule_is_d24s_on_the_pooled_ensemble(pooled):
    more = sys.modules["oracle_distill_more"]
    summ = {"alarm_pump_off": {"cost": 2.0},
            "pooled_ensemble": {"cost": 1.9, "vs_alarm_pump_off": {"mean": 3.0, "ci95": [0.1, 6.0]}}}
    assert more.gate(summ, "pooled_ensemble")
    summ["pooled_ensemble"]["cost"] = 2.1
    assert not more.gate(summ, "pooled_ensemble")


@pytest.mark.parametrize("script", [SCRIPT, SCRIPT.with_name("oracle_distill_wells.py"),  # g40's and d42's
                                    SCRIPT.with_name("oracle_distill_described.py")])  # share the check
@pytest.mark.parametrize("precheck", [None, {"precheck": False}, {"precheck": "yes"}])
def test_no_gate_without_a_passed_precheck(tmp_path, precheck, script):
    out = tmp_path / "o"
    out.mkdir()
    if precheck is not None:
        (out / "precheck.json").write_text(json.dumps(precheck))
    r = subprocess.run([sys.executable, str(script), "--stage", "gate", "--out", str(out)], check=False,
                       capture_output=True, text=True, cwd=REPO, timeout=120, env=_env())
    assert r.returncode == 2 and "Traceback" not in r.stderr
    assert "no passed pre-check" in r.stderr.strip().splitlines()[-1] and not (out / "gate").exists()


@pytest.mark.parametrize("args, match", [
    (["--stage", "select", "--reference", "nowhere"], "--reference 'nowhere'"),
    (["--stage", "precheck", "--workers", "3"], "--workers 3"),
    (["--stage", "label", "--workers", "3"], "--workers 3"),  # g40's oracle_distill_wells.py
])
def test_bad_arguments_refused_in_one_line(tmp_path, args, match):
    script = SCRIPT.with_name("oracle_distill_wells.py") if "label" in args else SCRIPT
    r = subprocess.run([sys.executable, str(script), *args, "--out", str(tmp_path / "o")], check=False,
                       capture_output=True, text=True, cwd=REPO, timeout=120, env=_env())
    assert r.returncode == 2 and "Traceback" not in r.stderr
    assert match in r.stderr.strip().splitlines()[-1] and not (tmp_path / "o").exists()
