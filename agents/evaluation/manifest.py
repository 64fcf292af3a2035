"""The repository's trained models (``models/``) and their manifest, ``models/MANIFEST.json``: for every file
its sha256 and size, the training config and seed it came from, and the benchmark run (report) that tested
it, so a model can be checked and traced without reading the report. ``python -m agents benchmark`` rewrites
it after the shipped run; ``tests/agents/test_models.py`` checks it against the files.
"""

from __future__ import annotations

import hashlib
import json
import re
from pathlib import Path
from typing import Any

MODELS_HOME = Path(__file__).resolve().parents[2] / "models"  # the repository's trained models (a checkout)
MANIFEST = "MANIFEST.json"
# the v0 models of docs/agents.md: trained by python -m agents train configs/train/<stem>.yaml, evaluated there
_V0 = re.compile(r"^(?P<stem>[a-z0-9]+_default)(?:_vecnormalize)?\.(?:zip|json|pkl)$")


def sha256(path: Path) -> str:
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        for block in iter(lambda: fh.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


# the shipped report of each env version, relative to the repository: a shipped benchmark run (no --out-dir)
# writes its report there and the manifest names it (agents.evaluation.shipped.shipped_report)
SHIPPED_REPORTS = {"v1": "docs/benchmark.json", "v2": "docs/v2/benchmark.json"}


def shipped_out_dir(env_tag: str) -> Path | None:
    """Where a shipped benchmark run of env version ``env_tag`` writes its report (relative), None if that
    version has no shipped report."""
    rel = SHIPPED_REPORTS.get(env_tag)
    return Path(rel).parent if rel else None


def shipped_reports(repo: Path) -> dict[str, Path]:
    """The shipped reports that exist in ``repo``, by env version."""
    return {v: repo / rel for v, rel in SHIPPED_REPORTS.items() if (repo / rel).is_file()}


def _origins(report: dict[str, Any], report_name: str) -> dict[str, dict[str, Any]]:
    """Model file name -> where it came from, from a benchmark report's training record."""
    out: dict[str, dict[str, Any]] = {}
    training = report.get("training", {})
    for run_name, run in training.get("runs", {}).items():
        for k, entry in enumerate(run.get("per_seed", [])):
            models = report["policies"][run_name]["models"]
            out[Path(models[k]).name] = {"run": run_name, "training_config": run["config"], "seed": entry["seed"]}
        out[Path(run["shipped_model"]).name] = {"run": run_name, "training_config": run["config"],
                                                "seed": run["shipped_seed"], "shipped_pick": True}
        for k, teacher in enumerate(run.get("teacher", {}).get("models", [])):
            out[Path(teacher).name] = {"run": run_name, "training_config": run["config"], "seed": run["seeds"][k],
                                       "teacher": True, "observation": "privileged"}
    # students distilled from a teacher that is not a model (the causal oracle): their files are the ensemble's
    for ens in training.get("ensembles", {}).values():
        student = training.get("students", {}).get(ens.get("of"))
        if student is None:
            continue
        for k, model in enumerate(ens["models"]):
            out[Path(model).name] = {"run": ens["of"], "training_config": student["config"],
                                     "seed": student["seeds"][k], "teacher": student["teacher"]["kind"]}
    for origin in out.values():
        origin["env_id"] = report.get("env_id")
        origin["benchmark_run"] = report_name
    return out


def build_manifest(models_dir: Path, reports: dict[str, Path]) -> dict[str, Any]:
    """The manifest of every file in ``models_dir``: hashes, and origins from the shipped reports (by env
    version, e.g. ``{"v1": docs/benchmark.json}``; v0's files by name)."""
    origins: dict[str, dict[str, Any]] = {}
    names = {}
    for version, path in sorted(reports.items()):
        names[version] = SHIPPED_REPORTS.get(version, f"docs/{path.name}")
        origins.update(_origins(json.loads(path.read_text(encoding="utf-8")), names[version]))
    files = {}
    for path in sorted(p for p in models_dir.iterdir() if p.is_file() and p.name != MANIFEST):
        base = path.name.removesuffix("_obs_norm.npz") + ".zip" if path.name.endswith("_obs_norm.npz") else path.name
        origin = origins.get(base)
        if origin is None and (m := _V0.match(path.name)):
            origin = {"training_config": f"configs/train/{m['stem']}.yaml", "benchmark_run": None,
                      "evaluated_in": "docs/agents.md (srenv/SuckerRod-v0)"}
        files[path.name] = {"sha256": sha256(path), "bytes": path.stat().st_size, **(origin or {})}
    # "report" is v1's, as manifests before v2 agents were shipped had it
    return {"schema": "srenv models v2", "report": names.get("v1"), "reports": names, "files": files}


def write_manifest(models_dir: Path, reports: dict[str, Path]) -> Path:
    dest = models_dir / MANIFEST
    tmp = dest.with_suffix(".json.tmp")
    tmp.write_text(json.dumps(build_manifest(models_dir, reports), indent=1) + "\n", encoding="utf-8")
    tmp.replace(dest)
    return dest
