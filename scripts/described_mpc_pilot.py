"""Issue 24, helper t24b: ``estimated_mpc`` on the twin its operator's well file describes (``twin: described``,
srenv/task/well_file.py) with the classifier's condition in the twin and the guard, and the guard's pound signal
``pound_prob`` (the classifier's ``prob_fluid_pound``).

    PYTHONPATH=. nice -n 5 python scripts/described_mpc_pilot.py --stage train --out runs/t24b_train
    PYTHONPATH=. nice -n 5 python scripts/described_mpc_pilot.py --stage gate --out runs/t24b_gate

``--stage train`` (design aid: TRAINING wells 16..31, seeds 30016..30031 - never a validation, test or fresh
episode): the design with ``pound_prob`` in :data:`CANDIDATES` (None = m24's guard as it is) beside the tuned
``alarm_pump_off`` and ``pump_off`` (docs/v2/benchmark.json's tuned parameters). THE CHOICE (written before any of
these episodes was played): P = the candidate with the highest mean d against alarm_pump_off (d = paired return
difference / 144, USD/h); a candidate within 0.05 USD/h of it with a higher P wins (it hands fewer intervals over).
Nothing else of the design is chosen here.

``--stage gate``: the pre-registered design (configs/benchmark/v2_described_mpc.yaml) on its validation episodes
against ``alarm_pump_off``, and THE GATE written there (the rule of configs/benchmark/v2_estimated_mpc.yaml:
scripts/estimated_mpc_pilot.py::gate).

"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Any

import yaml

sys.path.insert(0, str(Path(__file__).resolve().parent))
import estimated_mpc_pilot as emp

from agents.evaluation.replay import load_report

ROOT = Path(__file__).resolve().parents[1]
CONFIG = ROOT / "configs/benchmark/v2_described_mpc.yaml"
REPORT = ROOT / "docs/v2/benchmark.json"
TRAIN_SEEDS = list(range(30016, 30032))  # training wells 16..31 (seed mod 200), schedules of their own
CANDIDATES = (None, 0.3, 0.5, 0.7)
BASES = ("alarm_pump_off", "pump_off")
ENV = {"env_id": "srenv/SuckerRod-v2", "env_kwargs": {"observation": "field"}}


def design(tuned: dict[str, dict[str, Any]], pound_prob: float | None) -> dict[str, Any]:
    """The described-twin design (the planner as m24's, condition_prob 0.6 in the twin, m24's guard) with
    ``pound_prob`` added to the guard when not None."""
    guard: dict[str, Any] = {"fallback": ["alarm_pump_off", tuned["alarm_pump_off"]], "pound_below": 0.9,
                             "load_above": 0.95, "condition_prob": 0.6}
    if pound_prob is not None:
        guard["pound_prob"] = pound_prob
    return {"kind": "baseline", "name": "estimated_mpc",
            "params": {"horizon": 6, "replan_every": 3, "twin": "described", "condition_prob": 0.6,
                       "policies": [[b, tuned[b]] for b in ("pump_off", "fillage_pi")], "guard": guard}}


def specs_for(stage: str, tuned: dict[str, dict[str, Any]], cfg: dict[str, Any] | None) -> dict[str, Any]:
    out = {b: {"kind": "baseline", "name": b, "params": tuned[b]} for b in BASES}
    if stage == "train":
        out.update({f"described_pound_{p}": design(tuned, p) for p in CANDIDATES})
    else:
        out.update(cfg["designs"])
    return out


def choose(summ: dict[str, Any]) -> float | None:
    """THE CHOICE of the train stage (module doc)."""
    d = {p: summ[f"described_pound_{p}"]["vs_alarm_pump_off"]["mean"] for p in CANDIDATES}
    best = max(d.values())
    return max((p for p in CANDIDATES if d[p] >= best - 0.05), key=lambda p: -1.0 if p is None else p)


def seeds_of(cfg: dict[str, Any]) -> list[int]:
    s = cfg["validation"]["seeds"]
    return list(range(int(s["start"]), int(s["start"]) + int(s["count"])))


def main() -> None:
    a = emp.arguments(argparse.ArgumentParser(description=__doc__.splitlines()[0]), ("train", "gate"))
    tuned = {k: v["params"] for k, v in load_report(REPORT)["tuned"].items()}
    cfg = yaml.safe_load(CONFIG.read_text()) if a.stage == "gate" else None
    seeds = TRAIN_SEEDS if a.stage == "train" else seeds_of(cfg)
    specs = specs_for(a.stage, tuned, cfg)
    eps = emp.play(ENV, specs, seeds, a.out, a.workers)
    res = emp.outcome(a.stage, seeds, specs, eps, BASES)
    res["well_id"] = [e["well_id"] for e in eps["alarm_pump_off"]]
    res["guarded_intervals"] = {n: [e.get("guarded_intervals") for e in v] for n, v in eps.items() if n not in BASES}
    summ = res["summary"]
    if a.stage == "train":
        res["chosen_pound_prob"] = choose(summ)
    else:
        res["gate"] = {n: emp.gate(summ[n], summ["alarm_pump_off"]) for n in cfg["designs"]}
    tmp = a.out / "pilot.json.tmp"
    tmp.write_text(json.dumps(res, indent=1))
    tmp.replace(a.out / "pilot.json")
    print("\n".join(emp.table(summ, BASES, res["guarded_intervals"])))
    print("CHOSEN pound_prob:" if a.stage == "train" else "GATE:",
          res.get("chosen_pound_prob") if a.stage == "train" else
          {n: "passed" if ok else "failed" for n, ok in res["gate"].items()})


if __name__ == "__main__":
    main()
