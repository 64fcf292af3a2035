"""The benchmark's YAML (``configs/benchmark/*.yaml``): read, checked before any work, ``quick:`` merged.

Checks: seed lists (``[..]`` or ``{start, count}``), tuning on the training split only (the test split is
refused), tuning / validation / test seeds pairwise disjoint, known baseline names, agent runs with a
readable training YAML that does not train on the test split, residual bases.
"""

from __future__ import annotations

import copy
from pathlib import Path
from typing import Any

from srenv.errors import short_repr
from srenv.safe_yaml import load_yaml_file, yaml_kind
from srenv.shipped import shipped_dir

from ..envs import ENV_ID_V1
from ..inputs import FIELDS, seeds
from ..policies.factory import BASELINE_NAMES, OPTIONAL_BASELINES, SEARCHED_BASELINES
from ..policies.residual import RESIDUAL_BASES, check_scales
from ..training.tuning import refuse_test_split
from .config_error import BenchmarkConfigError, Declared
from .splits import SPLIT_KEYS, check_splits

Z95 = 1.959963984540054


# -------------------------------------------------------------------------------------------- config
_REPLACED = ("space", "runs")  # a quick block's search space / agent runs replace the full ones


def _deep_merge(base: dict, over: dict) -> dict:
    out = copy.deepcopy(base)
    for k, v in over.items():
        merge = isinstance(v, dict) and isinstance(out.get(k), dict) and k not in _REPLACED
        out[k] = _deep_merge(out[k], v) if merge else copy.deepcopy(v)
    return out


def _seeds(value: Any, key: str) -> list[int]:
    """A seed list: ``[1, 2, 3]`` or ``{start: S, count: N}``, bounded (agents/inputs.py)."""
    return seeds(value, key)


# The top-level keys of a benchmark YAML, the one declaration (anything else is refused by name, before the
# blocks are checked), each with the YAML types it takes and what that is: the env, the splits, the contenders,
# and the pipeline's settings. Each block's contents are checked below.
_NULL = type(None)
TOP_KEYS: Declared = {
    "env_id": ((str,), "an srenv env id (srenv/SuckerRod-v1, -v2 or -v3)"),
    "env_kwargs": ((dict,), "a mapping of the env's keywords"),
    "workers": ((int, float), "a positive integer (worker processes; bounded in agents/inputs.py)"),
    "tuning": ((dict,), "a mapping with seeds"),
    "validation": ((dict,), "a mapping with seeds"),
    "test": ((dict,), "a mapping with seeds"),
    "figure_episode": ((int,), "an integer (the test episode of the report's figure)"),
    "history": ((list,), "a list of strings (one line per earlier test evaluation)"),
    "baselines": ((dict,), "a mapping baseline -> its search"),
    "agents": ((dict,), "a mapping {selection, runs}"),
    "guarded": ((dict, _NULL), "a mapping {fallback, scale, guard}"),
    "evaluate_only": ((dict, _NULL), "a mapping {agents, alarm_params, references, tuned}"),
    "quick": ((dict, _NULL), "a mapping of the top-level blocks --quick replaces"),
    "work_dir": ((str, _NULL), "a directory path (the runs' temporary files)"),
}
QUICK_KEYS = {k: v for k, v in TOP_KEYS.items() if k != "quick"}
AGENTS_KEYS: Declared = {"selection": ((str,), "mean or best_on_validation"), "runs": ((dict,), "a mapping algo -> run")}
EVALUATE_ONLY_KEYS: Declared = {
    "agents": ((list,), "a list of the shipped report's agent names"),
    "alarm_params": ((dict, _NULL), "a mapping of alarm_pump_off's parameters"),
    "references": ((dict, _NULL), "a mapping causal_oracle / oracle -> parameters or null"),
    "tuned": ((str, _NULL), "a path to a tuned-baselines archive (its `tuned` replaces the report's baselines)"),
}


def _check_keys(block: Any, where: str, declared: Declared) -> dict:
    """``block`` is a mapping whose keys are all ``declared``, each value of its declared type: else one line
    naming the unknown keys (listing the declared ones), or the key, the value and the type found."""
    if not isinstance(block, dict):
        raise BenchmarkConfigError(f"{where} = {short_repr(block, 80)} ({yaml_kind(block)}): expected a mapping of "
                                   f"the keys {', '.join(declared)}")
    unknown = sorted(map(str, set(block) - set(declared)))
    if unknown:
        raise BenchmarkConfigError(f"{where}: unknown key(s) {short_repr(unknown, 120)}: expected only "
                                   f"{', '.join(declared)}")
    for key, value in block.items():
        types, what = declared[key]
        if not isinstance(value, types) or (isinstance(value, bool) and bool not in types):
            raise BenchmarkConfigError(f"{where}: {key} = {short_repr(value, 80)} ({yaml_kind(value)}): "
                                       f"expected {what}")
    return block


