"""Issue 24, helper q44: the causal oracle distilled into field students TRAINED ON ``srenv/SuckerRod-v3``
(configs/benchmark/v3_oracle_distilled.yaml: v2_oracle_distilled.yaml's design on v3's physics), pre-registered,
gated, and only if the gate passes its one test look (the fresh look is the benchmark's ``--evaluate-only``).

    PYTHONPATH=. nice -n 5 python scripts/v3_oracle_distilled.py --stage dagger --out runs/q44 2> runs/q44_dagger.log
    PYTHONPATH=. nice -n 5 python scripts/v3_oracle_distilled.py --stage gate --out runs/q44
    PYTHONPATH=. nice -n 5 python scripts/v3_oracle_distilled.py --stage test --out runs/q44

``--stage dagger``: the config's 3 students (agents.benchmark.runs.oracle_student: DAgger from the causal oracle on
training-split episodes), on v3's tuned baselines of docs/v3/tuned.json -> OUT/models/oracle_distilled_v3_seed{k}
(+ statistics), their DAgger records in OUT/dagger.json (a student recorded there is not redone).
``--stage gate``: THE GATE, once: v3's tuned baselines and the students' ensemble on v3's validation split, the 50
episodes of :data:`GATE_SEEDS`, played and reported as scripts/v3_validation.py does (its ``play`` and ``figures``)
-> OUT/gate.json; :func:`gate` is the rule.
``--stage test`` (only after a passed gate): THE TEST LOOK, scripts/v2_test_look.py's ``test_look`` (the baselines
re-tuned by the benchmark's code and checked equal to docs/v3/tuned.json; the tuned baselines and the ensemble on
v3's 100 test episodes) -> OUT/benchmark.json (beside OUT/models, where ``--evaluate-only --report`` finds the
students); :func:`judge` is the rule -> OUT/test_judge.json.
``--stage fresh_judge`` (plays nothing): THE FRESH LOOK is the benchmark's own command (the config's history)

    python -m agents benchmark configs/benchmark/v3_oracle_distilled.yaml --evaluate-only --fresh-seed 20261207 \
        --episodes 40 --report runs/q44/benchmark.json --out-dir runs/q44/fresh

and this stage judges its report (OUT/fresh/benchmark.json) by :func:`judge` -> OUT/fresh_judge.json.
Each stage refuses to play (exit 2, one line) unless the config's history registers it in a committed file
(scripts/agreement_guard.py's ``require_registered`` with :data:`REGISTERS`).

``--design continued`` (helper w44; default ``trained``, q44's above): the same stages on
configs/benchmark/v3_oracle_distilled_continued.yaml - v2's SHIPPED students (models/oracle_distilled_v2_seed{k},
sha256 pinned: :data:`SHIPPED_SHA256`, checked before the DAgger and the gate) continued by DAgger from v3's causal
oracle; its gate on its own seeds (:data:`DESIGNS`) beside the unchanged shipped students (a reference):

    PYTHONPATH=. nice -n 5 python scripts/v3_oracle_distilled.py --design continued --stage dagger --out runs/w44
    PYTHONPATH=. nice -n 5 python scripts/v3_oracle_distilled.py --design continued --stage gate --out runs/w44
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
sys.path.insert(0, str(Path(__file__).resolve().parent))
from agreement_guard import require_registered
from estimated_mpc_pilot import arguments
from guard_described import registered
from guard_stroke import MODELS_SHA256
from oracle_distill_more import SHIPPED, SHIPPED_SEEDS, dagger, students
from v2_test_look import test_look
from v3_tune import OUT as TUNED
from v3_tune import ROOT
from v3_validation import TUNED_BASELINES, best_tuned, figures, play

from agents.benchmark.assemble import _ensemble_record
from agents.benchmark.config import load_benchmark_config
from agents.benchmark.fresh import _policies, load_tuned
from agents.benchmark.report import _atomic_write, _json_clean, build_report
from agents.benchmark.runs import residual_spec
from agents.policies.ensemble import ensemble_spec

CONFIG = ROOT / "configs/benchmark/v3_oracle_distilled.yaml"
GATE_SEEDS = list(range(21850, 21900))  # THE GATE's: v3 validation wells 0..49 once each (seed mod 50), unplayed
# the inner of the continued design: the shipped v2 students and their statistics, as its history registers them
SHIPPED_SHA256 = {**MODELS_SHA256,
                  "oracle_distilled_v2_seed0_obs_norm.npz": "ab90843de732475343f06582da0237419965bd66453ed651f7772b566842b9f8",
                  "oracle_distilled_v2_seed1_obs_norm.npz": "b3871fd9c69212ad7d2fc9236f9c2d568244ad36708e0d1132dd23c9b2ca6d23",
                  "oracle_distilled_v2_seed2_obs_norm.npz": "c73b91f46a8f8eae1f4b3cb8a9de74b36bb742028c6a58134a3d0426e216a3ec"}
# the designs (--design): q44's students trained on v3 from scratch, w44's shipped v2 students continued on v3 (their
# gate beside the unchanged shipped students, a reference); each its own config, gate seeds and out-of-git students
DESIGNS: dict[str, dict[str, Any]] = {
    "trained": {"config": CONFIG, "gate_seeds": GATE_SEEDS, "inner": False},
    "continued": {"config": ROOT / "configs/benchmark/v3_oracle_distilled_continued.yaml",
                  "gate_seeds": list(range(21900, 21950)),  # v3 validation wells 0..49 once each, unplayed
                  "inner": True}}
STAGES = ("dagger", "gate", "test", "fresh_judge")
# the words that start a history line (after "<date> <time> UTC, ") registering a stage, committed before it is played
REGISTERS = {"dagger": "REGISTERS THE DAGGER AND THE GATE", "gate": "REGISTERS THE DAGGER AND THE GATE",
             "test": "REGISTERS THE TEST LOOK", "fresh_judge": "REGISTERS THE FRESH LOOK"}
MARGIN = 0.10  # the test look's: >= +10 % of the best tuned baseline's reward rate


def setup(design: str = "trained") -> tuple[dict[str, Any], str, dict[str, Any], dict[str, Any], dict[str, Any]]:
    """(a design's config, run name, its run block, v3's tuned baselines, the residual spec)."""
    cfg = load_benchmark_config(str(DESIGNS[design]["config"]))
    (name, run), = cfg["agents"]["runs"].items()
    tuned = load_tuned(TUNED)
    return cfg, name, run, tuned, residual_spec(run, tuned)


def write(path: Path, obj: Any) -> None:
    _atomic_write(path, json.dumps(_json_clean(obj), indent=1))


def check_inner(design: str) -> None:
    """Stop unless a continued design's inner (the shipped v2 students and statistics) is the registered files."""
    if DESIGNS[design]["inner"]:
        for seed in SHIPPED_SEEDS:
            for f in (f"oracle_distilled_v2_seed{seed}.zip", f"oracle_distilled_v2_seed{seed}_obs_norm.npz"):
                registered(SHIPPED / f, SHIPPED_SHA256, "shipped v2 student's")


