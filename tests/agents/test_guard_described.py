"""The guard on d42's described students (scripts/guard_described.py, configs/benchmark/v2_oracle_distilled_described_guarded
.yaml, issue 24, helper a43): the config is d42's but its history, which registers the inner's files, the guard family,
the selection's training seeds, the rule and the gate's unused validation seeds; the family is declared once and
every variant passes check_guard on v2's field observation; THE SELECTION RULE on fixed numbers (including none
qualifying); a guarded spec composes with a described inner; --stage plumbing and refusals."""

from __future__ import annotations

import importlib
import json
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
from agents.policies.field import obs_names_of
from agents.policies.guarded import check_guard

REPO = Path(__file__).resolve().parents[2]
SCRIPT = REPO / "scripts" / "guard_described.py"
CONFIG = REPO / "configs/benchmark/v2_oracle_distilled_described_guarded.yaml"
DESCRIBED = REPO / "configs/benchmark/v2_oracle_distilled_described.yaml"
KEEP_SHA = ("359b418671b20164fa823b09f38cc8594eef06b5a4fede689480546106f25463",
            "32d4036bc512231ba8aceeda9b0ed0480856f243be2cb0c2adf03ceaede3d623",
            "8a445f9731bcffd75a98ae8c8dcb73bc8ffbabd3ab0f7892c617688fe760f0ea")


@pytest.fixture(scope="module")
def gd():
    sys.path.insert(0, str(SCRIPT.parent))  # the script and the pilots it imports, as when it runs
    return importlib.import_module(SCRIPT.stem)


def _hist(monkeypatch, config: Path = CONFIG) -> str:
    """A config's history lines, joined (read from the repository's root, as the stages read it)."""
    monkeypatch.chdir(REPO)
    return " ".join(load_benchmark_config(config)["history"])


def same_but_history(monkeypatch, a: Path, b: Path) -> bool:
    """Whether two design configs differ in their history only (the later designs' check against their parent)."""
    monkeypatch.chdir(REPO)
    x, y = load_benchmark_config(a), load_benchmark_config(b)
    return {k: v for k, v in x.items() if k not in ("history", "source")} == {k: v for k, v in y.items()
                                                                       if k not in ("history", "source")}


def test_config_is_d42s_but_its_history(monkeypatch):
    monkeypatch.chdir(REPO)
    a, b = load_benchmark_config(CONFIG), load_benchmark_config(DESCRIBED)
    assert a["evaluate_only"]["agents"] == ["oracle_distilled_guarded"]
    for c in (a, b):  # the design's name in the looks' reports is this config's own
        del c["evaluate_only"]["agents"]
    assert {k: v for k, v in a.items() if k not in ("history", "source")} == {k: v for k, v in b.items()
                                                                     if k not in ("history", "source")}


def test_the_history_registers_inner_family_data_rule_and_gate(gd, monkeypatch):
    hist = _hist(monkeypatch)
    assert all(h in hist for h in KEEP_SHA) and "BEFORE any episode" in hist
    assert all(s in hist for s in ("59400..59449", "scenario train", "21700..21749", "scenario validation",
                                   "spm_cap: 0", "described: true", "scale 0.5", "follow_shut_in true",
                                   "highest CI lower bound", "fewer guard conditions", "lower bound is <= 0",
                                   "lower bound of d > 0", "cost <= alarm_pump_off's", "20261205", ">= 10 %"))
    # the grid as written in the history is the declared one
    assert f"T in {{{', '.join(map(str, gd.TAG))}}}" in hist and "grid of 24" in hist
    assert "fillage_est below 0.85 and spm below 0.45" in hist and "pprl above 0.95" in hist
    assert f"HOLD {' | '.join(map(str, gd.HOLD))} intervals" in hist


