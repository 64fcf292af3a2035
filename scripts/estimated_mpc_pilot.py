"""Issue 24, helper m24: how much of the causal oracle's edge a deployable model-based controller can keep.

``--stage voi`` (value of information; the first ``--first`` = 8 validation episodes): the causal oracle as shipped
(true well, true state, future frozen) and variants whose model is degraded toward what a field controller can
know - ``level``: the annulus level of the model set to the last acoustic shot (stale up to 4 h); ``inflow``: the
reservoir at multiplier 1 (its present draw unknown); ``condition``: no condition in the model (the active one
unknown); ``state``: all three (the true well, every state estimated) - and ``estimated_mpc`` (the deployable
policy: the planner on a twin of the nearest TRAINING well, agents/policies/estimated_mpc.py), beside the tuned
``alarm_pump_off`` and ``pump_off`` (docs/v2/benchmark.json's tuned parameters = docs/v2/fresh.json's). Round 2
(added after the gate failed): ``twin_true_well`` / ``twin_true_well_guarded``, the two pre-registered designs
with the played well itself as their twin (the pilot reads it; the policy does not) - the value of identifying the
well, with the deployable state estimate kept.

``--stage gate``: the pre-registered design (configs/benchmark/v2_estimated_mpc.yaml) on all 16 validation
episodes against ``alarm_pump_off``, and THE GATE written there.

Validation as the guard, alarm and history pilots play it (scripts/guard_pilot.py::play_validation): training
wells, the config's validation seeds 20000..20015. USD/h = return / 144.

    PYTHONPATH=. nice -n 5 python scripts/estimated_mpc_pilot.py --stage voi --out runs/m24_voi
    PYTHONPATH=. nice -n 5 python scripts/estimated_mpc_pilot.py --stage gate --out runs/m24_gate
"""

from __future__ import annotations

import argparse
import copy
import json
import sys
from concurrent.futures import ProcessPoolExecutor
from multiprocessing import get_context
from pathlib import Path
from typing import Any

import numpy as np
import yaml

sys.path.insert(0, str(Path(__file__).resolve().parent))
from guard_pilot import INTERVALS, summarise

from agents.benchmark.config import load_benchmark_config
from agents.evaluation.replay import load_report
from agents.evaluation.rollout import _cached_env, run_episode
from agents.evaluation.v1_view import build_policy_any
from agents.policies.causal_oracle import CausalOraclePolicy, freeze_future

ROOT = Path(__file__).resolve().parents[1]
CONFIG = ROOT / "configs/benchmark/v2_estimated_mpc.yaml"
V2 = ROOT / "configs/benchmark/v2.yaml"
REPORT = ROOT / "docs/v2/benchmark.json"
DEGRADED = {"co_level_shot": ("level",), "co_inflow1": ("inflow",), "co_nocondition": ("condition",),
            "co_state_estimated": ("level", "inflow", "condition")}
TWIN_TRUE = ("twin_true_well", "twin_true_well_guarded")
PLANNER = {"horizon": 6, "replan_every": 3}  # the causal oracle's, as shipped and on the fresh split


class DegradedOracle(CausalOraclePolicy):
    """The causal oracle on the true well with parts of its state replaced (the module doc); pilot only."""

    def __init__(self, degrade: tuple[str, ...] = (), **kw: Any) -> None:
        super().__init__(**kw)
        self.degrade = tuple(degrade)
        self._obs = np.zeros(0)

    def predict(self, observation: Any, state: Any = None, episode_start: Any = None,
                deterministic: bool = True) -> tuple[np.ndarray, Any]:
        self._obs = np.asarray(observation, np.float64).reshape(-1)
        return super().predict(observation, state, episode_start, deterministic)

    def _model(self) -> Any:
        from srenv.task import events as ev

        m = freeze_future(copy.deepcopy(self._env))
        ann = m.sim.annulus
        if "level" in self.degrade:
            shot = float(self._obs[list(m.obs_names).index("level_shot")])
            ann.volume_m3 = ann.area_m2 * min(max(shot * float(m.sim.mesh.x_m[-1]), 0.0), ann.pump_md_m)
        if "inflow" in self.degrade:
            m.inflow_multiplier = lambda t_s: 1.0
        if "condition" in self.degrade:
            ev.apply_condition(m.sim, m.cfg, None, 0.0)
            m._condition = (None, 0.0)
            m._schedule = ev.Schedule([])
        return m


class _TrueWell:
    """A 'library' that answers the played well itself (pilot only: the value of knowing the well)."""

    def __init__(self, well: int) -> None:
        self.well = well

    def nearest(self, obs: Any, names: Any) -> int:
        return self.well


