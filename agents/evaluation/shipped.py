"""Where the shipped, benchmarked reports live: one lookup, so a move is one edit here.

The trained models are in the repository's ``models/`` folder, whose ``MANIFEST.json`` names the benchmark report
each env version's agents were shipped with (``reports``: ``{"v1": "docs/benchmark.json", "v2":
"docs/v2/benchmark.json"}``, relative to the repository; a manifest from before v2 agents has only v1's
``report``); the report's model paths are resolved by :func:`agents.evaluation.replay.locate_model`.
"""

from __future__ import annotations

import json
from pathlib import Path

from .manifest import MANIFEST, MODELS_HOME


def shipped_report(version: str = "v1") -> Path:
    """The shipped benchmark report of an env version (``models/MANIFEST.json``'s ``reports[version]``)."""
    manifest = MODELS_HOME / MANIFEST
    try:
        data = json.loads(manifest.read_text(encoding="utf-8"))
        reports = data.get("reports") or {"v1": data["report"]}
    except (OSError, ValueError, KeyError, TypeError, AttributeError):
        raise FileNotFoundError(f"{manifest}: no readable models manifest with a 'reports' entry") from None
    if not isinstance(reports, dict) or version not in reports:
        known = ", ".join(repr(v) for v in reports) if isinstance(reports, dict) else "none"
        raise ValueError(f"shipped report version = {version!r}: expected one of {known} (the env versions whose "
                         "agents are shipped in models/)")
    rel = reports[version]
    path = (MODELS_HOME.parent / str(rel)).resolve()
    if MODELS_HOME.parent.resolve() not in path.parents or path.suffix != ".json":
        raise FileNotFoundError(f"{manifest}: reports.{version} = {rel!r}, expected a .json path inside the "
                                "repository")
    return path