def test_seeds_are_unused_and_play_the_wells_they_say(gd):
    sel, gate = gd.SELECT_SEEDS, gd.GATE_SEEDS
    assert sel == list(range(59400, 59450)) and gate == list(range(21700, 21750))
    used = [(0, 10), (20000, 21700), (50000, 59200), (100000, 100100)]  # every earlier design's and split's seeds
    assert not any(lo <= s < hi for s in sel + gate for lo, hi in used)
    mine = (CONFIG, SCRIPT, Path(__file__).resolve())
    b43 = (REPO / "configs/benchmark/v2_oracle_distilled_stroke_guarded.yaml", SCRIPT.with_name("guard_stroke.py"),
           Path(__file__).with_name("test_guard_stroke.py"),  # b43's design: its own blocks, checked there
           REPO / "configs/benchmark/v2_oracle_distilled_agreement.yaml", SCRIPT.with_name("agreement_guard.py"),
           Path(__file__).with_name("test_agreement_guard.py"))  # u44's, which plays b43's unplayed gate block
    others = " ".join(f.read_text() for d in ("configs", "scripts", "tests") for f in (REPO / d).rglob("*.*")
                      if f.suffix in (".yaml", ".py") and f.resolve() not in mine + b43)
    assert not re.search(r"\b(594\d\d|217\d\d)\b", others.replace("range(21650, 21700)", ""))
    assert not re.search(r"\b(594\d\d|217\d\d)\b", (REPO / "docs/agents.md").read_text().split("(v2, helper a43")[0])
    for scenario, seed, well in (("train", sel[0], "train-000"), ("train", sel[-1], "train-049"),
                                 ("validation", gate[0], "validation-000"), ("validation", gate[-1], "validation-049")):
        env = gym.make("srenv/SuckerRod-v2", scenario=scenario, observation="field")
        env.reset(seed=seed)
        assert env.unwrapped.well.well_id == well


def test_the_family_is_declared_once_and_bounded(gd):
    v = gd.VARIANTS
    assert next(iter(v)) == "unguarded" and v["unguarded"] is None and len(v) == 25
    names = obs_names_of(gym.make("srenv/SuckerRod-v2", scenario="train", observation="field"))
    guards = [g for g in v.values() if g is not None]
    for g in guards:
        check_guard(g, names)  # every key bounded, every limit's name in v2's field observation
        assert g["follow_shut_in"] is True and g["above"]["prob_tagging_up"] == g["above"]["prob_tagging_down"]
    assert len({json.dumps(g, sort_keys=True) for g in guards}) == 24
    assert sorted({gd.conditions(g) for g in guards}) == [2, 3, 4, 5] and gd.conditions(None) == 0


def _summ(**rows: tuple[float, float]) -> dict:
    """{name: (lower bound of the CI vs alarm_pump_off, cost)}, alarm_pump_off's cost 2.0."""
    return {"alarm_pump_off": {"cost": 2.0}, **{k: {"cost": c, "vs_alarm_pump_off": {"ci95": [lo, lo + 5.0]}}
                                                   for k, (lo, c) in rows.items()}}


FAM = {"unguarded": None, "a": {"above": {"x": 1}, "below": {"y": 1}}, "b": {"above": {"x": 1}},
       "c": {"above": {"x": 1, "z": 1}, "below": {"y": 1}}, "d": {"above": {"x": 1}}}


RULE_CASES = [  # (rows, the variant THE RULE chooses); also b43's design's (tests/agents/test_guard_stroke.py)
    ({"unguarded": (9.0, 1.0), "a": (1.0, 2.0), "b": (2.0, 2.1), "c": (1.5, 1.9)}, "c"),  # best LB at cost <= base's
    ({"a": (1.0, 2.1), "b": (3.0, 2.5)}, None),  # none qualifies on cost -> a negative result
    ({"a": (0.0, 1.0), "c": (-1.0, 1.0)}, None),  # the best lower bound is not above zero -> no gate
    ({"a": (1.0, 1.0), "b": (1.0, 1.5), "c": (1.0, 1.0)}, "b"),  # a tie: fewer guard conditions
    ({"d": (1.0, 1.0), "b": (1.0, 1.0)}, "b"),  # a tie with as many conditions: the declared order
    ({"unguarded": (5.0, 1.0)}, None),  # the reference is never a candidate
]


@pytest.mark.parametrize("rows, chosen", RULE_CASES)
def test_the_selection_rule(gd, rows, chosen):
    assert gd.choose(_summ(**rows), FAM) == chosen


def test_a_guard_composes_with_a_described_inner(gd, described_student):
    from agents.evaluation.agent import build_policy
    from agents.policies.guarded import guarded_spec
    from agents.policies.residual import _Base

    base = {"threshold": 0.95, "idle_time_s": 1800, "a_spm": 0.1, "a_stroke": 0.0}
    inner = {"kind": "ensemble", "members": [described_student] * 2, "described": True,
             "residual": {"base": "pump_off", "params": base, "scale": 0.5, "cap": {"spm_cap": 0.0}}}
    fb = {**base, "load_drop": 0.5, "alarm_prob": 0.6, "gas_slowdown": 0.3}
    env = gym.make("srenv/SuckerRod-v2", scenario="validation", observation="field", episode_hours=1.0)
    never = build_policy(guarded_spec(inner, "alarm_pump_off", fb, {"above": {"prob_tagging_up": 2.0}}), env)
    always = build_policy(guarded_spec(inner, "alarm_pump_off", fb, {"above": {"prob_tagging_up": -1.0}}), env)
    plain, alarm = build_policy(inner, env), _Base("alarm_pump_off", fb, env)  # the fallback as the guard drives it
    for seed in (3, 4):
        obs, _ = env.reset(seed=seed)
        for p in (never, always, plain, alarm):
            p.reset(env)
        for _ in range(3):
            a = plain.predict(obs)[0]
            np.testing.assert_array_equal(never.predict(obs)[0], a)  # the described inner, as it acts unguarded
            np.testing.assert_array_equal(always.predict(obs)[0], alarm.act(obs).reshape(-1))
            obs = env.step(a)[0]
        assert never.fired == 0 and always.fired == 3


