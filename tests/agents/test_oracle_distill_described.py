"""The described student's pre-check (scripts/oracle_distill_described.py, configs/benchmark/v2_oracle_distilled_described
.yaml, issue 24, helper d42): the config is g40's but its history, which names the data (g40's seeds), the 13
features, the bar, the folds and the gate's unused validation seeds; every row's input gets ITS well's features, as
``well_file(env)`` hands them over after ``reset``. tests/agents/test_oracle_distill_pooled.py checks this script's
refusals (no gate without a passed pre-check), test_oracle_distill_capped.py that the config is g40's but its
history."""

from __future__ import annotations

import importlib
import os
import re
import subprocess
import sys
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest

import srenv  # noqa: F401  (registers the envs)
from agents.benchmark.config import load_benchmark_config
from agents.policies.described_features import FEATURES, features
from srenv.task.well_file import well_file

REPO = Path(__file__).resolve().parents[2]
SCRIPT = REPO / "scripts" / "oracle_distill_described.py"
DESCRIBED = REPO / "configs/benchmark/v2_oracle_distilled_described.yaml"
WELLS = REPO / "configs/benchmark/v2_oracle_distilled_wells.yaml"


@pytest.fixture(scope="module")
def described():
    sys.path.insert(0, str(SCRIPT.parent))  # the script and the pilots it imports, as when it runs
    return importlib.import_module(SCRIPT.stem)


def test_gate_seeds_are_unused_validation_seeds(described):
    gate = described.GATE_SEEDS
    assert gate == list(range(21600, 21616))
    used = [(0, 10), (20000, 21416), (50000, 60000), (100000, 100100)]  # every earlier design's and split's seeds
    assert not any(lo <= s < hi for s in gate for lo, hi in used)
    others = " ".join(f.read_text() for d in ("configs", "scripts") for f in (REPO / d).rglob("*.*")
                      if f.suffix in (".yaml", ".py") and f not in (DESCRIBED, SCRIPT))
    assert not re.search(r"\b216\d\d\b", others)
    assert not re.search(r"\b216\d\d\b", (REPO / "docs/agents.md").read_text().split("(v2, helper d42")[0])


def test_the_history_registers_data_features_bar_folds_and_gate(described, monkeypatch):
    monkeypatch.chdir(REPO)
    hist = load_benchmark_config(DESCRIBED)["history"]
    assert hist[:2] == load_benchmark_config(WELLS)["history"]  # g40's lines, then this design's
    mine = " ".join(hist[2:])
    assert all(s in mine for s in ("59032..59199", "wells 0..31", "<= 0.45", "fold w mod 4", "21600..21615", "scenario validation", "spm_cap: 0",
                                   "13 scalars", "0.524", "0.515", "BEFORE any label"))
    # every declared range is written down in the history, in its order (the geometry's codes 0, 0.5, 1: [0, 1])
    ranges = re.findall(r"\[([-0-9.e]+), ([-0-9.e]+)\]", mine.split("(1) pump depth")[1])
    assert [(float(a), float(b)) for a, b in ranges][:12] + [(0.0, 1.0)] == [v[:2] for v in FEATURES.values()]
    assert described.PRECHECK_MAX == 0.45 and described.CANDIDATE == {"epochs": 30, "weight_decay": 0.0,
                                                                        "net_arch": [128, 128]}


def test_every_row_gets_its_wells_features(described):
    x = np.arange(12, dtype=np.float32).reshape(6, 2)
    well = np.array([0, 0, 2, 1, 2, 0])
    table = np.array([[10.0, 11.0], [20.0, 21.0], [30.0, 31.0]])
    out = described.described_inputs(x, well, table)
    assert out.dtype == np.float32 and out.shape == (6, 4)
    np.testing.assert_array_equal(out[:, :2], x)
    np.testing.assert_array_equal(out[:, 2:], table[well])


def test_well_features_are_the_files_the_env_hands_over(described):
    table = described.well_features({"observation": "field", "scenario": "train"}, [3, 0])
    env = gym.make("srenv/SuckerRod-v2", scenario="train", observation="field")
    for row, w in zip(table, (3, 0)):
        env.reset(seed=200 + w)  # seed mod 200 = the well, whatever the episode
        assert env.unwrapped.well.well_id == f"train-{w:03d}"
        np.testing.assert_array_equal(row, features(well_file(env)))
    assert not np.array_equal(table[0], table[1])


