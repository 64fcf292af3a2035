"""``python -m agents benchmark CONFIG [--quick] [--out-dir DIR]``: tuned baselines vs PPO / SAC on unseen wells.

The protocol (one YAML under ``configs/benchmark/``; :func:`load_benchmark_config` checks it first):

1. **Tune** the baselines on the tuning episodes - ``reset(seed=S)`` on the TRAINING split for the
   config's tuning seeds (:mod:`agents.tuning`; the test split is refused): ``best_constant`` (grid over
   the whole action box + pattern search), then ``pump_off`` and ``fillage_pi`` (coordinate search);
   ``installed`` has nothing to tune; ``oracle`` is a perfect-model lookahead (its candidates include the
   tuned constant).
2. **Train** each algorithm (``agents.runs``: PPO, SAC) on every listed training seed from its training
   YAML (``configs/train/*_v1.yaml``) on the training split, runs in parallel over ``workers`` processes.
   Optionally score each model on validation episodes (training wells, seeds disjoint from tuning and test)
   to pick one seed (``agents.selection: best_on_validation``); the default, ``mean``, reports the
   per-episode reward averaged over all seeds' models: the training procedure, not a lucky seed.
3. **Test** every policy on the same test episodes: ``reset(seed=S)`` on ``scenario="test"`` for the test
   seeds (disjoint from every tuning and validation seed).
4. **Report**: ``OUT/benchmark.json`` (schema in :func:`build_report`), ``OUT/benchmark.md`` (tables,
   verdict, figure ``OUT/figures/benchmark_v1.png``), models in ``OUT/models/<algo>_v1*.zip`` with the
   observation normalisation as ``.npz``. Files are written atomically, nothing partial is left behind.

``--quick`` deep-merges the config's ``quick:`` block (tiny training, fewer episodes) and writes, by
default, to ``runs/benchmark_quick`` instead of ``docs``.
"""

from __future__ import annotations

import copy
import json
import math
import os
import platform
import shutil
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np
import yaml

from .baselines_v1 import BASELINE_NAMES, interval_s_of
from .rollout_v1 import ENV_ID_V1, ObsNormalizer, Runner, episode_jobs
from .tuning import Evaluator, TuningSet, coordinate_search, refuse_test_split, search_best_constant

REPO = Path(__file__).resolve().parent.parent
Z95 = 1.959963984540054


class BenchmarkConfigError(ValueError):
    """A benchmark YAML that cannot be used; the message names the key, the value and what is expected."""


# -------------------------------------------------------------------------------------------- config
_REPLACED = ("space", "runs")  # a quick block's search space / agent runs replace the full ones


def _deep_merge(base: dict, over: dict) -> dict:
    out = copy.deepcopy(base)
    for k, v in over.items():
        merge = isinstance(v, dict) and isinstance(out.get(k), dict) and k not in _REPLACED
        out[k] = _deep_merge(out[k], v) if merge else copy.deepcopy(v)
    return out


def _seeds(value: Any, key: str) -> list[int]:
    """A seed list: ``[1, 2, 3]`` or ``{start: S, count: N}``."""
    if isinstance(value, dict) and set(value) == {"start", "count"}:
        s, n = value["start"], value["count"]
        if isinstance(s, int) and isinstance(n, int) and s >= 0 and n > 0:
            return list(range(s, s + n))
    elif (isinstance(value, list) and value and all(isinstance(v, int) and v >= 0 for v in value)
          and len(set(value)) == len(value)):
        return list(value)
    raise BenchmarkConfigError(f"benchmark config: {key} = {value!r}: expected a list of distinct "
                               "non-negative integers or {start: S, count: N}")


def load_benchmark_config(path: str | Path, quick: bool = False) -> dict[str, Any]:
    """Read and check a benchmark YAML (``quick``: merge its ``quick:`` block); the resolved dict."""
    p = Path(path)
    if not p.is_file():
        raise FileNotFoundError(f"benchmark config {path}: no such file")
    with open(p, encoding="utf-8") as fh:
        raw = yaml.safe_load(fh)
    if not isinstance(raw, dict):
        raise BenchmarkConfigError(f"benchmark config {path}: expected a mapping")
    cfg = _deep_merge(raw, raw.get("quick") or {}) if quick else copy.deepcopy(raw)
    cfg.pop("quick", None)
    cfg["source"] = str(path)
    cfg.setdefault("env_id", ENV_ID_V1)
    cfg.setdefault("env_kwargs", {"observation": "field"})
    if "scenario" in cfg["env_kwargs"]:
        raise BenchmarkConfigError("benchmark config: env_kwargs.scenario: expected none (the protocol sets "
                                   "train for tuning/training and test for the evaluation)")
    w = cfg.setdefault("workers", 2)
    if not (isinstance(w, int) and w >= 1):
        raise BenchmarkConfigError(f"benchmark config: workers = {w!r}: expected a positive integer")
    for part in ("tuning", "test"):
        if not isinstance(cfg.get(part), dict) or "seeds" not in cfg[part]:
            raise BenchmarkConfigError(f"benchmark config: {part}: expected a mapping with seeds")
        cfg[part]["seeds"] = _seeds(cfg[part]["seeds"], f"{part}.seeds")
    cfg["tuning"].setdefault("scenario", "train")
    refuse_test_split(cfg["tuning"]["scenario"], "tune")
    val = cfg.setdefault("validation", {"seeds": []})
    val["seeds"] = _seeds(val["seeds"], "validation.seeds") if val.get("seeds") else []
    sets = {"tuning": set(cfg["tuning"]["seeds"]), "validation": set(val["seeds"]), "test": set(cfg["test"]["seeds"])}
    for a, b in (("tuning", "test"), ("validation", "test"), ("tuning", "validation")):
        if sets[a] & sets[b]:
            raise BenchmarkConfigError(f"benchmark config: {a}.seeds and {b}.seeds share "
                                       f"{sorted(sets[a] & sets[b])[:5]}: expected disjoint seed sets")
    bl = cfg.setdefault("baselines", {})
    for name in bl:
        if name not in BASELINE_NAMES:
            raise BenchmarkConfigError(f"benchmark config: baselines.{name}: expected one of {BASELINE_NAMES}")
    ag = cfg.setdefault("agents", {})
    sel = ag.setdefault("selection", "mean")
    if sel not in ("mean", "best_on_validation"):
        raise BenchmarkConfigError(f"benchmark config: agents.selection = {sel!r}: expected mean or "
                                   "best_on_validation")
    if sel == "best_on_validation" and not val["seeds"]:
        raise BenchmarkConfigError("benchmark config: agents.selection = best_on_validation needs "
                                   "validation.seeds")
    runs = ag.setdefault("runs", {})
    if not isinstance(runs, dict):
        raise BenchmarkConfigError(f"benchmark config: agents.runs = {runs!r}: expected a mapping algo -> run")
    from .train import load_train_config

    for algo, run in runs.items():
        if not isinstance(run, dict) or "config" not in run:
            raise BenchmarkConfigError(f"benchmark config: agents.runs.{algo}: expected {{config: YAML, seeds: [...]}}")
        run["config"] = str(_resolve(run["config"]))
        run["seeds"] = _seeds(run.get("seeds", [0, 1, 2]), f"agents.runs.{algo}.seeds")
        tc = load_train_config(run["config"])  # checks the YAML now, not after the tuning
        refuse_test_split(tc.env_kwargs.get("scenario", "train"), "train")
        res = run.get("residual")
        if res is not None and (not isinstance(res, dict) or res.get("base", "best_tuned") not in
                                ("best_tuned", "best_constant", "pump_off", "fillage_pi")):
            raise BenchmarkConfigError(f"benchmark config: agents.runs.{algo}.residual = {res!r}: expected "
                                       "{base: best_tuned | best_constant | pump_off | fillage_pi, scale: S}")
    return cfg


