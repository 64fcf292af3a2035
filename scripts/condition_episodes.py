"""What the shipped v2 agent does when a condition appears, beside the best tuned baselines (issue 24, item 4).

    PYTHONPATH=. nice -n 5 python scripts/condition_episodes.py

For each event kind of ``srenv.task.events.EVENTS`` the episode is chosen by a rule fixed before any episode is
played (docs/agents.md, "What the agent does when a condition appears (v2)"): on v2's **validation** split, the
first seed from ``--first-seed`` (22000) upward whose drawn schedule has that event starting in the episode's first
half. The schedule is drawn at reset from the episode's seed alone (``SuckerRodV2Env._episode_spec``: its own
stream seeded by the seeded ``np_random``), before any action, so the rule cannot depend on a policy.

On that episode (the same seed: the same well, schedule and inflow) it plays the shipped agent (the shipped
report's best agent, ``oracle_distilled_ensemble``, built by ``agents.evaluation.replay.policy_specs``) and the
report's tuned baselines ``alarm_pump_off`` and ``fillage_pi``, and writes

- ``FIGURES/v2_condition_<event>.png``: over time the actions (average SPM, stroke length), the pump fillage and
  the controller's estimate, the classifier's probability of the condition, the reward rate and the cost per
  interval, the event's onset and end marked; the surface cards of the last interval before the onset and a few
  after, one panel per policy;
- ``--json`` (docs/archive/condition_episodes.json): per condition the seed, well, event, each policy's return,
  USD/h and cost over the episode and over the window after the onset, and what the classifier's probability of
  that condition did (keys: :data:`KEYS`).

Outputs are checked before any episode and written together at the end, atomically.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

from srenv.cli_types import OneLineParser
from srenv.declarations import Number
from srenv.errors import ConfigError

TOOL = "condition_episodes.py"
AGENT = "oracle_distilled_ensemble"
BASELINES = ("alarm_pump_off", "fillage_pi")
# every numeric flag, declared once: its type, unit and range
FLAGS = {
    "--first-seed": Number("--first-seed", int, lo=0, lo_open=False, hi=2**31 - 1, why="a reset's seed"),
    "--max-seeds": Number("--max-seeds", int, hi=100_000, why="wall time of the search (a reset each, ~0.03 s)"),
    "--episode-hours": Number("--episode-hours", float, "h", hi=48.0, why="wall time (~1 s of CPU per hour)"),
}
KEYS = {  # the JSON's keys per condition, and per policy (documented in docs/agents.md)
    "condition": ("event", "seed", "well_id", "onset_h", "end_h", "severity", "ramp_h", "schedule",
                  "window_h", "policies", "lead_in_window_usd_h"),
    "policy": ("return", "reward_rate_usd_h", "cost", "steps", "failure", "window", "before", "prob"),
    "window": ("return", "reward_rate_usd_h", "cost", "mean_avg_spm", "mean_stroke_length_m", "mean_duty",
               "mean_fillage", "intervals", "terms"),
    "prob": ("hour_before_mean", "window_mean", "window_max", "first_above_half_h"),
}


def parse(argv: list[str] | None) -> argparse.Namespace:
    from srenv.task.events import EVENTS

    ap = OneLineParser(prog=TOOL, description=__doc__.splitlines()[0])
    ap.tool = TOOL
    for flag, default, text in (("--first-seed", 22000, "first validation seed searched"),
                                ("--max-seeds", 2000, "seeds searched per condition"),
                                ("--episode-hours", None, "horizon (h; default: the report's env, 12)")):
        ap.add_argument(flag, type=FLAGS[flag].parse, default=default, help=text)
    ap.add_argument("--event", action="append", choices=list(EVENTS), help="repeatable; default: every event")
    ap.add_argument("--baseline", action="append", choices=list(BASELINES), help=f"repeatable; default: {BASELINES}")
    ap.add_argument("--report", default=None, help="benchmark report (default: the shipped v2 report)")
    ap.add_argument("--figures", default="docs/figures", help="folder of the PNGs")
    ap.add_argument("--json", default="docs/archive/condition_episodes.json", help="the summary (.json)")
    args = ap.parse_args(argv)
    args.event = args.event or list(EVENTS)
    args.baseline = tuple(args.baseline or BASELINES)
    from srenv.outputs import check_output_dir, check_outputs

    try:
        check_outputs({"--json": (args.json, (".json",))})
        check_output_dir(Path(args.figures), tuple(png_name(e) for e in args.event), "--figures")
    except ConfigError as exc:
        ap.error(f"{exc.field} = {exc.value!r}: expected {exc.expected}")
    return args


def png_name(event: str) -> str:
    return f"v2_condition_{event}.png"


# ------------------------------------------------------------------------------------------ selection
def pick_seed(env: Any, event: str, first_seed: int, max_seeds: int) -> int | None:
    """The rule: the first seed from ``first_seed`` whose schedule (drawn at reset, from the seed alone) has
    ``event`` starting in the episode's first half; None when none of ``max_seeds`` seeds has."""
    for seed in range(first_seed, first_seed + max_seeds):
        env.reset(seed=seed)
        u = env.unwrapped
        half_h = u.cfg.task.episode_hours / 2
        if any(e.label == event and e.start_h < half_h for e in u._schedule.events):
            return seed
    return None


