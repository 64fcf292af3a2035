"""``python -m agents replay REPORT``: re-run a benchmark report's test episodes and compare the returns.

A benchmark report (``docs/benchmark.json``) is data: it names, for every policy, what ran (a baseline and
its tuned parameters; an agent's model zips, their observation statistics and the residual base) and what
each test episode returned. This rebuilds each named policy from that record alone, plays the first N test
episodes from ``reset(seed=S)`` on ``scenario="test"``, and puts every return beside the stored one.

- An agent entry that is the mean over its seeds' models is replayed as such: every model plays the episode,
  and the mean of their returns is compared.
- A ``*_ensemble`` entry is one policy (:mod:`agents.policies.ensemble`); with a ``guarded`` record (fallback,
  guard, scale) it is that ensemble under the constraint guard (:mod:`agents.policies.guarded`); with
  ``described: true`` its students read the well file's features (:mod:`agents.policies.described_features`).
- Model zips are read as data (:class:`agents.evaluation.agent.AgentPolicy`). A report names each as
  ``models/<file>.zip``; :func:`locate_model` looks for it in the report's own folder (a fresh run's
  ``OUT/models``), then in the repository's ``models/`` (:data:`MODELS_HOME`, where the shipped report's
  models live, beside their ``MANIFEST.json``), and nowhere else. A record with ``sha256`` (every report written
  since issue 24's pinning) names its files by content too: a member whose found zip or obs_norm has another digest
  is refused in one line before any episode (:mod:`agents.evaluation.model_pins`); older records are trusted by name.
- The oracle re-plans each episode, about 20 episodes of simulation each; it runs only when named.

It returns True when every return matches to ``tol`` (relative, default 1e-9). The CLI then exits 0, and 1 on a
mismatch; bad input (a report that is not one, an unknown policy, a missing model) exits 2 with one line.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np

from srenv.input_files import read_json

from ..envs import ENV_ID_V1, ENV_ID_V2, ENV_ID_V3, make_env
from ..inputs import baseline_params, report_env_kwargs, report_episodes
from ..policies.ensemble import ensemble_spec
from ..policies.guarded import guarded_spec
from ..policies.residual import RESIDUAL_BASES, check_cap, check_scales
from .manifest import MODELS_HOME
from .model_pins import PINS, check_pins, check_record, obs_norm_path
from .rollout import run_episode
from .v1_view import build_policy_any

REPLAYABLE = (ENV_ID_V1, ENV_ID_V2, ENV_ID_V3)

MAX_REPORT_BYTES = 50_000_000


class ReplayError(ValueError):
    """A report, policy name or model that cannot be replayed; the message names the field and the value."""


def load_report(path: str | Path) -> dict[str, Any]:
    p = Path(path)
    if not p.is_file():
        raise ReplayError(f"report {p}: no such file (expected a benchmark.json)")
    rep = read_json(p, "report", "benchmark report", MAX_REPORT_BYTES)  # data only, bounded, one line
    if not isinstance(rep, dict) or rep.get("schema") != "srenv benchmark v1":
        raise ReplayError(f"report {p}: schema = {rep.get('schema') if isinstance(rep, dict) else None!r}, "
                          "expected 'srenv benchmark v1'")
    if rep.get("env_id") not in REPLAYABLE:
        raise ReplayError(f"report {p}: env_id = {rep.get('env_id')!r}, expected one of {', '.join(REPLAYABLE)}")
    if not isinstance(rep.get("env_kwargs"), dict) or not isinstance(rep.get("policies"), dict):
        raise ReplayError(f"report {p}: expected env_kwargs and policies mappings")
    report_env_kwargs(rep["env_kwargs"])
    for name, pol in rep["policies"].items():
        if not isinstance(pol, dict):
            raise ReplayError(f"report {p}: policies.{name} = {str(pol)[:60]!r}, expected a mapping")
    seeds = (rep.get("test") or {}).get("seeds")
    if not (isinstance(seeds, list) and seeds and all(isinstance(s, int) and s >= 0 for s in seeds)):
        raise ReplayError(f"report {p}: test.seeds = {str(seeds)[:60]}, expected a list of non-negative integers")
    return rep


def locate_model(root: Path, rel: Any, name: str) -> Path:
    """The one place a report's model is looked up: ``rel`` (``models/<file>.zip``, relative to the report)
    in the report's folder ``root``, else ``<file>.zip`` in :data:`MODELS_HOME`; each confined to its folder."""
    if not isinstance(rel, str) or not rel.endswith(".zip") or Path(rel).is_absolute():
        raise ReplayError(f"policies.{name}.models: {rel!r}, expected a .zip path relative to the report")
    path = (root / rel).resolve()
    if root.resolve() not in path.parents:
        raise ReplayError(f"policies.{name}.models: {rel!r} leaves the report's folder {root}")
    home = MODELS_HOME / Path(rel).name
    for candidate in (path, home) if Path(rel).parent == Path("models") else (path,):
        if candidate.is_file():
            return candidate
    raise ReplayError(f"policies.{name}.models: {rel!r}: no such model file in {root} or {MODELS_HOME}")


