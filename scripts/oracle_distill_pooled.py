"""Issue 24, helper e24: a pooled field student - one fit on every labelled DAgger episode, chosen on held-out episodes.

The design, its pre-check and its gate are pre-registered in configs/benchmark/v2_oracle_distilled_pooled.yaml (its
``history``); the fit and the selection are agents/training/pooled_fit.py's, the labelled episodes
agents/training/oracle_distill.py's, the gate scripts/oracle_distill_more.py's.

    PYTHONPATH=. nice -n 5 python scripts/oracle_distill_pooled.py --stage select --out runs/e24_pooled
    PYTHONPATH=. nice -n 5 python scripts/oracle_distill_pooled.py --stage dagger --out runs/e24_pooled
    PYTHONPATH=. nice -n 5 python scripts/oracle_distill_pooled.py --stage precheck --out runs/e24_pooled
    PYTHONPATH=. nice -n 5 python scripts/oracle_distill_pooled.py --stage gate --out runs/e24_pooled

``--stage select`` (training labels only, no episode played): the pool P0 (``teacher.pool.labels``: d24's
continuation labels, copied to runs/), every candidate's grouped K-fold held-out MSE, the zero-correction MSE and
d24's students' MSE on the other seeds' labels, the chosen candidate fitted on P0 -> OUT/select.json,
OUT/models/pool0.zip. ``--stage dagger``: the teacher block's training episodes with that student acting, labelled
by the oracle (OUT/labels_dagger.npz); the ensemble = the chosen candidate fitted on P0 + them once per
``pool.fit_seeds`` -> OUT/models/oracle_distilled_v2_seed{k}.zip. ``--stage precheck``: the pre-check's
training episodes with the ensemble acting, THE PRE-CHECK against d24's students (``--reference``, default
OUT/d24_models) -> OUT/precheck.json. ``--stage gate``: only after a passed pre-check; THE GATE -> OUT/gate.json.
``--stage schedules`` (training labels only, after ``select``, chooses nothing): every candidate held out by d24
file instead (the same wells, other schedules) -> OUT/schedules.json.
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
from oracle_distill_more import ROOT, play_design_gate, setup, students, table, write_json

from agents.evaluation.agent import AgentPolicy
from agents.evaluation.rollout import Runner
from agents.policies.ensemble import ensemble_spec
from agents.training.config import load_train_config
from agents.training.oracle_distill import ORACLE_POLICIES, oracle_episode_job, oracle_jobs
from agents.training.pooled_fit import (
    candidates,
    choose,
    clipped_mse,
    cv_table,
    fit_student,
    load_pool,
    precheck_passes,
)

CONFIG = ROOT / "configs/benchmark/v2_oracle_distilled_pooled.yaml"
GATE_SEEDS = list(range(21000, 21016))  # THE GATE's validation seeds (the config's history)
STAGES = ("select", "dagger", "precheck", "gate", "schedules")
NAME = "oracle_distilled"


def design(config: Path = CONFIG) -> dict[str, Any]:
    cfg, _, run, tuned, res = setup(config)
    t = run["teacher"]
    return {"cfg": cfg, "run": run, "tuned": tuned, "res": res, "teacher": t, "pool": t["pool"],
            "pk": load_train_config(run["config"], run.get("overrides")).policy_kwargs,
            "oracle": {**t["params"], "policies": [[b, tuned[b]["params"]] for b in ORACLE_POLICIES]},
            "env_kwargs": {**cfg["env_kwargs"], "scenario": "train"}}


def pool_paths(d: dict[str, Any], out: Path, with_dagger: bool) -> list[Path]:
    paths = [ROOT / d["pool"]["labels"].format(k=k) for k in range(d["pool"]["files"])]
    return paths + ([out / "labels_dagger.npz"] if with_dagger else [])


def model_mse(members: list[Any], x: np.ndarray, y: np.ndarray) -> float:
    """The clipped correction of the students' ensemble (one student: itself) - its members' mean - against the
    labels."""
    pred = np.mean([np.clip(m.model.predict(m.norm(x), deterministic=True)[0], -1, 1) for m in members], 0)
    return clipped_mse(pred, y)


def d24_heldout(ref: Path, d: dict[str, Any]) -> dict[str, Any]:
    """d24's continued students on the OTHER seeds' continuation labels (held out from them), for comparison."""
    labels = [np.load(p) for p in pool_paths(d, ref, False)]
    rows = {}
    for k in range(len(labels)):
        pol = AgentPolicy(str(ref / f"{NAME}_v2_seed{k}.zip"), str(ref / f"{NAME}_v2_seed{k}_obs_norm.npz"))
        rows[f"d24_seed{k}"] = {str(j): model_mse([pol], z["x"], z["label"]) for j, z in enumerate(labels) if j != k}
    rows["mean"] = float(np.mean([v for r in rows.values() for v in r.values()]))
    return rows


def select(out: Path, workers: int, ref: Path) -> dict[str, Any]:
    d = design()
    pool = load_pool(pool_paths(d, out, False), d["pool"]["episode_steps"])
    np.savez(out / "pool0.npz", x=pool["x"], label=pool["label"])
    with Runner(workers) as runner:
        rows = cv_table(runner, out / "pool0.npz", d["pool"], pool["key"], d["pk"], 0, out / "cv")
    best = choose(rows)
    zero = [float(np.mean(pool["label"][pool["key"] % d["pool"]["folds"] == f] ** 2))
            for f in range(d["pool"]["folds"])]
    fit_student(pool["x"], pool["label"], candidates(d["pool"])[best], d["pk"], 0, out / "models" / "pool0.zip")
    rec = {"stage": "select", "episodes": int(pool["group"].max()) + 1, "labels": len(pool["x"]), "table": rows,
           "chosen": best, "candidate": candidates(d["pool"])[best], "zero_correction_mse": float(np.mean(zero)),
           "zero_correction_mse_folds": zero, "d24_heldout": d24_heldout(ref, d)}
    write_json(out / "select.json", rec)
    return rec


def schedules(out: Path, workers: int) -> dict[str, Any]:
    """Read after the selection, used for nothing: every candidate held out by d24 FILE (the same training wells
    0..31, other schedules: what d24's held-out figures measured), against the pre-registered folds' held-out
    wells (episode j of every file is training well j)."""
    d = design()
    pool = load_pool(pool_paths(d, out, False), d["pool"]["episode_steps"])
    with Runner(workers) as runner:
        rows = cv_table(runner, out / "pool0.npz", {**d["pool"], "folds": d["pool"]["files"]}, pool["file"], d["pk"],
                        0, out / "cv_schedules")
    zero = [float(np.mean(pool["label"][pool["file"] == f] ** 2)) for f in range(d["pool"]["files"])]
    rec = {"stage": "schedules", "table": rows, "zero_correction_mse": float(np.mean(zero)),
           "zero_correction_mse_folds": zero}
    write_json(out / "schedules.json", rec)
    return rec


def label_episodes(d: dict[str, Any], student: dict[str, Any], seeds: list[int], workers: int,
                   dest: Path) -> list[dict[str, Any]]:
    """The oracle's labels on training ``seeds`` with ``student`` acting (beta 0), saved to ``dest``."""
    with Runner(workers) as runner:
        eps = runner.map(oracle_jobs(d["cfg"]["env_id"], d["env_kwargs"], d["oracle"], d["res"], student, seeds,
                                     0.0, d["run"]["seeds"][0]), fn=oracle_episode_job)
    if any(e["steps"] != d["pool"]["episode_steps"] for e in eps):
        raise RuntimeError(f"an episode of {[e['steps'] for e in eps]} rows: expected {d['pool']['episode_steps']}")
    np.savez(dest, **{k: np.concatenate([e[k] for e in eps]) for k in ("x", "label", "a_oracle", "a_base")})
    return eps


def summary(eps: list[dict[str, Any]]) -> dict[str, Any]:
    return {"episodes": len(eps), "mean_return": float(np.mean([e["reward"] for e in eps])),
            "cpu_s": float(sum(e["cpu_s"] for e in eps)), "seeds": [e["seed"] for e in eps]}


def dagger(out: Path, workers: int) -> dict[str, Any]:
    d = design()
    sel = json.loads((out / "select.json").read_text())
    t = d["teacher"]
    seeds = list(range(t["seed_start"], t["seed_start"] + t["iterations"] * t["episodes"]))
    first = {"path": str(out / "models" / "pool0.zip"), "obs_norm": str(out / "models" / "pool0_obs_norm.npz")}
    eps = label_episodes(d, first, seeds, workers, out / "labels_dagger.npz")
    pool = load_pool(pool_paths(d, out, True), d["pool"]["episode_steps"])
    losses = {}
    for k in d["pool"]["fit_seeds"]:
        pol, _ = fit_student(pool["x"], pool["label"], sel["candidate"], d["pk"], k,
                             out / "models" / f"{NAME}_v2_seed{k}.zip")
        losses[str(k)] = model_mse([pol], pool["x"], pool["label"])
    rec = {"stage": "dagger", "rollout": summary(eps), "pool_episodes": int(pool["group"].max()) + 1,
           "pool_labels": len(pool["x"]), "in_sample_mse": losses}
    write_json(out / "dagger.json", rec)
    return rec


def precheck(out: Path, workers: int, ref: Path) -> dict[str, Any]:
    d = design()
    p = d["pool"]
    ens = ensemble_spec(students(out / "models", NAME, p["fit_seeds"], d["res"]))
    seeds = list(range(p["precheck_seed_start"], p["precheck_seed_start"] + p["precheck_episodes"]))
    eps = label_episodes(d, {"members": ens["members"]}, seeds, workers, out / "labels_precheck.npz")
    z = np.load(out / "labels_precheck.npz")
    pooled = [AgentPolicy(m["path"], m["obs_norm"]) for m in ens["members"]]
    d24 = [AgentPolicy(s["path"], s["obs_norm"]) for s in students(ref, NAME, [0, 1, 2], {})]
    m_pooled = model_mse(pooled, z["x"], z["label"])
    m_d24 = {str(k): model_mse([s], z["x"], z["label"]) for k, s in enumerate(d24)}
    m_ref = float(np.mean(list(m_d24.values())))
    rec = {"stage": "precheck", "rollout": summary(eps), "pooled_ensemble_mse": m_pooled,
           "pooled_member_mse": {str(k): model_mse([s], z["x"], z["label"]) for k, s in zip(p["fit_seeds"], pooled)},
           "d24_student_mse": m_d24, "d24_mean_mse": m_ref, "ratio": m_pooled / m_ref, "ratio_max": p["precheck_ratio"],
           "d24_ensemble_mse": model_mse(d24, z["x"], z["label"]),
           "zero_correction_mse": float(np.mean(z["label"] ** 2)),
           "precheck": precheck_passes(m_pooled, m_ref, p["precheck_ratio"])}
    write_json(out / "precheck.json", rec)
    return rec


def require_precheck(out: Path) -> None:
    """Exit 2 in one line unless OUT/precheck.json records a passed pre-check (before any validation episode)."""
    pre = out / "precheck.json"
    if not pre.is_file() or json.loads(pre.read_text()).get("precheck") is not True:
        print(f"{Path(sys.argv[0]).stem}: {pre}: no passed pre-check: expected --stage precheck to pass before any "
              "validation episode", file=sys.stderr)
        sys.exit(2)


def gate(out: Path, workers: int) -> dict[str, Any]:
    require_precheck(out)
    d = design()
    ens = ensemble_spec(students(out / "models", NAME, d["pool"]["fit_seeds"], d["res"]))
    return play_design_gate(d["cfg"], CONFIG, GATE_SEEDS, {"pooled_ensemble": ens}, d["tuned"], d["res"], out,
                            workers)


def print_outcome(stage: str, rec: dict[str, Any]) -> None:
    """The pre-check's record (but its rollout) or the gate's table, then the verdict, as the stage prints them."""
    if stage == "precheck":
        print(json.dumps({k: v for k, v in rec.items() if k != "rollout"}))
        print("PRE-CHECK:", "passed" if rec["precheck"] else "failed")
    else:
        print("\n".join(table(rec["summary"])))
        print("GATE:", "passed" if rec["gate"] else "failed")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--reference", type=Path, default=None, help="d24's continued students (default OUT/d24_models)")
    a = arguments(ap, STAGES)
    ref = a.reference or a.out / "d24_models"
    if a.stage in ("select", "precheck") and not all(p.is_file() and not p.is_symlink() for p in
                                                      (ref / f"{NAME}_v2_seed{k}.zip" for k in range(3))):
        print(f"oracle_distill_pooled: --reference {str(ref)!r}: expected d24's students {NAME}_v2_seed0..2.zip "
              "(regular files)", file=sys.stderr)
        sys.exit(2)
    a.out.mkdir(parents=True, exist_ok=True)
    if a.stage in ("select", "schedules"):
        rec = select(a.out, a.workers, ref) if a.stage == "select" else schedules(a.out, a.workers)
        for i, r in enumerate(rec["table"]):
            print(f"{i:2d} epochs {r['epochs']:4d} wd {r['weight_decay']:g} net {r['net_arch']}: held-out MSE "
                  f"{r['heldout_mse']:.4f}" + ("  <- chosen" if i == rec.get("chosen") else ""))
        print(f"zero correction {rec['zero_correction_mse']:.4f}")
    elif a.stage == "dagger":
        print(json.dumps(dagger(a.out, a.workers)))
    else:
        print_outcome(a.stage, precheck(a.out, a.workers, ref) if a.stage == "precheck" else gate(a.out, a.workers))


if __name__ == "__main__":
    main()