def _twin_on_true_well(spec: dict[str, Any], env: Any) -> Any:
    """estimated_mpc whose twin is the played (training) well: the true parameters, the state estimated as the
    deployable policy estimates it (shots, pound corrections, no condition, deliverability 1)."""
    pol = build_policy_any(spec, env)
    pol.library = _TrueWell(int(env.unwrapped.well.well_id.split("-")[1]))
    return pol


def _job(job: dict[str, Any]) -> dict[str, Any]:
    import time

    import torch

    torch.set_num_threads(1)
    env = _cached_env(job["env_id"], job["env_kwargs"])
    if job["name"] in DEGRADED:
        pol: Any = DegradedOracle(DEGRADED[job["name"]], **job["spec"]["params"])
    elif job["name"].startswith(TWIN_TRUE[0]):  # also level_observer_pilot.py's twin_true_well_* rows
        pol = None  # built after reset, when the played well is known (the pilot reads it; the policy never does)
    else:
        pol = build_policy_any(job["spec"], env)
    t0 = time.process_time()
    if pol is None:
        env.reset(seed=job["seed"])
        pol = _twin_on_true_well(job["spec"], env)  # run_episode resets the env again: the same episode
    rec = run_episode(env, pol, job["seed"])
    rec["cpu_s"] = time.process_time() - t0
    rec["model_well"] = getattr(pol, "model_well", None)
    rec["sim_steps"] = getattr(pol, "sim_steps", None)
    rec["guarded_intervals"] = getattr(pol, "guarded_intervals", None)
    rec["observer_prod"] = getattr(getattr(pol, "_obs_level", None), "prod", None)  # the deliverability estimate
    return rec


def play(cfg: dict[str, Any], specs: dict[str, dict[str, Any]], seeds: list[int], out: Path,
         workers: int) -> dict[str, list[dict[str, Any]]]:
    """Every spec on the given validation seeds, cached per name in ``out/episodes.json`` (a later call plays only
    what is missing)."""
    kw = {**cfg["env_kwargs"], "scenario": "train"}  # the validation split: training wells, its own seeds
    out.mkdir(parents=True, exist_ok=True)
    cache = out / "episodes.json"
    eps: dict[str, Any] = json.loads(cache.read_text()) if cache.exists() else {}
    todo = [(n, s) for n in specs for s in seeds if s not in {e["seed"] for e in eps.get(n, [])}]
    jobs = [{"env_id": cfg["env_id"], "env_kwargs": kw, "name": n, "spec": specs[n], "seed": s} for n, s in todo]
    with ProcessPoolExecutor(workers, mp_context=get_context("spawn")) as pool:
        for (n, _), rec in zip(todo, pool.map(_job, jobs)):
            eps.setdefault(n, []).append(rec)
            tmp = cache.with_suffix(".tmp")
            tmp.write_text(json.dumps(eps))
            tmp.replace(cache)
    return {n: sorted([e for e in eps[n] if e["seed"] in seeds], key=lambda e: e["seed"]) for n in specs}


def specs_for(stage: str, tuned: dict[str, dict[str, Any]], designs: dict[str, Any] | None) -> dict[str, Any]:
    weigh = {"policies": [[b, tuned[b]] for b in ("pump_off", "fillage_pi")]}
    out = {b: {"kind": "baseline", "name": b, "params": tuned[b]} for b in ("alarm_pump_off", "pump_off")}
    if stage == "voi":
        out["causal_oracle"] = {"kind": "baseline", "name": "causal_oracle", "params": {**PLANNER, **weigh}}
        out.update({n: {"kind": "pilot", "name": n, "params": {**PLANNER, **weigh}} for n in DEGRADED})
        out["estimated_mpc"] = {"kind": "baseline", "name": "estimated_mpc", "params": {**PLANNER, **weigh}}
        # round 2 (after the gate of configs/benchmark/v2_estimated_mpc.yaml): the same policies, twin = true well
        designs = yaml.safe_load(CONFIG.read_text())["designs"]
        out["twin_true_well"] = {**designs["estimated_mpc"]}
        out["twin_true_well_guarded"] = {**designs["estimated_mpc_guarded"]}
    else:
        out.update(designs or {})
    return out


def gate(row: dict[str, Any], base: dict[str, Any]) -> bool:
    """THE GATE of configs/benchmark/v2_estimated_mpc.yaml: mean d >= +10 % of alarm_pump_off's USD/h AND the 95 %
    CI of mean d above zero AND mean cost <= alarm_pump_off's (d = paired return difference / 144)."""
    d = row["vs_alarm_pump_off"]
    return d["mean"] >= 0.10 * base["usd_h"] and d["ci95"][0] > 0 and row["cost"] <= base["cost"]


