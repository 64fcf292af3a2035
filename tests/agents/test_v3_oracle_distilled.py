"""The causal oracle distilled on v3 (scripts/v3_oracle_distilled.py, configs/benchmark/v3_oracle_distilled.yaml,
issue 24, helper q44): the config is v3.yaml's protocol with v2's design on v3's training YAML; its DAgger seeds, the
gate's seeds and the fresh seed are disjoint from every split and earlier design; the stages refuse what the
history does not register; the gate and the looks' judge on fixed numbers."""

from __future__ import annotations

import importlib
import re
import shutil
import sys
from pathlib import Path

import gymnasium as gym
import pytest
import yaml

import srenv  # noqa: F401  (registers the envs)
from agents.benchmark.config import distill_seeds, load_benchmark_config

REPO = Path(__file__).resolve().parents[2]
SCRIPT = REPO / "scripts" / "v3_oracle_distilled.py"
CONFIG = REPO / "configs/benchmark/v3_oracle_distilled.yaml"
V2_DESIGN = REPO / "configs/benchmark/v2_oracle_distilled.yaml"
sys.path.insert(0, str(SCRIPT.parent))  # the script and the scripts it imports, as when it runs
vod = importlib.import_module(SCRIPT.stem)
ag = importlib.import_module("agreement_guard")


def _cfg(monkeypatch, path: Path) -> dict:
    monkeypatch.chdir(REPO)
    return load_benchmark_config(path)


def test_config_is_v3s_protocol_with_v2s_design_on_v3(monkeypatch):
    mine, v3, v2 = (_cfg(monkeypatch, p) for p in (CONFIG, REPO / "configs/benchmark/v3.yaml", V2_DESIGN))
    drop = ("history", "source", "agents", "quick")
    assert {k: v for k, v in mine.items() if k not in drop} == {k: v for k, v in v3.items() if k not in drop}
    q, q3 = (yaml.safe_load(p.read_text())["quick"] for p in (CONFIG, REPO / "configs/benchmark/v3.yaml"))
    assert {k: v for k, v in q.items() if k != "agents"} == {k: v for k, v in q3.items() if k != "agents"}
    run, run2 = mine["agents"]["runs"]["oracle_distilled"], v2["agents"]["runs"]["oracle_distilled"]
    assert run["config"] == "configs/train/ppo_residual_v3.yaml"
    for k in ("seeds", "ensemble", "residual"):
        assert run[k] == run2[k]
    t, t2 = run["teacher"], run2["teacher"]
    assert t["kind"] == t2["kind"] == "causal_oracle" and t["params"] == t2["params"]
    # the cut, registered once before any episode: 2 x 10, not 3 x 20
    assert (t["iterations"], t["episodes"], t2["iterations"], t2["episodes"]) == (2, 10, 3, 20)
    hist = " ".join(mine["history"])
    assert "2 iterations x 10" in hist and "81000 + 1000 k" in hist and "21850..21899" in hist
    assert vod.residual_spec(run, vod.load_tuned(vod.TUNED))["base"] == "pump_off"  # best residual base on v3


def test_dagger_seeds_are_disjoint_from_splits_and_earlier_designs(monkeypatch):
    run = _cfg(monkeypatch, CONFIG)["agents"]["runs"]["oracle_distilled"]
    mine = [s for k in run["seeds"] for s in distill_seeds(run["teacher"], k)]
    assert len(set(mine)) == 60 and min(mine) == 81000 and max(mine) == 83019
    used = [(0, 10), (20000, 21900), (100000, 100100)]  # tuning, validation (incl. the gate's), test
    for p in sorted((REPO / "configs/benchmark").glob("*.yaml")):
        if p == CONFIG:
            continue
        for r in ((yaml.safe_load(p.read_text()).get("agents") or {}).get("runs") or {}).values():
            if (r.get("teacher") or {}).get("seed_start") is not None:
                used += [(min(s), max(s) + 1) for s in (distill_seeds(r["teacher"], k) for k in r["seeds"])]
    assert not any(lo <= s < hi for s in mine for lo, hi in used)
    others = " ".join(f.read_text() for d in ("configs", "scripts") for f in (REPO / d).rglob("*.*")
                      if f.suffix in (".yaml", ".py") and f.resolve() not in (CONFIG, SCRIPT))
    assert not re.search(r"\b8[1-3]\d{3}\b", others)  # no other file names a seed of this block
    rest = others.replace("range(21800, 21850)", "")  # v3_validation.py's block, its end exclusive
    assert not re.search(r"\b21(8[5-9]|9\d)\d\b", rest) and "20261207" not in others


