"""The core install is the simulator, the CLI and the envs, without torch or Ray: srenv's wheel installed ALONE
into a fresh venv (``python -m venv`` + ``pip install srenv-*.whl``, its core dependencies from the package
index) makes and steps every registered env, runs ``srenv simulate``, and finds no learning stack.

It downloads the core dependencies (pip's cache makes a rerun cheap) and compiles the kernel once, so it is
marked ``core_install``: CI runs it (the README's test command selects every test), ``-m "not core_install"``
leaves it out of a quick local run.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

PROBE = r"""
import importlib.util, json, subprocess, sys
import gymnasium as gym
import srenv
heavy = [m for m in ("torch", "ray", "stable_baselines3", "tensorboard", "rl_zoo3") if importlib.util.find_spec(m)]
ids = sorted(i for i in gym.registry if i.startswith("srenv/"))
for i in ids:
    env = gym.make(i)
    env.reset(seed=0)
    env.step(env.action_space.sample())
    env.close()
# the agents' baselines need numpy only; their CLI parses without torch
from srenv_agents.policies.factory import BASELINE_NAMES
cli = subprocess.run([sys.executable, "-m", "srenv_agents", "--help"], capture_output=True, text=True)
print("PROBE " + json.dumps({"heavy": heavy, "ids": ids, "baselines": list(BASELINE_NAMES),
                             "agents_help": cli.returncode, "file": srenv.__file__}))
"""


@pytest.mark.core_install
def test_the_core_wheel_alone_makes_every_env_without_torch_or_ray(wheel: Path, tmp_path: Path) -> None:
    venv = tmp_path / "venv"
    subprocess.run([sys.executable, "-m", "venv", str(venv)], check=True, timeout=120)
    py = venv / "bin" / "python"
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "VIRTUAL_ENV")}
    env.update(MPLBACKEND="Agg", PIP_DISABLE_PIP_VERSION_CHECK="1")
    pip = subprocess.run([str(py), "-m", "pip", "install", "-q", "--only-binary", ":all:", str(wheel)],
                         capture_output=True, text=True, timeout=1200, env=env, check=False)
    assert pip.returncode == 0, pip.stderr[-2000:]
    frozen = subprocess.run([str(py), "-m", "pip", "freeze"], capture_output=True, text=True, env=env,
                            check=True).stdout.lower()
    assert not any(f"{h}==" in frozen for h in ("torch", "ray", "stable-baselines3", "stable_baselines3",
                                                  "tensorboard")), frozen
    work = tmp_path / "elsewhere"
    work.mkdir()
    p = subprocess.run([str(py), "-c", PROBE], cwd=work, capture_output=True, text=True, timeout=900, env=env,
                       check=False)
    assert p.returncode == 0, p.stderr[-2000:]
    probe = json.loads(next(line for line in p.stdout.splitlines() if line.startswith("PROBE "))[6:])
    assert probe["heavy"] == [] and probe["file"].startswith(str(venv))
    assert {"srenv/SuckerRod-v0", "srenv/SuckerRod-v1"} <= set(probe["ids"])
    assert "pump_off" in probe["baselines"] and probe["agents_help"] == 0
    sim = subprocess.run([str(venv / "bin" / "srenv"), "simulate", "paper_fig3_vertical", "--strokes", "1",
                          "--out", "card.csv"], cwd=work, capture_output=True, text=True, timeout=600, env=env,
                         check=False)
    assert sim.returncode == 0, sim.stderr[-2000:]
    assert len((work / "card.csv").read_text().splitlines()) > 100
