"""Issue 24, helper s24: the annulus-level observer and the classifier's condition in estimated_mpc's twin.

``--stage observer`` (training wells only: 16..40 by default, seeds 30016..; never a validation, test or fresh
well): ``alarm_pump_off`` (tuned, docs/v2/benchmark.json) drives each episode; three level estimates ride along,
given the same observations and actions - ``shot`` (the last acoustic shot, held), ``m24`` (estimated_mpc's twin as
merged: shots and the pound/refill rules) and ``observer`` (agents/policies/level_observer.py: the inflow balance
with the deliverability estimated from successive shots) - each with the played well as the twin and with the
nearest OTHER training well (leave-one-out on the library). The pilot reads the true level to MEASURE the error;
the estimators never do. The classifier's condition (``condition_estimate``, threshold 0.6) is scored against the
true condition of each interval.

``--stage voi``: m24's value-of-information rows with these estimates on the first 8 validation episodes
(scripts/estimated_mpc_pilot.py's player): twin = the played well (names ``twin_true_well*``: the pilot tells the
policy the well), then twin = the nearest training well (``estimated_mpc*``).

    PYTHONPATH=. nice -n 5 python scripts/level_observer_pilot.py --stage observer --out runs/s24_observer
    PYTHONPATH=. nice -n 5 python scripts/level_observer_pilot.py --stage voi --out runs/s24_voi_floor1
"""

from __future__ import annotations

import argparse
import json
import sys
from concurrent.futures import ProcessPoolExecutor
from multiprocessing import get_context
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from estimated_mpc_pilot import PLANNER, REPORT, V2, _TrueWell, play
from guard_pilot import summarise

from agents.benchmark.config import load_benchmark_config
from agents.evaluation.replay import load_report
from agents.policies.alarms import make_field_controller
from agents.policies.estimated_mpc import LIBRARY, EstimatedMPCPolicy, WellLibrary
from agents.policies.level_observer import condition_estimate
from srenv.task.events import NORMAL

THRESHOLD = 0.6  # the classifier's probability for a condition in the twin (m24's guard used the same)
ESTIMATES = {"m24": {}, "observer": {"observer": True}}


def _library_without(well: int) -> WellLibrary:
    with np.load(LIBRARY, allow_pickle=False) as d:
        keep = d["wells"] != well
        return WellLibrary(d["wells"][keep], d["features"][keep], d["names"])


def observe_episode(job: dict[str, Any]) -> dict[str, Any]:
    """One training-well episode driven by alarm_pump_off; every estimate's level and the truth per interval."""
    from srenv.envs.sucker_rod_v2 import SuckerRodV2Env

    env = SuckerRodV2Env(scenario="train", observation="field")
    obs, _ = env.reset(seed=job["seed"])
    well = int(env.unwrapped.well.well_id.split("-")[1])
    names = list(env.unwrapped.obs_names)
    driver = make_field_controller("alarm_pump_off", job["alarm"], names)
    driver.reset(env)
    ests = {}
    for twin in ("true", "nearest"):
        for k, kw in ESTIMATES.items():
            pol = EstimatedMPCPolicy(**PLANNER, **kw)
            pol.library = _TrueWell(well) if twin == "true" else _library_without(well)
            pol.reset(env)
            ests[f"{k}_{twin}"] = pol
    rec: dict[str, Any] = {"seed": job["seed"], "well": well, "true_m": [], "shot_m": [],
                           **{k: [] for k in ests}, "label": [], "true_label": [], "prod": []}
    st, start, done = None, True, False
    depth = float(env.unwrapped.sim.mesh.x_m[-1])
    i = names.index
    info: dict[str, Any] = {"condition": "full"}
    while not done:
        row = np.asarray(obs, np.float64)
        rec["true_m"].append(float(env.unwrapped.sim.annulus.level_m))  # measuring only
        rec["shot_m"].append(float(row[i("level_shot")]) * depth)
        for k, pol in ests.items():
            pol.track(row)
            rec[k].append(float(pol._twin.sim.annulus.level_m))
        rec["prod"].append(float(ests["observer_true"]._obs_level.prod))
        rec["label"].append(condition_estimate(row, names, THRESHOLD)[0])
        rec["true_label"].append(info["condition"])  # the condition of the interval whose card this is
        a, st = driver.predict(row, state=st, episode_start=np.array([start]))
        start = False
        for pol in ests.values():
            pol.played(a)
        obs, _, term, trunc, info = env.step(np.asarray(a, np.float32).reshape(2))
        rec.setdefault("true_prod", []).append(float(info["inflow_multiplier"]))
        done = term or trunc
    return rec