def test_gate_refuses_without_a_chosen_variant(tmp_path):
    for rec in (None, {"chosen": None, "summary": {}}, {"chosen": "tag0.3_none_noload_hold3", "summary": {}}):
        if rec is not None:
            (tmp_path / "select.json").write_text(json.dumps(rec))
        r = subprocess.run([sys.executable, str(SCRIPT), "--stage", "gate", "--out", str(tmp_path)], check=False,
                           capture_output=True, text=True, cwd=REPO, timeout=120,
                           env={**os.environ, "PYTHONPATH": str(REPO)})
        assert r.returncode == 2 and "Traceback" not in r.stderr and not (tmp_path / "gate").exists()
        assert "expected a variant chosen by --stage select" in r.stderr.strip().splitlines()[-1]


@pytest.mark.parametrize("script", [SCRIPT, SCRIPT.with_name("guard_stroke.py")])  # a43's and b43's designs
def test_bad_flags_refused_in_one_line(tmp_path, script):
    for args, match in ((["--stage", "select", "--workers", "3"], "--workers 3"), (["--stage", "look"], "invalid choice")):
        r = subprocess.run([sys.executable, str(script), *args, "--out", str(tmp_path / "o")], check=False,
                           capture_output=True, text=True, cwd=REPO, timeout=120,
                           env={**os.environ, "PYTHONPATH": str(REPO)})
        assert r.returncode == 2 and "Traceback" not in r.stderr
        assert match in r.stderr.strip().splitlines()[-1] and not (tmp_path / "o").exists()
        assert "--out" not in r.stderr.strip().splitlines()[-1]  # only the wrong flag is named
    (tmp_path / "link").symlink_to(tmp_path)
    r = subprocess.run([sys.executable, str(script), "--stage", "select", "--out", str(tmp_path / "link")], check=False,
                       capture_output=True, text=True, cwd=REPO, timeout=120, env={**os.environ, "PYTHONPATH": str(REPO)})
    line = r.stderr.strip().splitlines()[-1]
    assert r.returncode == 2 and "--out" in line and "symlink" in line and "--workers" not in line


def test_stages_play_their_seeds_on_their_split(gd, monkeypatch, tmp_path):
    """--stage select plays alarm_pump_off and every variant on SELECT_SEEDS (training wells) and applies the rule;
    --stage gate hands play_design_gate the chosen variant's spec, GATE_SEEDS, v2's validation split, OUT/gate."""
    seen: dict = {}
    inner = {"kind": "ensemble", "members": [], "described": True, "residual": {"base": "pump_off"}}

    def play_validation(cfg, specs, out, workers):
        seen["select"] = (cfg["validation"], list(specs), out)
        rec = {"reward": 144.0, "cost": 1.0, "well_id": "train-000", "cost_pound": 1.0}
        return {n: [{**rec, "reward": 144.0 * (2 + (n == "tag0.5_none_noload_hold3") + 0.1 * i)} if n != "alarm_pump_off"
                    else {**rec, "reward": 144.0 * (1 + 0.1 * i)} for i in range(4)] for n in specs}

    def play(cfg, config, seeds, design, tuned, res, out, workers, scenario="train", also=None, shipped=True):
        seen["gate"] = {"seeds": seeds, "design": design, "out": out, "scenario": scenario, "shipped": shipped}
        return {"summary": {}, "gate": False}

    monkeypatch.setattr(gd, "require_precheck", lambda out: None)
    monkeypatch.setattr(gd, "design_spec", lambda out, d: inner)
    monkeypatch.setattr(gd, "design", lambda config: {"cfg": {"validation": {}}, "tuned": {"alarm_pump_off": {
        "params": {"threshold": 0.99}}}, "res": {}})
    monkeypatch.setattr(gd, "play_validation", play_validation)
    monkeypatch.setattr(gd, "play_design_gate", play)
    rec = gd.select(tmp_path, 2)
    assert seen["select"] == ({"seeds": list(range(59400, 59450)), "scenario": "train"},
                              ["alarm_pump_off", *gd.VARIANTS], tmp_path / "select")
    assert rec["chosen"] == "tag0.5_none_noload_hold3" and json.loads((tmp_path / "select.json").read_text())["chosen"] \
        == rec["chosen"]
    gd.gate(tmp_path, 2)
    g = seen["gate"]
    assert (g["seeds"], g["out"], g["scenario"], g["shipped"]) == (list(range(21700, 21750)), tmp_path / "gate",
                                                                   "validation", False)
    (name, spec), = g["design"].items()
    assert name == rec["chosen"] and spec["kind"] == "guarded" and spec["inner"] == inner
    assert spec["guard"] == gd.VARIANTS[name] and spec["fallback"] == {"name": "alarm_pump_off",
                                                                       "params": {"threshold": 0.99}}