def test_gate_seeds_play_each_validation_well_once():
    assert vod.GATE_SEEDS == list(range(21850, 21900))
    env = gym.make("srenv/SuckerRod-v3", scenario="validation", observation="field")
    ids = [env.reset(seed=s)[1]["well_id"] for s in (vod.GATE_SEEDS[0], vod.GATE_SEEDS[-1])]
    assert ids == ["validation-000", "validation-049"]


def test_stages_refuse_an_unregistered_or_uncommitted_config(tmp_path, capsys):
    cfg = tmp_path / "v3_oracle_distilled.yaml"
    shutil.copyfile(CONFIG, cfg)
    text = cfg.read_text()
    for stage in vod.STAGES:
        cfg.write_text(text.replace(vod.REGISTERS[stage], "registers nothing"))
        with pytest.raises(SystemExit) as e:
            vod.require_registered(stage, cfg, vod.REGISTERS, "v3_oracle_distilled")
        assert e.value.code == 2
        err = capsys.readouterr().err.strip()
        assert err.startswith("v3_oracle_distilled: v3_oracle_distilled.yaml: no history line with")
        assert len(err.splitlines()) == 1
    cfg.write_text(text)  # registered but outside the repository's committed files: refused too
    with pytest.raises(SystemExit) as e:
        vod.require_registered("gate", cfg, vod.REGISTERS, "v3_oracle_distilled")
    assert e.value.code == 2 and "not committed" in capsys.readouterr().err
    # a stage's words start its line after "<date> <time> UTC, "; the words in the middle of a line register nothing
    assert ag.registers("2026-12-08 03:00 UTC, REGISTERS THE TEST LOOK: ...", "test", vod.REGISTERS)
    assert not ag.registers("2026-12-08 03:00 UTC, the REGISTERS THE TEST LOOK line", "test", vod.REGISTERS)


def _fig(d_lo: float, cost: float, base_cost: float = 5.0) -> dict:
    return {"ens": {"vs_best_tuned_usd_h": {"ci95_by_well": [d_lo, d_lo + 5]}, "cost": cost},
            "alarm_pump_off": {"vs_best_tuned_usd_h": {"ci95_by_well": [0, 0]}, "cost": base_cost}}


@pytest.mark.parametrize(("lo", "cost", "passed"), [(0.1, 5.0, True), (0.0, 4.0, False), (-1, 4, False),
                                                     (2.0, 5.01, False)])
def test_gate_rule(lo, cost, passed):
    assert vod.gate(_fig(lo, cost), "ens", "alarm_pump_off") is passed


def _report(diff: list[float], cost: float, base: float = 100.0) -> dict:
    """Two wells twice each: ``diff`` the design's per-episode return minus pump_off's (the best baseline)."""
    eps = {"pump_off": [base] * 4, "fillage_pi": [base - 50] * 4, "ens": [base + d for d in diff]}
    costs = {"pump_off": 1.0, "fillage_pi": 0.5, "ens": cost}
    wells = ["w0", "w1", "w0", "w1"]
    pol = {n: {"kind": "agent" if n == "ens" else "baseline",
               "episodes": [{"well_id": w, "seed": i, "reward": r, "cost": costs[n], "steps": 2}
                            for i, (w, r) in enumerate(zip(wells, rs))]} for n, rs in eps.items()}
    pol["installed"] = pol.pop("fillage_pi")
    from agents.benchmark.report import paired_table

    summ = {n: {"mean_reward": sum(e["reward"] for e in p["episodes"]) / 4} for n, p in pol.items()}
    return {"policies": pol, "summary": summ, "paired": paired_table(pol)}


@pytest.mark.parametrize(("diff", "cost", "passed"), [([10, 12, 11, 13], 1.0, True), ([9, 9.5, 9, 9.4], 0.9, False),
                                                      ([10, 12, 11, 13], 1.01, False), ([30, -10, 28, -9], 1, False)])
def test_look_judge(diff, cost, passed):
    v = vod.judge(_report(diff, cost), "ens")
    assert v["baseline"] == "pump_off" and v["passed"] is passed
    assert v["diff_usd_h"] == pytest.approx(sum(diff) / 4 / 2) and v["relative"] == pytest.approx(sum(diff) / 400)


def test_test_look_refuses_a_failed_gate(tmp_path, capsys):
    (tmp_path / "gate.json").write_text('{"gate": {"design": "oracle_distilled_ensemble", "passed": false}}')
    with pytest.raises(SystemExit) as e:
        vod.play_test(tmp_path, 1)
    assert e.value.code == 2 and "gate passed = False" in capsys.readouterr().err
