"""The causal oracle distilled into a field student (agents/training/oracle_distill.py), on v2's VALIDATION split.

The baselines' tuned parameters come from the v2 pilot's report (tuned on training wells); the student is
distilled on training-split episodes (seeds from --seed-start, outside tuning 0..9 and validation 20000..);
then the student (deterministic), fillage_pi and pump_off play the pilot's validation episodes (scenario
"validation", its seeds) with the same code, and the paired differences are reported per episode (USD/h =
return / 144 intervals), beside the causal oracle's figures from --oracle-jsonl if given. No test split.

    nice -n 8 python scripts/oracle_distill_pilot.py --out runs/oracle_distill \\
        --iterations 3 --episodes 30 --workers 2 --oracle-jsonl docs/archive/causal_oracle_pilot.jsonl
    # refit a student of another residual scale on the same labels, no new rollouts:
    python scripts/oracle_distill_pilot.py --out runs/oracle_distill --refit-scale 2.0
    # evaluate a distilled student again (no distillation): add --evaluate-only; a seed ensemble of several runs'
    # students: --evaluate-only --members DIR1 DIR2 DIR3
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np

from agents.benchmark.report import mean_ci
from agents.evaluation.rollout import Runner, episode_jobs
from agents.training.config import load_train_config
from agents.training.oracle_distill import distill_oracle

ROOT = Path(__file__).resolve().parents[1]
INTERVALS = 144  # a v2 episode: 24 h of 10-min intervals


def pilot_setup(path: Path, scale: float) -> dict:
    rep = json.loads(path.read_text())
    tuned = {k: v["params"] for k, v in rep["tuned"].items()}
    base = max(("best_constant", "pump_off", "fillage_pi"), key=lambda n: rep["tuned"][n]["score"])
    return {"env_id": rep["env_id"], "env_kwargs": rep["env_kwargs"], "tuned": tuned,
            "seeds": [e["seed"] for e in rep["policies"][base]["episodes"]],
            "residual": {"base": base, "params": tuned[base], "scale": scale},
            "oracle": {"horizon": 6, "replan_every": 3,
                       "policies": [[b, tuned[b]] for b in ("pump_off", "fillage_pi")]}}


def refit(out: Path, scale: float, seed: int, policy_kwargs: dict) -> dict:
    """A student of residual ``scale`` fitted on the saved labels (no DAgger of its own): the reach check."""
    from agents.evaluation.agent import AgentPolicy
    from agents.training.distill import fit_actor, write_student
    from agents.training.oracle_distill import fresh_student, label_of

    z = np.load(out / "student_labels.npz")
    dest = out / f"student_scale{scale:g}.zip"
    init = out / f"student_scale{scale:g}_init.zip"
    fresh_student(z["x"].shape[1], policy_kwargs, seed, init)
    st = AgentPolicy(str(init), str(out / "student_obs_norm.npz"))
    y = label_of(z["a_oracle"], z["a_base"], scale)
    for it in range(3):  # as many fits as the DAgger run, on all its labels
        fit_actor(st.model, st.norm(z["x"]), y, seed + it)
    write_student(init, st.model, dest)
    init.unlink()
    return {"path": str(dest), "obs_norm": str(out / "student_obs_norm.npz")}


def evaluate(setup: dict, specs: dict, workers: int) -> dict:
    kw = {**setup["env_kwargs"], "scenario": "validation"}
    out = {}
    with Runner(workers) as runner:
        for name, spec in specs.items():
            t0 = time.process_time()
            out[name] = runner.map(episode_jobs(setup["env_id"], kw, spec, setup["seeds"]))
            print(f"evaluated {name} ({time.process_time() - t0:.0f} s driver CPU)", file=sys.stderr, flush=True)
    return out


def table(eps: dict, oracle_jsonl: Path | None) -> dict:
    rewards = {k: np.array([e["reward"] for e in v]) for k, v in eps.items()}
    costs = {k: float(np.mean([e["cost"] for e in v])) for k, v in eps.items()}
    if oracle_jsonl:
        rows = [json.loads(line) for line in oracle_jsonl.read_text().splitlines() if line.strip()]
        rewards["causal_oracle"] = np.array([r["reward"] for r in rows])
        costs["causal_oracle"] = float(np.mean([r["cost"] for r in rows]))
    res = {"usd_h": {k: float(v.mean() / INTERVALS) for k, v in rewards.items()}, "mean_cost": costs,
           "paired_usd_h": {}}
    for a, ra in rewards.items():
        for b in ("fillage_pi", "pump_off"):
            rb = rewards.get(b)
            if a != b and rb is not None and len(ra) == len(rb):
                m, lo, hi = mean_ci((ra - rb) / INTERVALS)
                res["paired_usd_h"][f"{a} - {b}"] = {"mean": m, "ci95": [lo, hi], "wins": int(np.sum(ra > rb)),
                                                     "n": len(ra)}
    res["per_episode"] = {k: v.tolist() for k, v in rewards.items()}
    # the reward's terms and the mean operating point (SPM, stroke, ...) per policy: what each does differently
    res["terms_usd_h"] = {k: {t: float(np.mean([e[t] for e in v])) / INTERVALS for t in sorted(v[0])
                              if t.startswith(("reward_", "cost_"))} for k, v in eps.items()}
    res["operating_point"] = {k: {t: float(np.mean([e[t] for e in v])) for t in sorted(v[0]) if t.startswith("mean_")}
                              for k, v in eps.items()}
    res["episodes"] = eps
    return res


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--pilot", type=Path, default=ROOT / "docs/archive/benchmark_v2_pilot.json")
    ap.add_argument("--out", type=Path, required=True)
    ap.add_argument("--train-config", default=str(ROOT / "configs/train/ppo_residual_v2.yaml"))
    ap.add_argument("--iterations", type=int, default=3)
    ap.add_argument("--episodes", type=int, default=30)
    ap.add_argument("--seed-start", type=int, default=50000)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--scale", type=float, default=0.5)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--refit-scale", type=float, default=None)
    ap.add_argument("--evaluate-only", action="store_true", help="evaluate OUT/student.zip, no distillation")
    ap.add_argument("--members", type=Path, nargs="*", default=None,
                    help="with --evaluate-only: the seed ensemble of these runs' students (their mean correction)")
    ap.add_argument("--oracle-jsonl", type=Path, default=None)
    ap.add_argument("--val-episodes", type=int, default=None, help="the first N validation episodes (smoke runs)")
    a = ap.parse_args()
    setup = pilot_setup(a.pilot, a.scale)
    setup["seeds"] = setup["seeds"][:a.val_episodes]
    pk = load_train_config(a.train_config).policy_kwargs
    a.out.mkdir(parents=True, exist_ok=True)
    summary_path = a.out / "distill.json"
    if a.evaluate_only:
        spec = {"path": str(a.out / "student.zip"), "obs_norm": str(a.out / "student_obs_norm.npz")}
        residual, name = setup["residual"], "student"
    elif a.refit_scale is None:
        teacher = {"kind": "causal_oracle", "iterations": a.iterations, "episodes": a.episodes}
        seeds = list(range(a.seed_start, a.seed_start + a.iterations * a.episodes))
        with Runner(a.workers) as runner:
            spec = distill_oracle(runner, teacher, setup["oracle"], setup["residual"], setup["env_id"],
                                  {**setup["env_kwargs"], "scenario": "train"}, pk, seeds, a.seed,
                                  a.out / "student.zip", log=lambda m: print(m, file=sys.stderr, flush=True))
        summary_path.write_text(json.dumps({"args": {k: str(v) for k, v in vars(a).items()}, "spec": spec}, indent=1))
        residual, name = setup["residual"], "student"
    else:
        spec = refit(a.out, a.refit_scale, a.seed, pk)
        residual, name = {**setup["residual"], "scale": a.refit_scale}, f"student_scale{a.refit_scale:g}"
    specs = {name: {"kind": "agent", "path": spec["path"], "obs_norm": spec["obs_norm"], "residual": residual}}
    if a.members:
        name = "student_ensemble"
        specs = {name: {"kind": "ensemble", "residual": residual,
                        "members": [{"path": str(d / "student.zip"), "obs_norm": str(d / "student_obs_norm.npz")}
                                    for d in a.members]}}
    for b in ("fillage_pi", "pump_off"):
        specs[b] = {"kind": "baseline", "name": b, "params": setup["tuned"][b]}
    res = table(evaluate(setup, specs, a.workers), a.oracle_jsonl)
    (a.out / f"validation_{name}.json").write_text(json.dumps(res, indent=1))
    for k, v in res["usd_h"].items():
        print(f"{k:22s} {v:8.2f} USD/h  mean cost {res['mean_cost'][k]:.2f}")
    for k, v in res["paired_usd_h"].items():
        print(f"{k:36s} {v['mean']:+7.2f} [{v['ci95'][0]:+.2f}, {v['ci95'][1]:+.2f}] USD/h  wins {v['wins']}/{v['n']}")


if __name__ == "__main__":
    main()
