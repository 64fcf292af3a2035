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


def _origins(report: dict[str, Any], report_name: str) -> dict[str, dict[str, Any]]:
    """Model file name -> where it came from, from a benchmark report's training record."""
    out: dict[str, dict[str, Any]] = {}
    for run_name, run in report.get("training", {}).get("runs", {}).items():
        for k, entry in enumerate(run.get("per_seed", [])):
            models = report["policies"][run_name]["models"]
            out[Path(models[k]).name] = {"run": run_name, "training_config": run["config"], "seed": entry["seed"]}
        out[Path(run["shipped_model"]).name] = {"run": run_name, "training_config": run["config"],
                                                "seed": run["shipped_seed"], "shipped_pick": True}
        for k, teacher in enumerate(run.get("teacher", {}).get("models", [])):
            out[Path(teacher).name] = {"run": run_name, "training_config": run["config"], "seed": run["seeds"][k],
                                       "teacher": True, "observation": "privileged"}
    for origin in out.values():
        origin["benchmark_run"] = report_name
    return out


def build_manifest(models_dir: Path, report_path: Path) -> dict[str, Any]:
    """The manifest of every file in ``models_dir``: hashes, and origins from the report (v0's by name)."""
    origins = _origins(json.loads(report_path.read_text(encoding="utf-8")), f"docs/{report_path.name}")
    files = {}
    for path in sorted(p for p in models_dir.iterdir() if p.is_file() and p.name != MANIFEST):
        base = path.name.removesuffix("_obs_norm.npz") + ".zip" if path.name.endswith("_obs_norm.npz") else path.name
        origin = origins.get(base)
        if origin is None and (m := _V0.match(path.name)):
            origin = {"training_config": f"configs/train/{m['stem']}.yaml", "benchmark_run": None,
                      "evaluated_in": "docs/agents.md (srenv/SuckerRod-v0)"}
        files[path.name] = {"sha256": sha256(path), "bytes": path.stat().st_size, **(origin or {})}
    return {"schema": "srenv models v1", "report": f"docs/{report_path.name}", "files": files}


def write_manifest(models_dir: Path, report_path: Path) -> Path:
    dest = models_dir / MANIFEST
    tmp = dest.with_suffix(".json.tmp")
    tmp.write_text(json.dumps(build_manifest(models_dir, report_path), indent=1) + "\n", encoding="utf-8")
    tmp.replace(dest)
    return dest
