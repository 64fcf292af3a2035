"""Issue 24, helper d42: does a student that SEES THE OPERATOR'S WELL FILE generalise to new wells?

The data, the described features, the pre-check, the design and the gate are pre-registered in
configs/benchmark/v2_oracle_distilled_described.yaml (its ``history``). The labels are g40's, regenerated with g40's
script and seeds (scripts/oracle_distill_wells.py --stage label) after copying what it needs from
/work/keep/e24_pooled (read only):

    mkdir -p runs/d42 runs/e24_pooled && cp -r /work/keep/e24_pooled/models /work/keep/e24_pooled/labels_dagger.npz \\
        runs/d42/ && cp -r /work/keep/e24_pooled/labels runs/e24_pooled/
    PYTHONPATH=. nice -n 5 python scripts/oracle_distill_wells.py --stage label --out runs/d42 --workers 2
    PYTHONPATH=. nice -n 5 python scripts/oracle_distill_described.py --stage precheck --out runs/d42 --workers 2
    PYTHONPATH=. nice -n 5 python scripts/oracle_distill_described.py --stage fit --out runs/d42
    PYTHONPATH=. nice -n 5 python scripts/oracle_distill_described.py --stage gate --out runs/d42 --workers 2
    PYTHONPATH=. nice -n 5 python scripts/oracle_distill_described.py --stage gate2 --out runs/d42 --workers 2

``--stage precheck`` (training labels only): g40's pool (:func:`oracle_distill_wells.wells_pool`), every row's input
with the 13 features of its training well's file appended (:func:`agents.policies.described_features.features` of
``well_file(env)`` after ``reset``), g40's candidate with g40's well-grouped folds (:func:`oracle_distill_wells.well_cv`)
-> OUT/precheck.json; reported beside it, not judged: the same fit without the features on the same pool, the
no-correction MSE and g40's recorded figures. ``--stage fit`` (only after a passed pre-check): THE DESIGN's 3 fits on
the described pool -> OUT/design/. ``--stage gate`` (only after a passed pre-check): THE GATE on v2's validation
split -> OUT/gate.json, the design's policy spec ``described: true`` (:class:`agents.policies.described_features.DescribedInputs`).
``--stage gate2`` (helper g42, after the first gate failed on its CI): GATE 2, the same frozen design on the 50
validation wells once each (GATE2_SEEDS) -> OUT/gate2/gate.json.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from estimated_mpc_pilot import arguments
from oracle_distill_capped import capped
from oracle_distill_more import ROOT, play_design_gate, students, write_json
from oracle_distill_pooled import NAME, design, print_outcome, require_precheck
from oracle_distill_wells import CANDIDATE, CAP, PRECHECK_MAX, well_cv, wells_pool, zero_mse_folds

from agents.evaluation.rollout import Runner
from agents.policies.described_features import FEATURES, append_features, features
from agents.policies.ensemble import ensemble_spec
from agents.training.pooled_fit import fit_student

CONFIG = ROOT / "configs/benchmark/v2_oracle_distilled_described.yaml"
GATE_SEEDS = list(range(21600, 21616))  # THE GATE's seeds, on v2's validation split (the config's history)
GATE2_SEEDS = list(range(21650, 21700))  # GATE 2's (helper g42): the 50 validation wells once each (seed mod 50)
G40 = ROOT / "docs/archive/oracle_distill_wells.json"  # g40's recorded pre-check (read as data, for comparison)
STAGES = ("precheck", "fit", "gate", "gate2")


def well_features(env_kwargs: dict[str, Any], wells: list[int]) -> np.ndarray:
    """(len(wells), len(FEATURES)): each training well's described features, from the file ``well_file(env)`` hands
    over after ``reset`` (seed w plays training well w) - what the acting student reads."""
    import gymnasium as gym

    import srenv  # noqa: F401  (registers the envs)
    from srenv.task.well_file import well_file

    env = gym.make("srenv/SuckerRod-v2", **env_kwargs)
    try:
        rows = []
        for w in wells:
            env.reset(seed=int(w))
            rows.append(features(well_file(env)))
        return np.stack(rows)
    finally:
        env.close()


def described_inputs(x: np.ndarray, well: np.ndarray, table: np.ndarray) -> np.ndarray:
    """Every row's input ``x`` with its well's features (``table[w]``) appended: the described student's input."""
    return append_features(x, np.asarray(table)[np.asarray(well)])