def test_bad_flags_refused_in_one_line(tmp_path):
    for args, match in ((["--stage", "precheck", "--workers", "3"], "--workers 3"),
                        (["--stage", "label"], "invalid choice")):
        r = subprocess.run([sys.executable, str(SCRIPT), *args, "--out", str(tmp_path / "o")], check=False,
                           capture_output=True, text=True, cwd=REPO, timeout=120,
                           env={**os.environ, "PYTHONPATH": str(REPO)})
        assert r.returncode == 2 and "Traceback" not in r.stderr
        assert match in r.stderr.strip().splitlines()[-1] and not (tmp_path / "o").exists()


def test_gate2_seeds_are_the_50_validation_wells_unused_and_registered(described, monkeypatch):
    """GATE 2 (helper g42): seeds 21650..21699 play validation-000..049 once each (seed mod 50), are disjoint from
    the first gate's and every earlier design's seeds, appear in no other config or script, and the history names
    them, the rule and the looks that a pass would have allowed (the fresh seed never played)."""
    gate2 = described.GATE2_SEEDS
    assert gate2 == list(range(21650, 21700)) and not set(gate2) & set(described.GATE_SEEDS)
    used = [(0, 10), (20000, 21416), (21600, 21616), (50000, 60000), (100000, 100100)]
    assert not any(lo <= s < hi for s in gate2 for lo, hi in used)
    assert sorted(s % 50 for s in gate2) == list(range(50))
    env = gym.make("srenv/SuckerRod-v2", scenario="validation", observation="field")
    for s in (gate2[0], gate2[17], gate2[-1]):
        env.reset(seed=s)
        assert env.unwrapped.well.well_id == f"validation-{s % 50:03d}"
    others = " ".join(f.read_text() for d in ("configs", "scripts") for f in (REPO / d).rglob("*.*")
                      if f.suffix in (".yaml", ".py") and f not in (DESCRIBED, SCRIPT))
    assert not re.search(r"\b216[5-9]\d\b", others)
    monkeypatch.chdir(REPO)
    hist = load_benchmark_config(DESCRIBED)["history"]
    g42 = " ".join(h for h in hist if "helper g42" in h)
    assert all(s in g42 for s in ("21650..21699", "scenario validation", "--stage gate2", "lower bound > 0",
                                  "constraint cost <=", "A failed gate 2 means no look", "100000..100099",
                                  "ci95_by_well", ">= 10 %", "--fresh-seed", "20261205", "spm_cap: 0"))
    assert any("GATE 2 played once" in h and "FAILED" in h for h in hist)


def test_the_registered_fresh_seed_was_never_played():
    """No fresh look in docs/ played seed 20261205 for this design (those played before: 20261203, 20261204); the one
    report that played it is helper a43's guarded described design's fresh look, registered in its own config."""
    import json

    played: dict[int, list[str]] = {}
    for f in (REPO / "docs").rglob("*.json"):
        rep = json.loads(f.read_text())
        fresh = rep.get("fresh") if isinstance(rep, dict) else None
        if isinstance(fresh, dict) and "seed" in fresh:
            played.setdefault(fresh["seed"], []).append(f.name)
    assert {20261203, 20261204} <= set(played)
    assert played.get(20261205, []) in ([], ["benchmark_v2_oracle_distilled_described_guarded_fresh.json"])


def test_stage_gate2_plays_the_first_gates_code_on_its_seeds(described, monkeypatch, tmp_path):
    """--stage gate2 hands play_design_gate the frozen design, GATE2_SEEDS, v2's validation split and OUT/gate2."""
    seen = {}

    def play(cfg, config, seeds, design, tuned, res, out, workers, scenario="train", also=None, shipped=True):
        seen.update(seeds=seeds, design=design, out=out, scenario=scenario, shipped=shipped)
        return {"summary": {}, "gate": False}

    monkeypatch.setattr(described, "require_precheck", lambda out: None)
    monkeypatch.setattr(described, "design_spec", lambda out, d: {"kind": "ensemble", "described": True})
    monkeypatch.setattr(described, "play_design_gate", play)
    monkeypatch.setattr(described, "print_outcome", lambda stage, rec: None)
    monkeypatch.setattr(sys, "argv", ["oracle_distill_described.py", "--stage", "gate2", "--out", str(tmp_path)])
    described.main()
    assert seen == {"seeds": list(range(21650, 21700)), "design": {"described_capped": {"kind": "ensemble",
                                                                                         "described": True}},
                    "out": tmp_path / "gate2", "scenario": "validation", "shipped": False}