def _model(root: Path, rel: Any, name: str, pins: dict[str, str | None] | None) -> dict[str, Any]:
    """``{"path", "obs_norm"}`` of one model named in the report; refused when the record pins other files."""
    path = locate_model(root, rel, name)
    try:
        check_pins(pins, rel, path, f"policies.{name}.{PINS}", root)
    except ValueError as exc:
        raise ReplayError(str(exc)) from None
    norm = obs_norm_path(path)
    return {"path": str(path), "obs_norm": str(norm) if norm.is_file() else None}


def _residual(res: Any, name: str) -> dict[str, Any] | None:
    if res is None:
        return None
    scale = res.get("scale") if isinstance(res, dict) else None
    idle = res.get("idle_scale") if isinstance(res, dict) else None
    try:
        check_scales(scale, idle)
        scales_ok = scale is not None
    except ValueError:
        scales_ok = False
    if not (isinstance(res, dict) and res.get("base") in RESIDUAL_BASES and isinstance(res.get("params"), dict)
            and scales_ok):
        raise ReplayError(f"policies.{name}.residual_on = {str(res)[:80]}: expected {{base: one of "
                          f"{', '.join(RESIDUAL_BASES)}, params: {{...}}, scale in (0, 2], idle_scale in (0, 2] "
                          "or absent}}")
    out = {"base": res["base"], "params": res["params"], "scale": float(scale)}
    if idle is not None:
        out["idle_scale"] = float(idle)
    if res.get("cap") is not None:  # a capped correction replays capped (f24's residual.cap), never silently not
        try:
            check_cap(res["cap"])
        except ValueError as exc:
            raise ReplayError(f"policies.{name}.residual_on: {exc}") from None
        out["cap"] = dict(res["cap"])
    return out


def policy_specs(rep: dict[str, Any], name: str, root: Path) -> list[dict[str, Any]]:
    """The policy specs whose mean return is ``name``'s stored return (one, or one per seed model)."""
    pol = rep["policies"].get(name)
    if not isinstance(pol, dict):
        raise ReplayError(f"--policy {name}: not in the report (it has {', '.join(rep['policies'])})")
    if pol.get("kind") == "baseline":
        return [{"kind": "baseline", "name": name,
                 "params": baseline_params(name, pol.get("params") or {}, f"policies.{name}.params")}]
    models = pol.get("models")
    if pol.get("kind") != "agent" or not isinstance(models, list) or not models:
        raise ReplayError(f"policies.{name}: expected a baseline, or an agent with a list of models")
    res = _residual(pol.get("residual_on"), name)
    described = pol.get("described", False)
    if not isinstance(described, bool):
        raise ReplayError(f"policies.{name}.described = {str(described)[:80]}: expected true or false")
    flag = {"described": True} if described else {}  # the well file's features on the students' input
    try:  # the files the report played, by content (absent in older reports: trusted by name)
        pins = check_record(pol.get(PINS), f"policies.{name}.{PINS}")
    except ValueError as exc:
        raise ReplayError(str(exc)) from None
    specs = [{"kind": "agent", **_model(root, m, name, pins), **({"residual": res} if res else {}), **flag}
             for m in models]
    if pol.get("guarded") is not None:
        return [_guarded(pol["guarded"], {**ensemble_spec(specs), **flag}, name)]
    return [{**ensemble_spec(specs), **flag}] if pol.get("ensemble_of") else specs