def load_benchmark_config(path: str | Path, quick: bool = False) -> dict[str, Any]:
    """Read and check a benchmark YAML (``quick``: merge its ``quick:`` block); the resolved dict."""
    p = Path(path)
    if not p.is_file():
        raise FileNotFoundError(f"benchmark config {path}: no such file")
    raw = load_yaml_file(p, "benchmark config")  # bounded: alias bombs, duplicate keys, syntax in one line
    _check_keys(raw, f"benchmark config {path}", TOP_KEYS)
    for name, declared in (("quick", QUICK_KEYS), ("agents", AGENTS_KEYS), ("evaluate_only", EVALUATE_ONLY_KEYS),
                           ("tuning", SPLIT_KEYS), ("validation", SPLIT_KEYS), ("test", SPLIT_KEYS)):
        if raw.get(name) is not None:
            _check_keys(raw[name], f"benchmark config {path}: {name}", declared)
        if name != "quick" and (raw.get("quick") or {}).get(name) is not None:
            _check_keys(raw["quick"][name], f"benchmark config {path}: quick.{name}", declared)
    cfg = _deep_merge(raw, raw.get("quick") or {}) if quick else copy.deepcopy(raw)
    cfg.pop("quick", None)
    cfg["source"] = str(path)
    cfg.setdefault("env_id", ENV_ID_V1)
    cfg.setdefault("env_kwargs", {"observation": "field"})
    if "scenario" in cfg["env_kwargs"]:
        raise BenchmarkConfigError("benchmark config: env_kwargs.scenario: expected none (the protocol sets "
                                   "train for tuning/training and test for the evaluation)")
    hist = cfg.setdefault("history", [])
    if not (isinstance(hist, list) and all(isinstance(h, str) for h in hist)):
        raise BenchmarkConfigError(f"benchmark config: history = {str(hist)[:120]!r}: expected a list of strings "
                                   "(one line per earlier test evaluation)")
    cfg["workers"] = FIELDS["benchmark"]["workers"].check(cfg.setdefault("workers", 2))
    sets = check_splits(cfg)
    bl = cfg.setdefault("baselines", {})
    for name in bl:
        if name not in (*BASELINE_NAMES, *OPTIONAL_BASELINES):
            raise BenchmarkConfigError(f"benchmark config: baselines.{name}: expected one of "
                                       f"{(*BASELINE_NAMES, *OPTIONAL_BASELINES)}")
    _check_inits(bl)
    ag = cfg.setdefault("agents", {})
    sel = ag.setdefault("selection", "mean")
    if sel not in ("mean", "best_on_validation"):
        raise BenchmarkConfigError(f"benchmark config: agents.selection = {sel!r}: expected mean or "
                                   "best_on_validation")
    if sel == "best_on_validation" and not cfg["validation"]["seeds"]:
        raise BenchmarkConfigError("benchmark config: agents.selection = best_on_validation needs "
                                   "validation.seeds")
    runs = ag.setdefault("runs", {})
    if not isinstance(runs, dict):
        raise BenchmarkConfigError(f"benchmark config: agents.runs = {runs!r}: expected a mapping algo -> run")
    for algo, run in runs.items():
        _check_run(algo, run, cfg["env_id"])
    for algo, run in runs.items():
        if run.get("teacher") is not None:
            _check_teacher(algo, run, runs, sets["tuning"] | sets["validation"])
    if cfg.get("guarded") is not None:
        _check_guarded(cfg["guarded"], bl, runs)
    return cfg