def _resolve(path: str | Path) -> Path:
    p = Path(path)
    return p if p.is_absolute() or p.exists() else REPO / p


# ---------------------------------------------------------------------------------------- statistics
def mean_ci(x: np.ndarray) -> tuple[float, float, float]:
    """Mean and its normal-approximation 95 % interval (the acceptance check's own formula)."""
    x = np.asarray(x, np.float64)
    m = float(x.mean())
    h = Z95 * float(x.std(ddof=1)) / math.sqrt(len(x)) if len(x) > 1 else math.nan
    return m, m - h, m + h


def iqm(x: np.ndarray) -> float:
    """Interquartile mean: the mean of the middle 50 % (rliable's IQM, scipy's trim_mean(x, 0.25))."""
    from scipy.stats import trim_mean

    return float(trim_mean(np.asarray(x, np.float64).ravel(), 0.25))


def _key(e: dict[str, Any]) -> tuple[str, int]:
    return str(e["well_id"]), int(e["seed"])


def _average_episodes(per_seed: list[list[dict[str, Any]]]) -> list[dict[str, Any]]:
    """Per test episode, the mean over the seeds' models of every numeric field."""
    out = []
    for rows in zip(*per_seed):
        assert len({_key(r) for r in rows}) == 1
        e = {"well_id": rows[0]["well_id"], "seed": rows[0]["seed"]}
        for k, v in rows[0].items():
            if k not in e and isinstance(v, (int, float)) and not isinstance(v, bool):
                e[k] = float(np.mean([r[k] for r in rows]))
        e["failure"] = next((r["failure"] for r in rows if r.get("failure")), None)
        out.append(e)
    return out


# ------------------------------------------------------------------------------------------ training
def train_job(job: dict[str, Any]) -> dict[str, Any]:
    """Worker entry: train one (algo, seed) run with :func:`agents.train.train`."""
    import torch

    from .train import load_train_config, train

    torch.set_num_threads(1)
    over = {"seed": job["seed"], **job.get("overrides", {})}
    cfg = load_train_config(job["config"], over)
    refuse_test_split(cfg.env_kwargs.get("scenario", "train"), "train")
    summary = train(cfg, job["out"], progress_bar=False,
                    log=lambda m: print(f"[{job['algo']} seed {job['seed']}] {m}", file=sys.stderr, flush=True))
    summary["seed"] = job["seed"]
    return summary


def export_model(summary: dict[str, Any], dest_zip: Path) -> dict[str, Any]:
    """Copy a trained model to ``dest_zip`` and its observation statistics to ``<stem>_obs_norm.npz``
    (plain arrays: the VecNormalize pickle, our own file from training, is read here and not shipped)."""
    import pickle

    dest_zip.parent.mkdir(parents=True, exist_ok=True)
    tmp = dest_zip.with_suffix(".zip.tmp")
    shutil.copyfile(summary["model"], tmp)
    os.replace(tmp, dest_zip)
    norm_path = None
    if summary.get("vecnormalize"):
        with open(summary["vecnormalize"], "rb") as fh:
            vn = pickle.load(fh)  # written by this benchmark's own training run
        if vn.norm_obs:
            norm_path = dest_zip.with_name(dest_zip.stem + "_obs_norm.npz")
            ObsNormalizer(vn.obs_rms.mean, vn.obs_rms.var, vn.clip_obs, vn.epsilon).save(str(norm_path))
    return {"kind": "agent", "path": str(dest_zip), "obs_norm": str(norm_path) if norm_path else None}


# -------------------------------------------------------------------------------------------- report
def machine() -> dict[str, Any]:
    import gymnasium
    import stable_baselines3
    import torch

    try:
        affinity = len(os.sched_getaffinity(0))
    except AttributeError:
        affinity = os.cpu_count()
    return {"node": platform.node(), "platform": platform.platform(), "processor": platform.processor(),
            "cpu_count": os.cpu_count(), "cpus_usable": affinity, "python": platform.python_version(),
            "torch": torch.__version__, "stable_baselines3": stable_baselines3.__version__,
            "gymnasium": gymnasium.__version__}


