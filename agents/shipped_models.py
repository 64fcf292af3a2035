"""Where the shipped, benchmarked models and their report live: one lookup, so a move is one edit here.

Today the v1 benchmark writes ``docs/benchmark.json`` with the models under ``docs/models/`` (paths in the
report are relative to it). The ``layout`` work moves models to a top-level ``models/`` folder with a manifest;
when it lands, :func:`shipped_report` is the one function to change.
"""

from __future__ import annotations

from pathlib import Path

REPO = Path(__file__).resolve().parent.parent


def shipped_report(version: str = "v1") -> Path:
    """The shipped benchmark report of an env version (its models are read relative to its folder)."""
    if version != "v1":
        raise ValueError(f"shipped report version = {version!r}: expected 'v1' (no v2 agents are shipped yet)")
    return REPO / "docs" / "benchmark.json"