def arguments(ap: argparse.ArgumentParser, stages: tuple[str, ...]) -> argparse.Namespace:
    """The pilots' common flags (``--stage``, ``--out``, ``--workers``) parsed and checked: a bad one is refused in
    one line, exit 2, before anything is played or written."""
    ap.add_argument("--stage", choices=stages, required=True)
    ap.add_argument("--out", type=Path, required=True)
    ap.add_argument("--workers", type=int, default=2, help="worker processes, 1 or 2")
    a = ap.parse_args()
    bad = (f"--workers {a.workers}: expected 1 or 2 worker processes" if not 1 <= a.workers <= 2 else
           f"--out {str(a.out)!r}: expected a directory that is not a symlink (or a path not yet made)"
           if a.out.is_symlink() or a.out.is_file() else None)
    if bad:  # one line naming only the flag that is wrong
        print(f"{Path(ap.prog).stem}: {bad}", file=sys.stderr)
        sys.exit(2)
    return a


def outcome(stage: str, seeds: list[int], specs: dict[str, Any], eps: dict[str, list[dict[str, Any]]],
            bases: tuple[str, ...]) -> dict[str, Any]:
    """A pilot's record: its stage, seeds and specs, the summary against ``bases`` (with CPU s per episode) and
    every episode's USD/h."""
    summ = summarise(eps, bases)
    for n, e in eps.items():
        summ[n]["cpu_s_per_episode"] = float(np.mean([x["cpu_s"] for x in e]))
    return {"stage": stage, "seeds": seeds, "specs": specs, "summary": summ,
            "per_episode_usd_h": {k: [round(e["reward"] / INTERVALS, 3) for e in v] for k, v in eps.items()}}


def table(summ: dict[str, Any], bases: tuple[str, ...], guarded: dict[str, list[Any]] | None = None) -> list[str]:
    """The pilots' markdown table: USD/h, cost, paired differences against ``bases`` [95 % CI] wins, CPU s per
    episode, and (``guarded``) the intervals each design handed to its guard's fallback."""
    head = ["policy", "USD/h", "cost", *(f"vs {b} [95 % CI] wins" for b in bases), "CPU s/episode"]
    head += ["guarded intervals"] if guarded is not None else []
    rows = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for k, r in summ.items():
        cells = [f"{r[f'vs_{b}']['mean']:+.2f} [{r[f'vs_{b}']['ci95'][0]:+.2f}, {r[f'vs_{b}']['ci95'][1]:+.2f}] "
                 f"{r[f'vs_{b}']['wins']}/{r[f'vs_{b}']['n']}" if f"vs_{b}" in r else "0" for b in bases]
        row = [k, f"{r['usd_h']:.2f}", f"{r['cost']:.2f}", *cells, f"{r['cpu_s_per_episode']:.0f}"]
        if guarded is not None:
            g = guarded.get(k)
            row.append(str(sum(g)) if g else "-")
        rows.append("| " + " | ".join(row) + " |")
    return rows


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--first", type=int, default=8, help="voi: the first N validation episodes")
    a = arguments(ap, ("voi", "gate"))
    if not 1 <= a.first <= 16:
        print(f"estimated_mpc_pilot: --first {a.first}: expected 1 <= N <= 16", file=sys.stderr)
        sys.exit(2)
    cfg = load_benchmark_config(str(V2))  # the env, its kwargs and the validation seeds (= the design file's)
    seeds = list(cfg["validation"]["seeds"])[: a.first if a.stage == "voi" else None]
    tuned = {k: v["params"] for k, v in load_report(REPORT)["tuned"].items()}
    designs = yaml.safe_load(CONFIG.read_text())["designs"] if a.stage == "gate" else None
    specs = specs_for(a.stage, tuned, designs)
    eps = play(cfg, specs, seeds, a.out, min(a.workers, 2))
    res = outcome(a.stage, seeds, specs, eps, ("alarm_pump_off", "pump_off"))
    summ = res["summary"]
    res["model_well"] = [e["model_well"] for e in eps["estimated_mpc"]]
    res["guarded_intervals"] = {n: [e.get("guarded_intervals") for e in v] for n, v in eps.items()
                                if n.startswith("estimated_mpc")}
    if a.stage == "gate":
        res["gate"] = {n: gate(summ[n], summ["alarm_pump_off"]) for n in designs}
    (a.out / "pilot.json").write_text(json.dumps(res, indent=1))
    print("\n".join(table(summ, ("alarm_pump_off", "pump_off"))))
    if a.stage == "gate":
        print("GATE:", {n: "passed" if ok else "failed" for n, ok in res["gate"].items()})


if __name__ == "__main__":
    main()
