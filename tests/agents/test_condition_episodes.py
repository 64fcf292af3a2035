"""scripts/condition_episodes.py (issue 24, item 4): the episode of each condition is chosen by a rule that reads the
seed's drawn schedule only (the first validation seed with the event in the first half; deterministic, and the
schedule does not depend on the policy); bad flags are one line and exit 2; a tiny run writes the PNG and a JSON
whose keys are the documented ones."""

from __future__ import annotations

import importlib.util
import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from agents.envs import make_env

REPO = Path(__file__).resolve().parents[2]
SCRIPT = REPO / "scripts" / "condition_episodes.py"


@pytest.fixture(scope="module")
def mod():
    spec = importlib.util.spec_from_file_location("condition_episodes", SCRIPT)
    m = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(m)
    return m


@pytest.fixture(scope="module")
def env():
    e = make_env("srenv/SuckerRod-v2", observation="field", scenario="validation")
    yield e
    e.close()


def _starts(env, seed: int, event: str) -> bool:
    env.reset(seed=seed)
    u = env.unwrapped
    return any(e.label == event and e.start_h < u.cfg.task.episode_hours / 2 for e in u._schedule.events)


def test_the_rule_picks_the_first_seed_with_the_event_in_the_first_half(mod, env):
    seed = mod.pick_seed(env, "heavy_oil", 22000, 200)
    assert seed is not None and _starts(env, seed, "heavy_oil")
    assert not any(_starts(env, s, "heavy_oil") for s in range(22000, seed))
    assert mod.pick_seed(env, "heavy_oil", 22000, 200) == seed  # deterministic
    assert mod.pick_seed(env, "heavy_oil", 22000, seed - 22000) is None  # the search's end: none found


def test_the_schedule_is_the_seeds_not_the_policys(env):
    """Drawn at reset from the seed: the same after episodes played with different actions."""
    seen = []
    for a in (-1.0, 1.0):
        env.reset(seed=22013)
        sched = env.unwrapped._schedule
        for _ in range(3):
            env.step(np.full(2, a, np.float32))
        seen.append((sched, env.unwrapped._schedule))
    assert seen[0][0] == seen[0][1] == seen[1][0] == seen[1][1] and seen[0][0].events


def test_every_declared_flag_refuses_bad_values_in_one_line(mod, capsys, tmp_path):
    for flag, decl in mod.FLAGS.items():
        for text in decl.bad_texts():
            with pytest.raises(SystemExit) as ex:
                mod.main([flag, text, "--figures", str(tmp_path / "f"), "--json", str(tmp_path / "s.json")])
            err = capsys.readouterr().err.strip().splitlines()
            assert ex.value.code == 2 and len(err) == 1 and flag in err[0] and "expected" in err[0], (flag, text, err)
    link = tmp_path / "link.json"
    link.symlink_to(tmp_path / "target.json")
    with pytest.raises(SystemExit) as ex:
        mod.main(["--json", str(link), "--figures", str(tmp_path / "f")])
    assert ex.value.code == 2 and "symbolic link" in capsys.readouterr().err
    assert not (tmp_path / "f").exists() and not (tmp_path / "target.json").exists()
    p = subprocess.run([sys.executable, str(SCRIPT), "--max-seeds", "0"], capture_output=True, text=True,
                       check=False, timeout=120, cwd=REPO, env={"PYTHONPATH": str(REPO), "PATH": ""})
    assert p.returncode == 2 and p.stderr.strip().splitlines() == [(
        "condition_episodes.py: error: argument --max-seeds: --max-seeds = '0': expected a positive integer at most "
        "100000")]


def test_a_tiny_run_writes_the_figure_and_the_documented_json(mod, tmp_path):
    figs, out = tmp_path / "figs", tmp_path / "episodes.json"
    assert mod.main(["--event", "gas_interference", "--baseline", "alarm_pump_off", "--episode-hours", "2",
                     "--figures", str(figs), "--json", str(out)]) == 0
    assert (figs / "v2_condition_gas_interference.png").stat().st_size > 10_000
    rep = json.loads(out.read_text())
    c = rep["conditions"]["gas_interference"]
    k = mod.KEYS
    assert tuple(c) == k["condition"] and set(c["policies"]) == {mod.AGENT, "alarm_pump_off"}
    for p in c["policies"].values():
        assert tuple(p) == k["policy"] and tuple(p["window"]) == k["window"] and tuple(p["prob"]) == k["prob"]
    assert c["onset_h"] < 1.0 and c["window_h"][0] <= c["onset_h"] + 5 / 60 and c["well_id"].startswith("validation-")
    assert c["seed"] >= 22000 and c["policies"]["alarm_pump_off"]["steps"] == 24
    docs = (REPO / "docs" / "agents.md").read_text()
    section = docs[docs.index("## What the agent does when a condition appears (v2)"):]
    assert all(f"`{key}`" in section for keys in k.values() for key in keys)
