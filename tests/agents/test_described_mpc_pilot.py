"""The described-twin pilot (scripts/described_mpc_pilot.py, issue 24): its train stage plays training wells only,
its candidates differ in pound_prob alone, THE CHOICE follows its written rule, bad arguments are refused in one
line (exit 2), and its designs build as estimated_mpc policies."""

from __future__ import annotations

import importlib.util
import subprocess
import sys
from pathlib import Path

import pytest

from agents.envs import make_env
from agents.policies.estimated_mpc import EstimatedMPCPolicy
from agents.policies.factory import make_baseline

REPO = Path(__file__).resolve().parents[2]
SCRIPT = REPO / "scripts" / "described_mpc_pilot.py"


@pytest.fixture(scope="module")
def pilot():
    sys.path.insert(0, str(SCRIPT.parent))
    spec = importlib.util.spec_from_file_location("described_mpc_pilot", SCRIPT)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


@pytest.fixture(scope="module")
def tuned(pilot):
    from agents.evaluation.replay import load_report

    return {k: v["params"] for k, v in load_report(pilot.REPORT)["tuned"].items()}


def test_train_stage_plays_training_wells_16_to_31_only(pilot):
    assert [s % 200 for s in pilot.TRAIN_SEEDS] == list(range(16, 32))
    assert not set(pilot.TRAIN_SEEDS) & set(range(20000, 20016))  # no validation episode of any design


def test_candidates_differ_in_pound_prob_only(pilot, tuned):
    specs = pilot.specs_for("train", tuned, None)
    designs = [s for n, s in specs.items() if n.startswith("described_pound_")]
    assert len(designs) == len(pilot.CANDIDATES) and set(pilot.BASES) <= set(specs)
    strip = [{**d["params"], "guard": {k: v for k, v in d["params"]["guard"].items() if k != "pound_prob"}}
             for d in designs]
    assert all(s == strip[0] for s in strip)
    assert strip[0]["twin"] == "described" and strip[0]["guard"]["fallback"] == ["alarm_pump_off", tuned["alarm_pump_off"]]
    env = make_env("srenv/SuckerRod-v2", scenario="train", observation="field", episode_hours=0.5)
    pol = make_baseline("estimated_mpc", designs[-1]["params"], env.unwrapped.obs_names)
    assert isinstance(pol, EstimatedMPCPolicy) and pol.guard["pound_prob"] == pilot.CANDIDATES[-1]


def _summ(pilot, means):
    return {f"described_pound_{p}": {"vs_alarm_pump_off": {"mean": m}} for p, m in zip(pilot.CANDIDATES, means)}


def test_the_choice_rule(pilot):
    assert pilot.choose(_summ(pilot, [1.0, 3.0, 2.0, 0.0])) == 0.3
    assert pilot.choose(_summ(pilot, [1.0, 3.0, 2.97, 0.0])) == 0.5  # within 0.05: the higher P
    assert pilot.choose(_summ(pilot, [4.0, 3.0, 2.0, 0.0])) is None


def _run(args: list[str]) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, str(SCRIPT), *args], capture_output=True, text=True, cwd=REPO, check=False,
                          env={"PYTHONPATH": str(REPO), "PATH": "/usr/bin:/bin"}, timeout=300)


@pytest.mark.parametrize("args", [["--stage", "train", "--workers", "3"], ["--stage", "train", "--workers", "0"]])
def test_bad_arguments_refused_in_one_line(tmp_path, args):
    r = _run([*args, "--out", str(tmp_path / "o")])
    assert r.returncode == 2 and len(r.stderr.strip().splitlines()) == 1 and "workers" in r.stderr
    assert not (tmp_path / "o").exists()


def test_out_through_a_symlink_refused(tmp_path):
    (tmp_path / "real").mkdir()
    (tmp_path / "link").symlink_to(tmp_path / "real")
    r = _run(["--stage", "train", "--out", str(tmp_path / "link")])
    assert r.returncode == 2 and "symlink" in r.stderr and not any((tmp_path / "real").iterdir())