def _names(spec: dict) -> dict:
    """The spec with every member's files by name (the look plays OUT/design's, the report names models/ copies)."""
    inner = spec["inner"]
    members = [{k: Path(v).name for k, v in m.items()} for m in inner["members"]]
    return {**spec, "inner": {**inner, "members": members}}


def test_a_report_with_the_described_guarded_design_rebuilds_its_spec(gd, described_student, monkeypatch, tmp_path):
    """The look's record (guarded_record of the chosen variant on d42's fits) holds ``described: true``; replay's
    policy_specs and the fresh look's record copy rebuild the very spec the look played; a bad flag is refused."""
    import hashlib
    import shutil

    from agents.benchmark.fresh import _policies
    from agents.evaluation.replay import ReplayError, load_report, policy_specs

    out, to = tmp_path / "out", tmp_path / "out" / "test"
    (out / "design").mkdir(parents=True)
    sha = {}
    for k in (0, 1, 2):
        f = out / "design" / f"oracle_distilled_v2_seed{k}.zip"
        shutil.copyfile(described_student["path"], f)
        shutil.copyfile(described_student["obs_norm"], f.with_name(f.stem + "_obs_norm.npz"))
        sha[f.name] = hashlib.sha256(f.read_bytes()).hexdigest()
    monkeypatch.setattr(gd, "FITS_SHA256", sha)
    tuned = load_report(REPO / "docs/v2/benchmark.json")["tuned"]
    name, spec, rec = gd.look_design(out, "tag0.3_none_noload_hold3", tuned, to)
    assert name == "oracle_distilled_guarded" and rec["described"] is True and spec["inner"]["described"] is True
    assert spec["inner"]["residual"]["cap"] == {"spm_cap": 0.0} and spec["guard"] == gd.VARIANTS["tag0.3_none_noload_hold3"]
    assert rec["guarded"]["fallback"] == {"name": "alarm_pump_off", "params": tuned["alarm_pump_off"]["params"]}
    (rebuilt,) = policy_specs({"policies": {name: rec}}, name, to)
    assert _names(rebuilt) == _names(spec) and all(Path(m["path"]).parent == to / "models"
                                                  for m in rebuilt["inner"]["members"])
    fresh = _policies({"policies": {name: rec}}, {name: [rebuilt]}, [name], [{"reward": 0.0}], 1)
    assert policy_specs({"policies": fresh}, name, to) == [rebuilt]  # the fresh look's report rebuilds it too
    with pytest.raises(ReplayError, match="described = yes: expected true or false"):
        policy_specs({"policies": {name: {**rec, "described": "yes"}}}, name, to)
    monkeypatch.setattr(gd, "FITS_SHA256", {**sha, "oracle_distilled_v2_seed1.zip": "0" * 64})
    with pytest.raises(SystemExit, match="not d42's frozen design"):
        gd.look_design(out, "tag0.3_none_noload_hold3", tuned, to)


def test_an_ensemble_without_the_flag_records_none(tmp_path):
    from agents.benchmark.assemble import _ensemble_record

    (tmp_path / "x.zip").write_bytes(b"x")  # a record pins its members' files (tests/agents/test_model_pins.py)
    ens = {"kind": "ensemble", "members": [{"path": str(tmp_path / "x.zip"), "obs_norm": None}], "of": "r"}
    runs = {"r": {"config": "configs/train/ppo_residual_v2.yaml", "seeds": [0]}}
    assert "described" not in _ensemble_record(ens, runs, [])  # earlier reports' records unchanged
    assert _ensemble_record({**ens, "described": True}, runs, [])["described"] is True