def shipped(res: dict[str, Any], runs: dict[str, Any]) -> tuple[dict[str, Any], dict[str, Any]]:
    """(spec, report record) of the unchanged shipped v2 students' ensemble on the design's residual base."""
    spec = {**ensemble_spec(students(SHIPPED, "oracle_distilled", SHIPPED_SEEDS, res)), "of": "oracle_distilled"}
    return spec, _ensemble_record(spec, runs, [])


def ensemble(out: Path, design: str = "trained") -> tuple[str, dict[str, Any], dict[str, Any]]:
    """(name, spec, report record) of the design: the run's students' ensemble, residual on its base."""
    cfg, name, run, _, res = setup(design)
    members = []
    for seed in run["seeds"]:
        path = out / "models" / f"{name}_v3_seed{seed}.zip"
        if not path.is_file():
            print(f"v3_oracle_distilled: {path}: no such student (run --stage dagger first)", file=sys.stderr)
            sys.exit(2)
        members.append({"kind": "agent", "path": str(path), "residual": res,
                        "obs_norm": str(path.with_name(path.stem + "_obs_norm.npz"))})
    spec = {**ensemble_spec(members), "of": name}
    return f"{name}_ensemble", spec, _ensemble_record(spec, cfg["agents"]["runs"], [])


def gate(fig: dict[str, Any], design: str, best: str) -> bool:
    """THE GATE: (design - best) paired 95 % CI lower bound over the wells > 0 AND design's mean cost <= best's."""
    return fig[design]["vs_best_tuned_usd_h"]["ci95_by_well"][0] > 0 and fig[design]["cost"] <= fig[best]["cost"]


