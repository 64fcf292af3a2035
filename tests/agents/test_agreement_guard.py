"""The shipped students trusted only where they agree, alarms first (scripts/agreement_guard.py,
configs/benchmark/v2_oracle_distilled_agreement.yaml, issue 24, helper u44): the config is b43's but its history,
which registers the shipped models' sha256, the disagreement and its taus, the family, the selection's training
seeds, the rule, the gate's validation seeds and the fresh seed; the family is declared once and bounded; THE RULE on
fixed numbers; the gate on the shipped ensemble (tau 1: the ensemble, tau 0: the base); the reference's measured
disagreement is the played policy's; the stages refuse what their history does not register."""

from __future__ import annotations

import hashlib
import importlib
import json
import os
import re
import subprocess
import sys
from pathlib import Path

import gymnasium as gym
import pytest
from test_guard_described import REPO, RULE_CASES, _hist, _summ, same_but_history
from test_guard_stroke import CONFIG as B43
from test_guard_stroke import gd

import srenv  # noqa: F401  (registers the envs)
from agents.evaluation.agent import build_policy
from agents.evaluation.rollout import run_episode
from agents.policies.field import obs_names_of
from agents.policies.guarded import check_guard

SCRIPT = REPO / "scripts" / "agreement_guard.py"  # on sys.path as b43's test put its folder, as when it runs
CONFIG = REPO / "configs/benchmark/v2_oracle_distilled_agreement.yaml"
ag = importlib.import_module(SCRIPT.stem)  # handing guard_described (gd) its plan: its stages and RULE
TUNED = json.loads((REPO / "docs/v2/benchmark.json").read_text())["tuned"]


def test_config_is_b43s_but_its_history(monkeypatch):
    assert same_but_history(monkeypatch, CONFIG, B43)


def test_the_history_registers_inner_taus_family_data_rule_gate_and_looks(monkeypatch):
    hist = _hist(monkeypatch, CONFIG)
    assert ag.REGISTERS["select"] in hist
    for name in ("oracle_distilled_v2_seed0.zip", "oracle_distilled_v2_seed1.zip", "oracle_distilled_v2_seed2.zip"):
        sha = hashlib.sha256((REPO / "models" / name).read_bytes()).hexdigest()
        assert sha in hist and ag.inner()  # the registered files are the shipped ones, checked by inner()
    assert all(s in hist for s in ("59500..59549", "scenario train", "21750..21799", "scenario validation",
                                   "scale 0.5", "uncapped", "HARD gate", "ddof 0", "the larger of the 2 entries",
                                   "NOT a candidate", "highest CI lower bound", "lower bound is <= 0",
                                   "lower bound of d > 0", "cost <= alarm_pump_off's", f"--fresh-seed {ag.FRESH_SEED}",
                                   ">= 10 %", "follow_alarms true", "follow_idle true", "9 = q in"))
    assert f"q in {{{', '.join(map(str, ag.QUANTILES))}}}" in hist
    assert all(f"{m} (" in hist for m in ag.MODES) and "named q{q}_{agree|alarms|alarms_idle}" in hist


def test_seeds_are_unused_and_play_the_wells_they_say():
    sel = ag.SELECT_SEEDS
    assert sel == list(range(59500, 59550)) and ag.GATE_SEEDS == list(range(21750, 21800))
    used = [(0, 10), (20000, 21750), (50000, 59500), (100000, 100100)]  # every earlier design's and split's seeds
    assert not any(lo <= s < hi for s in sel for lo, hi in used)
    mine = (CONFIG, SCRIPT, Path(__file__).resolve())
    others = " ".join(f.read_text() for d in ("configs", "scripts", "tests") for f in (REPO / d).rglob("*.*")
                      if f.suffix in (".yaml", ".py") and f.resolve() not in mine)
    assert not re.search(r"\b595[0-4]\d\b", others.replace("range(59450, 59500)", ""))  # b43's block's end
    assert not re.search(r"\b595[0-4]\d\b", (REPO / "docs/agents.md").read_text().split("(v2, helper u44")[0])
    env = gym.make("srenv/SuckerRod-v2", scenario="train", observation="field")
    assert [env.reset(seed=s)[1]["well_id"] for s in (sel[0], sel[-1])] == ["train-100", "train-149"]


def test_the_family_is_declared_once_and_bounded():
    v = ag.VARIANTS
    assert next(iter(v)) == "unguarded" and v["unguarded"] is None and len(v) == 10
    names = obs_names_of(gym.make("srenv/SuckerRod-v2", scenario="train", observation="field"))
    for x in (y for y in v.values() if y is not None):
        check_guard({**x["guard"], "disagreement_above": 0.5}, names)
        assert x["fallback"] == ("pump_off" if not x["guard"] else "alarm_pump_off")
        assert x["guard"].get("follow_alarms", False) == (x["fallback"] == "alarm_pump_off")
    assert len({json.dumps(x, sort_keys=True) for x in v.values() if x is not None}) == 9
    assert {gd.conditions(gd.guard_of(x)) for x in v.values()} == {0}  # ties go to the declared order


FAM = {n: None if n == "unguarded" else {"quantile": 0.5, "guard": {}, "fallback": "pump_off"}
       for n in ("unguarded", "a", "b", "c", "d")}


@pytest.mark.parametrize("rows, chosen", [c for c in RULE_CASES if c[1] != "b" or "d" in c[0]])
def test_the_selection_rule(rows, chosen):
    """design A's cases (those that do not turn on the number of guard conditions: every variant here has none)"""
    assert gd.choose(_summ(**rows), FAM) == chosen


def _taus(tmp_path, taus):
    (tmp_path / "select").mkdir(exist_ok=True)
    (tmp_path / "select" / "disagreement.json").write_text(json.dumps({"taus": taus}))


