"""The built wheel is a library: it ships the well configs, the unit catalogue and the training and benchmark
YAMLs, installs the agents as ``srenv_agents`` (no top-level ``agents`` package), and, unpacked and imported
from another directory, makes every registered srenv env and runs ``srenv simulate`` on a shipped name.

The wheel (the ``wheel`` fixture of conftest.py) is built from a copy of the sources; the subprocess sees only
the unpacked wheel and the dependencies installed in this interpreter, and checks that srenv is imported from
the wheel.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import zipfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

PROBE = r"""
import json, os, sys
import gymnasium as gym
import srenv
from srenv.tools.cli import main
from srenv.config import shipped_configs
site = os.environ["SRENV_SITE"]
assert srenv.__file__.startswith(site), f"srenv imported from {srenv.__file__}, not the wheel"
ids = sorted(i for i in gym.registry if i.startswith("srenv/"))
for i in ids:
    env = gym.make(i)
    env.reset(seed=0)
    obs, reward, *_ = env.step(env.action_space.sample())
    assert env.observation_space.contains(obs), i
    env.close()
try:
    main(["simulate", "paper_fig3_vertical", "--strokes", "1", "--out", "card.csv"])
except SystemExit as exc:
    assert not exc.code, f"simulate exited {exc.code}"
# the agents under their installed name: relative imports, configs found as package data, module:id env ids
import srenv_agents.cli, srenv_agents.training.residual_env as residual_env
from srenv_agents.cli import QUICK_BENCHMARK
assert srenv_agents.cli.__file__.startswith(site) and QUICK_BENCHMARK.is_file(), QUICK_BENCHMARK
assert residual_env.RESIDUAL_ENV_ID.startswith("srenv_agents.training.residual_env:")
print("PROBE " + json.dumps({"ids": ids, "shipped": shipped_configs(), "file": srenv.__file__}))
"""


def test_wheel_contents(wheel: Path) -> None:
    names = zipfile.ZipFile(wheel).namelist()
    tops = {n.split("/", 1)[0] for n in names}
    assert "agents" not in tops  # python -m agents runs from a checkout; the name is too generic to install
    assert {t for t in tops if not t.endswith(".dist-info")} == {"srenv", "srenv_agents"}
    agents = {str(p.parent.relative_to(ROOT)) for p in (ROOT / "agents").rglob("__init__.py")}
    assert all(f"srenv_{pkg}/__init__.py" in names for pkg in agents), agents
    assert "srenv/configs/benchmark/v1_quick.yaml" in names and "srenv/configs/train/ppo_v1.yaml" in names
    entry_points = next(n for n in names if n.endswith(".dist-info/entry_points.txt"))
    assert "srenv-agents = srenv_agents.cli:main" in zipfile.ZipFile(wheel).read(entry_points).decode()
    wells = sorted(p.name for p in (ROOT / "configs" / "wells").glob("*.yaml"))
    assert wells and all(f"srenv/configs/wells/{w}" in names for w in wells)
    assert "srenv/configs/units/catalogue.yaml" in names
    # every package of the source tree is in the wheel (setup.py finds them; none forgotten by a list)
    packages = {str(p.parent.relative_to(ROOT)) for p in (ROOT / "srenv").rglob("__init__.py")}
    assert all(f"{pkg}/__init__.py" in names for pkg in packages), packages


def test_wheel_runs_from_elsewhere(wheel: Path, tmp_path: Path) -> None:
    site = tmp_path / "site"
    zipfile.ZipFile(wheel).extractall(site)
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    env.update(PYTHONPATH=str(site), SRENV_SITE=str(site), MPLBACKEND="Agg")
    p = subprocess.run([sys.executable, "-c", PROBE], cwd=elsewhere, env=env, capture_output=True, text=True,
                       timeout=300, check=False)
    assert p.returncode == 0, p.stderr[-2000:]
    probe = json.loads(next(line for line in p.stdout.splitlines() if line.startswith("PROBE "))[6:])
    assert "srenv/SuckerRod-v0" in probe["ids"]
    assert probe["shipped"] == sorted(p.stem for p in (ROOT / "configs" / "wells").glob("*.yaml"))
    card = (elsewhere / "card.csv").read_text().splitlines()
    assert len(card) > 100  # one stroke of the shipped paper_fig3_vertical well, written where we ran


def test_spec_shows_the_default_kwargs() -> None:
    import gymnasium as gym

    import srenv

    spec = gym.spec(srenv.ENV_ID)
    assert spec.kwargs == {"config": "default"} and spec.entry_point == srenv.ENVS[srenv.ENV_ID][0]
    # no TimeLimit: the env truncates itself from its config (one source of the episode length)
    assert spec.max_episode_steps is None
    env = gym.make(srenv.ENV_ID, control__max_episode_steps=3)
    env.reset(seed=0)
    ends = [env.step(env.action_space.sample())[3] for _ in range(3)]
    assert ends == [False, False, True]
    env.close()

