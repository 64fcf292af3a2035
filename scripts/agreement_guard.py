"""Issue 24, helper u44: the SHIPPED oracle-distilled students trusted only where they agree, alarms first; chosen on
training wells; one gate; the looks only if it passes.

The shipped ensemble (models/oracle_distilled_v2_seed{0,1,2}.zip, residual on the tuned pump_off at scale 0.5, as its
test and fresh looks played it: scripts/guard_stroke.py's ``inner``, sha256 checked) failed its fresh look on cost
alone. Where its three members disagree they are extrapolating; there the residual is dropped and the base acts
(agents/policies/guarded.py ``disagreement_above``, a hard gate per interval), and with "alarms first" the tuned
alarm_pump_off is the base and acts on every interval its alarms act (``follow_alarms``), optionally on every
interval it idles (``follow_idle``). Everything is pre-registered in
configs/benchmark/v2_oracle_distilled_agreement.yaml (its ``history``); the stages are scripts/guard_described.py's,
handed this design's :data:`PLAN`:

    PYTHONPATH=. nice -n 5 python scripts/agreement_guard.py --stage select --out runs/u44 --workers 2
    PYTHONPATH=. nice -n 5 python scripts/agreement_guard.py --stage gate --out runs/u44 --workers 2
    PYTHONPATH=. nice -n 5 python scripts/agreement_guard.py --stage test --out runs/u44 --workers 2

``--stage select`` first plays the reference (the unguarded ensemble) on the selection's training wells with its
members' disagreement recorded on every interval (OUT/select/disagreement.json: the taus are its :data:`QUANTILES`),
then alarm_pump_off and every variant, THE RULE (guard_described.choose) -> OUT/select.json. Each stage refuses to
play unless the config's history registers it (:func:`require_registered`) in a committed file.
``--stage read`` (judging nothing): per variant, the selection episodes it changed (guard_stroke.read), and the
reference's disagreement on the played gate's validation wells beside the training wells' -> OUT/read.json.
"""

from __future__ import annotations

import argparse
import itertools
import json
import subprocess
import sys
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from estimated_mpc_pilot import arguments
from guard_described import BASE, REFERENCE, Plan, run_stage
from guard_stroke import FRESH_SEED, GATE_SEEDS, LOOK_NAME, inner, read
from oracle_distill_more import ROOT, write_json

from agents.benchmark.assemble import guarded_record
from agents.benchmark.config import load_benchmark_config
from agents.policies.guarded import check_guard, guarded_spec

CONFIG = ROOT / "configs/benchmark/v2_oracle_distilled_agreement.yaml"
SELECT_SEEDS = list(range(59500, 59550))  # THE SELECTION's: training wells 100..149 once each (seed mod 200)
STAGES = ("select", "gate", "test", "read")
# the words a history line must hold to register a stage (written, committed, before the stage is played): the
# design's first line holds the selection's; a later stage's line starts with its words ("<date> <time> UTC, REGISTERS
# THE GATE ...": the first line only names them)
REGISTERS = {"select": "BEFORE any selection or gate episode", "gate": "REGISTERS THE GATE",
             "test": "REGISTERS THE TEST LOOK"}


def registers(line: str, stage: str, words: dict[str, str] | None = None) -> bool:
    """Whether a history line registers ``stage`` (``words``: a design's {stage: words}, :data:`REGISTERS` by
    default; a stage's words start a line after its "<date> <time> UTC, ", except the selection's)."""
    w = (words or REGISTERS)[stage]
    return w in line if stage == "select" else line.partition(" UTC, ")[2].startswith(w)
assert FRESH_SEED == 20261206 and GATE_SEEDS == list(range(21750, 21800))  # b43's, registered and never played

# THE FAMILY (the config's history), declared once: the disagreement gate's tau (a quantile of the reference's
# per-interval disagreement on the selection's training wells) x the base the gate falls back to and what it follows
QUANTILES = (0.5, 0.8, 0.95)
MODES: dict[str, tuple[str, dict[str, bool]]] = {
    "agree": ("pump_off", {}),  # (a): the residual's own base, pump_off as trained
    "alarms": ("alarm_pump_off", {"follow_alarms": True}),  # (a) + (b) alarms first
    "alarms_idle": ("alarm_pump_off", {"follow_alarms": True, "follow_idle": True})}  # + (c) pump-off's idle


def family() -> dict[str, dict[str, Any] | None]:
    """{name: {"quantile", "guard", "fallback"}} - variant 0 (the reference: None), then the grid in declared order."""
    out: dict[str, dict[str, Any] | None] = {REFERENCE: None}
    for q, (m, (fb, flags)) in itertools.product(QUANTILES, MODES.items()):
        out[f"q{q}_{m}"] = {"quantile": q, "guard": dict(flags), "fallback": fb}
    return out


VARIANTS = family()
for _v in VARIANTS.values():  # every guard bounded where the guarded policy bounds it
    if _v is not None:
        check_guard({**_v["guard"], "disagreement_above": 0.0})


def require_registered(stage: str, config: Path = CONFIG, words: dict[str, str] | None = None,
                       who: str = "agreement_guard") -> None:
    """Stop (exit 2, one line) unless the config's history has the line registering ``stage`` and the config is
    committed as it is (no uncommitted change to it): a stage is played only after its registration. ``words``
    and ``who``: another design's registration words and script name (scripts/v3_oracle_distilled.py)."""
    hist = load_benchmark_config(str(config)).get("history") or []
    r = subprocess.run(["git", "status", "--porcelain", "--", str(config)], cwd=ROOT, capture_output=True, text=True,
                       check=False)
    why = (f"no history line with {(words or REGISTERS)[stage]!r}" if not any(registers(h, stage, words) for h in hist)
           else "not committed as it is (git status shows a change)" if r.returncode or r.stdout.strip() else None)
    if why:
        print(f"{who}: {config.name}: {why}: expected --stage {stage} registered before it is played",
              file=sys.stderr)
        sys.exit(2)