# ------------------------------------------------------------------------------------------ episodes
def play_traced(env: Any, policy: Any, seed: int, label: str) -> dict[str, Any]:
    """One deterministic episode (the one loop, :func:`agents.evaluation.rollout.play`) with, per interval, the
    actions, fillage, reward, cost, the true condition, the classifier's probability of ``label`` and the card."""
    from agents.evaluation.rollout import play
    from srenv.envs.sucker_rod_v2 import FIELD_OBS_NAMES

    info, steps = play(env, policy, seed)
    j = FIELD_OBS_NAMES.index(f"prob_{label}")
    keys = ("time_h", "avg_spm", "duty", "stroke_length_m", "fillage", "fillage_est", "cost", "condition_severity")
    tr: dict[str, list] = {k: [] for k in (*keys, "reward", "condition", "prob", "card", "terms")}
    failure = None
    for obs, reward, terminated, _, inf in steps:
        for k in keys:
            tr[k].append(float(inf.get(k, math.nan)))
        tr["reward"].append(float(reward))
        tr["condition"].append(str(inf.get("condition", "")))
        tr["terms"].append({k: float(v) for k, v in inf.items() if k.startswith(("reward_", "cost_"))})
        o = np.asarray(obs, np.float64)
        tr["prob"].append(float(o[j]))
        tr["card"].append(o[:64].round(4).tolist())
        failure = inf.get("failure") if terminated else failure
    return {"well_id": str(info.get("well_id", "?")), "failure": failure, "trace": tr,
            "schedule": [vars(e).copy() for e in env.unwrapped._schedule.events]}


def window_of(ep: dict[str, Any], onset_h: float, end_h: float, dt_h: float) -> tuple[int, int]:
    """Intervals [i0, i1) after the onset: the first interval that starts at or after the onset, to the one the
    event ends in (the episode's end for a persistent event or an episode cut short)."""
    n = len(ep["trace"]["reward"])
    i0 = min(n, math.ceil(onset_h / dt_h - 1e-9))
    i1 = n if not math.isfinite(end_h) else min(n, max(i0 + 1, math.ceil(end_h / dt_h - 1e-9)))
    return i0, i1


def window_terms(ep: dict[str, Any], i0: int, i1: int) -> dict[str, float]:
    """The window's reward terms as mean rates (USD/h, as the reward) and its cost terms summed (as ``cost``)."""
    rows = ep["trace"]["terms"][i0:i1]
    keys = sorted({k for r in rows for k in r})
    sums = {k: sum(r.get(k, 0.0) for r in rows) for k in keys}
    return {k: v / len(rows) if k.startswith("reward_") else v for k, v in sums.items() if rows}


def policy_summary(ep: dict[str, Any], i0: int, i1: int, dt_h: float) -> dict[str, Any]:
    t = {k: np.asarray(v, float) for k, v in ep["trace"].items() if k not in ("condition", "card", "terms")}
    n = len(t["reward"])
    w = slice(i0, i1)
    before = slice(max(0, i0 - round(1 / dt_h)), i0)
    above = np.flatnonzero(t["prob"][w] > 0.5)

    def mean(k: str, s: slice) -> float | None:
        x = t[k][s]
        return float(np.mean(x)) if len(x) and np.all(np.isfinite(x)) else None

    win = {"return": float(t["reward"][w].sum()), "reward_rate_usd_h": mean("reward", w),
           "cost": float(t["cost"][w].sum()), "mean_avg_spm": mean("avg_spm", w),
           "mean_stroke_length_m": mean("stroke_length_m", w), "mean_duty": mean("duty", w),
           "mean_fillage": mean("fillage", w), "intervals": i1 - i0, "terms": window_terms(ep, i0, i1)}
    return {"return": float(t["reward"].sum()), "reward_rate_usd_h": float(t["reward"].sum()) / max(n, 1),
            "cost": float(t["cost"].sum()), "steps": n, "failure": ep["failure"], "window": win,
            "before": {"mean_avg_spm": mean("avg_spm", before), "mean_stroke_length_m": mean("stroke_length_m", before),
                       "mean_duty": mean("duty", before), "reward_rate_usd_h": mean("reward", before)},
            "prob": {"hour_before_mean": mean("prob", before), "window_mean": mean("prob", w),
                     "window_max": float(t["prob"][w].max()) if i1 > i0 else None,
                     "first_above_half_h": float(above[0] * dt_h) if len(above) else None}}