def test_specs_put_the_measured_tau_on_each_variant(tmp_path):
    _taus(tmp_path, {"0.5": 0.31, "0.8": 0.52, "0.95": 0.7})
    sp = ag.specs(tmp_path, {"tuned": TUNED}, ag.VARIANTS)
    assert list(sp) == ["alarm_pump_off", *ag.VARIANTS] and sp["unguarded"] == ag.inner()
    g = sp["q0.8_alarms_idle"]
    assert g["guard"] == {"follow_alarms": True, "follow_idle": True, "disagreement_above": 0.52}
    assert g["fallback"] == {"name": "alarm_pump_off", "params": TUNED["alarm_pump_off"]["params"]}
    assert sp["q0.95_agree"]["fallback"] == {"name": "pump_off", "params": TUNED["pump_off"]["params"]}
    assert sp["q0.5_agree"]["guard"] == {"disagreement_above": 0.31} and sp["q0.5_agree"]["inner"] == ag.inner()


def test_without_the_reference_run_the_specs_are_refused(tmp_path):
    with pytest.raises(SystemExit):
        ag.specs(tmp_path, {"tuned": TUNED}, {"q0.5_agree": ag.VARIANTS["q0.5_agree"]})


def test_the_gate_on_the_shipped_ensemble_tau_one_is_the_ensemble_tau_zero_the_base(tmp_path):
    """On a 1 h training episode: tau 1 (the largest std of actions in [-1, 1]) never gates; tau 0 gates every
    interval whose members do not agree exactly, so the 'agree' variant is pump_off as tuned."""
    env = gym.make("srenv/SuckerRod-v2", scenario="train", observation="field", episode_hours=1.0)
    v = {"q0.5_agree": ag.VARIANTS["q0.5_agree"]}
    played = {}
    for tau in (1.0, 0.0):
        _taus(tmp_path, {"0.5": tau})
        played[tau] = run_episode(env, build_policy(ag.specs(tmp_path, {"tuned": TUNED}, v)["q0.5_agree"], env), 3)
    ens = run_episode(env, build_policy(ag.inner(), env), 3)
    base = run_episode(env, build_policy({"kind": "baseline", "name": "pump_off",
                                          "params": TUNED["pump_off"]["params"]}, env), 3)
    assert played[1.0]["reward"] == ens["reward"] and played[0.0]["reward"] == base["reward"]
    assert ens["reward"] != base["reward"]


def test_the_measured_reference_is_the_played_ensemble():
    """The reference run that measures the disagreement plays the very policy the rollout plays (same return)."""
    rec = ag._episode(3)
    env = gym.make("srenv/SuckerRod-v2", scenario="train", observation="field")
    ref = run_episode(env, build_policy(ag.inner(), env), 3)
    assert rec["reward"] == pytest.approx(ref["reward"], rel=1e-9) and rec["well_id"] == ref["well_id"]
    assert len(rec["disagreement"]) == 144 and all(0.0 <= d <= 1.0 for d in rec["disagreement"])


def test_a_stage_its_history_does_not_register_is_refused(tmp_path, capsys, monkeypatch):
    ag.require_registered("select")  # registered, committed
    raw = CONFIG.read_text()
    bare = tmp_path / "c.yaml"
    bare.write_text(raw.replace(ag.REGISTERS["select"], "before"))
    for stage, cfg, why in (("select", bare, "no history line with 'BEFORE any selection"),
                            ("test", CONFIG, "no history line with 'REGISTERS THE TEST LOOK'"),
                            ("select", tmp_path / "c2.yaml", "not committed as it is")):
        if cfg.name == "c2.yaml":
            cfg.write_text(raw)
        with pytest.raises(SystemExit) as e:
            ag.require_registered(stage, cfg)
        assert e.value.code == 2 and why in capsys.readouterr().err
    assert not ag.registers(_hist(monkeypatch, CONFIG), "gate")  # the first line only names the words
    assert ag.registers("2026-12-08 02:40 UTC, REGISTERS THE GATE: the chosen variant ...", "gate")


@pytest.mark.parametrize("stage", ["gate", "test"])
def test_gate_and_look_refuse_without_their_stage_before(tmp_path, stage):
    r = subprocess.run([sys.executable, str(SCRIPT), "--stage", stage, "--out", str(tmp_path)], check=False,
                       capture_output=True, text=True, cwd=REPO, timeout=120,
                       env={**os.environ, "PYTHONPATH": str(REPO)})
    assert r.returncode == 2 and "Traceback" not in r.stderr and not (tmp_path / stage).exists()
    assert "expected" in r.stderr.strip().splitlines()[-1]


def test_a_report_of_the_look_rebuilds_its_spec(tmp_path):
    """The look's record (guarded_record of the chosen variant) keeps the measured tau and the flags; replay's
    policy_specs and the fresh look's record copy rebuild the very spec the look played."""
    from agents.benchmark.fresh import _policies
    from agents.evaluation.replay import load_report, policy_specs

    _taus(tmp_path, {"0.5": 0.31, "0.8": 0.52, "0.95": 0.7})
    tuned = load_report(REPO / "docs/v2/benchmark.json")["tuned"]
    name, spec, rec = ag.look_design(tmp_path, "q0.8_alarms", tuned, None)
    assert name == "oracle_distilled_guarded"
    assert rec["guarded"]["guard"] == {"follow_alarms": True, "disagreement_above": 0.52}
    (rebuilt,) = policy_specs({"policies": {name: rec}}, name, REPO / "docs/v2")
    assert rebuilt == spec
    fresh = _policies({"policies": {name: rec}}, {name: [rebuilt]}, [name], [{"reward": 0.0}], 1)
    assert policy_specs({"policies": fresh}, name, REPO / "docs/v2") == [rebuilt]