def _check_guarded(g: Any, bl: dict[str, Any], runs: dict[str, Any]) -> None:
    """``guarded: {fallback, scale, guard}``: the design's one ensemble under a constraint guard
    (agents/policies/guarded.py, which bounds the guard and the scale)."""
    from ..policies.guarded import guarded_spec

    if not isinstance(g, dict) or set(g) - {"fallback", "scale", "guard"}:
        raise BenchmarkConfigError(f"benchmark config: guarded = {str(g)[:80]!r}: expected {{fallback: BASELINE, "
                                   "scale: S, guard: {...}}")
    if g.get("fallback") not in bl or g.get("fallback") == "oracle":
        raise BenchmarkConfigError(f"benchmark config: guarded.fallback = {g.get('fallback')!r}: expected a tuned "
                                   f"field baseline of this config ({', '.join(n for n in bl if n != 'oracle')})")
    if len(runs) != 1 or not all(r.get("residual") for r in runs.values()):
        raise BenchmarkConfigError("benchmark config: guarded: expected one residual agent run (its students' ensemble)")
    try:
        guarded_spec({"kind": "ensemble", "residual": {"base": "best_tuned"}, "members": []}, g["fallback"], {}, g.get("guard") or {},
                     g.get("scale"))
    except ValueError as exc:
        raise BenchmarkConfigError(f"benchmark config: guarded.{str(exc).removeprefix('guarded.')}") from None


def _check_inits(bl: dict[str, Any]) -> None:
    """A search's ``init`` value that names a baseline starts from that baseline's tuned value: it must be one
    tuned before (``best_constant``, then :data:`SEARCHED_BASELINES` in order) that has the parameter."""
    done = ["best_constant"]
    for name in SEARCHED_BASELINES:
        spec = bl.get(name) or {}
        init = spec.get("init") or {}
        if not isinstance(init, dict):
            raise BenchmarkConfigError(f"benchmark config: baselines.{name}.init = {init!r}: expected a mapping")
        for k, v in init.items():
            if not isinstance(v, str):
                continue
            src = bl.get(v) or {}
            has = v == "best_constant" or k in {**(src.get("init") or {}), **(src.get("space") or {})}
            if v not in done or not has:
                raise BenchmarkConfigError(f"benchmark config: baselines.{name}.init.{k} = {v!r}: expected a "
                                           f"number or a baseline tuned before it with a {k} ({', '.join(done)})")
        done.append(name)


def _check_run(algo: str, run: Any, env_id: str) -> None:
    """One ``agents.runs`` entry: its training YAML (read now, not after the tuning) on the benchmark's env
    ``env_id`` (a v3 benchmark never trains on v2), seeds and residual."""
    from ..training.config import load_train_config

    if not isinstance(run, dict) or "config" not in run:
        raise BenchmarkConfigError(f"benchmark config: agents.runs.{algo}: expected {{config: YAML, seeds: [...]}}")
    run["config"] = str(_resolve(run["config"]))
    run["seeds"] = _seeds(run.get("seeds", [0, 1, 2]), f"agents.runs.{algo}.seeds")
    if not isinstance(run.get("ensemble", False), bool) or (run.get("ensemble") and len(run["seeds"]) < 2):
        raise BenchmarkConfigError(f"benchmark config: agents.runs.{algo}.ensemble = {run.get('ensemble')!r}: "
                                   "expected true or false (true needs >= 2 seeds)")
    over = run.get("overrides")
    if over is not None and not (isinstance(over, dict) and all(isinstance(k, str) for k in over)):
        raise BenchmarkConfigError(f"benchmark config: agents.runs.{algo}.overrides = {str(over)[:80]!r}: "
                                   "expected a mapping of training-YAML keys")
    tc = load_train_config(run["config"], over)  # checks the YAML and its overrides now, not after tuning
    if tc.env_id != env_id:
        raise BenchmarkConfigError(f"benchmark config: agents.runs.{algo}.config = {run['config']}: env_id = "
                                   f"{tc.env_id!r}: expected the benchmark's env_id {env_id!r}")
    refuse_test_split(tc.env_kwargs.get("scenario", "train"), "train")
    res = run.get("residual")
    if res is not None and (not isinstance(res, dict) or res.get("base", "best_tuned") not in
                            ("best_tuned", *RESIDUAL_BASES)):
        raise BenchmarkConfigError(f"benchmark config: agents.runs.{algo}.residual = {res!r}: expected "
                                   "{base: best_tuned | best_constant | pump_off | fillage_pi, scale: S}")
    if res is not None and res.get("shaping") not in (None, "potential"):
        raise BenchmarkConfigError(f"benchmark config: agents.runs.{algo}.residual.shaping = "
                                   f"{res.get('shaping')!r}: expected potential or nothing")
    if res is not None:
        extra = set(res) - {"base", "scale", "idle_scale", "shaping"}
        if extra:
            raise BenchmarkConfigError(f"benchmark config: agents.runs.{algo}.residual: unknown key(s) "
                                       f"{sorted(extra)}: expected base, scale, idle_scale, shaping")
        try:
            check_scales(res.get("scale"), res.get("idle_scale"))
        except ValueError as exc:
            raise BenchmarkConfigError(f"benchmark config: agents.runs.{algo}.{exc}") from None


