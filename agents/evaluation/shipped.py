"""Where the shipped, benchmarked report lives: one lookup, so a move is one edit here.

The trained models are in the repository's ``models/`` folder, whose ``MANIFEST.json`` names the benchmark report
they were shipped with (``report``, relative to the repository: ``docs/benchmark.json`` today); the report's
model paths are resolved by :func:`agents.evaluation.replay.locate_model`.
"""

from __future__ import annotations

import json
from pathlib import Path

from .manifest import MANIFEST, MODELS_HOME


def shipped_report(version: str = "v1") -> Path:
    """The shipped benchmark report of an env version (``models/MANIFEST.json``'s ``report``)."""
    if version != "v1":
        raise ValueError(f"shipped report version = {version!r}: expected 'v1' (no v2 agents are shipped yet)")
    manifest = MODELS_HOME / MANIFEST
    try:
        rel = json.loads(manifest.read_text(encoding="utf-8"))["report"]
    except (OSError, ValueError, KeyError, TypeError):
        raise FileNotFoundError(f"{manifest}: no readable models manifest with a 'report' entry") from None
    path = (MODELS_HOME.parent / str(rel)).resolve()
    if MODELS_HOME.parent.resolve() not in path.parents or path.suffix != ".json":
        raise FileNotFoundError(f"{manifest}: report = {rel!r}, expected a .json path inside the repository")
    return path
