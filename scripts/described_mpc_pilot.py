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

Round 2 (helper t24c): the same design with the twin's level AND deliverability from the level observer
(``observer: true``; agents/policies/level_observer.py), its one obvious parameter - the weight of each shot's
deliverability estimate, ``observer_gain`` - in :data:`GAINS`:

    PYTHONPATH=. nice -n 5 python scripts/described_mpc_pilot.py --stage train2 --out runs/t24c_train2
    PYTHONPATH=. nice -n 5 python scripts/described_mpc_pilot.py --stage gate2 --out runs/t24c_gate2

``--stage train2`` (TRAINING wells 16..31, the seeds of ``--stage train``): the candidates beside the tuned
baselines and the round-1 design (``described_mpc``, observer off: a reference, not a candidate). THE CHOICE
(written before any of these episodes was played): G = the candidate with the highest mean d against
alarm_pump_off; a candidate within 0.05 USD/h of it with a LOWER gain wins (the observer as merged, 0.5, first).
``--stage gate2``: the design pre-registered in configs/benchmark/v2_described_observer_mpc.yaml on its
validation episodes, and the same gate. ``--stage after2`` (read AFTER the gate2 result was recorded; no gate, no
choice): round 1's design (observer off) beside round 2's on gate2's validation episodes - what the observer changed.

    PYTHONPATH=. nice -n 5 python scripts/described_mpc_pilot.py --stage after2 --out runs/t24c_after2

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
CONFIG2 = ROOT / "configs/benchmark/v2_described_observer_mpc.yaml"
GAINS = (0.5, 0.75, 1.0)  # observer_gain: 0.5 = the observer as merged (its default, left out of the params)
STAGES = ("train", "gate", "train2", "gate2", "after2")
ROUND1 = 0.7  # round 1's chosen pound_prob (configs/benchmark/v2_described_mpc.yaml)
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


def observer_design(tuned: dict[str, dict[str, Any]], gain: float) -> dict[str, Any]:
    """Round 2: round 1's design with ``observer: true`` (and ``observer_gain`` unless it is the default 0.5)."""
    d = design(tuned, ROUND1)
    extra = {"observer": True, **({"observer_gain": gain} if gain != GAINS[0] else {})}
    return {**d, "params": {**d["params"], **extra}}


def specs_for(stage: str, tuned: dict[str, dict[str, Any]], cfg: dict[str, Any] | None) -> dict[str, Any]:
    out = {b: {"kind": "baseline", "name": b, "params": tuned[b]} for b in BASES}
    if stage == "train":
        out.update({f"described_pound_{p}": design(tuned, p) for p in CANDIDATES})
    elif stage == "train2":
        out["described_mpc"] = design(tuned, ROUND1)  # round 1, observer off: the reference
        out.update({f"observer_gain_{g}": observer_design(tuned, g) for g in GAINS})
    else:
        out.update(cfg["designs"])
        if stage == "after2":
            out.update(yaml.safe_load(CONFIG.read_text())["designs"])
    return out


def choose(summ: dict[str, Any]) -> float | None:
    """THE CHOICE of the train stage (module doc)."""
    d = {p: summ[f"described_pound_{p}"]["vs_alarm_pump_off"]["mean"] for p in CANDIDATES}
    best = max(d.values())
    return max((p for p in CANDIDATES if d[p] >= best - 0.05), key=lambda p: -1.0 if p is None else p)


def choose_gain(summ: dict[str, Any]) -> float:
    """THE CHOICE of the train2 stage (module doc)."""
    d = {g: summ[f"observer_gain_{g}"]["vs_alarm_pump_off"]["mean"] for g in GAINS}
    best = max(d.values())
    return min(g for g in GAINS if d[g] >= best - 0.05)


def seeds_of(cfg: dict[str, Any]) -> list[int]:
    s = cfg["validation"]["seeds"]
    return list(range(int(s["start"]), int(s["start"]) + int(s["count"])))


def main() -> None:
    a = emp.arguments(argparse.ArgumentParser(description=__doc__.splitlines()[0]), STAGES)
    tuned = {k: v["params"] for k, v in load_report(REPORT)["tuned"].items()}
    training = a.stage.startswith("train")
    cfg = None if training else yaml.safe_load((CONFIG if a.stage == "gate" else CONFIG2).read_text())
    seeds = TRAIN_SEEDS if training else seeds_of(cfg)
    specs = specs_for(a.stage, tuned, cfg)
    eps = emp.play(ENV, specs, seeds, a.out, a.workers)
    res = emp.outcome(a.stage, seeds, specs, eps, BASES)
    res["well_id"] = [e["well_id"] for e in eps["alarm_pump_off"]]
    res["guarded_intervals"] = {n: [e.get("guarded_intervals") for e in v] for n, v in eps.items() if n not in BASES}
    res["deliverability_estimate"] = {n: [e.get("observer_prod") for e in v] for n, v in eps.items()
                                      if v and v[0].get("observer_prod") is not None}
    summ = res["summary"]
    if a.stage == "train":
        res["chosen_pound_prob"] = choose(summ)
    elif a.stage == "train2":
        res["chosen_observer_gain"] = choose_gain(summ)
    elif a.stage != "after2":
        res["gate"] = {n: emp.gate(summ[n], summ["alarm_pump_off"]) for n in cfg["designs"]}
    tmp = a.out / "pilot.json.tmp"
    tmp.write_text(json.dumps(res, indent=1))
    tmp.replace(a.out / "pilot.json")
    print("\n".join(emp.table(summ, BASES, res["guarded_intervals"])))
    if training:
        print("CHOSEN:", res.get("chosen_pound_prob", res.get("chosen_observer_gain")))
    elif "gate" in res:
        print("GATE:", {n: "passed" if ok else "failed" for n, ok in res["gate"].items()})


if __name__ == "__main__":
    main()
