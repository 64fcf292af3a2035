"""The causal oracle distilled on v3 (scripts/v3_oracle_distilled.py, issue 24): q44's design trained from scratch
(configs/benchmark/v3_oracle_distilled.yaml) and w44's shipped v2 students continued
(configs/benchmark/v3_oracle_distilled_continued.yaml, ``--design continued``). Each config is v3.yaml's protocol with
its design on v3's training YAML; its DAgger seeds, the gate's seeds and the fresh seed are disjoint from every split
and earlier design; the continued design's inner is the shipped students by sha256; the stages refuse what the
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
CONTINUED = REPO / "configs/benchmark/v3_oracle_distilled_continued.yaml"
V2_DESIGN = REPO / "configs/benchmark/v2_oracle_distilled.yaml"
V2_MORE = REPO / "configs/benchmark/v2_oracle_distilled_more.yaml"  # d24's continuation scheme on v2
sys.path.insert(0, str(SCRIPT.parent))  # the script and the scripts it imports, as when it runs
vod = importlib.import_module(SCRIPT.stem)
ag = importlib.import_module("agreement_guard")


def _cfg(monkeypatch, path: Path) -> dict:
    monkeypatch.chdir(REPO)
    return load_benchmark_config(path)


@pytest.mark.parametrize("design", list(vod.DESIGNS))
def test_config_is_v3s_protocol(monkeypatch, design):
    path = vod.DESIGNS[design]["config"]
    mine, v3 = (_cfg(monkeypatch, p) for p in (path, REPO / "configs/benchmark/v3.yaml"))
    drop = ("history", "source", "agents", "quick")
    assert {k: v for k, v in mine.items() if k not in drop} == {k: v for k, v in v3.items() if k not in drop}
    q, q3 = (yaml.safe_load(p.read_text())["quick"] for p in (path, REPO / "configs/benchmark/v3.yaml"))
    assert {k: v for k, v in q.items() if k != "agents"} == {k: v for k, v in q3.items() if k != "agents"}
    assert mine["agents"]["runs"]["oracle_distilled"]["config"] == "configs/train/ppo_residual_v3.yaml"


def test_continued_config_is_d24s_scheme_from_the_shipped_students_on_v3(monkeypatch):
    mine, more = (_cfg(monkeypatch, p) for p in (CONTINUED, V2_MORE))
    run, run2 = mine["agents"]["runs"]["oracle_distilled"], more["agents"]["runs"]["oracle_distilled"]
    assert {k: v for k, v in run.items() if k not in ("config", "teacher")} == \
        {k: v for k, v in run2.items() if k not in ("config", "teacher")}
    t, t2 = run["teacher"], run2["teacher"]
    assert {k: v for k, v in t.items() if k != "seed_start"} == {k: v for k, v in t2.items() if k != "seed_start"}
    assert (t["iterations"], t["episodes"], t["beta0"], t["params"]) == (2, 16, 0.0, {"horizon": 6, "replan_every": 3})
    assert t["init"]["path"] == "models/oracle_distilled_v2_seed{seed}.zip"  # the shipped students, as d24's
    hist = " ".join(mine["history"])
    assert "2 iterations x 16" in hist and "85000 + 1000 k" in hist and "21900..21949" in hist
    assert vod.residual_spec(run, vod.load_tuned(vod.TUNED))["base"] == "pump_off"  # v3's tuned, as q44's


def test_continued_inner_is_the_shipped_students_by_sha256(tmp_path, monkeypatch, capsys):
    hist = " ".join(yaml.safe_load(CONTINUED.read_text())["history"][0].split())
    assert len(vod.SHIPPED_SHA256) == 6 and all(d in hist for d in vod.SHIPPED_SHA256.values())
    vod.check_inner("continued")  # the shipped files are the registered ones
    for f in vod.SHIPPED_SHA256:
        shutil.copyfile(vod.SHIPPED / f, tmp_path / f)
    (tmp_path / "oracle_distilled_v2_seed1_obs_norm.npz").write_bytes(b"not the registered statistics")
    monkeypatch.setattr(vod, "SHIPPED", tmp_path)
    with pytest.raises(SystemExit) as e:
        vod.check_inner("continued")
    assert "seed1_obs_norm.npz: sha256 differs from the registered shipped v2 student's" in str(e.value.code)
    vod.check_inner("trained")  # q44's design has no inner


def test_config_is_v2s_design_on_v3(monkeypatch):
    mine, v2 = (_cfg(monkeypatch, p) for p in (CONFIG, V2_DESIGN))
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


@pytest.mark.parametrize(("design", "n", "lo", "hi", "block"),
                         [("trained", 60, 81000, 83019, r"\b8[1-3]\d{3}\b"),
                          ("continued", 96, 85000, 87031, r"\b8[5-7]\d{3}\b")])
def test_dagger_seeds_are_disjoint_from_splits_and_earlier_designs(monkeypatch, design, n, lo, hi, block):
    path = vod.DESIGNS[design]["config"]
    run = _cfg(monkeypatch, path)["agents"]["runs"]["oracle_distilled"]
    mine = [s for k in run["seeds"] for s in distill_seeds(run["teacher"], k)]
    assert len(set(mine)) == n and min(mine) == lo and max(mine) == hi
    used = [(0, 10), (20000, 21950), (100000, 100100)]  # tuning, validation (incl. the gates'), test
    for p in sorted((REPO / "configs/benchmark").glob("*.yaml")):
        if p == path:
            continue
        for r in ((yaml.safe_load(p.read_text()).get("agents") or {}).get("runs") or {}).values():
            if (r.get("teacher") or {}).get("seed_start") is not None:
                used += [(min(s), max(s) + 1) for s in (distill_seeds(r["teacher"], k) for k in r["seeds"])]
    assert not any(lo <= s < hi for s in mine for lo, hi in used)
    # no other file names a seed of this block; the two designs' configs and their script name the gates' seeds
    others = " ".join(f.read_text() for d in ("configs", "scripts") for f in (REPO / d).rglob("*.*")
                      if f.suffix in (".yaml", ".py") and f.resolve() not in (CONFIG, CONTINUED, SCRIPT))
    assert not re.search(block, others)
    rest = others.replace("range(21800, 21850)", "")  # v3_validation.py's block, its end exclusive
    assert not re.search(r"\b21(8[5-9]|9\d)\d\b", rest) and "20261207" not in others


@pytest.mark.parametrize(("design", "first"), [("trained", 21850), ("continued", 21900)])
def test_gate_seeds_play_each_validation_well_once(design, first):
    seeds = vod.DESIGNS[design]["gate_seeds"]
    assert seeds == list(range(first, first + 50))
    env = gym.make("srenv/SuckerRod-v3", scenario="validation", observation="field")
    ids = [env.reset(seed=s)[1]["well_id"] for s in (seeds[0], seeds[-1])]
    assert ids == ["validation-000", "validation-049"]
    assert set(vod.DESIGNS["trained"]["gate_seeds"]).isdisjoint(vod.DESIGNS["continued"]["gate_seeds"])


@pytest.mark.parametrize("design", list(vod.DESIGNS))
def test_stages_refuse_an_unregistered_or_uncommitted_config(tmp_path, capsys, design):
    cfg = tmp_path / "v3_oracle_distilled.yaml"
    shutil.copyfile(vod.DESIGNS[design]["config"], cfg)
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


@pytest.mark.parametrize("design", list(vod.DESIGNS))
def test_test_look_refuses_a_failed_gate(tmp_path, capsys, design):
    (tmp_path / "gate.json").write_text('{"gate": {"design": "oracle_distilled_ensemble", "passed": false}}')
    with pytest.raises(SystemExit) as e:
        vod.play_test(tmp_path, 1, design)
    assert e.value.code == 2 and "gate passed = False" in capsys.readouterr().err


@pytest.mark.parametrize("design", list(vod.DESIGNS))
def test_gate_refuses_missing_students_before_any_episode(tmp_path, capsys, monkeypatch, design):
    monkeypatch.setattr(vod, "play", lambda *a, **k: pytest.fail("played without its students"))
    with pytest.raises(SystemExit) as e:
        vod.play_gate(tmp_path, 1, design)
    err = capsys.readouterr().err.strip()
    assert e.value.code == 2 and err.endswith("no such student (run --stage dagger first)")
    assert "oracle_distilled_v3_seed0.zip" in err and len(err.splitlines()) == 1


def test_design_flag_is_refused_in_one_line(capsys, monkeypatch):
    monkeypatch.setattr(sys, "argv", ["v3_oracle_distilled.py", "--design", "bogus", "--stage", "gate", "--out", "x"])
    with pytest.raises(SystemExit) as e:
        vod.main()
    assert e.value.code == 2 and "--design: invalid choice: 'bogus'" in capsys.readouterr().err