def _guarded(rec: Any, inner: dict[str, Any], name: str) -> dict[str, Any]:
    """The guarded spec a report's ``guarded`` record names (its fallback baseline, guard and scale)."""
    fb = rec.get("fallback") if isinstance(rec, dict) else None
    if not (isinstance(fb, dict) and isinstance(fb.get("name"), str) and isinstance(fb.get("params"), dict)):
        raise ReplayError(f"policies.{name}.guarded = {str(rec)[:80]}: expected {{fallback: {{name, params}}, "
                          "guard: {...}, scale: S | null}")
    try:
        return guarded_spec(inner, fb["name"], baseline_params(fb["name"], fb["params"], f"policies.{name}.guarded"),
                            rec.get("guard") or {}, rec.get("scale"))
    except ValueError as exc:
        raise ReplayError(f"policies.{name}.{exc}") from None


def _scenario(rep: dict[str, Any], k: int) -> str:
    """The scenario of the report's k-th test episode: the test split, or (evaluate-only) its fresh family well."""
    fresh = rep.get("fresh")
    if isinstance(fresh, dict) and isinstance(fresh.get("family_seeds"), list):
        w = fresh["family_seeds"][k]
        if not (isinstance(w, int) and w >= 0):
            raise ReplayError(f"fresh.family_seeds[{k}] = {w!r}: expected a non-negative integer")
        return f"family:{w}"
    sc = (rep.get("test") or {}).get("scenario", "test")  # a quick run plays v2's validation split
    if sc not in ("test", "validation"):
        raise ReplayError(f"test.scenario = {sc!r}: expected 'test' or 'validation'")
    return sc


def replay(report: str | Path, names: list[str] | None = None, episodes: int = 3,
           tol: float = 1e-9) -> dict[str, Any]:
    """Re-run ``episodes`` test episodes of each policy in ``names`` (default: every policy but the oracle)."""
    rep = load_report(report)
    root = Path(report).resolve().parent
    names = list(names or [n for n in rep["policies"] if n != "oracle"])
    specs = {n: policy_specs(rep, n, root) for n in names}  # every name and model checked before any episode
    stored_all = {n: report_episodes(rep["policies"][n], n) for n in names}  # and every stored episode
    seeds = rep["test"]["seeds"][:episodes]
    envs = {sc: make_env(rep["env_id"], **{**rep["env_kwargs"], "scenario": sc})
            for sc in {_scenario(rep, k) for k in range(len(seeds))}}
    out: dict[str, Any] = {"report": str(report), "episodes": len(seeds), "tol": tol, "policies": {}}
    try:
        for n, sp in specs.items():
            stored = stored_all[n]
            rows, worst = [], 0.0
            for k, s in enumerate(seeds):
                env = envs[_scenario(rep, k)]
                ret = float(np.mean([run_episode(env, build_policy_any(x, env), s)["reward"] for x in sp]))
                ref = stored.get(int(s), math.nan)  # an episode the report lacks counts as a mismatch
                diff = abs(ret - ref) if math.isfinite(ref) else math.inf
                rows.append({"seed": int(s), "reward": ret, "stored_reward": ref, "abs_diff": diff})
                worst = max(worst, diff / max(1.0, abs(ref) if math.isfinite(ref) else 1.0))
            out["policies"][n] = {"runs": len(sp), "episodes": rows, "max_rel_diff": worst, "reproduced": worst <= tol}
    finally:
        for env in envs.values():
            env.close()
    out["reproduced"] = all(p["reproduced"] for p in out["policies"].values())
    return out
