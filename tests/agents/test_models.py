"""The trained models live in the repository's models/ with a manifest (agents/evaluation/manifest.py), not in
docs/: every file is listed with its sha256 and origin, and each env version's shipped report finds its models
there."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from agents.evaluation import manifest as manifest_mod
from agents.evaluation import shipped
from agents.evaluation.manifest import (
    MANIFEST,
    MODELS_HOME,
    SHIPPED_REPORTS,
    build_manifest,
    sha256,
    shipped_out_dir,
    shipped_reports,
)
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
    # rebuilt from the files and every shipped report: the same
    assert manifest == build_manifest(MODELS_HOME, shipped_reports(REPO))
    assert manifest["reports"] == SHIPPED_REPORTS and manifest["report"] == SHIPPED_REPORTS["v1"]
    assert not list((REPO / "docs").rglob("*.zip")) and not list((REPO / "docs").rglob("*.npz"))


@pytest.mark.parametrize("version", sorted(SHIPPED_REPORTS))
def test_every_model_of_each_shipped_report_is_in_models_named_for_its_env(version: str) -> None:
    path = shipped.shipped_report(version)
    rep = load_report(path)
    assert rep["env_id"].endswith(f"-{version}")
    named = {m for p in rep["policies"].values() for m in p.get("models") or []}
    assert named and all(locate_model(path.parent, m, "x").parent == MODELS_HOME for m in named)
    entries = json.loads((MODELS_HOME / MANIFEST).read_text())["files"]
    for m in named:  # a v2 agent's file is never named as a v1 one, and its manifest entry says which env
        assert f"_{version}_" in Path(m).name and entries[Path(m).name]["env_id"] == rep["env_id"], m


def test_a_shipped_run_writes_where_its_version_is_shipped() -> None:
    # one version's shipped run never overwrites another's report
    assert shipped_out_dir("v1") == Path("docs") and shipped_out_dir("v2") == Path("docs/v2")
    assert shipped_out_dir("v0") is None


def test_shipped_report_names_the_versions_it_knows(tmp_path: Path, monkeypatch) -> None:
    with pytest.raises(ValueError, match=r"version = 'v9': expected one of 'v1', 'v2'"):
        shipped.shipped_report("v9")
    # a manifest from before v2 agents were shipped (only "report") still gives v1's
    home = tmp_path / "models"
    home.mkdir()
    (home / MANIFEST).write_text(json.dumps({"report": "docs/benchmark.json", "files": {}}))
    monkeypatch.setattr(shipped, "MODELS_HOME", home)
    assert shipped.shipped_report("v1") == (tmp_path / "docs" / "benchmark.json").resolve()
    with pytest.raises(ValueError, match="expected one of 'v1'"):
        shipped.shipped_report("v2")
    (home / MANIFEST).write_text(json.dumps({"reports": {"v1": "../outside.json"}}))
    with pytest.raises(FileNotFoundError, match="inside the repository"):
        shipped.shipped_report("v1")
    assert manifest_mod.MODELS_HOME == MODELS_HOME  # the module's own constant untouched


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


def test_evaluate_only_plays_the_shipped_report_that_holds_the_configs_agents() -> None:
    """The team evaluates the shipped v2 agent on fresh wells with the v2 design's config and no --report."""
    from agents.benchmark.config import load_benchmark_config
    from agents.benchmark.fresh import default_report

    v2od = load_benchmark_config(REPO / "configs/benchmark/v2_oracle_distilled.yaml")
    assert default_report(v2od) == shipped.shipped_report("v2")
    v2 = load_benchmark_config(REPO / "configs/benchmark/v2.yaml")  # names v1's agents, played on v2
    assert default_report(v2) == shipped.shipped_report("v1")


def test_every_v2_report_in_docs_finds_its_models_in_models() -> None:
    """The v2 reports kept in docs/ (the shipped one, its fresh split, the guarded design's look and fresh split) name
    the students by the files shipped in models/, so `python -m agents replay REPORT` runs from a checkout."""
    paths = [REPO / "docs/v2/benchmark.json", REPO / "docs/v2/fresh.json",
             *sorted((REPO / "docs/archive").glob("benchmark_v2_oracle_distilled_guarded_*.json"))]
    assert len(paths) == 4
    for path in paths:
        rep = load_report(path)
        named = {m for p in rep["policies"].values() for m in p.get("models") or []}
        assert named and all(locate_model(path.parent, m, "x").parent == MODELS_HOME for m in named), path
