"""The shipped students under a guard whose fallback changes what alarm_pump_off pumps (scripts/guard_stroke.py,
configs/benchmark/v2_oracle_distilled_stroke_guarded.yaml, issue 24, helper b43): the config is a43's but its
history, which registers the shipped models' sha256, the mechanism check, the family, the selection's training seeds,
the rule, the gate's unused validation seeds and the fresh seed; the family is declared once and bounded (guards by
check_guard, fallbacks by the baselines' declared bounds); THE RULE on fixed numbers; the inner is the shipped
record; the mechanism (only idling stops the tagging cost) on the env; the stages' plumbing and refusals."""

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
from test_guard_described import FAM as A43_FAM  # a43's design: THE RULE's cases, the history reader
from test_guard_described import REPO, RULE_CASES, _hist, _summ, same_but_history

import srenv  # noqa: F401  (registers the envs)
from agents.inputs import ConfigError, baseline_params
from agents.policies.field import IDLE, obs_names_of
from agents.policies.guarded import check_guard

SCRIPT = REPO / "scripts" / "guard_stroke.py"
CONFIG = REPO / "configs/benchmark/v2_oracle_distilled_stroke_guarded.yaml"
A43 = REPO / "configs/benchmark/v2_oracle_distilled_described_guarded.yaml"
sys.path.insert(0, str(SCRIPT.parent))  # the script and the pilots it imports, as when it runs
gs = importlib.import_module(SCRIPT.stem)
gd = importlib.import_module("guard_described")  # whose stages and RULE this design hands its plan


def test_config_is_a43s_but_its_history(monkeypatch):
    assert same_but_history(monkeypatch, CONFIG, A43)


def test_the_history_registers_inner_mechanism_family_data_rule_gate_and_looks(monkeypatch):
    hist = _hist(monkeypatch, CONFIG)
    assert "BEFORE any selection or gate episode" in hist
    for name, sha in gs.MODELS_SHA256.items():  # the registered files are the shipped ones
        assert sha in hist and hashlib.sha256((REPO / "models" / name).read_bytes()).hexdigest() == sha
    assert all(s in hist for s in ("59450..59499", "scenario train", "21750..21799", "scenario validation",
                                   "scale 0.5", "uncapped", "follow_shut_in true", "NOT a candidate", "seed 59404",
                                   "only idling (a_spm -1) stops it", "highest CI lower bound",
                                   "fewer guard conditions", "lower bound is <= 0", "lower bound of d > 0",
                                   "cost <= alarm_pump_off's", f"--fresh-seed {gs.FRESH_SEED}", ">= 10 %"))
    assert f"T in {{{', '.join(map(str, gs.TAG))}}}" in hist and "grid of 24" in hist
    assert f"HOLD {' | '.join(map(str, gs.HOLD))} intervals" in hist and "fillage_est below 0.85" in hist
    assert "idle (a_spm -1" in hist and "short_slow (a_stroke -1, a_spm -0.6)" in hist and "short (a_stroke -1)" in hist
    assert gs.FALLBACK == {"idle": {"a_spm": -1.0}, "short_slow": {"a_stroke": -1.0, "a_spm": -0.6},
                           "short": {"a_stroke": -1.0}}


def test_seeds_are_unused_and_play_the_wells_they_say():
    sel, gate = gs.SELECT_SEEDS, gs.GATE_SEEDS
    assert sel == list(range(59450, 59500)) and gate == list(range(21750, 21800)) and gs.FRESH_SEED == 20261206
    used = [(0, 10), (20000, 21750), (50000, 59450), (100000, 100100)]  # every earlier design's and split's seeds
    assert not any(lo <= s < hi for s in sel + gate for lo, hi in used)
    mine = (CONFIG, SCRIPT, Path(__file__).resolve(),  # and u44's, which registers b43's unplayed gate and fresh seeds
            REPO / "configs/benchmark/v2_oracle_distilled_agreement.yaml", SCRIPT.with_name("agreement_guard.py"),
            Path(__file__).with_name("test_agreement_guard.py"))
    others = " ".join(f.read_text() for d in ("configs", "scripts", "tests") for f in (REPO / d).rglob("*.*")
                      if f.suffix in (".yaml", ".py") and f.resolve() not in mine)
    assert not re.search(r"\b(594[5-9]\d|217[5-9]\d|20261206)\b", others.replace("range(59400, 59450)", "")
                         .replace("range(21700, 21750)", ""))
    before = (REPO / "docs/agents.md").read_text().split("(v2, helper b43")[0]
    assert not re.search(r"\b(594[5-9]\d|217[5-9]\d|20261206)\b", before)
    for scenario, seed, well in (("train", sel[0], "train-050"), ("train", sel[-1], "train-099"),
                                 ("validation", gate[0], "validation-000"), ("validation", gate[-1], "validation-049")):
        env = gym.make("srenv/SuckerRod-v2", scenario=scenario, observation="field")
        env.reset(seed=seed)
        assert env.unwrapped.well.well_id == well