def build_report(cfg: dict[str, Any], policies: dict[str, dict[str, Any]], splits: dict[str, Any],
                 tuning: dict[str, Any], training: dict[str, Any], wall: dict[str, float]) -> dict[str, Any]:
    """The benchmark JSON. ``policies.NAME = {kind, params|models, episodes: [{well_id, seed, reward, cost,
    reward_*, cost_*, ...}]}``; ``tuning`` / ``validation`` / ``test`` = {scenario, well_ids, seeds};
    ``summary.NAME`` = mean return with 95 % CI, rate, cost, normalised score (0 = installed, 1 = oracle,
    ratio of mean returns); ``paired.AGENT.BASELINE`` = mean paired difference of returns with its 95 % CI
    over the test episodes; ``agents.ALGO`` = per-seed mean returns and the IQM over (seed, episode)."""
    keys = [_key(e) for e in policies["installed"]["episodes"]]
    ret = {n: np.array([{_key(e): e["reward"] for e in p["episodes"]}[k] for k in keys])
           for n, p in policies.items()}
    base = ret["installed"].mean()
    span = ret["oracle"].mean() - base if "oracle" in ret else math.nan
    summary = {}
    for n, p in policies.items():
        m, lo, hi = mean_ci(ret[n])
        eps = p["episodes"]
        summary[n] = {"kind": p["kind"], "mean_reward": m, "ci95_reward": [lo, hi],
                      "mean_reward_rate_usd_h": float(np.mean([e["reward_rate_usd_h"] for e in eps])),
                      "mean_cost": float(np.mean([e["cost"] for e in eps])),
                      "normalised_score": (m - base) / span if span and math.isfinite(span) else math.nan,
                      "failures": int(sum(bool(e.get("failure")) for e in eps))}
    agents = [n for n, p in policies.items() if p["kind"] == "agent"]
    paired: dict[str, dict[str, Any]] = {}
    for a in agents:
        paired[a] = {}
        for b, p in policies.items():
            if p["kind"] == "agent":
                continue
            m, lo, hi = mean_ci(ret[a] - ret[b])
            paired[a][b] = {"mean_diff_reward": m, "ci95": [lo, hi], "n_episodes": len(keys),
                            "significant_positive": bool(lo > 0), "relative_rate_gain": m / abs(ret[b].mean())
                            if ret[b].mean() else math.nan}
    return {
        "schema": "srenv benchmark v1",
        "config": cfg["source"],
        "env_id": cfg["env_id"], "env_kwargs": cfg["env_kwargs"],
        "units": {"reward": "episode return: sum over control intervals of the interval's reward rate, "
                            "USD per hour of well time", "reward_rate_usd_h": "return / intervals",
                  "cost": "sum over intervals of info['cost'] (constraint cost, >= 0)"},
        "policies": policies,
        **splits,
        "tuned": tuning,
        "training": training,
        "summary": summary,
        "paired": paired,
        "normalised_score": {n: s["normalised_score"] for n, s in summary.items()},
        "wall_time_s": wall,
        "machine": machine(),
    }


def _fmt(x: float, nd: int = 1) -> str:
    return "n/a" if x is None or not math.isfinite(x) else f"{x:,.{nd}f}"


def verdict(report: dict[str, Any]) -> str:
    """One line: the reward's scale and whether the best agent's lead over the best tuned baseline is real."""
    s, pol = report["summary"], report["policies"]
    steps = int(np.mean([e["steps"] for e in pol["installed"]["episodes"]]))
    agents = [n for n in s if s[n]["kind"] == "agent"]
    bases = [n for n in s if s[n]["kind"] != "agent" and n != "oracle"]
    best_b = max(bases, key=lambda n: s[n]["mean_reward"])
    scale = (f"reward = USD per hour of well time; an episode's return sums its {steps} intervals, so 1 USD/h "
             f"held all episode = {steps} return units")
    if not agents:
        return f"{scale}; no agent trained; best tuned baseline {best_b}."
    best_a = max(agents, key=lambda n: s[n]["mean_reward"])
    d = report["paired"][best_a][best_b]
    lo, hi = d["ci95"]
    beaten = [b for b in bases if report["paired"][best_a][b]["significant_positive"]]
    if lo > 0:
        call = "significant (95 % CI above zero)"
    elif hi < 0:
        call = "agent significantly WORSE (95 % CI below zero)"
    else:
        call = "within noise (95 % CI spans zero)"
    return (f"{scale}. Best agent {best_a} vs best tuned baseline {best_b}: {d['mean_diff_reward']:+.1f} "
            f"[{lo:+.1f}, {hi:+.1f}] per episode = {d['mean_diff_reward'] / steps:+.2f} USD/h, {call}; "
            f"it beats {len(beaten)}/{len(bases)} baselines significantly; normalised score "
            f"{_fmt(s[best_a]['normalised_score'], 2)} (0 installed, 1 oracle).")


def markdown_tables(report: dict[str, Any]) -> str:
    s = report["summary"]
    lines = ["| policy | kind | mean return (95 % CI) | USD/h | normalised score | mean cost | failures |",
             "|---|---|---|---|---|---|---|"]
    for n in sorted(s, key=lambda n: -s[n]["mean_reward"]):
        r = s[n]
        lines.append(f"| {n} | {r['kind']} | {_fmt(r['mean_reward'])} [{_fmt(r['ci95_reward'][0])}, "
                     f"{_fmt(r['ci95_reward'][1])}] | {_fmt(r['mean_reward_rate_usd_h'], 2)} | "
                     f"{_fmt(r['normalised_score'], 2)} | {_fmt(r['mean_cost'], 3)} | {r['failures']} |")
    if report["paired"]:
        lines += ["", "Paired differences of returns on the same test episodes (agent - baseline, 95 % CI):", "",
                  "| agent | " + " | ".join(next(iter(report["paired"].values()))) + " |",
                  "|---" * (1 + len(next(iter(report["paired"].values())))) + "|"]
        for a, row in report["paired"].items():
            cells = [f"{_fmt(d['mean_diff_reward'])} [{_fmt(d['ci95'][0])}, {_fmt(d['ci95'][1])}]"
                     + (" *" if d["significant_positive"] else "") for d in row.values()]
            lines.append(f"| {a} | " + " | ".join(cells) + " |")
        lines.append("")
        lines.append("`*`: the 95 % CI is above zero.")
    return "\n".join(lines)


