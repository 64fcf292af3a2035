"""The capped pooled student's design (scripts/oracle_distill_capped.py, configs/benchmark/v2_oracle_distilled_capped.yaml,
issue 24, helper f24): the config keeps e24's splits, baselines, protocol and agents on unused seeds, its look and
selection seeds are unused training seeds and its gate seeds v2's validation split, THE SELECTION RULE picks the best
candidate at alarm_pump_off's cost or below (none -> a negative), a candidate's spec bounds the pooled ensemble's
correction, and no gate is played without a chosen candidate."""

from __future__ import annotations

import importlib
import json
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

from agents.benchmark.config import distill_seeds, load_benchmark_config

REPO = Path(__file__).resolve().parents[2]
SCRIPT = REPO / "scripts" / "oracle_distill_capped.py"
CAPPED = REPO / "configs/benchmark/v2_oracle_distilled_capped.yaml"
POOLED = REPO / "configs/benchmark/v2_oracle_distilled_pooled.yaml"
LATER = REPO / "configs/benchmark/v2_oracle_distilled_wells.yaml"  # g40's: it names the earlier seeds as used
DESCRIBED = REPO / "configs/benchmark/v2_oracle_distilled_described.yaml"  # d42's: g40's copied


@pytest.fixture(scope="module")
def capped():
    sys.path.insert(0, str(SCRIPT.parent))  # the script and the pilots it imports, as when it runs
    return importlib.import_module(SCRIPT.stem)


@pytest.mark.parametrize("config, source", [(CAPPED, POOLED), (LATER, CAPPED), (DESCRIBED, LATER)])  # copies
def test_config_is_e24s_but_its_history(monkeypatch, config, source):
    monkeypatch.chdir(REPO)
    a, b = load_benchmark_config(config), load_benchmark_config(source)
    assert {k: v for k, v in a.items() if k not in ("history", "source")} == {k: v for k, v in b.items()
                                                                     if k not in ("history", "source")}


def test_seeds_are_unused(capped, monkeypatch):
    monkeypatch.chdir(REPO)
    cfg = load_benchmark_config(CAPPED)
    run = cfg["agents"]["runs"]["oracle_distilled"]
    p = run["teacher"]["pool"]
    used = (set(distill_seeds(run["teacher"], 0)) | set(range(p["precheck_seed_start"], p["precheck_seed_start"] + 16))
            | {s for k in (0, 1, 2) for s in range(53000 + 1000 * k, 53032 + 1000 * k)} | set(range(50000, 53000))
            | set(range(10)) | set(range(20000, 21016)) | set(range(100000, 100100)))
    look, sel, gate = set(capped.LOOK_SEEDS), set(capped.SELECT_SEEDS), set(capped.GATE_SEEDS)
    assert not (look | sel | gate) & used and not look & sel and not (look | sel) & gate
    assert (min(sel), len(sel), min(gate), len(gate)) == (58000, len(capped.SELECT_SEEDS), 21200, 16)
    others = " ".join(f.read_text() for f in (REPO / "configs").rglob("*.yaml") if f not in (CAPPED, LATER, DESCRIBED))
    assert not re.search(r"\b(58[01]\d\d|212\d\d)\b", others)
    hist = " ".join(cfg["history"])
    assert all(s in hist for s in ("58100..58107", "58000..58011", "21200..21215", "scenario validation"))


def test_every_candidate_is_named_in_the_history(capped):
    hist = " ".join(load_benchmark_config(CAPPED)["history"])
    assert all(n in hist for n in capped.CANDIDATES) and 1 <= len(capped.CANDIDATES) <= 6
    assert all(c for c in capped.CANDIDATES.values()) and capped.UNCAPPED == {"s1_nocap": None}


def _rows(**cands: tuple[float, float]) -> dict:
    return {"alarm_pump_off": {"usd_h": 10.0, "cost": 1.3}, **{k: {"usd_h": u, "cost": c} for k, (u, c) in cands.items()}}