def condition_summary(event: str, seed: int, eps: dict[str, dict[str, Any]], dt_h: float,
                      horizon_h: float) -> dict[str, Any]:
    first = next(iter(eps.values()))
    ev = next(e for e in first["schedule"] if e["label"] == event and e["start_h"] < horizon_h / 2)
    end_h = ev["end_h"] if math.isfinite(ev["end_h"]) else None
    i0, i1 = window_of(first, ev["start_h"], ev["end_h"], dt_h)
    pols = {n: policy_summary(ep, *window_of(ep, ev["start_h"], ev["end_h"], dt_h), dt_h) for n, ep in eps.items()}
    agent, bases = AGENT, [n for n in pols if n != AGENT]
    lead = {b: pols[agent]["window"]["reward_rate_usd_h"] - pols[b]["window"]["reward_rate_usd_h"]
            for b in bases if pols[agent]["window"]["reward_rate_usd_h"] is not None
            and pols[b]["window"]["reward_rate_usd_h"] is not None}
    sched = [{**e, "end_h": e["end_h"] if math.isfinite(e["end_h"]) else None} for e in first["schedule"]]
    return {"event": event, "seed": seed, "well_id": first["well_id"], "onset_h": ev["start_h"], "end_h": end_h,
            "severity": ev["severity"], "ramp_h": ev["ramp_h"], "schedule": sched,
            "window_h": [i0 * dt_h, i1 * dt_h], "policies": pols, "lead_in_window_usd_h": lead}


# ------------------------------------------------------------------------------------------ figure
COLOURS = {AGENT: "tab:orange", "alarm_pump_off": "tab:blue", "fillage_pi": "tab:green"}


def card_picks(i0: int, i1: int, n: int, dt_h: float) -> list[int]:
    """The cards drawn: the last interval before the onset, the first after, one hour after, the window's last."""
    return sorted({i for i in (i0 - 1, i0, i0 + round(1 / dt_h), i1 - 1) if 0 <= i < min(n, max(i1, i0 + 1))})


def draw(summary: dict[str, Any], eps: dict[str, dict[str, Any]], dt_h: float) -> Any:
    import matplotlib

    matplotlib.use("Agg", force=False)
    from matplotlib.figure import Figure

    from agents.benchmark.figure import surface_card

    rows = (("avg_spm", "average SPM"), ("stroke_length_m", "stroke length (m)"),
            ("fillage", "pump fillage (-), estimate dashed"), ("prob", f"P({summary['event']}) (classifier)"),
            ("reward", "reward rate (USD/h)"), ("cost", "cost per interval (-)"))
    fig = Figure(figsize=(14, 2.0 * len(rows) + 1), dpi=90)
    gs = fig.add_gridspec(len(rows), 2, width_ratios=[1.6, 1])
    onset, end = summary["onset_h"], summary["end_h"]
    axes = []
    for r, (key, ylabel) in enumerate(rows):
        ax = fig.add_subplot(gs[r, 0], sharex=axes[0] if axes else None)
        axes.append(ax)
        for n, ep in eps.items():
            t = ep["trace"]
            hours = np.asarray(t["time_h"])
            ax.step(hours, t[key], where="pre", color=COLOURS.get(n), lw=1, label=n)
            if key == "fillage":
                ax.step(hours, t["fillage_est"], where="pre", color=COLOURS.get(n), lw=0.8, ls="--")
        ax.axvline(onset, color="k", lw=1)
        last = max(ep["trace"]["time_h"][-1] for ep in eps.values())
        ax.axvspan(onset, min(end, last) if end is not None else last, color="tab:red", alpha=0.08)
        if end is not None and end <= last:
            ax.axvline(end, color="k", lw=1, ls=":")
        ax.set_ylabel(ylabel, fontsize=8)
        ax.ticklabel_format(axis="y", useOffset=False)  # a fillage of 0.99999 reads as itself, not an offset
        ax.grid(alpha=0.3)
    axes[0].legend(fontsize=7, loc="lower left")
    axes[0].set_title(f"{summary['event']} (severity {summary['severity']:.2f}) on {summary['well_id']} "
                      f"(validation seed {summary['seed']}): onset {onset:.2f} h, "
                      f"end {'-' if end is None else f'{end:.2f} h'}", fontsize=9)
    axes[-1].set_xlabel("time (h); the event shaded from its onset (solid line) to its end (dotted)")
    cards = gs[:, 1].subgridspec(len(eps), 1)
    for k, (n, ep) in enumerate(eps.items()):
        t = ep["trace"]
        i0, i1 = window_of(ep, onset, end if end is not None else math.inf, dt_h)
        ax = fig.add_subplot(cards[k, 0])
        for i in card_picks(i0, i1, len(t["card"]), dt_h):
            when = "before the onset" if i < i0 else f"{(t['time_h'][i] - onset) * 60:+.0f} min"
            surface_card(ax, t["card"][i], t["stroke_length_m"][i], label=f"{t['time_h'][i]:.2f} h ({when})")
        ps = summary["policies"][n]
        ax.set_title(f"{n}: return {ps['return']:.0f}, window {ps['window']['reward_rate_usd_h'] or 0:.2f} USD/h, "
                     f"cost {ps['window']['cost']:.2f}", fontsize=8)
        ax.set(xlabel="polished-rod position (m)", ylabel="load / PPRL rating (-)")
        ax.legend(fontsize=7)
        ax.grid(alpha=0.3)
    fig.tight_layout()
    return fig


