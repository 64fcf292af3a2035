"""A validation-only pilot of a student that sees a short history (issue 24, task h24): the last K field
observations stacked (agents/policies/history.py) instead of one card.

Why: the causal oracle acts on the annulus trend, which one card does not show. Two steps, no test or fresh
episode, no pre-registration:

1. ``--distill DIR --history K``: one DAgger student (agents/training/oracle_distill.py, the causal oracle as
   teacher, residual on the tuned pump_off at scale 0.5 as the shipped students) on training-split episodes
   ``--seed-start`` .. (default 70000: a fresh range, outside tuning 0..9, validation 20000.., the shipped
   students' 50000.. and the alarm pilot's 60000..); K = 1 and K = 3 use the same seeds and run seed;
2. ``--out DIR --student NAME=DIR ...``: the students, the shipped seed-0 student and ensemble, and the tuned
   pump_off, fillage_pi and alarm_pump_off on the 16 validation episodes (training wells, seeds 20000..20015,
   as scripts/alarm_base_pilot.py plays them); paired USD/h differences vs alarm_pump_off, pump_off and the
   first student named (the K = 1 reference).

    nice -n 5 python scripts/history_pilot.py --distill runs/h24_k3 --history 3 --workers 2
    nice -n 5 python scripts/history_pilot.py --distill runs/h24_k1 --history 1 --workers 2
    nice -n 5 python scripts/history_pilot.py --out runs/h24_pilot --student k1=runs/h24_k1 k3=runs/h24_k3
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parent))
from alarm_base_pilot import CONFIG, SHIPPED, distill_student, member, on_base, tuned_params
from guard_pilot import play_validation, summarise

from agents.benchmark.config import load_benchmark_config
from agents.policies.history import check_history

BASELINES = ("pump_off", "fillage_pi", "alarm_pump_off")
RESIDUAL = {"base": "pump_off", "scale": 0.5}  # the shipped students' base and scale


def distill(out: Path, history: int, seed: int, seed_start: int, iterations: int, episodes: int,
            workers: int) -> None:
    check_history(history)  # refused before anything is written
    res = {**RESIDUAL, "params": tuned_params()[RESIDUAL["base"]]}
    seeds, spec = distill_student(out, res, seed, seed_start, iterations, episodes, workers, {"history": history})
    (out / "distill.json").write_text(json.dumps({"residual": res, "seeds": seeds, "history": history,
                                                  "seed": seed, "spec": spec}, indent=1))


def student_spec(d: Path, tuned: dict[str, Any]) -> dict[str, Any]:
    """A distilled student's residual spec on pump_off, with the history it was trained with."""
    k = json.loads((d / "distill.json").read_text())["history"]
    spec = {"kind": "agent", **member(d / "student.zip"), "residual": {**RESIDUAL, "params": tuned["pump_off"]}}
    return {**spec, "history": k} if k != 1 else spec


def evaluate(out: Path, students: dict[str, Path], workers: int) -> None:
    cfg = load_benchmark_config(str(CONFIG))
    tuned = tuned_params()
    specs = {b: {"kind": "baseline", "name": b, "params": tuned[b]} for b in BASELINES}
    specs["shipped_seed0"] = on_base([member(SHIPPED[0])], "pump_off", tuned)
    specs["shipped_ensemble"] = on_base([member(p) for p in SHIPPED], "pump_off", tuned)
    specs.update({n: student_spec(d, tuned) for n, d in students.items()})
    eps = play_validation(cfg, specs, out, workers)
    bases = ("alarm_pump_off", "pump_off", *list(students)[:1])
    runs = {n: json.loads((d / "distill.json").read_text()) for n, d in students.items()}
    res = {"specs": specs, "summary": summarise(eps, bases),
           "dagger": {n: {"seeds": [r["seeds"][0], r["seeds"][-1]], "history": r["history"],
                          "iterations": r["spec"]["distill"], "wall_time_s": r["spec"]["wall_time_s"]}
                      for n, r in runs.items()}}
    (out / "pilot.json").write_text(json.dumps(res, indent=1))
    print("| policy | USD/h | cost | " + " | ".join(f"vs {b} [95 % CI] wins" for b in bases) + " |")
    for k, r in res["summary"].items():
        cells = [f"{r[f'vs_{b}']['mean']:+.2f} [{r[f'vs_{b}']['ci95'][0]:+.2f}, {r[f'vs_{b}']['ci95'][1]:+.2f}] "
                 f"{r[f'vs_{b}']['wins']}/{r[f'vs_{b}']['n']}" if f"vs_{b}" in r else "-" for b in bases]
        print(f"| {k} | {r['usd_h']:.2f} | {r['cost']:.2f} | " + " | ".join(cells) + " |")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--distill", type=Path, help="train one DAgger student into this directory")
    ap.add_argument("--history", type=int, default=3, help="K: the field observations the student sees, stacked")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--seed-start", type=int, default=70000)
    ap.add_argument("--iterations", type=int, default=3)
    ap.add_argument("--episodes", type=int, default=16)
    ap.add_argument("--out", type=Path, help="evaluate on validation into this directory")
    ap.add_argument("--student", nargs="*", default=[], help="NAME=DIR of --distill runs (the first: the reference)")
    ap.add_argument("--workers", type=int, default=2)
    a = ap.parse_args()
    students = {}
    for s in a.student:
        name, sep, d = s.partition("=")
        if not sep or not (Path(d) / "distill.json").is_file():
            print(f"--student {s!r}: expected NAME=DIR with DIR/distill.json", file=sys.stderr)
            sys.exit(2)
        students[name] = Path(d)
    if a.distill:
        try:
            distill(a.distill, a.history, a.seed, a.seed_start, a.iterations, a.episodes, a.workers)
        except ValueError as exc:
            print(f"history_pilot: {exc}", file=sys.stderr)
            sys.exit(2)
    if a.out:
        evaluate(a.out, students, a.workers)


if __name__ == "__main__":
    main()