@pytest.mark.parametrize("cands, chosen", [
    ({"a": (30.0, 1.6), "b": (20.0, 1.3), "c": (25.0, 1.2), "d": (5.0, 0.5)}, "c"),  # argmax over the qualifying
    ({"a": (30.0, 1.6), "b": (20.0, 1.31)}, None),  # none qualifies -> negative
    ({"a": (20.0, 1.0), "b": (20.0, 1.1)}, "a"),  # ties to the first
    ({"a": (5.0, 1.0)}, "a"),  # a qualifying candidate below alarm_pump_off's reward is still chosen (the gate judges)
])
def test_the_selection_rule(capped, cands, chosen):
    assert capped.choose(_rows(**cands)) == chosen


def test_a_candidate_bounds_the_pooled_ensembles_correction(capped, tmp_path):
    specs = capped.specs_of(tmp_path, {**capped.UNCAPPED, **capped.CANDIDATES})
    assert specs["alarm_pump_off"]["kind"] == "baseline" and "cap" not in specs["s1_nocap"]["residual"]
    for n, cap in {**capped.UNCAPPED, **capped.CANDIDATES}.items():
        s = specs[n]
        assert s["kind"] == "ensemble" and len(s["members"]) == 3 and s["residual"]["scale"] == 0.5
        assert s["residual"].get("cap") == cap and s["residual"]["base"] == "pump_off"


def _run(args: list[str], out: Path) -> subprocess.CompletedProcess:
    """The script as a user runs it (PYTHONPATH = the repository only)."""
    env = dict(os.environ, PYTHONPATH=str(REPO))
    return subprocess.run([sys.executable, str(SCRIPT), *args, "--out", str(out)], check=False, capture_output=True,
                          text=True, cwd=REPO, timeout=120, env=env)


@pytest.mark.parametrize("select", [None, {"chosen": None}, {"chosen": "nonsense"}])
def test_no_gate_without_a_chosen_candidate(tmp_path, select):
    out = tmp_path / "o"
    out.mkdir()
    if select is not None:
        (out / "select.json").write_text(json.dumps(select))
    r = _run(["--stage", "gate"], out)
    assert r.returncode == 2 and "Traceback" not in r.stderr
    assert "no chosen candidate" in r.stderr.strip().splitlines()[-1] and not (out / "gate").exists()


def test_bad_arguments_refused_in_one_line(tmp_path):
    r = _run(["--stage", "select", "--workers", "3"], tmp_path / "o")
    assert r.returncode == 2 and "Traceback" not in r.stderr
    assert "--workers 3" in r.stderr.strip().splitlines()[-1] and not (tmp_path / "o").exists()


@pytest.mark.parametrize("shipped", [True, False])
def test_the_gate_plays_the_shipped_ensemble_only_when_asked(capped, tmp_path, monkeypatch, shipped):
    more = sys.modules["oracle_distill_more"]
    played = {}

    def fake_play(cfg, specs, out, workers):
        played.update(specs)
        ep = {"reward": 144.0, "cost": 1.0, "cost_pound": 1.0, "reward_revenue": 144.0, "mean_avg_spm": 5.0,
              "well_id": "validation-000"}
        return {k: [dict(ep, reward=144.0 * (i + 1)) for _ in range(3)] for i, k in enumerate(specs)}

    monkeypatch.setattr(more, "play_validation", fake_play)
    cfg, _, _, tuned, res = more.setup(capped.CONFIG)
    sp = capped.specs_of(REPO, {"pooled_ensemble": None, "s1_spm0": capped.CANDIDATES["s1_spm0"]})  # models/: shipped
    rec = more.play_design_gate(cfg, capped.CONFIG, capped.GATE_SEEDS, {"capped_s1_spm0": sp["s1_spm0"]}, tuned, res,
                                tmp_path, 1, scenario="validation", also={"pooled_ensemble": sp["pooled_ensemble"]},
                                shipped=shipped)
    names = ["alarm_pump_off", *(["shipped_ensemble"] if shipped else []), "pooled_ensemble", "capped_s1_spm0"]
    assert list(played) == names and list(rec["summary"]) == names and rec["scenario"] == "validation"
    assert played["capped_s1_spm0"]["residual"]["cap"] == {"spm_cap": 0.0} and rec["gate"] is True
