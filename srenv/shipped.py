"""Where the data shipped with srenv lives: the well configs and the pumping-unit catalogue.

The source is the repository's top-level ``configs/`` (``configs/wells/*.yaml``,
``configs/units/catalogue.yaml``). A built wheel installs that directory as the package data
``srenv/configs/`` (``setup.py`` maps the package ``srenv.configs`` onto ``configs/``), found here through
:mod:`importlib.resources`; a source checkout (``PYTHONPATH`` or an editable install) has no
``srenv/configs`` and reads ``configs/`` next to the package.
"""

from __future__ import annotations

from importlib import resources
from pathlib import Path


def shipped_dir(kind: str) -> Path:
    """The directory of shipped ``kind`` files (``"wells"``, ``"units"``, ``"train"`` or ``"benchmark"``),
    installed or in the checkout."""
    package = resources.files("srenv")
    installed = package / "configs" / kind
    if installed.is_dir():
        # a regular package on the file system: a Traversable that is a real path (open(), glob())
        return Path(str(installed))
    return Path(str(package)).parent / "configs" / kind
