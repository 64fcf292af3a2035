"""The benchmark's statistics and outputs: the JSON report, the markdown page, the figure.

Paired statistics over the same test episodes: mean with a normal 95 % interval (the acceptance check's own
formula), paired differences agent - baseline, the IQM over (training seed, episode), the normalised score
(0 = installed, 1 = oracle). Files are written atomically.
"""

from __future__ import annotations

import json
import math
import os
import platform
from pathlib import Path
from typing import Any

import numpy as np

Z95 = 1.959963984540054


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


# -------------------------------------------------------------------------------------------- report
def paired_table(policies: dict[str, dict[str, Any]]) -> dict[str, dict[str, Any]]:
    """``AGENT -> BASELINE ->`` the mean paired difference of returns over the test episodes and its 95 % CI.

    When a test well has several episodes they are not independent draws, so the interval over the per-well
    means (each well counted once) is added, and it is the one ``significant_positive`` is judged on."""
    keys = [_key(e) for e in policies["installed"]["episodes"]]
    ret = {n: np.array([{_key(e): e["reward"] for e in p["episodes"]}[k] for k in keys])
           for n, p in policies.items()}
    wells: dict[str, list[int]] = {}
    for i, (w, _) in enumerate(keys):
        wells.setdefault(w, []).append(i)
    paired: dict[str, dict[str, Any]] = {}
    for a in [n for n, p in policies.items() if p["kind"] == "agent"]:
        paired[a] = {}
        for b, p in policies.items():
            if p["kind"] == "agent":
                continue
            d = ret[a] - ret[b]
            m, lo, hi = mean_ci(d)
            row = {"mean_diff_reward": m, "ci95": [lo, hi], "n_episodes": len(keys),
                   "relative_rate_gain": m / abs(ret[b].mean()) if ret[b].mean() else math.nan}
            if len(wells) < len(keys):
                _, wlo, whi = mean_ci(np.array([d[idx].mean() for idx in wells.values()]))
                row.update({"ci95_by_well": [wlo, whi], "n_wells": len(wells)})
            row["significant_positive"] = bool(judged_ci(row)[0] > 0)
            paired[a][b] = row
    return paired


def judged_ci(row: dict[str, Any]) -> list[float]:
    """The interval a paired row is judged on: over the per-well means when wells repeat, else over episodes."""
    return row.get("ci95_by_well", row["ci95"])


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
    """The benchmark JSON. ``policies.NAME = {kind, params|models (+ sha256: each member file's digest,
    agents.evaluation.model_pins), episodes: [{well_id, seed, reward, cost, reward_*, cost_*, ...}]}``; ``tuning`` / ``validation`` / ``test`` = {scenario, well_ids, seeds};
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
    paired = paired_table(policies)
    return {
        "schema": "srenv benchmark v1",
        "config": cfg["source"],
        "history": [str(h) for h in cfg.get("history") or []],  # earlier test evaluations, as the config lists them
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


def contenders(summary: dict[str, Any]) -> tuple[list[str], list[str]]:
    """(agents, tuned baselines) of a report's summary: the oracles are references, not baselines."""
    return ([n for n in summary if summary[n]["kind"] == "agent"],
            [n for n in summary if summary[n]["kind"] != "agent" and n not in ("oracle", "causal_oracle")])