def write_markdown(report: dict[str, Any], path: Path, figure: str | None) -> None:
    tuned = report["tuned"]
    tr = report["training"]
    w = report["wall_time_s"]
    m = report["machine"]
    parts = [
        "# Benchmark: tuned baselines vs learned controllers on unseen wells (srenv/SuckerRod-v1)",
        "",
        f"Generated by `python -m agents benchmark {report['config']}`"
        + (" --quick" if report.get("quick") else "") + f"; wall time {w['total']:.0f} s on "
        f"{m['cpus_usable']} usable cores ({m['node']}). Data: `benchmark.json` next to this file.",
        "",
        (f"- Test: {len(report['test']['seeds'])} episodes, `reset(seed=S)` on `scenario=\"test\"`, S = "
        f"{_seed_text(report['test']['seeds'])}; {len(set(report['test']['well_ids']))} test wells."),
        (f"- Tuning (baselines): {len(report['tuning']['seeds'])} episodes on training wells, seeds "
        f"{_seed_text(report['tuning']['seeds'])}. Validation (agent seed choice, if used): "
        f"{_seed_text(report['validation']['seeds']) or 'none'}."),
        (f"- Agents: {_runs_text(tr)}; "
        f"reported as: {tr.get('selection', 'n/a')}."),
        "",
        "## Result",
        "",
        verdict(report),
        "",
        markdown_tables(report),
        "",
    ]
    if figure:
        parts += [f"![benchmark]({figure})", ""]
    parts += behaviour_table(report)
    parts += [PROTOCOL, "", "## Tuned baselines (training wells only)", ""]
    for n, t in tuned.items():
        parts.append(f"- `{n}`: {json.dumps(t.get('params'))}" + (f" (tuning score {t['score']:.1f})"
                                                                  if "score" in t else ""))
    if tr.get("runs"):
        parts += ["", "## Agents: per training seed", "",
                  "| algo | seed | mean test return | validation return | steps | train wall (s) |",
                  "|---|---|---|---|---|---|"]
        for a, info in tr["runs"].items():
            for r in info["per_seed"]:
                parts.append(f"| {a} | {r['seed']} | {_fmt(r['mean_test_reward'])} | "
                             f"{_fmt(r.get('validation_reward', math.nan))} | {r['num_timesteps']} | "
                             f"{r['wall_time_s']:.0f} |")
            parts.append(f"| {a} | IQM over (seed, episode) | {_fmt(info['iqm_test_reward'])} | | | |")
    parts += ["", "Wall time (s): " + ", ".join(f"{k} {v:.0f}" for k, v in w.items()), ""]
    _atomic_write(path, "\n".join(parts))


PROTOCOL = """## Protocol

- **Episodes.** An episode is `reset(seed=S)` on a split: it draws well `S % n_wells` of that split and the
  episode's inflow schedule from the seed. Every policy runs the very same test episodes
  (`scenario="test"`, wells no tuning or training touched; the tuning code refuses that split), with
  deterministic actions, so policies are compared by **paired** differences per episode.
- **Reward.** Each control interval's reward is a rate in USD per hour of well time (revenue of the oil
  lifted, the value of the change of liquid stored in the annulus, minus energy, rod fatigue, stick-slip,
  peak-load, fluid-pound and VSD-ramp costs: `info["reward_*"]`); the episode return is their sum over
  the intervals. The constraint cost `info["cost"]` is summed the same way and reported beside it.
- **Baselines, field observation only** (`agents/baselines_v1.py`), parametrised in action coordinates
  (fractions of each well's speed and stroke range), tuned on the training wells by `agents/tuning.py`:
  `installed` - the well's configured SPM and stroke, constant; `best_constant` - one action for all
  wells, from a grid over the whole action box plus a pattern search; `pump_off` - pump at a set point
  until the card's fillage estimate falls below a threshold, idle a set time, restart (threshold, idle
  time, pumping speed and stroke tuned by coordinate search); `fillage_pi` - VSD speed PI on the
  fillage estimate, output over the whole speed range so it can go intermittent below the VSD minimum
  (set-point, gains, stroke tuned).
- **Oracle.** A perfect-model planner (`OraclePolicy`, mode `plan`): at the episode's start it
  deep-copies the true environment - the hidden well, its annulus state, the inflow schedule and the
  random stream - and simulates whole episodes on copies: every constant action of a grid over the
  whole box, then a piecewise-constant schedule (a few segments of the horizon, so it can follow the
  inflow step) refined by coordinate search, and the closed-loop trajectories of the tuned `installed`,
  `pump_off` and `fillage_pi`. It plays the best, open loop; the model is exact, so it gets what it
  planned. It is a *fair top of the score*: it knows everything a field controller cannot (level,
  inflow schedule, parameters), is at least as good as every constant of its grid and every field
  baseline on every episode by construction, and its compute is bounded and stated (model steps per
  episode in the JSON, `model_steps`). It is not a proven optimum (a schedule of a few segments, local
  search): a learned closed-loop policy may exceed 1.
- **Normalised score** = (mean return - installed) / (oracle - installed) on the test episodes.
- **Agents** (PPO, SAC from Stable-Baselines3, `configs/train/*_v1.yaml`) train on the training split
  only, from several seeds. Unless the run says otherwise, an agent's test episode reward is the mean
  over its seeds' models (the training procedure, not a lucky seed); the shipped single model
  `models/<name>_v1.zip` is the seed best on the validation episodes (training wells). A `*_residual`
  agent acts as `clip(b + scale * r)`: the tuned baseline's action `b` plus the network's learned
  correction `r` (residual policy learning; it sees `b`), trained the same way.
- **Statistics.** Mean return with a normal 95 % interval; paired differences with their 95 %
  interval over the test episodes (`*` = above zero); the IQM over (training seed, episode)."""


_BEHAVIOUR = (("mean_avg_spm", "avg SPM", 2), ("mean_duty", "duty (-)", 2), ("mean_stroke_length_m", "stroke (m)", 2),
              ("mean_production_m3_day", "liquid (m3/day)", 1), ("mean_fluid_level_m", "level (m)", 0),
              ("mean_fillage", "fillage (true)", 2), ("mean_fillage_est", "fillage_est (card)", 2),
              ("reward_revenue", "revenue", 0), ("reward_stick_slip", "stick-slip", 0), ("reward_pound", "pound", 0),
              ("reward_energy", "energy", 0), ("reward_ramp", "ramp", 0))


