"""Package layout that pyproject.toml alone cannot express (metadata and dependencies live there).

Every ``srenv*`` package found under ``srenv/``; the top-level ``configs/`` directory installed as
``srenv.configs`` (the well configs, the unit catalogue, the training and benchmark YAMLs become package data
of the wheel, found by :mod:`srenv.shipped` through ``importlib.resources``, while ``configs/`` stays the one
source in the repository); and the top-level ``agents/`` folder installed as ``srenv_agents`` (a name no
other distribution uses; command ``srenv-agents``), while a checkout keeps ``python -m agents``. The
agents' modules import each other relatively, so the same files work under either name.
"""

from setuptools import find_packages, setup

AGENTS = find_packages(include=["agents", "agents.*"])

setup(
    packages=[*find_packages(include=["srenv", "srenv.*"]), "srenv.configs",
              *(p.replace("agents", "srenv_agents", 1) for p in AGENTS)],
    package_dir={"srenv.configs": "configs", "srenv_agents": "agents"},
    package_data={"srenv.configs": ["wells/*.yaml", "units/*.yaml", "train/*.yaml", "train/*.yml",
                                    "benchmark/*.yaml"],
                  "srenv": ["models/*.npz"],  # the condition classifier's weights (docs/conditions.md)
                  "srenv_agents.policies": ["*.npz"]},  # estimated_mpc's well library (agents/policies/estimated_mpc.py)
)
