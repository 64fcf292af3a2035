"""Package layout that pyproject.toml alone cannot express (metadata and dependencies live there).

Every ``srenv*`` package found under ``srenv/``, plus the top-level ``configs/`` directory installed as
``srenv.configs``: the well configs and the unit catalogue become package data of the wheel, found by
:mod:`srenv.shipped` through ``importlib.resources``, while ``configs/`` stays the one source in the
repository. The top-level ``agents/`` folder is not installed (run it from a checkout: ``python -m agents``).
"""

from setuptools import find_packages, setup

setup(
    packages=[*find_packages(include=["srenv", "srenv.*"]), "srenv.configs"],
    package_dir={"srenv.configs": "configs"},
    package_data={"srenv.configs": ["wells/*.yaml", "units/*.yaml"],
                  "srenv": ["models/*.npz"]},  # the condition classifier's weights (docs/conditions.md)
)
