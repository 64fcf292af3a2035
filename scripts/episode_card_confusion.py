"""Issues 23/24, helper c43 (measurement only): how well the classifiers read v2's OWN episode cards.

N v2 episodes on TRAINING wells (scenario ``train``, seeds ``--seed-start`` .. + N - 1; 68000..68199 by default, a
block no other script plays: every training well once, seed mod 200) under the tuned ``alarm_pump_off`` of the shipped v2 report (docs/v2/benchmark.json, its
parameters through replay's ``policy_specs``). The env is built with a ``classifier`` (its public constructor kwarg)
that returns run 2's pinned probabilities (:func:`srenv.envs.sucker_rod_v2.default_classifier`, exactly what the
observation carries) and, on the same trace, records run 7's (srenv/models/classifier.npz, the model ``srenv classify`` ships,
read by the same ``default_classifier`` with that file: a card it cannot read gets the uniform vector, as v2 does). The env calls it once per
new card, so the card behind each interval's observation is the last one classified. Per interval that pumped
(``info["strokes"] > 0``): the true label (``info["condition"]``), its severity, both models' probabilities, the
card's index in the episode (0: the reset's card; ``first_card``: index <= 1, the well's first card) and whether
the previous interval idled (``idle_s > 0``). Choosing nothing, changing no model and no env:

    PYTHONPATH=. nice -n 5 python scripts/episode_card_confusion.py --episodes 200 --workers 2

writes docs/archive/episode_card_confusion.json (``KEYS``; ``--rows FILE``: also every interval's row): per model the confusion (true -> argmax) and the rate of
``max(prob_tagging_up, prob_tagging_down) > T`` per true label (a false alarm on a non-tagging label, a hit on a
tagging one), overall and split by first card / after idle / other, and per episode whether it ever fired.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

from srenv.cli_types import OneLineParser
from srenv.declarations import Number
from srenv.errors import ConfigError

TOOL = "episode_card_confusion.py"
BASE = "alarm_pump_off"
MODELS = ("run2", "run7")
THRESHOLDS = (0.5, 0.8)
TAGGING = ("tagging_up", "tagging_down")
SPLITS = ("all", "first_card", "after_idle", "other")
FLAGS = {  # every numeric flag, declared once: its type, unit and range
    "--episodes": Number("--episodes", int, hi=200, why="wall time (~18 s of CPU an episode)"),
    "--seed-start": Number("--seed-start", int, lo=0, lo_open=False, hi=2**31 - 1000, why="a reset's seed"),
    "--workers": Number("--workers", int, hi=2, why="the machine's 2 cores"),
    "--max-intervals": Number("--max-intervals", int, hi=10_000, why="intervals played per episode (a short run)"),
}
KEYS = {  # the JSON's keys (documented in docs/conditions.md)
    "top": ("command", "report", "policy", "scenario", "seeds", "labels", "intervals", "distinct_cards",
            "models", "episodes", "wall_time_s", "rows_columns"),
    "model": ("confusion", "accuracy", "tagging_alarm"),
    "alarm": ("by_label", "false_alarm_rate", "hit_rate", "by_split", "distinct_cards", "episodes_fired"),
}
ROW = ("seed", "step", "true", "severity", "card_index", "first_card", "after_idle",
       "run2_label", "run2_tagging_up", "run2_tagging_down", "run7_label", "run7_tagging_up", "run7_tagging_down")


def parse(argv: list[str] | None) -> argparse.Namespace:
    ap = OneLineParser(prog=TOOL, description=__doc__.splitlines()[0])
    ap.tool = TOOL
    for flag, default, text in (("--episodes", 200, "episodes, one per seed (200: every training well once)"), ("--seed-start", 68000, "first seed"),
                                ("--workers", 2, "worker processes"),
                                ("--max-intervals", None, "intervals per episode (default: the whole episode)")):
        ap.add_argument(flag, type=FLAGS[flag].parse, default=default, help=text)
    ap.add_argument("--out", default="docs/archive/episode_card_confusion.json", help="the record (.json)")
    ap.add_argument("--rows", default=None, help="also every interval's row (.json: rows_columns, rows)")
    args = ap.parse_args(argv)
    from srenv.outputs import check_outputs

    try:
        check_outputs({"--out": (args.out, (".json",)), "--rows": (args.rows, (".json",))})
    except ConfigError as exc:
        ap.error(f"{exc.field} = {exc.value!r}: expected {exc.expected}")
    return args


class Recorder:
    """The env's classifier: run 2's probabilities (returned, so the observation is v2's own) and run 7's on the same
    trace, kept with the card's index in the episode (the env calls it once per new card)."""

    def __init__(self) -> None:
        from srenv.analysis.card_classifier import DEFAULT_MODEL
        from srenv.envs.sucker_rod_v2 import default_classifier

        self.run2, self.run7 = default_classifier(), default_classifier(DEFAULT_MODEL)
        self.calls, self.last = 0, (np.zeros(0), np.zeros(0))

    def __call__(self, trace: dict) -> np.ndarray:
        p2, p7 = (np.asarray(clf(trace), np.float64) for clf in (self.run2, self.run7))
        self.calls += 1
        self.last = (p2, p7)
        return p2


def episode(job: dict[str, Any]) -> list[list[Any]]:
    """One episode's rows (:data:`ROW`), one per interval that pumped."""
    from agents.envs import make_env
    from agents.evaluation.rollout import play
    from agents.evaluation.v1_view import build_policy_any
    from srenv.envs.sucker_rod_v2 import LABELS

    rec = Recorder()
    env = make_env(job["env_id"], **job["env_kwargs"], classifier=rec)
    _, steps = play(env, build_policy_any(job["spec"], env), job["seed"])
    rows, prev_idle, up, down = [], False, LABELS.index("tagging_up"), LABELS.index("tagging_down")
    for k, (_, _, _, _, info) in enumerate(steps):
        if info["strokes"] > 0:
            p2, p7 = rec.last
            idx = rec.calls - 1
            rows.append([job["seed"], k, str(info["condition"]), round(float(info["condition_severity"]), 4), idx,
                         idx <= 1, prev_idle, *(v for p in (p2, p7) for v in (LABELS[int(np.argmax(p))],
                                                                             round(float(p[up]), 4),
                                                                             round(float(p[down]), 4)))])
        prev_idle = float(info["idle_s"]) > 0
        if job["max_intervals"] and k + 1 >= job["max_intervals"]:
            break
    env.close()
    return rows


def confusion(true: list[str], pred: list[str], labels: tuple[str, ...]) -> dict[str, dict[str, int]]:
    """{true label: {predicted label: count}} for the true labels that occur."""
    out: dict[str, dict[str, int]] = {}
    for t, p in zip(true, pred):
        row = out.setdefault(t, dict.fromkeys(labels, 0))
        row[p] += 1
    return out


def rate(fired: list[bool]) -> dict[str, Any]:
    return {"n": len(fired), "fired": int(sum(fired)), "rate": sum(fired) / len(fired) if fired else None}


def tagging_alarm(rows: list[dict[str, Any]], model: str, t: float) -> dict[str, Any]:
    """The rate of max(prob_tagging_up, prob_tagging_down) > t: per true label, on non-tagging intervals (false
    alarms) and tagging ones (hits), per split, per distinct card (an interval that reused a stroke shows its
    card again) and over episodes (did it ever fire; did the episode ever tag)."""
    fire = [max(r[f"{model}_tagging_up"], r[f"{model}_tagging_down"]) > t for r in rows]
    tag = [r["true"] in TAGGING for r in rows]
    split = {"all": [True] * len(rows), "first_card": [r["first_card"] for r in rows],
             "after_idle": [r["after_idle"] and not r["first_card"] for r in rows],
             "other": [not (r["first_card"] or r["after_idle"]) for r in rows]}

    def on(mask: list[bool], tagging: bool) -> dict[str, Any]:
        return rate([f for f, m, g in zip(fire, mask, tag) if m and g == tagging])

    cards: dict[tuple, bool] = {}  # (seed, card index, tagging): fired on any interval that showed the card
    for r, f, g in zip(rows, fire, tag):
        cards[(r["seed"], r["card_index"], g)] = cards.get((r["seed"], r["card_index"], g), False) or f
    by_ep: dict[int, list[bool]] = {}
    for r, f, g in zip(rows, fire, tag):
        e = by_ep.setdefault(r["seed"], [False, False])
        e[0], e[1] = e[0] or f, e[1] or g
    return {"by_label": {k: rate([f for f, r in zip(fire, rows) if r["true"] == k])
                         for k in sorted({r["true"] for r in rows})},
            "false_alarm_rate": on(split["all"], False), "hit_rate": on(split["all"], True),
            "by_split": {s: {"false_alarm_rate": on(m, False), "hit_rate": on(m, True)} for s, m in split.items()},
            "distinct_cards": {"false_alarm_rate": rate([f for k, f in cards.items() if not k[2]]),
                               "hit_rate": rate([f for k, f in cards.items() if k[2]])},
            "episodes_fired": {"never_tagged": rate([f for f, g in by_ep.values() if not g]),
                               "tagged": rate([f for f, g in by_ep.values() if g])}}


def summarise(rows: list[dict[str, Any]], labels: tuple[str, ...]) -> dict[str, Any]:
    """Per model: the confusion, the accuracy of the argmax and the tagging alarm at each threshold."""
    true = [r["true"] for r in rows]
    out = {}
    for m in MODELS:
        pred = [r[f"{m}_label"] for r in rows]
        out[m] = {"confusion": confusion(true, pred, labels),
                  "accuracy": float(np.mean([t == p for t, p in zip(true, pred)])) if rows else None,
                  "tagging_alarm": {str(t): tagging_alarm(rows, m, t) for t in THRESHOLDS}}
    return out


def main(argv: list[str] | None = None) -> int:
    args = parse(argv)
    from agents.evaluation.replay import load_report, policy_specs
    from agents.evaluation.rollout import Runner
    from agents.evaluation.shipped import shipped_report
    from srenv.envs.sucker_rod_v2 import LABELS
    from srenv.outputs import atomic_write_all

    t0 = time.perf_counter()
    path = shipped_report("v2")
    rep = load_report(path)
    spec = policy_specs(rep, BASE, path.resolve().parent)[0]
    seeds = list(range(args.seed_start, args.seed_start + args.episodes))
    jobs = [{"env_id": rep["env_id"], "env_kwargs": {**rep["env_kwargs"], "scenario": "train"}, "spec": spec,
             "seed": s, "max_intervals": args.max_intervals} for s in seeds]
    with Runner(args.workers) as runner:
        per_ep = runner.map(jobs, fn=episode)
    table = [r for ep in per_ep for r in ep]
    rows = [dict(zip(ROW, r)) for r in table]
    out = {"command": "PYTHONPATH=. nice -n 5 python scripts/episode_card_confusion.py"
                      + (" " + " ".join(argv if argv is not None else sys.argv[1:])).rstrip(),
           "report": str(path.relative_to(Path.cwd())) if path.is_relative_to(Path.cwd()) else str(path),
           "policy": spec, "scenario": "train", "seeds": [seeds[0], seeds[-1]], "labels": list(LABELS),
           "intervals": len(rows), "distinct_cards": len({(r["seed"], r["card_index"]) for r in rows}),
           "models": summarise(rows, LABELS), "episodes": len(per_ep), "wall_time_s": time.perf_counter() - t0,
           "rows_columns": list(ROW)}
    texts = {args.out: json.dumps(out, indent=1, allow_nan=False)}
    if args.rows:
        texts[args.rows] = json.dumps({"rows_columns": list(ROW), "rows": table}, separators=(",", ":"))
    atomic_write_all([(Path(p), lambda tmp, t=t: Path(tmp).write_text(t + "\n", encoding="utf-8"))
                      for p, t in texts.items()])
    for m in MODELS:
        a = out["models"][m]["tagging_alarm"]
        print(f"{m}: accuracy {out['models'][m]['accuracy']:.3f}; " + "; ".join(
            f"T={t}: false alarms {a[str(t)]['false_alarm_rate']['rate']}, hits {a[str(t)]['hit_rate']['rate']}"
            for t in THRESHOLDS), file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