def _int_in(value: Any, lo: int, hi: int) -> bool:
    return isinstance(value, int) and not isinstance(value, bool) and lo <= value <= hi


def _check_teacher(algo: str, run: dict[str, Any], runs: dict[str, Any], held: set[int]) -> None:
    """A teacher-student run (agents/training/distill.py): its teachers are this run's seeds on the privileged
    observation, its students start from ``students_from``'s models of the same seeds."""
    from ..training.distill import DISTILL_KEYS

    key = f"benchmark config: agents.runs.{algo}.teacher"
    t = run["teacher"]
    if isinstance(t, dict) and "kind" in t:
        _check_oracle_teacher(key, run, t, held)
        return
    if not isinstance(t, dict) or set(t) - DISTILL_KEYS or not {"students_from", "iterations", "episodes",
                                                                  "seed_start"} <= set(t):
        raise BenchmarkConfigError(f"{key} = {str(t)[:120]!r}: expected {{students_from: RUN, iterations: N, "
                                   "episodes: N, seed_start: S[, idle_scale: X]}}")
    src = runs.get(t["students_from"]) if isinstance(t["students_from"], str) else None
    if src is None or t["students_from"] == algo or src.get("teacher"):
        raise BenchmarkConfigError(f"{key}.students_from = {t['students_from']!r}: expected another run of "
                                   f"agents.runs without a teacher (one of {sorted(set(runs) - {algo})})")
    res, src_res = run.get("residual"), src.get("residual")
    if not res or not src_res or any(res.get(k, d) != src_res.get(k, d) for k, d in
                                      (("base", "best_tuned"), ("scale", None), ("idle_scale", None))):
        raise BenchmarkConfigError(f"{key}: expected a residual run whose base, scale and idle_scale are those of "
                                   f"{t['students_from']} (the students start from its models)")
    if src["seeds"] != run["seeds"]:
        raise BenchmarkConfigError(f"{key}.students_from = {t['students_from']!r}: its seeds {src['seeds']} "
                                   f"differ from this run's {run['seeds']}: expected the same (one student each)")
    _check_schedule(key, t)
    try:
        check_scales(res.get("scale"), t.get("idle_scale"))
    except ValueError as exc:
        raise BenchmarkConfigError(f"{key}.{str(exc).removeprefix('residual.')}") from None
    _check_disjoint(key, run, t, held)


def _check_oracle_teacher(key: str, run: dict[str, Any], t: dict[str, Any], held: set[int]) -> None:
    """``teacher: {kind: causal_oracle, params: {horizon, replan_every[, steps]}, iterations, episodes,
    seed_start[, beta0][, init: {path, obs_norm}]}`` (agents/training/oracle_distill.py): a fresh student (or the
    one ``init`` names, continued), no PPO teacher."""
    from ..training.oracle_distill import ORACLE_KIND, ORACLE_PARAM_KEYS, ORACLE_TEACHER_KEYS, init_files

    if t["kind"] != ORACLE_KIND:
        raise BenchmarkConfigError(f"{key}.kind = {t['kind']!r}: expected {ORACLE_KIND} (or no kind: PPO teachers)")
    extra = set(t) - ORACLE_TEACHER_KEYS
    if extra:
        raise BenchmarkConfigError(f"{key}: unknown key(s) {sorted(extra)}: expected {sorted(ORACLE_TEACHER_KEYS)}")
    _check_schedule(key, t)
    beta = t.get("beta0", 0.5)
    if isinstance(beta, bool) or not isinstance(beta, (int, float)) or not 0.0 <= beta <= 1.0:
        raise BenchmarkConfigError(f"{key}.beta0 = {beta!r}: expected a number in [0, 1] (the oracle's share "
                                   "of the acting corrections in iteration 0)")
    params = t.setdefault("params", {})
    if not isinstance(params, dict) or set(params) - ORACLE_PARAM_KEYS:
        raise BenchmarkConfigError(f"{key}.params = {str(params)[:80]!r}: expected a mapping of "
                                   f"{sorted(ORACLE_PARAM_KEYS)}")
    for name in ("horizon", "replan_every"):
        if name in params and not _int_in(params[name], 1, 144):
            raise BenchmarkConfigError(f"{key}.params.{name} = {params[name]!r}: expected an integer in [1, 144] "
                                       "(intervals)")
    steps = params.get("steps", [0.3])
    if not (isinstance(steps, list) and steps and all(isinstance(v, (int, float)) and not isinstance(v, bool)
                                                       and 0 < v <= 2 for v in steps)):
        raise BenchmarkConfigError(f"{key}.params.steps = {steps!r}: expected a list of numbers in (0, 2]")
    if not run.get("residual"):
        raise BenchmarkConfigError(f"{key}: expected a residual run (the label is the oracle's action as a "
                                   "correction of the run's residual base)")
    for seed in run["seeds"] if t.get("init") is not None else ():  # a warm start: every seed's student exists
        try:
            init_files(t["init"], seed)
        except ValueError as exc:
            raise BenchmarkConfigError(f"{key}.{str(exc).removeprefix('teacher.')}") from None
    _check_disjoint(key, run, t, held)
    if t.get("pool") is not None:
        _check_pool(key, run, t, held)