def test_the_family_is_declared_once_and_bounded():
    v = gs.VARIANTS
    assert next(iter(v)) == "unguarded" and v["unguarded"] is None and len(v) == 25
    names = obs_names_of(gym.make("srenv/SuckerRod-v2", scenario="train", observation="field"))
    tuned = {"threshold": 0.99, "idle_time_s": 3600, "a_spm": 0.4, "a_stroke": 0.0, "load_drop": 0.5,
             "alarm_prob": 0.6, "gas_slowdown": 0.6}
    for x in (y for y in v.values() if y is not None):
        check_guard(x["guard"], names)  # every key bounded, every limit's name in v2's field observation
        g = x["guard"]
        assert g["follow_shut_in"] is True and g["above"]["prob_tagging_up"] == g["above"]["prob_tagging_down"]
        assert gs.fallback_params(tuned, x["fallback"]) == {**tuned, **x["fallback"]}  # within the declared bounds
    assert len({json.dumps(x, sort_keys=True) for x in v.values() if x is not None}) == 24
    assert sorted({gd.conditions(gd.guard_of(x)) for x in v.values()}) == [0, 2, 3]
    with pytest.raises(ConfigError, match="fallback.alarm_pump_off.a_stroke"):
        gs.fallback_params(tuned, {"a_stroke": -1.5})  # a change out of the action range is refused by name
    assert baseline_params("alarm_pump_off", {"a_spm": IDLE}, "x") == {"a_spm": -1.0}


# a43's cases of THE RULE, on this design's variant form ({"guard", "fallback"}): the same choices
FAM = {n: None if g is None else {"guard": g, "fallback": {"a_spm": -1.0}} for n, g in A43_FAM.items()}


@pytest.mark.parametrize("rows, chosen", RULE_CASES)
def test_the_selection_rule(rows, chosen):
    assert gd.choose(_summ(**rows), FAM) == chosen


def test_the_inner_is_the_shipped_record(monkeypatch):
    ens = gs.inner()
    assert ens["kind"] == "ensemble" and "described" not in ens and "cap" not in ens["residual"]
    assert ens["residual"]["base"] == "pump_off" and ens["residual"]["scale"] == 0.5
    assert [Path(m["path"]) for m in ens["members"]] == [REPO / "models" / n for n in gs.MODELS_SHA256]
    monkeypatch.setattr(gs, "MODELS_SHA256", {**gs.MODELS_SHA256, "oracle_distilled_v2_seed1.zip": "0" * 64})
    with pytest.raises(SystemExit, match="registered shipped student"):
        gs.inner()


def test_the_mechanism_only_idling_stops_the_tagging_cost(tmp_path):
    """On the registered training well with a tagging event, a shorter stroke and a lower SPM leave the tagging cost
    as it is (cost_tagging = severity x the fraction pumped); idling stops it."""
    rows = gs.mechanism(tmp_path)["rows"]
    tuned = rows["tuned"]
    assert tuned["tagging_intervals"] > 50 and tuned["cost_tagging"] > 10 and tuned["prob_tagging_down"] > 0.9
    for k in ("stroke-0.5", "stroke-1", "stroke-1_spm0.0", "stroke-1_spm-0.6"):
        assert rows[k]["cost_tagging"] == pytest.approx(tuned["cost_tagging"])
        assert rows[k]["stroke_length_m"] < tuned["stroke_length_m"]
    assert rows["stroke-1_spm-0.6"]["avg_spm"] < rows["stroke-1"]["avg_spm"]
    assert rows["stroke-1_spm-0.6"]["reward_tagging_usd_h"] > tuned["reward_tagging_usd_h"]  # fewer strokes
    assert rows["idle"]["cost_tagging"] == 0.0 and rows["idle"]["duty"] == 0.0
    assert json.loads((tmp_path / "mechanism.json").read_text())["well_id"] == "train-004"