def behaviour_table(report: dict[str, Any]) -> list[str]:
    """How each policy runs the test wells: means over the test episodes (interval means, return terms)."""
    s, pol = report["summary"], report["policies"]
    lines = ["## What the policies do on the test wells", "",
             ("Means over the test episodes: operating point (interval means) and the main reward terms "
              "(episode sums, same units as the return)."), "",
             "| policy | " + " | ".join(h for _, h, _ in _BEHAVIOUR) + " |", "|---" * (len(_BEHAVIOUR) + 1) + "|"]
    for n in sorted(s, key=lambda n: -s[n]["mean_reward"]):
        eps = pol[n]["episodes"]
        cells = [_fmt(float(np.mean([e.get(k, math.nan) for e in eps])), nd) for k, _, nd in _BEHAVIOUR]
        lines.append(f"| {n} | " + " | ".join(cells) + " |")
    gap = _fillage_gap(pol)
    if gap is not None:
        lines += ["", f"The field baselines act on `fillage_est`, the controller's estimate from the surface card; "
                  f"over all policies' test episodes it differs from the true pump fillage by {gap:.2f} on average "
                  "(episode means)" + (": where it stays near 1 while the pump is pounding, pump-off control and the "
                                       "fillage PI cannot see the pump-off, while an agent reading the whole card can."
                                       if gap > 0.1 else ".")]
    return [*lines, ""]


def _fillage_gap(policies: dict[str, Any]) -> float | None:
    d = [abs(e["mean_fillage"] - e["mean_fillage_est"]) for p in policies.values() for e in p["episodes"]
         if "mean_fillage" in e and "mean_fillage_est" in e]
    return float(np.mean(d)) if d else None


def rerender(out_dir: str | Path) -> None:
    """Rewrite ``OUT/benchmark.md`` from ``OUT/benchmark.json`` (no simulation; the figure is kept)."""
    out = Path(out_dir)
    report = json.loads((out / "benchmark.json").read_text())
    write_markdown(report, out / "benchmark.md", "figures/benchmark_v1.png")


def _runs_text(training: dict[str, Any]) -> str:
    runs = training.get("runs", {})
    return ", ".join(f"{a} seeds {v['seeds']}" for a, v in runs.items()) or "none"


def _seed_text(seeds: list[int]) -> str:
    if not seeds:
        return ""
    if seeds == list(range(seeds[0], seeds[0] + len(seeds))):
        return f"{seeds[0]}..{seeds[-1]}"
    return ", ".join(map(str, seeds))


def _atomic_write(path: Path, text: str) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    with os.fdopen(fd, "w", encoding="utf-8") as fh:
        fh.write(text)
    os.replace(tmp, path)


def _json_clean(v: Any) -> Any:
    if isinstance(v, dict):
        return {str(k): _json_clean(w) for k, w in v.items()}
    if isinstance(v, (list, tuple)):
        return [_json_clean(w) for w in v]
    if isinstance(v, (np.floating, float)):
        return float(v) if math.isfinite(float(v)) else None
    if isinstance(v, np.integer):
        return int(v)
    if isinstance(v, np.bool_):
        return bool(v)
    return v