def precheck(out: Path, workers: int) -> dict[str, Any]:
    d = design(CONFIG)
    pool, well = wells_pool(out, d)
    table = well_features(d["env_kwargs"], list(range(int(well.max()) + 1)))
    np.savez(out / "pool.npz", x=pool["x"], label=pool["label"])
    np.savez(out / "pool_described.npz", x=described_inputs(pool["x"], well, table), label=pool["label"])
    for sub in ("cv_described", "cv_plain"):
        (out / sub).mkdir(exist_ok=True)
    with Runner(workers) as runner:
        desc = well_cv(runner, out / "pool_described.npz", d, well, out / "cv_described")
        plain = well_cv(runner, out / "pool.npz", d, well, out / "cv_plain")
    zero = zero_mse_folds(pool["label"], well, d["pool"]["folds"])
    g40 = json.loads(G40.read_text())["precheck"]
    rec = {"stage": "precheck", "episodes": int(pool["group"].max()) + 1, "labels": len(pool["x"]),
           "wells": len(set(well.tolist())), "candidate": CANDIDATE, "features": list(FEATURES),
           "inputs": int(pool["x"].shape[1] + table.shape[1]),
           "heldout_well_mse_folds": desc["heldout_mse_folds"], "heldout_well_mse": desc["heldout_mse"],
           "precheck_max": PRECHECK_MAX, "precheck": bool(desc["heldout_mse"] <= PRECHECK_MAX),
           "without_features_mse_folds": plain["heldout_mse_folds"], "without_features_mse": plain["heldout_mse"],
           "zero_correction_mse_folds": zero, "zero_correction_mse": float(np.mean(zero)),
           "g40_heldout_well_mse": g40["heldout_well_mse"], "g40_zero_correction_mse": g40["zero_correction_mse"],
           "feature_table": {"min": table.min(0).tolist(), "max": table.max(0).tolist()}}
    write_json(out / "precheck.json", rec)
    return rec


def fit(out: Path) -> dict[str, Any]:
    """THE DESIGN's 3 fits (only after a passed pre-check): the candidate on the whole described pool, fit seeds
    ``pool.fit_seeds``, statistics from the pool's inputs -> OUT/design/."""
    require_precheck(out)
    d = design(CONFIG)
    with np.load(out / "pool_described.npz", allow_pickle=False) as z:
        x, y = z["x"], z["label"]
    (out / "design").mkdir(exist_ok=True)
    for k in d["pool"]["fit_seeds"]:
        fit_student(x, y, CANDIDATE, d["pk"], k, out / "design" / f"{NAME}_v2_seed{k}.zip")
    rec = {"stage": "fit", "fit_seeds": d["pool"]["fit_seeds"], "rows": len(x), "inputs": int(x.shape[1]),
           "spec": design_spec(out, d)}
    write_json(out / "fit.json", rec)
    return rec


def design_spec(out: Path, d: dict[str, Any]) -> dict[str, Any]:
    """THE DESIGN: the mean correction of the 3 fits on the described pool (OUT/design), f24's cap, the well file's
    features appended to every input (read at reset from ``well_file(env)``)."""
    return {**capped(ensemble_spec(students(out / "design", NAME, d["pool"]["fit_seeds"], d["res"])), CAP),
            "described": True}


def gate(out: Path, workers: int, seeds: list[int] = GATE_SEEDS, to: Path | None = None) -> dict[str, Any]:
    """THE GATE (``seeds`` GATE_SEEDS -> OUT/gate.json) or GATE 2 (GATE2_SEEDS -> OUT/gate2/gate.json): the same
    frozen design against alarm_pump_off on v2's validation split, by the same code."""
    require_precheck(out)
    d = design(CONFIG)
    return play_design_gate(d["cfg"], CONFIG, seeds, {"described_capped": design_spec(out, d)}, d["tuned"],
                            d["res"], to or out, workers, scenario="validation", shipped=False)


def main() -> None:
    a = arguments(argparse.ArgumentParser(description=__doc__.splitlines()[0]), STAGES)
    a.out.mkdir(parents=True, exist_ok=True)
    if a.stage == "fit":
        print(json.dumps(fit(a.out)))
    elif a.stage == "gate2":
        (a.out / "gate2").mkdir(exist_ok=True)
        print_outcome("gate", gate(a.out, a.workers, GATE2_SEEDS, a.out / "gate2"))
    else:
        print_outcome(a.stage, precheck(a.out, a.workers) if a.stage == "precheck" else gate(a.out, a.workers))


if __name__ == "__main__":
    main()