def observer_summary(recs: list[dict[str, Any]]) -> dict[str, Any]:
    truth = np.concatenate([r["true_m"] for r in recs])
    out: dict[str, Any] = {"wells": [r["well"] for r in recs], "intervals": int(truth.size), "level_error_m": {}}
    for k in ["shot", *(f"{e}_{t}" for t in ("true", "nearest") for e in ESTIMATES)]:
        est = np.concatenate([r[k if k != "shot" else "shot_m"] for r in recs])
        err = np.abs(est - truth)
        out["level_error_m"][k] = {"mae": float(err.mean()), "rmse": float(np.sqrt(np.mean(err ** 2))),
                                   "p90": float(np.quantile(err, 0.9)), "max": float(err.max())}
    lab = [(p, t) for r in recs for p, t in zip(r["label"][1:], r["true_label"][1:])]
    abnormal = [(p, t) for p, t in lab if t not in NORMAL and t != "parted_rods"]
    normal = [(p, t) for p, t in lab if t in NORMAL]
    out["condition"] = {"abnormal_intervals": len(abnormal), "right": sum(p == t for p, t in abnormal),
                        "none_given": sum(p is None for p, _ in abnormal), "normal_intervals": len(normal),
                        "false_alarms": sum(p is not None for p, _ in normal),
                        "by_true_label": {t: {"n": sum(tt == t for _, tt in abnormal),
                                              "right": sum(p == t for p, tt in abnormal if tt == t)}
                                          for t in sorted({t for _, t in abnormal})}}
    end = [(r["prod"][-1], r["true_prod"][-1]) for r in recs]
    out["deliverability_end"] = {"mae_observer_true_twin": float(np.mean([abs(a - b) for a, b in end])),
                                 "mae_of_1": float(np.mean([abs(1 - b) for _, b in end]))}
    return out


def voi_specs(tuned: dict[str, dict[str, Any]]) -> dict[str, Any]:
    import yaml
    from estimated_mpc_pilot import CONFIG

    designs = yaml.safe_load(CONFIG.read_text())["designs"]
    out: dict[str, Any] = {b: {"kind": "baseline", "name": b, "params": tuned[b]} for b in ("alarm_pump_off", "pump_off")}
    for twin in ("twin_true_well", "estimated_mpc"):
        for g, d in (("", "estimated_mpc"), ("_guarded", "estimated_mpc_guarded")):
            p = designs[d]["params"]
            out[f"{twin}_observer{g}"] = {**designs[d], "params": {**p, "observer": True}}
            out[f"{twin}_observer_condition{g}"] = {**designs[d], "params": {**p, "observer": True,
                                                                               "condition_prob": THRESHOLD}}
    for twin in ("twin_true_well", "estimated_mpc"):  # the condition alone (m24's level estimate)
        for g, d in (("", "estimated_mpc"), ("_guarded", "estimated_mpc_guarded")):
            out[f"{twin}_condition{g}"] = {**designs[d], "params": {**designs[d]["params"], "condition_prob": THRESHOLD}}
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--stage", choices=("observer", "voi"), required=True)
    ap.add_argument("--out", type=Path, required=True)
    ap.add_argument("--wells", type=int, nargs=2, default=(16, 40), help="observer: training wells FIRST LAST")
    ap.add_argument("--workers", type=int, default=2)
    a = ap.parse_args()
    lo, hi = a.wells
    if a.out.is_symlink() or a.out.is_file() or not 16 <= lo <= hi <= 199:
        print(f"level_observer_pilot: --out {str(a.out)!r} / --wells {lo} {hi}: expected a directory that is not a "
              "symlink and training wells within 16..199 (0..15 are the tuning and validation wells)", file=sys.stderr)
        sys.exit(2)
    a.out.mkdir(parents=True, exist_ok=True)
    tuned = {k: v["params"] for k, v in load_report(REPORT)["tuned"].items()}
    if a.stage == "observer":
        jobs = [{"seed": 30000 + w, "alarm": tuned["alarm_pump_off"]} for w in range(lo, hi + 1)]
        with ProcessPoolExecutor(min(a.workers, 2), mp_context=get_context("spawn")) as pool:
            recs = list(pool.map(observe_episode, jobs))
        res = {"stage": "observer", "seeds": [j["seed"] for j in jobs], "summary": observer_summary(recs)}
        (a.out / "episodes.json").write_text(json.dumps(recs))
    else:
        cfg = load_benchmark_config(str(V2))
        seeds = list(cfg["validation"]["seeds"])[:8]
        specs = voi_specs(tuned)
        eps = play(cfg, specs, seeds, a.out, min(a.workers, 2))
        summ = summarise(eps, ("alarm_pump_off",))
        for n, e in eps.items():
            summ[n]["cpu_s_per_episode"] = float(np.mean([x["cpu_s"] for x in e]))
        res = {"stage": "voi", "seeds": seeds, "specs": specs, "summary": summ,
               "per_episode_usd_h": {k: [round(e["reward"] / 144, 3) for e in v] for k, v in eps.items()},
               "model_well": {k: [e["model_well"] for e in v] for k, v in eps.items() if "observer" in k}}
    tmp = a.out / "pilot.json.tmp"
    tmp.write_text(json.dumps(res, indent=1))
    tmp.replace(a.out / "pilot.json")
    print(json.dumps(res["summary"], indent=1)[:6000])


if __name__ == "__main__":
    main()
