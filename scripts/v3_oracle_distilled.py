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
from oracle_distill_more import dagger
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
STAGES = ("dagger", "gate", "test", "fresh_judge")
# the words that start a history line (after "<date> <time> UTC, ") registering a stage, committed before it is played
REGISTERS = {"dagger": "REGISTERS THE DAGGER AND THE GATE", "gate": "REGISTERS THE DAGGER AND THE GATE",
             "test": "REGISTERS THE TEST LOOK", "fresh_judge": "REGISTERS THE FRESH LOOK"}
MARGIN = 0.10  # the test look's: >= +10 % of the best tuned baseline's reward rate


def setup() -> tuple[dict[str, Any], str, dict[str, Any], dict[str, Any], dict[str, Any]]:
    """(config, run name, its run block, v3's tuned baselines, the residual spec)."""
    cfg = load_benchmark_config(str(CONFIG))
    (name, run), = cfg["agents"]["runs"].items()
    tuned = load_tuned(TUNED)
    return cfg, name, run, tuned, residual_spec(run, tuned)


def write(path: Path, obj: Any) -> None:
    _atomic_write(path, json.dumps(_json_clean(obj), indent=1))


def ensemble(out: Path) -> tuple[str, dict[str, Any], dict[str, Any]]:
    """(name, spec, report record) of the design: the run's students' ensemble, residual on its base."""
    cfg, name, run, _, res = setup()
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


def play_gate(out: Path, workers: int) -> dict[str, Any]:
    t0 = time.perf_counter()
    cfg, _, _, tuned, res = setup()
    name, spec, rec = ensemble(out)
    specs = {n: [{"kind": "baseline", "name": n, "params": tuned[n]["params"]}] for n in TUNED_BASELINES}
    specs[name] = [spec]
    owner, recs = play({**cfg, "workers": workers}, specs, GATE_SEEDS)
    policies = _policies({"policies": {name: rec}}, specs, owner, recs, len(GATE_SEEDS))
    splits = {"test": {"scenario": "validation", "seeds": GATE_SEEDS,
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


def play_test(out: Path, workers: int) -> dict[str, Any]:
    g = json.loads((out / "gate.json").read_text())
    if not g["gate"]["passed"]:
        print(f"v3_oracle_distilled: {out / 'gate.json'}: gate passed = False: expected a passed gate before the "
              "test look", file=sys.stderr)
        sys.exit(2)
    _, _, _, tuned, _ = setup()
    expected = {n: t["params"] for n, t in tuned.items() if n != "oracle"}
    report = test_look(str(CONFIG), out, None, workers, out, expected=expected)
    verdict = judge(report, g["gate"]["design"])
    write(out / "test_judge.json", verdict)
    return verdict


def main() -> None:
    a = arguments(argparse.ArgumentParser(prog="v3_oracle_distilled", description=__doc__.split("\n")[0]), STAGES)
    require_registered(a.stage, CONFIG, REGISTERS, "v3_oracle_distilled")
    a.out.mkdir(parents=True, exist_ok=True)
    if a.stage == "dagger":
        print(json.dumps({k: v["distill"] for k, v in dagger(a.out, a.workers, setup).items()}, default=float))
    elif a.stage == "gate":
        rep = play_gate(a.out, a.workers)
        print(json.dumps({"gate": rep["gate"], "figures": {n: {k: f[k] for k in ("usd_h", "cost", "vs_best_tuned_usd_h")}
                                                            for n, f in rep["figures"].items()}}, default=float))
    elif a.stage == "test":
        print(json.dumps(play_test(a.out, a.workers), default=float))
    else:  # plays nothing: the fresh look's report (the benchmark's --evaluate-only, --out-dir OUT/fresh) judged
        verdict = judge(json.loads((a.out / "fresh" / "benchmark.json").read_text()), "oracle_distilled_ensemble")
        write(a.out / "fresh_judge.json", verdict)
        print(json.dumps(verdict, default=float))


if __name__ == "__main__":
    main()