# ------------------------------------------------------------------------------------------ main
def _shown(path: Path) -> str:
    """The report's path as the command names it: relative to the working directory when it lies below it."""
    p = Path(path).resolve()
    return str(p.relative_to(Path.cwd())) if p.is_relative_to(Path.cwd()) else str(p)


def main(argv: list[str] | None = None) -> int:
    args = parse(argv)
    from agents.envs import make_env
    from agents.evaluation.replay import ReplayError, load_report, policy_specs
    from agents.evaluation.shipped import shipped_report
    from agents.evaluation.v1_view import build_policy_any
    from srenv.outputs import atomic_write_all

    t0 = time.perf_counter()
    try:
        path = Path(args.report) if args.report else shipped_report("v2")
        rep = load_report(path)
        specs = {n: policy_specs(rep, n, path.resolve().parent) for n in (AGENT, *args.baseline)}
    except (ReplayError, FileNotFoundError) as exc:
        print(f"{TOOL}: error: {exc}", file=sys.stderr)
        return 2
    if any(len(s) != 1 for s in specs.values()):
        print(f"{TOOL}: error: --report {path}: expected one policy spec each for {', '.join(specs)}", file=sys.stderr)
        return 2
    kwargs = {**rep["env_kwargs"], "scenario": "validation"}
    if args.episode_hours is not None:
        kwargs["episode_hours"] = args.episode_hours
    env = make_env(rep["env_id"], **kwargs)
    out: dict[str, Any] = {"command": "PYTHONPATH=. nice -n 5 python scripts/condition_episodes.py"
                           + (" " + " ".join(argv) if argv else ""), "report": _shown(path), "agent": AGENT,
                           "baselines": list(args.baseline), "scenario": "validation", "env_kwargs": kwargs,
                           "rule": f"the first validation seed from {args.first_seed} whose drawn schedule has the "
                                   "event starting in the episode's first half", "keys": KEYS, "conditions": {}}
    writes = []
    for event in args.event:
        seed = pick_seed(env, event, args.first_seed, args.max_seeds)
        if seed is None:
            print(f"{TOOL}: error: --max-seeds = {args.max_seeds}: no seed in [{args.first_seed}, "
                  f"{args.first_seed + args.max_seeds}) has {event} in its first half; expected a larger count",
                  file=sys.stderr)
            return 2
        dt_h = env.unwrapped.cfg.task.interval_s / 3600  # the episode's (set at reset)
        eps = {n: play_traced(env, build_policy_any(specs[n][0], env), seed, event) for n in specs}
        summ = condition_summary(event, seed, eps, dt_h, env.unwrapped.cfg.task.episode_hours)
        out["conditions"][event] = summ
        fig = draw(summ, eps, dt_h)
        writes.append((Path(args.figures) / png_name(event), lambda tmp, f=fig: f.savefig(tmp, format="png")))
        print(f"{event}: seed {seed}, " + ", ".join(f"{n} {p['window']['reward_rate_usd_h']:.2f} USD/h in the window"
                                                    for n, p in summ["policies"].items()), file=sys.stderr, flush=True)
    env.close()
    out["wall_time_s"] = time.perf_counter() - t0
    text = json.dumps(out, indent=1, allow_nan=False)
    Path(args.figures).mkdir(parents=True, exist_ok=True)
    writes.append((Path(args.json), lambda tmp: Path(tmp).write_text(text + "\n", encoding="utf-8")))
    atomic_write_all(writes)
    return 0


if __name__ == "__main__":
    sys.exit(main())