def _episode(seed: int, scenario: str = "train") -> dict[str, Any]:
    """One episode of the reference (the unguarded shipped ensemble) with its members' disagreement per interval."""
    import gymnasium as gym

    from agents.evaluation.agent import build_policy
    from agents.policies.guarded import ensemble_in

    env = gym.make("srenv/SuckerRod-v2", observation="field", scenario=scenario)
    pol = build_policy(inner(), env)
    ens = ensemble_in(pol)
    obs, _ = env.reset(seed=seed)
    pol.reset(env)
    values, ret, cost, done, info = [], 0.0, 0.0, False, {}
    while not done:
        act, _ = pol.predict(obs)
        values.append(round(float(ens.last_disagreement), 6))
        obs, r, term, trunc, info = env.step(act)
        ret, cost, done = ret + float(r), cost + float(info["cost"]), term or trunc
    return {"seed": seed, "well_id": info["well_id"], "reward": ret, "cost": cost, "disagreement": values}


def measure(seeds: list[int], scenario: str, workers: int) -> dict[str, Any]:
    """The reference's disagreement on every interval of ``seeds``' episodes and its :data:`QUANTILES` (numpy's
    linear quantiles of the pooled intervals): the taus."""
    with ProcessPoolExecutor(workers) as ex:
        eps = list(ex.map(_episode, seeds, [scenario] * len(seeds)))
    pooled = np.concatenate([e["disagreement"] for e in eps])
    return {"seeds": seeds, "scenario": scenario, "intervals": int(pooled.size),
            "taus": {str(q): float(np.quantile(pooled, q)) for q in QUANTILES},
            "share_above": {str(q): float(np.mean(pooled > np.quantile(pooled, q))) for q in QUANTILES},
            "episodes": eps}


def taus(out: Path | None) -> dict[str, float]:
    """The taus --stage select measured (OUT/select/disagreement.json); exit 2 in one line without them."""
    path = (out or ROOT / "runs/u44") / "select" / "disagreement.json"
    if not path.is_file() or path.is_symlink():
        print(f"agreement_guard: {path}: no such file: expected --stage select's reference run", file=sys.stderr)
        sys.exit(2)
    return {q: float(v) for q, v in json.loads(path.read_text())["taus"].items()}


def specs(out: Path | None, d: dict[str, Any], variants: dict[str, Any]) -> dict[str, dict[str, Any]]:
    """alarm_pump_off (the tuned parameters) and every variant's spec: the shipped ensemble under its gate at the
    measured tau, the fallback its mode's tuned base."""
    ens = inner()
    tuned = d["tuned"]
    t = taus(out) if any(v is not None for v in variants.values()) else {}
    return {BASE: {"kind": "baseline", "name": BASE, "params": tuned[BASE]["params"]},
            **{n: ens if v is None else guarded_spec(ens, v["fallback"], tuned[v["fallback"]]["params"],
                                                     {**v["guard"], "disagreement_above": t[str(v["quantile"])]})
               for n, v in variants.items()}}


def look_design(out: Path | None, name: str, tuned: dict[str, Any], to: Path | None) -> tuple[str, dict, dict]:
    """(report name, spec, record) of the chosen variant on the re-tuned baselines (the shipped models in models/)."""
    from oracle_distill_pooled import NAME, design

    d = {**design(CONFIG), "tuned": tuned}
    spec = specs(out, d, {name: VARIANTS[name]})[name]
    return LOOK_NAME, spec, guarded_record({**spec, "of": NAME}, d["cfg"]["agents"]["runs"], [])


PLAN = Plan(CONFIG, SELECT_SEEDS, GATE_SEEDS, VARIANTS, specs, look_design, precheck=False)


def reading(out: Path, workers: int) -> dict[str, Any]:
    """--stage read (judging nothing): guard_stroke.read on the selection's episodes, and, once the gate was played,
    the reference's disagreement on the gate's validation wells: the share of intervals above each training tau."""
    sel = json.loads((out / "select" / "episodes.json").read_text())
    rec: dict[str, Any] = {"select": read(sel), "taus": taus(out)}
    if (out / "gate" / "gate.json").is_file():
        val = measure(GATE_SEEDS, "validation", workers)
        pooled = np.concatenate([e["disagreement"] for e in val["episodes"]])
        rec["validation"] = {"intervals": int(pooled.size), "quantiles": val["taus"],
                             "share_above_training_tau": {q: float(np.mean(pooled > t)) for q, t in rec["taus"].items()}}
    write_json(out / "read.json", rec)
    return rec


def main() -> None:
    a = arguments(argparse.ArgumentParser(description=__doc__.splitlines()[0]), STAGES)
    if a.stage == "read":
        if not (a.out / "select" / "episodes.json").is_file():
            print(f"agreement_guard: {a.out / 'select' / 'episodes.json'}: no such file: expected --stage select's "
                  "episodes", file=sys.stderr)
            sys.exit(2)
        print(json.dumps(reading(a.out, a.workers), indent=1))
        return
    require_registered(a.stage)
    a.out.mkdir(parents=True, exist_ok=True)
    if a.stage == "select" and not (a.out / "select" / "disagreement.json").is_file():
        (a.out / "select").mkdir(exist_ok=True)
        write_json(a.out / "select" / "disagreement.json", measure(SELECT_SEEDS, "train", a.workers))
    run_stage(a.stage, a.out, a.workers, PLAN)


if __name__ == "__main__":
    main()