def verdict(report: dict[str, Any]) -> str:
    """One line: the reward's scale and whether the best agent's lead over the best tuned baseline is real."""
    s, pol = report["summary"], report["policies"]
    steps = int(np.mean([e["steps"] for e in pol["installed"]["episodes"]]))
    agents, bases = contenders(s)
    best_b = max(bases, key=lambda n: s[n]["mean_reward"])
    scale = (f"reward = USD per hour of well time; an episode's return sums its {steps} intervals, so 1 USD/h "
             f"held all episode = {steps} return units")
    if not agents:
        return f"{scale}; no agent trained; best tuned baseline {best_b}."
    best_a = max(agents, key=lambda n: s[n]["mean_reward"])
    d = report["paired"][best_a][best_b]
    lo, hi = judged_ci(d)
    by_well = (f" over the episodes; over the {d['n_wells']} wells' means, each well once, "
               f"[{lo / steps:+.2f}, {hi / steps:+.2f}] USD/h") if "ci95_by_well" in d else ""
    beaten = [b for b in bases if report["paired"][best_a][b]["significant_positive"]]
    call = ("no 95 % CI: one episode (or one well) cannot tell a lead from noise" if not np.isfinite([lo, hi]).all()
            else "significant (95 % CI above zero)" if lo > 0 else "agent significantly WORSE (95 % CI below zero)"
            if hi < 0 else "within noise (95 % CI spans zero)")
    return (f"{scale}. Best agent {best_a} vs best tuned baseline {best_b}: {d['mean_diff_reward']:+.1f} "
            f"[{d['ci95'][0]:+.1f}, {d['ci95'][1]:+.1f}] per episode = {d['mean_diff_reward'] / steps:+.2f} USD/h"
            f"{by_well}: {call}; "
            f"it beats {len(beaten)}/{len(bases)} baselines significantly; normalised score "
            f"{_fmt(s[best_a]['normalised_score'], 2)} (0 installed, 1 {report.get('normalised_to', 'oracle')}).")


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
                     + (f"; wells [{_fmt(d['ci95_by_well'][0])}, {_fmt(d['ci95_by_well'][1])}]"
                        if "ci95_by_well" in d else "")
                     + (" *" if d["significant_positive"] else "") for d in row.values()]
            lines.append(f"| {a} | " + " | ".join(cells) + " |")
        lines.append("")
        many = any("ci95_by_well" in d for row in report["paired"].values() for d in row.values())
        lines.append("`*`: the 95 % CI is above zero" + (". A test well has several episodes, which are not "
                                                         "independent, so each cell also gives the CI over the "
                                                         "per-well means (`wells`), and `*` marks that one."
                                                         if many else "."))
    return "\n".join(lines)


ENV_V1 = "srenv/SuckerRod-v1"  # reports written before they recorded their env were all v1