def test_stages_play_their_seeds_on_their_split(monkeypatch, tmp_path):
    """--stage select plays alarm_pump_off and every variant on SELECT_SEEDS (training wells) and applies the rule;
    --stage gate hands play_design_gate the chosen variant's spec (its fallback changed), GATE_SEEDS, v2's validation
    split, OUT/gate."""
    seen: dict = {}
    pick = "tag0.8_none_idle_hold3"

    def play_validation(cfg, specs, out, workers):
        seen["select"] = (cfg["validation"], list(specs), out)
        rec = {"reward": 144.0, "cost": 1.0, "well_id": "train-050", "cost_pound": 1.0}
        return {n: [{**rec, "reward": 144.0 * (2 + (n == pick) + 0.1 * i)} if n != "alarm_pump_off"
                    else {**rec, "reward": 144.0 * (1 + 0.1 * i)} for i in range(4)] for n in specs}

    def play(cfg, config, seeds, design, tuned, res, out, workers, scenario="train", also=None, shipped=True):
        seen["gate"] = {"seeds": seeds, "design": design, "out": out, "scenario": scenario, "shipped": shipped}
        return {"summary": {}, "gate": False}

    fb = {"threshold": 0.99, "idle_time_s": 3600, "a_spm": 0.4, "a_stroke": 0.0}
    monkeypatch.setattr(gd, "require_precheck", lambda out: pytest.fail("this design has no precheck"))
    monkeypatch.setattr(gd, "design", lambda config: {"cfg": {"validation": {}}, "tuned": {"alarm_pump_off": {
        "params": fb}}, "res": {}})
    monkeypatch.setattr(gd, "play_validation", play_validation)
    monkeypatch.setattr(gd, "play_design_gate", play)
    rec = gd.select(tmp_path, 2, gs.PLAN)
    assert seen["select"] == ({"seeds": list(range(59450, 59500)), "scenario": "train"},
                              ["alarm_pump_off", *gs.VARIANTS], tmp_path / "select")
    assert rec["chosen"] == pick and rec["config"] == "configs/benchmark/v2_oracle_distilled_stroke_guarded.yaml"
    gd.gate(tmp_path, 2, gs.PLAN)
    g = seen["gate"]
    assert (g["seeds"], g["out"], g["scenario"], g["shipped"]) == (list(range(21750, 21800)), tmp_path / "gate",
                                                                   "validation", False)
    (name, spec), = g["design"].items()
    assert name == pick and spec["kind"] == "guarded" and spec["inner"] == gs.inner()
    assert spec["guard"] == gs.VARIANTS[pick]["guard"]
    assert spec["fallback"] == {"name": "alarm_pump_off", "params": {**fb, "a_spm": -1.0}}


def test_a_report_of_the_look_rebuilds_its_spec_with_the_changed_fallback():
    """The look's record (guarded_record of the chosen variant on the shipped students) keeps the fallback's changed
    parameters; replay's policy_specs and the fresh look's record copy rebuild the very spec the look played."""
    from agents.benchmark.fresh import _policies
    from agents.evaluation.replay import load_report, policy_specs

    tuned = load_report(REPO / "docs/v2/benchmark.json")["tuned"]
    name, spec, rec = gs.look_design(None, "tag0.8_pound_short_slow_hold6", tuned, None)
    assert name == "oracle_distilled_guarded" and "described" not in rec
    assert rec["guarded"]["fallback"]["params"] == {**tuned["alarm_pump_off"]["params"], "a_stroke": -1.0,
                                                    "a_spm": -0.6, "idle_time_s": 3600.0}
    (rebuilt,) = policy_specs({"policies": {name: rec}}, name, REPO / "docs/v2")
    assert rebuilt == spec
    fresh = _policies({"policies": {name: rec}}, {name: [rebuilt]}, [name], [{"reward": 0.0}], 1)
    assert policy_specs({"policies": fresh}, name, REPO / "docs/v2") == [rebuilt]