def _check_pool(key: str, run: dict[str, Any], t: dict[str, Any], held: set[int]) -> None:
    """``teacher.pool`` (agents/training/pooled_fit.py): its fields bounded, its pre-check episodes disjoint from
    tuning, validation and the DAgger episodes."""
    from ..training.pooled_fit import check_pool

    try:
        pool = check_pool(t["pool"], f"{key}.pool")
    except ValueError as exc:
        raise BenchmarkConfigError(str(exc)) from None
    pre = set(range(pool["precheck_seed_start"], pool["precheck_seed_start"] + pool["precheck_episodes"]))
    used = held | {s for seed in run["seeds"] for s in distill_seeds(t, seed)}
    if pre & used:
        raise BenchmarkConfigError(f"{key}.pool.precheck_seed_start = {pool['precheck_seed_start']!r}: its episodes "
                                   f"share seeds {sorted(pre & used)[:5]} with tuning, validation or the DAgger "
                                   "episodes: expected disjoint seeds")


def _check_schedule(key: str, t: dict[str, Any]) -> None:
    """A teacher's DAgger schedule (either kind): iterations x episodes from seed_start, within one seed stride."""
    from ..training.distill import SEED_STRIDE

    for name, lo, hi in (("iterations", 1, 20), ("episodes", 1, 500), ("seed_start", 0, 10**9)):
        if not _int_in(t.get(name), lo, hi):
            raise BenchmarkConfigError(f"{key}.{name} = {t.get(name)!r}: expected an integer in [{lo}, {hi}]")
    if t["iterations"] * t["episodes"] > SEED_STRIDE:
        raise BenchmarkConfigError(f"{key}: iterations x episodes = {t['iterations'] * t['episodes']}: expected "
                                   f"at most {SEED_STRIDE} (each student's episodes are seeds "
                                   f"seed_start + {SEED_STRIDE} x seed + 0, 1, ...)")


def _check_disjoint(key: str, run: dict[str, Any], t: dict[str, Any], held: set[int]) -> None:
    """The students' training episodes share no seed with tuning or validation."""
    used = {s for seed in run["seeds"] for s in distill_seeds(t, seed)}
    if used & held:
        raise BenchmarkConfigError(f"{key}.seed_start = {t['seed_start']!r}: its episodes share seeds "
                                   f"{sorted(used & held)[:5]} with tuning or validation: expected disjoint seeds")


def distill_seeds(teacher: dict[str, Any], seed: int) -> list[int]:
    """The training-split episodes one student's DAgger rolls out (agents/training/distill.py)."""
    from ..training.distill import SEED_STRIDE

    start = teacher["seed_start"] + SEED_STRIDE * seed
    return list(range(start, start + teacher["iterations"] * teacher["episodes"]))


def _resolve(path: str | Path) -> Path:
    """A training config named in a benchmark YAML: as given, else ``configs/...`` where srenv ships it
    (the checkout's ``configs/``, or the wheel's package data)."""
    p = Path(path)
    if p.is_absolute() or p.exists() or len(p.parts) < 3 or p.parts[0] != "configs":
        return p
    return shipped_dir(p.parts[1]).joinpath(*p.parts[2:])