def test_the_test_look_needs_a_passed_gate(gd, tmp_path):
    sel = {"chosen": "tag0.3_none_noload_hold3",
           "summary": {"alarm_pump_off": {"cost": 2.0},
                       "tag0.3_none_noload_hold3": {"cost": 1.0, "vs_alarm_pump_off": {"ci95": [1.0, 2.0]}}}}
    (tmp_path / "select.json").write_text(json.dumps(sel))
    (tmp_path / "gate").mkdir()
    for gate in (None, {"gate": False, "specs": {"tag0.3_none_noload_hold3": {}}}):
        if gate is not None:
            (tmp_path / "gate" / "gate.json").write_text(json.dumps(gate))
        r = subprocess.run([sys.executable, str(SCRIPT), "--stage", "test", "--out", str(tmp_path)], check=False,
                           capture_output=True, text=True, cwd=REPO, timeout=120,
                           env={**os.environ, "PYTHONPATH": str(REPO)})
        assert r.returncode == 2 and "Traceback" not in r.stderr and not (tmp_path / "test").exists()
        assert "expected a passed gate of tag0.3_none_noload_hold3" in r.stderr.strip().splitlines()[-1]


def test_stage_tails_replays_gate2s_two_tail_episodes(gd, monkeypatch, tmp_path):
    """--stage tails (read after the looks): alarm_pump_off, the unguarded inner and the chosen variant on gate 2's
    episodes of validation-003 and validation-020 (its seeds, by index), on v2's validation split."""
    sel = {"chosen": "tag0.3_none_noload_hold3",
           "summary": {"alarm_pump_off": {"cost": 2.0},
                       "tag0.3_none_noload_hold3": {"cost": 1.0, "vs_alarm_pump_off": {"ci95": [1.0, 2.0]}}}}
    (tmp_path / "select.json").write_text(json.dumps(sel))
    seen = {}

    def play_validation(cfg, specs, out, workers):
        seen.update(validation=cfg["validation"], names=list(specs), out=out)
        return {n: [{"reward": 0.0, "cost": 0.0, "well_id": w} for w in ("validation-003", "validation-020")]
                for n in specs}

    monkeypatch.setattr(gd, "design_spec", lambda out, d: {"kind": "ensemble", "members": [], "residual": {"b": 1}})
    monkeypatch.setattr(gd, "design", lambda config: {"cfg": {"validation": {}}, "tuned": {"alarm_pump_off": {
        "params": {}}}})
    monkeypatch.setattr(gd, "play_validation", play_validation)
    monkeypatch.setattr(gd, "trace", lambda spec, cfg, seed: {"spec": spec["kind"], "seed": seed})
    (tmp_path / "tails").mkdir()
    rec = gd.tails(tmp_path, 2)
    seeds = [gd.GATE2_SEEDS[3], gd.GATE2_SEEDS[20]]
    assert seen == {"validation": {"seeds": seeds, "scenario": "validation"},
                    "names": ["alarm_pump_off", "unguarded", "tag0.3_none_noload_hold3"], "out": tmp_path / "tails"}
    assert rec["seeds"] == seeds and rec["well_id"] == ["validation-003", "validation-020"]
    assert rec["trace"] == {str(s): {"spec": "guarded", "seed": s} for s in seeds}  # the chosen variant traced
    env = gym.make("srenv/SuckerRod-v2", scenario="validation", observation="field")
    for s, w in zip(seeds, ("validation-003", "validation-020")):
        env.reset(seed=s)
        assert env.unwrapped.well.well_id == w


def test_trace_splits_the_episode_between_the_fallback_and_the_inner(gd):
    """A guard that always fires: every interval is the fallback's; one that never fires: every one the inner's."""
    from agents.policies.guarded import guarded_spec

    base = {"threshold": 0.95, "idle_time_s": 1800, "a_spm": 0.1, "a_stroke": 0.0}
    inner = {"kind": "baseline", "name": "pump_off", "params": base}
    cfg = {"env_id": "srenv/SuckerRod-v2", "env_kwargs": {"observation": "field", "episode_hours": 1.0}}
    for lim, who in ((-1.0, "fallback"), (2.0, "inner")):
        tr = gd.trace(guarded_spec(inner, "pump_off", base, {"above": {"prob_tagging_down": lim}}), cfg, 3)
        other = "inner" if who == "fallback" else "fallback"
        assert tr[who]["intervals"] > 1 and tr[other] == {"intervals": 0, "tagging_cost": 0, "mean_spm": None}
        assert tr[who]["mean_spm"] > 0