def figure(report: dict[str, Any], traces: dict[str, dict[str, Any]], path: Path) -> None:
    """Top: mean return with its 95 % CI per policy. Below: on one test episode, the best agent beside
    the best tuned baseline - average SPM and duty over time, fluid level, and three surface cards."""
    import matplotlib

    matplotlib.use("Agg", force=False)
    from matplotlib.figure import Figure

    s = report["summary"]
    names = sorted(s, key=lambda n: s[n]["mean_reward"])
    shown = list(traces)
    fig = Figure(figsize=(12, 4 + 3.2 * 2), dpi=100)
    gs = fig.add_gridspec(3, max(2, len(shown)), height_ratios=[1.1, 1, 1])
    ax = fig.add_subplot(gs[0, :])
    y = np.arange(len(names))
    means = np.array([s[n]["mean_reward"] for n in names])
    lo = np.array([s[n]["ci95_reward"][0] for n in names])
    hi = np.array([s[n]["ci95_reward"][1] for n in names])
    colors = ["tab:orange" if s[n]["kind"] == "agent" else "tab:gray" for n in names]
    ax.barh(y, means, xerr=np.nan_to_num(np.vstack([means - lo, hi - means])), color=colors, capsize=3)
    ax.set_yticks(y, [f"{n}  (score {_fmt(s[n]['normalised_score'], 2)})" for n in names])
    ax.set_xlabel("mean episode return on the test episodes (sum of interval rates, USD/h), 95 % CI")
    ax.grid(alpha=0.3, axis="x")
    for col, (label, tr) in enumerate(traces.items()):
        t = tr["trace"]
        hours = np.arange(1, len(t["avg_spm"]) + 1) * tr["interval_s"] / 3600
        a1 = fig.add_subplot(gs[1, col])
        a1.step(hours, t["avg_spm"], where="pre", color="tab:blue", label="average SPM")
        a1.set(title=f"{label} on {tr['well_id']} (seed {tr['seed']}): return {tr['reward']:.0f}",
               xlabel="time (h)", ylabel="average SPM")
        tw = a1.twinx()
        tw.step(hours, t["duty"], where="pre", color="tab:orange", label="duty (-)", alpha=0.8)
        tw.plot(hours, np.asarray(t["fillage_est"]), color="tab:green", lw=0.8, label="fillage_est (-)")
        tw.set(ylim=(-0.05, 1.1), ylabel="duty, fillage estimate (-)")
        h1, l1 = a1.get_legend_handles_labels()
        h2, l2 = tw.get_legend_handles_labels()
        a1.legend(h1 + h2, l1 + l2, fontsize=7, loc="lower left")
        a1.grid(alpha=0.3)
        a2 = fig.add_subplot(gs[2, col])
        cards = np.asarray(t["card"])
        duty = np.asarray(t["duty"])
        pumped = np.flatnonzero(duty > 0)
        picks = sorted({int(pumped[0]), int(pumped[len(pumped) // 2]), int(pumped[-1])}) if len(pumped) else []
        for i in picks:
            c = cards[i]
            x = np.linspace(0, 1, len(c) // 2) * t["stroke_length_m"][i]
            a2.plot(np.r_[x, x[::-1]], np.r_[c[: len(c) // 2], c[len(c) // 2:][::-1]], lw=1,
                    label=f"t = {hours[i]:.1f} h")
        a2.set(xlabel="polished-rod position (m)", ylabel="load / PPRL rating (-)", title="surface cards")
        a2.legend(fontsize=7)
        a2.grid(alpha=0.3)
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(f".{path.name}.tmp.png")
    fig.savefig(tmp)
    os.replace(tmp, path)


# -------------------------------------------------------------------------------------------- driver
class _Progress:
    """A tqdm bar on stderr for one phase (plain lines when stderr is not a terminal)."""

    def __init__(self, total: int, desc: str) -> None:
        from tqdm import tqdm

        self.bar = tqdm(total=total, desc=desc, file=sys.stderr, dynamic_ncols=True,
                        mininterval=0.5 if sys.stderr.isatty() else 30.0)

    def __call__(self, n: int) -> None:
        self.bar.update(n)

    def close(self) -> None:
        self.bar.close()


def tune_baselines(cfg: dict[str, Any], runner: Runner, log: Any) -> tuple[dict[str, Any], dict[str, Any]]:
    """Tuned parameters of every baseline and the tuning episodes' well ids."""
    bl = cfg["baselines"]
    tset = TuningSet(cfg["tuning"]["seeds"], cfg["tuning"]["scenario"], cfg["env_id"], cfg["env_kwargs"])
    ev = Evaluator(tset, runner)
    tuned: dict[str, Any] = {"installed": {"params": {}}}
    bc = bl.get("best_constant", {})
    n_eps = len(tset.seeds)
    n_cand = (bc.get("n_spm", 9) * bc.get("n_stroke", 5) + 4 * bc.get("refine_iters", 6)
              + sum(len(v) * bl.get(b, {}).get("rounds", 2) for b in ("pump_off", "fillage_pi")
                    for v in bl.get(b, {}).get("space", {}).values()))
    bar = _Progress(n_cand * n_eps, "tuning")
    ev.progress = bar
    t0 = time.perf_counter()
    tuned["best_constant"] = search_best_constant(ev, bc.get("n_spm", 9), bc.get("n_stroke", 5),
                                                  bc.get("refine_iters", 6), bc.get("refine_step"))
    best_a = tuned["best_constant"]["params"]
    for name in ("pump_off", "fillage_pi"):
        spec = bl.get(name, {})
        init = {k: (best_a["a_spm" if k == "a_spm" else "a_stroke"] if v == "best_constant" else v)
                for k, v in spec.get("init", {}).items()}
        tuned[name] = coordinate_search(ev, name, init, spec.get("space", {}), spec.get("rounds", 2))
    bar.close()
    oc = dict(bl.get("oracle", {}))
    anchors = [[best_a["a_spm"], best_a["a_stroke"]]] if oc.pop("anchor_best_constant", True) else []
    # the planner also simulates the tuned field baselines' own trajectories: it is at least as good as
    # each of them on every episode, by construction
    given = [[n, tuned[n]["params"]] for n in ("installed", "pump_off", "fillage_pi")] \
        if oc.pop("include_baselines", True) else []
    tuned["oracle"] = {"params": {**oc, "anchors": anchors, "policies": given}}
    wells = sorted(set(_well_ids(tset)))
    log(f"tuning: {ev.episodes_run} episodes in {time.perf_counter() - t0:.0f} s; " + "; ".join(
        f"{n} {json.dumps(t['params'])}" for n, t in tuned.items() if n != "installed"))
    return tuned, {"scenario": tset.scenario, "seeds": tset.seeds, "well_ids": wells}


def _well_ids(tset: TuningSet) -> list[str]:
    """The well drawn by each tuning seed (a zero-length look: reset only, in this process)."""
    from .rollout_v1 import make_env

    env = make_env(tset.env_id, **tset.kwargs)
    try:
        return [str(env.reset(seed=s)[1]["well_id"]) for s in tset.seeds]
    finally:
        env.close()


def run_benchmark(cfg: dict[str, Any], out_dir: str | Path, quick: bool = False,
                  log: Any = None) -> dict[str, Any]:
    log = log or (lambda m: print(m, file=sys.stderr, flush=True))
    out = Path(out_dir)
    t_start = time.perf_counter()
    wall: dict[str, float] = {}
    env_id, env_kwargs = cfg["env_id"], cfg["env_kwargs"]
    test_kwargs = {**env_kwargs, "scenario": "test"}
    train_kwargs = {**env_kwargs, "scenario": "train"}
    workdir = Path(tempfile.mkdtemp(prefix="benchmark_runs_", dir=cfg.get("work_dir") or None))
    try:
        with Runner(cfg["workers"]) as runner:
            tuned, tuning_split = tune_baselines(cfg, runner, log)
            wall["tuning"] = time.perf_counter() - t_start

            # ---- agents: train every (algo, seed), then export
            t1 = time.perf_counter()
            runs = cfg["agents"]["runs"]
            residuals = {a: residual_spec(r, tuned) for a, r in runs.items()}
            jobs = [{"algo": a, "seed": s, "config": r["config"], "out": str(workdir / f"{a}_seed{s}"),
                     "overrides": {**r.get("overrides", {}), **residual_overrides(residuals[a], r, cfg)}}
                    for a, r in runs.items() for s in r["seeds"]]
            bar = _Progress(len(jobs), "training")
            summaries = runner.map(jobs, progress=bar, fn=train_job) if jobs else []
            bar.close()
            models_dir = out / "models"
            agent_specs: dict[str, list[dict[str, Any]]] = {}
            for job, summ in zip(jobs, summaries):
                spec = export_model(summ, models_dir / f"{job['algo']}_v1_seed{job['seed']}.zip")
                if residuals[job["algo"]]:
                    spec["residual"] = residuals[job["algo"]]
                spec["train_summary"] = {k: summ[k] for k in ("num_timesteps", "wall_time_s", "seed",
                                                              "best_eval_mean_reward")}
                agent_specs.setdefault(job["algo"], []).append(spec)
            wall["training"] = time.perf_counter() - t1

            # ---- validation (training wells) for the seed choice
            t2 = time.perf_counter()
            val_seeds = cfg["validation"]["seeds"]
            val_scores: dict[str, list[float]] = {}
            val_wells: list[str] = []
            if val_seeds and agent_specs:
                vjobs = [j for a, specs in agent_specs.items() for sp in specs
                         for j in episode_jobs(env_id, train_kwargs, _policy_part(sp), val_seeds)]
                bar = _Progress(len(vjobs), "validation")
                recs = runner.map(vjobs, progress=bar)
                bar.close()
                val_wells = sorted({r["well_id"] for r in recs})
                i = 0
                for a, specs in agent_specs.items():
                    val_scores[a] = []
                    for _ in specs:
                        val_scores[a].append(float(np.mean([r["reward"] for r in recs[i:i + len(val_seeds)]])))
                        i += len(val_seeds)
            wall["validation"] = time.perf_counter() - t2

            # ---- test: every policy on the same episodes
            t3 = time.perf_counter()
            test_seeds = cfg["test"]["seeds"]
            fig_seed = test_seeds[int(cfg.get("figure_episode", 0)) % len(test_seeds)]
            entries: list[tuple[str, int, dict[str, Any]]] = [
                (n, -1, {"kind": "baseline", "name": n, "params": tuned[n]["params"]}) for n in BASELINE_NAMES]
            for a, specs in agent_specs.items():
                entries += [(a, k, _policy_part(sp)) for k, sp in enumerate(specs)]
            tjobs = []
            for n, k, sp in entries:
                for j in episode_jobs(env_id, test_kwargs, sp, test_seeds):
                    j["trace"] = j["seed"] == fig_seed
                    tjobs.append(j)
            # the oracle is the slow one: start it first so the two workers finish together
            order = sorted(range(len(tjobs)), key=lambda i: tjobs[i]["policy"].get("name") != "oracle")
            bar = _Progress(len(tjobs), "test")
            done = runner.map([tjobs[i] for i in order], progress=bar)
            bar.close()
            recs = [None] * len(tjobs)
            for i, r in zip(order, done):
                recs[i] = r
            wall["test"] = time.perf_counter() - t3
    finally:
        shutil.rmtree(workdir, ignore_errors=True)

    # ---- assemble
    n_t = len(test_seeds)
    by_entry = {}
    for e_i, (n, k, _) in enumerate(entries):
        by_entry[(n, k)] = recs[e_i * n_t:(e_i + 1) * n_t]
    traces: dict[str, dict[str, Any]] = {}
    policies: dict[str, dict[str, Any]] = {}
    for n in BASELINE_NAMES:
        eps = by_entry[(n, -1)]
        policies[n] = {"kind": "baseline", "params": tuned[n]["params"], "episodes": eps}
    training: dict[str, Any] = {"selection": cfg["agents"]["selection"], "runs": {}}
    for a, specs in agent_specs.items():
        per_seed = [by_entry[(a, k)] for k in range(len(specs))]
        seed_means = [float(np.mean([e["reward"] for e in eps])) for eps in per_seed]
        if cfg["agents"]["selection"] == "best_on_validation":
            pick = int(np.argmax(val_scores[a]))
            eps, how = per_seed[pick], f"best_on_validation: seed {specs[pick]['train_summary']['seed']}"
        else:
            pick = int(np.argmax(val_scores[a])) if val_scores.get(a) else 0
            eps, how = _average_episodes(per_seed), "mean over training seeds' models, per test episode"
        # the shipped single model: the validation pick (training wells), else seed 0
        shipped = out / "models" / f"{a}_v1.zip"
        shutil.copyfile(specs[pick]["path"], shipped)
        if specs[pick].get("obs_norm"):
            shutil.copyfile(specs[pick]["obs_norm"], shipped.with_name(f"{a}_v1_obs_norm.npz"))
        policies[a] = {"kind": "agent", "algo": _algo_of(runs[a]), "selection": how,
                       "residual_on": specs[0].get("residual"),
                       "models": [_rel(sp["path"], out) for sp in specs], "episodes": eps}
        training["runs"][a] = {
            "config": runs[a]["config"], "seeds": runs[a]["seeds"], "shipped_model": _rel(str(shipped), out),
            "shipped_seed": specs[pick]["train_summary"]["seed"],
            "iqm_test_reward": iqm([e["reward"] for ep in per_seed for e in ep]),
            "per_seed": [{"seed": sp["train_summary"]["seed"], "mean_test_reward": m,
                          "validation_reward": val_scores[a][k] if val_scores.get(a) else None,
                          "num_timesteps": sp["train_summary"]["num_timesteps"],
                          "wall_time_s": sp["train_summary"]["wall_time_s"],
                          "episodes": [{"well_id": e["well_id"], "seed": e["seed"], "reward": e["reward"],
                                        "cost": e["cost"]} for e in per_seed[k]]}
                         for k, (sp, m) in enumerate(zip(specs, seed_means))]}
    # traces for the figure: best agent (the shipped model) and best tuned baseline
    bases = [n for n in BASELINE_NAMES if n != "oracle"]
    best_b = max(bases, key=lambda n: np.mean([e["reward"] for e in policies[n]["episodes"]]))
    shown = []
    if agent_specs:
        best_a = max(agent_specs, key=lambda a: np.mean([e["reward"] for e in policies[a]["episodes"]]))
        shown.append((best_a, (best_a, int(np.argmax(val_scores[best_a])) if val_scores.get(best_a) else 0)))
    shown.append((best_b, (best_b, -1)))
    interval_s = _interval_s(env_id, test_kwargs, fig_seed)
    for label, key in shown:
        rec = next(e for e in by_entry[key] if e["seed"] == fig_seed)
        traces[label] = {**{k: rec[k] for k in ("well_id", "seed", "reward")}, "trace": rec["trace"],
                         "interval_s": interval_s}
    for r in by_entry.values():
        for e in r:
            e.pop("trace", None)
    for p in policies.values():
        for e in p["episodes"]:
            e.pop("trace", None)
    splits = {"tuning": tuning_split,
              "validation": {"scenario": "train", "seeds": val_seeds, "well_ids": val_wells},
              "test": {"scenario": "test", "seeds": test_seeds,
                       "well_ids": sorted({e["well_id"] for e in policies["installed"]["episodes"]})}}
    wall["total"] = time.perf_counter() - t_start
    report = build_report(cfg, policies, splits, {n: {k: v for k, v in t.items() if k != "evaluated"}
                                                   for n, t in tuned.items()}, training, wall)
    report["quick"] = quick
    report["tuning_history"] = {n: t.get("evaluated", []) for n, t in tuned.items()}
    fig_rel = "figures/benchmark_v1.png"
    figure(report, traces, out / fig_rel)
    report = _json_clean(report)
    _atomic_write(out / "benchmark.json", json.dumps(report, indent=1))
    write_markdown(report, out / "benchmark.md", fig_rel)
    return report


def _algo_of(run: dict[str, Any]) -> str:
    from .train import load_train_config

    return load_train_config(run["config"]).algo


def _policy_part(spec: dict[str, Any]) -> dict[str, Any]:
    return {k: spec[k] for k in ("kind", "path", "obs_norm", "residual") if k in spec}


def residual_spec(run: dict[str, Any], tuned: dict[str, Any]) -> dict[str, Any] | None:
    """``{base, params, scale}`` of a residual agent run (``residual: {base: NAME | best_tuned, scale}``):
    the base is a tuned field baseline; ``best_tuned`` = the best tuning score (training wells)."""
    res = run.get("residual")
    if not res:
        return None
    base = res.get("base", "best_tuned")
    if base == "best_tuned":
        base = max(("best_constant", "pump_off", "fillage_pi"), key=lambda n: tuned[n]["score"])
    if base not in ("best_constant", "pump_off", "fillage_pi"):
        raise BenchmarkConfigError(f"residual base = {base!r}: expected best_constant, pump_off, fillage_pi "
                                   "or best_tuned")
    return {"base": base, "params": tuned[base]["params"], "scale": float(res.get("scale", 0.3))}


def residual_overrides(res: dict[str, Any] | None, run: dict[str, Any], cfg: dict[str, Any]) -> dict[str, Any]:
    """Training-YAML overrides that put a residual run on :class:`agents.residual_v1.ResidualEnv`."""
    if not res:
        return {}
    from .residual_v1 import ENV_ID
    from .train import load_train_config

    tc = load_train_config(run["config"])
    return {"env_id": f"agents.residual_v1:{ENV_ID}",
            "env_kwargs": {**tc.env_kwargs, "inner_env_id": tc.env_id, "base": res["base"],
                           "base_params": res["params"], "scale": res["scale"]}}


def _rel(path: str, root: Path) -> str:
    try:
        return str(Path(path).resolve().relative_to(root.resolve()))
    except ValueError:
        return str(path)


def _interval_s(env_id: str, kwargs: dict[str, Any], seed: int) -> float:
    from .rollout_v1 import make_env

    env = make_env(env_id, **kwargs)
    try:
        env.reset(seed=seed)
        return interval_s_of(env)
    finally:
        env.close()


def summary_line(report: dict[str, Any]) -> dict[str, Any]:
    """The CLI's one-line JSON: where the files are, the verdict's numbers."""
    s = report["summary"]
    return {"policies": {n: {"mean_reward": r["mean_reward"], "normalised_score": r["normalised_score"],
                             "mean_cost": r["mean_cost"]} for n, r in s.items()},
            "test_episodes": len(report["test"]["seeds"]), "wall_time_s": report["wall_time_s"]["total"]}


def benchmark_main(config: str, quick: bool = False, out_dir: str | None = None) -> dict[str, Any]:
    """``python -m agents benchmark``: the whole protocol; prints the table and returns the JSON summary."""
    cfg = load_benchmark_config(config, quick=quick)
    out = Path(out_dir or ("runs/benchmark_quick" if quick else "docs"))
    report = run_benchmark(cfg, out, quick=quick)
    print(markdown_tables(report), flush=True)
    print(verdict(report), flush=True)
    print(f"benchmark: wall time {report['wall_time_s']['total']:.0f} s; wrote {out / 'benchmark.json'}, "
          f"{out / 'benchmark.md'}", file=sys.stderr, flush=True)
    return {"benchmark_json": str(out / "benchmark.json"), "markdown": str(out / "benchmark.md"),
            **summary_line(report)}


def quickstart(config: str, out_dir: str, total_timesteps: int | None = None, episodes: int | None = None,
               first_seed: int | None = None) -> dict[str, Any]:
    """``python -m agents quickstart``: the benchmark on a small scale, its table and a one-line verdict on
    stdout; the long JSON goes to ``OUT/benchmark.json``."""
    cfg = load_benchmark_config(config, quick=False)
    if total_timesteps:
        for run in cfg["agents"]["runs"].values():
            run.setdefault("overrides", {})["n_timesteps"] = int(total_timesteps)
    if episodes or first_seed is not None:
        seeds = cfg["test"]["seeds"]
        start = seeds[0] if first_seed is None else first_seed
        cfg["test"]["seeds"] = list(range(start, start + (episodes or len(seeds))))
        clash = set(cfg["test"]["seeds"]) & (set(cfg["tuning"]["seeds"]) | set(cfg["validation"]["seeds"]))
        if clash:
            raise BenchmarkConfigError(f"quickstart: --seed/--episodes = test seeds {sorted(clash)[:5]} ...: "
                                       "expected seeds disjoint from the tuning and validation seeds")
    print(f"quickstart: tuning the baselines, training {', '.join(cfg['agents']['runs']) or 'no agents'}, "
          f"testing on {len(cfg['test']['seeds'])} unseen wells' episodes -> {out_dir}", file=sys.stderr)
    report = run_benchmark(cfg, Path(out_dir), quick=True)
    print(markdown_tables(report), flush=True)
    print(verdict(report), flush=True)
    return {"benchmark_json": str(Path(out_dir) / "benchmark.json"),
            "markdown": str(Path(out_dir) / "benchmark.md"), **summary_line(report)}
