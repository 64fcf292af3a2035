"""The trained models live in the repository's models/ with a manifest (agents/evaluation/manifest.py), not in
docs/: every file is listed with its sha256 and origin, and the shipped report finds its models there."""

from __future__ import annotations

import json
from pathlib import Path

from agents.evaluation.manifest import MANIFEST, MODELS_HOME, build_manifest, sha256
from agents.evaluation.replay import ReplayError, load_report, locate_model

REPO = Path(__file__).resolve().parents[2]
REPORT = REPO / "docs" / "benchmark.json"


def test_the_manifest_lists_every_model_file_with_its_hash_and_origin() -> None:
    manifest = json.loads((MODELS_HOME / MANIFEST).read_text())
    files = sorted(p.name for p in MODELS_HOME.iterdir() if p.name != MANIFEST)
    assert sorted(manifest["files"]) == files and len(files) >= 40
    for name, entry in manifest["files"].items():
        assert entry["sha256"] == sha256(MODELS_HOME / name), name
        assert Path(REPO / entry["training_config"]).is_file(), name
    assert manifest == build_manifest(MODELS_HOME, REPORT)  # rebuilt from the files and the report: the same
    assert not list((REPO / "docs").rglob("*.zip")) and not list((REPO / "docs").rglob("*.npz"))


def test_every_model_of_the_shipped_report_is_found_in_models(tmp_path: Path) -> None:
    rep = load_report(REPORT)
    named = {m for p in rep["policies"].values() for m in p.get("models") or []}
    assert named and all(locate_model(REPORT.parent, m, "x").parent == MODELS_HOME for m in named)
    # a fresh run's own folder comes first; nothing outside the report's folder or models/ is read
    (tmp_path / "models").mkdir()
    own = tmp_path / "models" / Path(min(named)).name
    own.write_bytes(b"zip")
    assert locate_model(tmp_path, min(named), "x") == own.resolve()
    for bad in ("../models/ppo_v1.zip", "elsewhere/ppo_v1.zip"):
        try:
            locate_model(tmp_path, bad, "x")
        except ReplayError:
            continue
        raise AssertionError(f"{bad} was found")