def write_markdown(report: dict[str, Any], path: Path, figure: str | None) -> None:
    tuned = report["tuned"]
    tr = report["training"]
    w = report["wall_time_s"]
    m = report["machine"]
    parts = [
        f"# Benchmark: tuned baselines vs learned controllers on unseen wells ({report.get('env_id', ENV_V1)})",
        "",
        f"Generated by `python -m agents benchmark {report['config']}`"
        + (" --quick" if report.get("quick") else "") + f"; wall time {w['total']:.0f} s on "
        f"{m['cpus_usable']} usable cores ({m['node']}). Data: `benchmark.json` next to this file; "
        "`python -m agents replay benchmark.json --policy NAME` re-runs its test episodes from it.",
        "",
        (f"- Test: {len(report['test']['seeds'])} episodes, `reset(seed=S)` on `scenario=\"{report['test'].get('scenario', 'test')}\"`, S = "
        f"{_seed_text(report['test']['seeds'])}; {len(set(report['test']['well_ids']))} test wells."),
        (f"- Tuning (baselines): {len(report['tuning']['seeds'])} episodes on training wells, seeds "
        f"{_seed_text(report['tuning']['seeds'])}. Validation (agent seed choice, if used): "
        f"{_seed_text(report['validation']['seeds']) or 'none'}."),
        (f"- Agents: {_runs_text(tr, report.get('policies'))}; "
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
    history = report.get("history") or []
    if history:  # every earlier evaluation on the test split, as the config records it (no silent re-runs)
        parts += ["## Test evaluations of this benchmark", "", *(f"- {h}" for h in history), ""]
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
- **Baselines, field observation only** (`agents/policies/field.py`), parametrised in action coordinates
  (fractions of each well's speed and stroke range), tuned on the training wells by `agents/training/tuning.py`:
  `installed` - the well's configured SPM and stroke, constant; `best_constant` - one action for all
  wells, from a grid over the whole action box plus a pattern search; `pump_off` - pump at a set point
  until the card's fillage estimate falls below a threshold, idle a set time, restart (threshold, idle
  time, pumping speed and stroke tuned by coordinate search); `fillage_pi` - VSD speed PI on the
  fillage estimate, output over the whole speed range so it can go intermittent below the VSD minimum
  (set-point, gains, stroke tuned). v2 adds `alarm_pump_off` (`agents/policies/alarms.py`): pump-off with a field
  controller's alarms (shut in on a parted-rod or tubing-leak signature, slow on gas), tuned from pump-off's set point.
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
  correction `r` (residual policy learning; it sees `b`), trained the same way. A `*_shaped` agent trained on
  a potential-based shaping of the reward (`agents/training/shaping.py`: `r + Phi(s') - Phi(s)`, `Phi` = the value of
  the present reservoir inflow for the time left), which telescopes to the true return minus the first state's
  potential and so ranks policies as the true return does; it is evaluated, like every policy, on the env's
  own reward. A `*_ensemble` agent is one policy made of a run's seed models (`agents/policies/ensemble.py`): it acts
  with the mean of their actions (for a residual run, `clip(b + scale * mean(r))`). Every seed takes part with
  the same weight, so no score on any split chose it; its CI is over test episodes only.
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
        lines += ["", "The field baselines act on `fillage_est`, the controller's estimate read off the downhole card "
                  f"(`task.fillage_estimator`); over all policies' test episodes it differs from the true pump fillage by {gap:.2f} on average "
                  "(episode means)" + (": where it stays near 1 while the pump is pounding, pump-off control and the "
                                       "fillage PI cannot see the pump-off, while an agent reading the whole card can."
                                       if gap > 0.1 else ".")]
    return [*lines, ""]


def _fillage_gap(policies: dict[str, Any]) -> float | None:
    d = [abs(e["mean_fillage"] - e["mean_fillage_est"]) for p in policies.values() for e in p["episodes"]
         if "mean_fillage" in e and "mean_fillage_est" in e]
    return float(np.mean(d)) if d else None


def rerender(out_dir: str | Path) -> None:
    """Recompute the paired differences from the stored episodes and rewrite ``OUT/benchmark.json`` and
    ``OUT/benchmark.md`` (no simulation; the figure is kept)."""
    out = Path(out_dir)
    report = json.loads((out / "benchmark.json").read_text())
    report["paired"] = _json_clean(paired_table(report["policies"]))
    _atomic_write(out / "benchmark.json", json.dumps(report, indent=1))
    write_markdown(report, out / "benchmark.md", "figures/benchmark_v1.png")


def _runs_text(training: dict[str, Any], policies: dict[str, Any] | None = None) -> str:
    runs, ens = training.get("runs", {}), training.get("ensembles", {})
    guard = {n: ", under the constraint guard" for n, p in (policies or {}).items() if (p or {}).get("guarded")}
    return (", ".join(f"{a} seeds {v['seeds']}" for a, v in runs.items()) or "none") + "".join(f"; {n}: the mean action of {v['of']}'s {len(v['models'])} seed models{guard.get(n, '')}"
                          for n, v in ens.items())


def _seed_text(seeds: list[int]) -> str:
    if not seeds:
        return ""
    if seeds == list(range(seeds[0], seeds[0] + len(seeds))):
        return f"{seeds[0]}..{seeds[-1]}"
    return ", ".join(map(str, seeds))


def _atomic_write(path: Path, text: str) -> None:
    from srenv.outputs import atomic_write  # the one writer: never a partial file, nothing left behind

    path.parent.mkdir(parents=True, exist_ok=True)
    atomic_write(path, lambda tmp: Path(tmp).write_text(text, encoding="utf-8"))


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


def summary_line(report: dict[str, Any]) -> dict[str, Any]:
    """The CLI's one-line JSON: where the files are, the verdict's numbers."""
    s = report["summary"]
    return {"policies": {n: {"mean_reward": r["mean_reward"], "normalised_score": r["normalised_score"],
                             "mean_cost": r["mean_cost"]} for n, r in s.items()},
            "test_episodes": len(report["test"]["seeds"]), "wall_time_s": report["wall_time_s"]["total"]}


