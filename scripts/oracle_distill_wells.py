"""Issue 24, helper g40: do the DAgger students generalise if they are taught on MANY training wells?

The data, the pre-check, the design and the gate are pre-registered in configs/benchmark/v2_oracle_distilled_wells.yaml
(its ``history``); the labelled episodes are scripts/oracle_distill_pooled.py's, the fit agents/training/pooled_fit.py's,
the cap scripts/oracle_distill_capped.py's, the gate scripts/oracle_distill_more.py's. e24's pooled ensemble
(/work/keep/e24_pooled/models) and its pool P1 (/work/keep/e24_pooled/labels -> runs/e24_pooled/labels, and
labels_dagger.npz -> OUT/) are copied in first:

    mkdir -p runs/g40 runs/e24_pooled && cp -r /work/keep/e24_pooled/models /work/keep/e24_pooled/labels_dagger.npz \
        runs/g40/ && cp -r /work/keep/e24_pooled/labels runs/e24_pooled/
    PYTHONPATH=. nice -n 5 python scripts/oracle_distill_wells.py --stage label --out runs/g40 --workers 2
    PYTHONPATH=. nice -n 5 python scripts/oracle_distill_wells.py --stage precheck --out runs/g40 --workers 2
    PYTHONPATH=. nice -n 5 python scripts/oracle_distill_wells.py --stage gate --out runs/g40 --workers 2

``--stage label``: one training episode per well of :data:`SEEDS` (seed mod 200 = the well), e24's pooled ensemble
acting, labelled by the oracle, in chunks OUT/labels_wells_{i}.npz (a finished chunk is kept: the stage resumes).
``--stage precheck`` (training labels only): THE PRE-CHECK, e24's chosen candidate with WELL-grouped folds on the
pool -> OUT/precheck.json; if it passes, the design's 3 fits -> OUT/design/. ``--stage gate``: only after a passed
pre-check; THE GATE on v2's validation split -> OUT/gate.json.
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
from oracle_distill_pooled import (
    NAME,
    design,
    label_episodes,
    model_mse,
    pool_paths,
    print_outcome,
    require_precheck,
)

from agents.evaluation.agent import AgentPolicy
from agents.evaluation.rollout import Runner
from agents.policies.ensemble import ensemble_spec
from agents.training.pooled_fit import clipped_mse, cv_table, fit_student, load_pool

CONFIG = ROOT / "configs/benchmark/v2_oracle_distilled_wells.yaml"
SEEDS = list(range(59032, 59200))  # the labelled episodes: training wells 32..199, one each (the config's history)
CHUNK = 24  # episodes per saved chunk
WELLS = 200  # training wells: seed mod WELLS = the well
GATE_SEEDS = list(range(21400, 21416))  # THE GATE's seeds, on v2's validation split (the config's history)
CANDIDATE = {"epochs": 30, "weight_decay": 0.0, "net_arch": [128, 128]}  # e24's chosen candidate (its select.json)
PRECHECK_MAX = 0.45  # PASS iff the mean held-out-well MSE <= this (the config's history)
CAP = {"spm_cap": 0.0}  # f24's chosen cap
STAGES = ("label", "precheck", "gate")


def chunks() -> list[list[int]]:
    return [SEEDS[i:i + CHUNK] for i in range(0, len(SEEDS), CHUNK)]


def label(out: Path, workers: int) -> dict[str, Any]:
    d = design(CONFIG)
    ens = ensemble_spec(students(out / "models", NAME, d["pool"]["fit_seeds"], d["res"]))
    done = []
    for i, seeds in enumerate(chunks()):
        dest = out / f"labels_wells_{i}.npz"
        if not dest.is_file():
            eps = label_episodes(d, {"members": ens["members"]}, seeds, workers, dest.with_name(dest.stem + "_tmp.npz"))
            dest.with_name(dest.stem + "_tmp.npz").replace(dest)
            print(f"chunk {i}: seeds {seeds[0]}..{seeds[-1]}, mean return {np.mean([e['reward'] for e in eps]):.1f}",
                  flush=True)
        done.append(str(dest))
    return {"stage": "label", "chunks": done}


def wells_pool(out: Path, d: dict[str, Any]) -> tuple[dict[str, np.ndarray], np.ndarray]:
    """The pool (e24's P1, then every finished chunk) and each row's training well: P1's episode j is well j (d24's
    files and e24's DAgger seeds 56000 + j), a chunk's episode j is its j-th seed's well."""
    done = [(out / f"labels_wells_{i}.npz", c[0] % WELLS) for i, c in enumerate(chunks())]
    done = [(f, w) for f, w in done if f.is_file()]
    p1 = pool_paths(d, out, True)
    pool = load_pool(p1 + [f for f, _ in done], d["pool"]["episode_steps"])
    first = [0] * len(p1) + [w for _, w in done]
    return pool, pool["key"] + np.asarray(first)[pool["file"]]


def well_cv(runner: Runner, pool_npz: Path, d: dict[str, Any], well: np.ndarray, workdir: Path) -> dict[str, Any]:
    """:data:`CANDIDATE`'s held-out MSE with folds by training well (well w in fold w mod K: the pre-check's fit)."""
    block = {**d["pool"], "epochs": [CANDIDATE["epochs"]], "weight_decay": [CANDIDATE["weight_decay"]],
             "net_arch": [CANDIDATE["net_arch"]]}
    (row,) = cv_table(runner, pool_npz, block, well, d["pk"], 0, workdir)
    return row


def zero_mse_folds(label: np.ndarray, well: np.ndarray, folds: int) -> list[float]:
    """Predicting no correction: the labels' mean square per well fold."""
    return [float(np.mean(label[well % folds == f] ** 2)) for f in range(folds)]


def precheck(out: Path, workers: int) -> dict[str, Any]:
    d = design(CONFIG)
    pool, well = wells_pool(out, d)
    np.savez(out / "pool.npz", x=pool["x"], label=pool["label"])
    with Runner(workers) as runner:
        row = well_cv(runner, out / "pool.npz", d, well, out / "cv")
    new = well >= 32
    e24 = [AgentPolicy(m["path"], m["obs_norm"]) for m in
           ensemble_spec(students(out / "models", NAME, d["pool"]["fit_seeds"], d["res"]))["members"]]
    rec = {"stage": "precheck", "episodes": int(pool["group"].max()) + 1, "labels": len(pool["x"]),
           "wells": len(set(well.tolist())), "candidate": CANDIDATE,
           "heldout_well_mse_folds": row["heldout_mse_folds"], "heldout_well_mse": row["heldout_mse"],
           "precheck_max": PRECHECK_MAX, "precheck": bool(row["heldout_mse"] <= PRECHECK_MAX),
           "zero_correction_mse_folds": zero_mse_folds(pool["label"], well, d["pool"]["folds"]),
           "e24_ensemble_mse_on_new_wells": model_mse(e24, pool["x"][new], pool["label"][new]),
           "zero_correction_mse_on_new_wells": clipped_mse(np.zeros_like(pool["label"][new]), pool["label"][new])}
    rec["zero_correction_mse"] = float(np.mean(rec["zero_correction_mse_folds"]))
    if rec["precheck"]:
        for k in d["pool"]["fit_seeds"]:
            fit_student(pool["x"], pool["label"], CANDIDATE, d["pk"], k, out / "design" / f"{NAME}_v2_seed{k}.zip")
    write_json(out / "precheck.json", rec)
    return rec


def gate(out: Path, workers: int) -> dict[str, Any]:
    require_precheck(out)
    d = design(CONFIG)
    return play_design_gate(d["cfg"], CONFIG, GATE_SEEDS, {"wells_capped": design_spec(out, d)}, d["tuned"], d["res"],
                            out, workers, scenario="validation", shipped=False)


def design_spec(out: Path, d: dict[str, Any]) -> dict[str, Any]:
    """THE DESIGN: the mean correction of the pre-check's 3 fits on the whole pool (OUT/design), capped."""
    return capped(ensemble_spec(students(out / "design", NAME, d["pool"]["fit_seeds"], d["res"])), CAP)


def main() -> None:
    a = arguments(argparse.ArgumentParser(description=__doc__.splitlines()[0]), STAGES)
    a.out.mkdir(parents=True, exist_ok=True)
    if a.stage == "label":
        print(json.dumps(label(a.out, a.workers)))
    else:
        print_outcome(a.stage, precheck(a.out, a.workers) if a.stage == "precheck" else gate(a.out, a.workers))

if __name__ == "__main__":
    main()
