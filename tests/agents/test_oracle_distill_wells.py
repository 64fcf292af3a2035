"""The many-wells pooled student's design (scripts/oracle_distill_wells.py,
configs/benchmark/v2_oracle_distilled_wells.yaml, issue 24, helper g40): its labelled episodes are one per training
well 32..199 on unused seeds, its gate seeds are v2's validation split, and every row of the pool carries its training
well (so a fold holds every episode of a well). tests/agents/test_oracle_distill_pooled.py checks this script's
refusals (no gate without a passed pre-check, a bad flag), tests/agents/test_oracle_distill_capped.py that the config
is f24's but its history."""

from __future__ import annotations

import importlib
import re
import sys
from pathlib import Path

import numpy as np
import pytest

from agents.benchmark.config import load_benchmark_config
from agents.training.pooled_fit import grouped_folds

REPO = Path(__file__).resolve().parents[2]
SCRIPT = REPO / "scripts" / "oracle_distill_wells.py"
WELLS = REPO / "configs/benchmark/v2_oracle_distilled_wells.yaml"
DESCRIBED = REPO / "configs/benchmark/v2_oracle_distilled_described.yaml"  # d42: regenerates these labels by design


@pytest.fixture(scope="module")
def wells():
    sys.path.insert(0, str(SCRIPT.parent))  # the script and the pilots it imports, as when it runs
    return importlib.import_module(SCRIPT.stem)


def test_seeds_are_unused_and_cover_wells_32_to_199(wells, monkeypatch):
    monkeypatch.chdir(REPO)
    cfg = load_benchmark_config(WELLS)
    # every seed an earlier design or split played: tuning, validation and the gates, d24, e24, f24, the test split
    used = [(0, 10), (20000, 21400), (50000, 56032), (57000, 57016), (58000, 58200), (100000, 100100)]
    assert not any(lo <= s < hi for s in wells.SEEDS + wells.GATE_SEEDS for lo, hi in used)
    assert not set(wells.SEEDS) & set(wells.GATE_SEEDS)
    assert sorted(s % wells.WELLS for s in wells.SEEDS) == list(range(32, 200))
    assert [s for c in wells.chunks() for s in c] == wells.SEEDS
    assert wells.GATE_SEEDS == list(range(21400, 21416))
    others = " ".join(f.read_text() for f in (REPO / "configs").rglob("*.yaml") if f not in (WELLS, DESCRIBED))
    assert not re.search(r"\b(59[01]\d\d|214\d\d)\b", others)
    hist = " ".join(cfg["history"])
    assert all(s in hist for s in ("59032..59199", "21400..21415", "scenario validation", "<= 0.45",
                                   "spm_cap: 0", "WELL-grouped"))
    assert wells.PRECHECK_MAX == 0.45 and wells.CAP == {"spm_cap": 0.0}


def test_the_candidate_is_e24s_choice(wells):
    hist = " ".join(load_benchmark_config(REPO / "configs/benchmark/v2_oracle_distilled_pooled.yaml")["history"])
    assert "30 epochs, weight decay 0, 128x128" in hist
    assert wells.CANDIDATE == {"epochs": 30, "weight_decay": 0.0, "net_arch": [128, 128]}


def test_every_row_carries_its_well_and_a_fold_holds_whole_wells(wells, tmp_path):
    steps = 3
    d = {"pool": {"labels": str(tmp_path / "p1_{k}.npz"), "files": 2, "episode_steps": steps}}

    def save(path: Path, n_eps: int, tag: float) -> None:
        x = np.full((n_eps * steps, 2), tag, np.float32)
        x[:, 1] = np.repeat(np.arange(n_eps), steps)
        np.savez(path, x=x, label=np.zeros((n_eps * steps, 2), np.float32))

    for k in range(2):
        save(tmp_path / f"p1_{k}.npz", 32, k)  # P1: episode j = well j
    save(tmp_path / "labels_dagger.npz", 32, 2)
    save(tmp_path / "labels_wells_0.npz", wells.CHUNK, 3)  # the first chunk: wells 32 .. 32 + CHUNK - 1
    save(tmp_path / "labels_wells_2.npz", wells.CHUNK, 4)  # chunk 1 missing (a stopped run): chunk 2's wells
    pool, well = wells.wells_pool(tmp_path, d)
    ep = pool["x"][:, 1].astype(int)
    tag = pool["x"][:, 0]
    assert np.array_equal(well[tag < 3], ep[tag < 3])
    assert np.array_equal(well[tag == 3], 32 + ep[tag == 3])
    assert np.array_equal(well[tag == 4], 32 + 2 * wells.CHUNK + ep[tag == 4])
    for tr, te in grouped_folds(well, 4):
        assert not set(well[tr]) & set(well[te])


def test_the_design_is_the_pools_three_fits_capped(wells, tmp_path, monkeypatch):
    monkeypatch.chdir(REPO)
    spec = wells.design_spec(tmp_path, wells.design(wells.CONFIG))
    assert spec["kind"] == "ensemble" and [m["path"] for m in spec["members"]] == [
        str(tmp_path / "design" / f"oracle_distilled_v2_seed{k}.zip") for k in (0, 1, 2)]
    assert spec["residual"] == {"base": "pump_off", "params": spec["residual"]["params"], "scale": 0.5,
                                "cap": {"spm_cap": 0.0}}