def test_the_preregistered_design_is_the_pilots_choice_on_unplayed_validation_seeds(pilot, tuned):
    import json

    import yaml

    cfg = yaml.safe_load(pilot.CONFIG.read_text())
    train = json.loads((REPO / "docs/archive/described_mpc_train.json").read_text())
    assert train["chosen_pound_prob"] == 0.7 == pilot.choose(train["summary"])
    assert cfg["designs"] == {"described_mpc": pilot.design(tuned, train["chosen_pound_prob"])}
    seeds = pilot.seeds_of(cfg)
    assert [s % 200 for s in seeds] == list(range(16))  # the validation wells, as every gate played them
    assert not set(seeds) & (set(range(20000, 20016)) | set(range(10)) | set(range(100000, 100100)))
    assert not set(seeds) & set(pilot.TRAIN_SEEDS)


# ---------------------------------------------------------------- round 2 (t24c): the observer on the described twin
def test_train2_candidates_are_round_1_with_the_observer_differing_in_gain_only(pilot, tuned):
    specs = pilot.specs_for("train2", tuned, None)
    assert specs["described_mpc"] == pilot.design(tuned, pilot.ROUND1)  # the reference: round 1, observer off
    cands = {g: specs[f"observer_gain_{g}"]["params"] for g in pilot.GAINS}
    assert len(cands) == len(pilot.GAINS) == 3 and set(pilot.BASES) <= set(specs)
    ref = specs["described_mpc"]["params"]
    for g, p in cands.items():
        assert {k: v for k, v in p.items() if k not in ("observer", "observer_gain")} == ref
        assert p["observer"] is True and p.get("observer_gain", 0.5) == g
    env = make_env("srenv/SuckerRod-v2", scenario="train", observation="field", episode_hours=0.5)
    pol = make_baseline("estimated_mpc", cands[1.0], env.unwrapped.obs_names)
    assert pol.observer and pol.observer_gain == 1.0 and pol.twin == "described"


def _summ2(pilot, means):
    return {f"observer_gain_{g}": {"vs_alarm_pump_off": {"mean": m}} for g, m in zip(pilot.GAINS, means)}


def test_the_gain_choice_rule(pilot):
    assert pilot.choose_gain(_summ2(pilot, [1.0, 3.0, 2.0])) == 0.75
    assert pilot.choose_gain(_summ2(pilot, [2.96, 2.0, 3.0])) == 0.5  # within 0.05: the lower gain
    assert pilot.choose_gain(_summ2(pilot, [-4.0, -3.0, -2.0])) == 1.0


def test_the_round_2_preregistration_is_the_pilots_choice_on_unplayed_validation_seeds(pilot, tuned):
    import json

    import yaml

    cfg = yaml.safe_load(pilot.CONFIG2.read_text())
    train = json.loads((REPO / "docs/archive/described_observer_train.json").read_text())
    assert train["chosen_observer_gain"] == 1.0 == pilot.choose_gain(train["summary"])
    assert cfg["designs"] == {"described_observer_mpc": pilot.observer_design(tuned, train["chosen_observer_gain"])}
    r1 = json.loads((REPO / "docs/archive/described_mpc_train.json").read_text())["per_episode_usd_h"]
    assert train["per_episode_usd_h"]["described_mpc"] == r1["described_pound_0.7"]  # observer off: as round 1
    seeds = pilot.seeds_of(cfg)
    assert [s % 200 for s in seeds] == list(range(16))  # the validation wells, as every gate played them
    played = set(range(20000, 20016)) | set(pilot.seeds_of(yaml.safe_load(pilot.CONFIG.read_text())))
    assert not set(seeds) & (played | set(range(10)) | set(range(100000, 100100)) | set(pilot.TRAIN_SEEDS))


def test_after2_plays_both_rounds_on_gate2s_seeds_without_a_gate(pilot, tuned):
    import json

    import yaml

    cfg2 = yaml.safe_load(pilot.CONFIG2.read_text())
    specs = pilot.specs_for("after2", tuned, cfg2)
    assert set(specs) == {*pilot.BASES, "described_mpc", "described_observer_mpc"}
    assert specs["described_mpc"] == pilot.design(tuned, pilot.ROUND1)
    gate, after = (json.loads((REPO / f"docs/archive/described_observer_{n}.json").read_text()) for n in ("gate", "after"))
    assert gate["seeds"] == after["seeds"] == pilot.seeds_of(cfg2) and "gate" not in after
    assert gate["gate"] == {"described_observer_mpc": False}
    for n in ("alarm_pump_off", "described_observer_mpc"):  # the gate's episodes, replayed to the cent
        assert after["per_episode_usd_h"][n] == gate["per_episode_usd_h"][n]