def test_an_idle_fallback_idles_the_well_while_the_guard_holds():
    from agents.evaluation.agent import build_policy

    env = gym.make("srenv/SuckerRod-v2", scenario="train", observation="field", episode_hours=1.0)
    fb = gs.fallback_params({"threshold": 0.99, "idle_time_s": 3600, "a_spm": 0.4, "a_stroke": 0.0}, {"a_spm": -1.0})
    from agents.policies.guarded import guarded_spec

    pol = build_policy(guarded_spec(gs.inner(), "alarm_pump_off", fb, {"above": {"prob_tagging_up": -1.0}}), env)
    obs, _ = env.reset(seed=3)
    pol.reset(env)
    for _ in range(3):
        a = pol.predict(obs)[0]
        assert a[0] == IDLE
        obs, *_ = env.step(a)
    assert pol.fired == 3


@pytest.mark.parametrize("stage, made, match", [
    ("gate", "gate", "expected a variant chosen by --stage select"),
    ("test", "test", "expected a variant chosen by --stage select"),
])
def test_gate_and_look_refuse_without_their_stage_before(tmp_path, stage, made, match):
    r = subprocess.run([sys.executable, str(SCRIPT), "--stage", stage, "--out", str(tmp_path)], check=False,
                       capture_output=True, text=True, cwd=REPO, timeout=120,
                       env={**os.environ, "PYTHONPATH": str(REPO)})
    assert r.returncode == 2 and "Traceback" not in r.stderr and not (tmp_path / made).exists()
    assert match in r.stderr.strip().splitlines()[-1]


def test_the_test_look_needs_a_passed_gate(tmp_path):
    n = "tag0.8_none_idle_hold3"
    sel = {"chosen": n, "summary": {"alarm_pump_off": {"cost": 2.0},
                                    n: {"cost": 1.0, "vs_alarm_pump_off": {"ci95": [1.0, 2.0]}}}}
    (tmp_path / "select.json").write_text(json.dumps(sel))
    (tmp_path / "gate").mkdir()
    (tmp_path / "gate" / "gate.json").write_text(json.dumps({"gate": False, "specs": {n: {}}}))
    r = subprocess.run([sys.executable, str(SCRIPT), "--stage", "test", "--out", str(tmp_path)], check=False,
                       capture_output=True, text=True, cwd=REPO, timeout=120,
                       env={**os.environ, "PYTHONPATH": str(REPO)})
    assert r.returncode == 2 and "Traceback" not in r.stderr and not (tmp_path / "test").exists()
    assert f"expected a passed gate of {n}" in r.stderr.strip().splitlines()[-1]


def test_read_counts_the_episodes_a_guard_changed_and_their_tagging():
    """--stage read on a fixed table: the episodes a variant changed, those with a tagging event, and the mean d vs
    the inner each part carries (USD/h over all episodes)."""
    def ep(well, reward, tag):
        return {"well_id": well, "reward": 144.0 * reward, "cost_tagging": tag}

    eps = {"alarm_pump_off": [ep("w0", 0, 0), ep("w1", 0, 0), ep("w2", 0, 0), ep("w3", 0, 0)],
           "unguarded": [ep("w0", 10, 5.0), ep("w1", 10, 0), ep("w2", 10, 0), ep("w3", 10, 0)],
           "v": [ep("w0", 8, 0.0), ep("w1", 6, 0), ep("w2", 10, 0), ep("w3", 2, 0)]}
    r = gs.read(eps)
    assert r["tagging_episodes"] == ["w0"] and set(r) == {"tagging_episodes", "v"}
    assert r["v"] == {"fired": 3, "fired_tagging": 1, "d_tagging": -0.5, "d_other": -3.0, "tagging_cost": [0.0]}


def test_why_traces_the_tagging_episode_to_its_first_tagging_card():
    """The traced variant on the selection's one tagging episode (train-068): its tagging limits first fire on a
    tagging card, and no followed shut-in acts."""
    w = gs.why(59468)
    assert w["well_id"] == "train-068" and w["shut_in"] == 0 and w["limits_fired"] > 100
    assert w["first_fired_on"]["condition"] == "tagging_down"