def play_gate(out: Path, workers: int, design: str = "trained") -> dict[str, Any]:
    """THE GATE of ``design``: v3's tuned baselines, the design's ensemble (and, for a continued design, the unchanged
    shipped students, a reference) on its gate seeds -> OUT/gate.json."""
    t0 = time.perf_counter()
    cfg, _, _, tuned, res = setup(design)
    seeds = DESIGNS[design]["gate_seeds"]
    name, spec, rec = ensemble(out, design)
    specs = {n: [{"kind": "baseline", "name": n, "params": tuned[n]["params"]}] for n in TUNED_BASELINES}
    recs_of = {name: rec}
    if DESIGNS[design]["inner"]:
        check_inner(design)
        ref, recs_of["shipped_v2_ensemble"] = shipped(res, cfg["agents"]["runs"])
        specs["shipped_v2_ensemble"] = [ref]
    specs[name] = [spec]
    owner, recs = play({**cfg, "workers": workers}, specs, seeds)
    policies = _policies({"policies": recs_of}, specs, owner, recs, len(seeds))
    splits = {"test": {"scenario": "validation", "seeds": seeds,
                       "well_ids": [e["well_id"] for e in policies["installed"]["episodes"]]}}
    report = build_report(cfg, policies, splits, tuned, {"students": rec["models"]}, {})
    best = best_tuned(tuned)
    intervals = max(e["steps"] for e in policies["installed"]["episodes"])
    report.update(mode="v3_oracle_distilled_gate", tuned_from=str(TUNED.relative_to(ROOT)), residual_on=res,
                  best_tuned_baseline=best, intervals_per_episode=intervals, figures=figures(report, best, intervals))
    report["gate"] = {"design": name, "baseline": best, "passed": gate(report["figures"], name, best),
                      "rule": "paired 95 % CI lower bound over the 50 wells > 0 AND mean cost <= the baseline's"}
    report["wall_time_s"] = {"total": time.perf_counter() - t0}
    write(out / "gate.json", report)
    return report


def judge(report: dict[str, Any], design: str) -> dict[str, Any]:
    """THE TEST (and fresh) LOOK's rule: the design minus the best tuned baseline ON THOSE EPISODES (highest mean
    reward among the tuned field baselines played), over the wells' means (ci95_by_well): passes iff the mean
    difference >= +10 % of that baseline's reward rate, its CI lower bound > 0, and the design's cost <= the
    baseline's."""
    s = report["summary"]
    best = max((n for n in TUNED_BASELINES if n in s), key=lambda n: s[n]["mean_reward"])
    row = report["paired"][design][best]
    lo, hi = row.get("ci95_by_well", row["ci95"])
    steps = max(e["steps"] for e in report["policies"][best]["episodes"])
    rel = row["mean_diff_reward"] / abs(s[best]["mean_reward"])
    cost_d = float(np.mean([e["cost"] for e in report["policies"][design]["episodes"]]))
    cost_b = float(np.mean([e["cost"] for e in report["policies"][best]["episodes"]]))
    return {"design": design, "baseline": best, "diff_usd_h": row["mean_diff_reward"] / steps,
            "ci95_by_well_usd_h": [lo / steps, hi / steps], "relative": rel, "cost": cost_d, "baseline_cost": cost_b,
            "passed": bool(rel >= MARGIN and lo > 0 and cost_d <= cost_b)}


def play_test(out: Path, workers: int, design: str = "trained") -> dict[str, Any]:
    g = json.loads((out / "gate.json").read_text())
    if not g["gate"]["passed"]:
        print(f"v3_oracle_distilled: {out / 'gate.json'}: gate passed = False: expected a passed gate before the "
              "test look", file=sys.stderr)
        sys.exit(2)
    _, _, _, tuned, _ = setup(design)
    expected = {n: t["params"] for n, t in tuned.items() if n != "oracle"}
    report = test_look(str(DESIGNS[design]["config"]), out, None, workers, out, expected=expected)
    verdict = judge(report, g["gate"]["design"])
    write(out / "test_judge.json", verdict)
    return verdict


def main() -> None:
    ap = argparse.ArgumentParser(prog="v3_oracle_distilled", description=__doc__.split("\n")[0])
    ap.add_argument("--design", choices=tuple(DESIGNS), default="trained", help="the design (its config and gate)")
    a = arguments(ap, STAGES)
    require_registered(a.stage, DESIGNS[a.design]["config"], REGISTERS, "v3_oracle_distilled")
    a.out.mkdir(parents=True, exist_ok=True)
    if a.stage == "dagger":
        check_inner(a.design)
        done = dagger(a.out, a.workers, lambda: setup(a.design))
        print(json.dumps({k: v["distill"] for k, v in done.items()}, default=float))
    elif a.stage == "gate":
        rep = play_gate(a.out, a.workers, a.design)
        print(json.dumps({"gate": rep["gate"], "figures": {n: {k: f[k] for k in ("usd_h", "cost", "vs_best_tuned_usd_h")}
                                                            for n, f in rep["figures"].items()}}, default=float))
    elif a.stage == "test":
        print(json.dumps(play_test(a.out, a.workers, a.design), default=float))
    else:  # plays nothing: the fresh look's report (the benchmark's --evaluate-only, --out-dir OUT/fresh) judged
        verdict = judge(json.loads((a.out / "fresh" / "benchmark.json").read_text()), "oracle_distilled_ensemble")
        write(a.out / "fresh_judge.json", verdict)
        print(json.dumps(verdict, default=float))


if __name__ == "__main__":
    main()
