"""The test look of a causal-oracle distillation benchmark (configs/benchmark/v2_oracle_distilled.yaml), played
on what its pre-registered judge reads: the tuned baselines and the students' ensemble (issue 24).

Why this exists: the benchmark's own test stage plays every policy on the 100 test episodes - the clairvoyant
oracle (re-plans, ~1 min of CPU an episode) and each seed's student besides the ensemble - about 13,000 s of CPU,
more than the session that trained the students had left. The judge (the config's history) is the ensemble minus
the best tuned baseline on the test wells' means, at no higher constraint cost; neither the oracle nor the single
students enter it. So after the run's DAgger had written its three students (RUN/models), the run was stopped
before its validation and test stages, and this script plays the test look:

1. the baselines are tuned again with the benchmark's own code (:func:`agents.benchmark.stages.tune_baselines`;
   training wells only, deterministic) and checked equal to the parameters the run logged (``--log``);
2. the students are the run's files (``<run>_v*_seed<k>.zip`` with their observation statistics), on the
   residual base the run used (``residual_spec``: the best tuning score), as one ensemble (``ensemble_spec``);
3. the tuned baselines but the oracle, and the ensemble, play the config's test episodes;
4. RUN/benchmark.json and RUN/benchmark.md in the benchmark's schema, with the DAgger histories the run logged
   (no normalised score and no rliable block: no oracle was played; the fresh-split headline has them).

    python scripts/v2_test_look.py configs/benchmark/v2_oracle_distilled.yaml --run runs/v2_oracle_distilled \
        --log runs/v2od.log
"""

from __future__ import annotations

import argparse
import ast
import json
import re
import sys
import time
from pathlib import Path
from typing import Any

from agents.benchmark.assemble import _ensemble_record
from agents.benchmark.config import load_benchmark_config
from agents.benchmark.report import (
    _atomic_write,
    _json_clean,
    build_report,
    markdown_tables,
    verdict,
    write_markdown,
)
from agents.benchmark.runs import _policy_part, residual_spec
from agents.benchmark.stages import _mapped, tune_baselines
from agents.evaluation.rollout import Runner, episode_jobs
from agents.policies.ensemble import ensemble_spec
from agents.policies.factory import benchmark_baselines

_DISTILL = re.compile(r"^oracle distill seed (\d+): iteration (\d+): (\{.*\})$")
_TUNED = re.compile(r"^tuning: .* in [\d.]+ s; (.*)$")


def logged_run(log: Path) -> tuple[dict[str, dict[str, Any]], dict[int, list[dict[str, Any]]]]:
    """(tuned parameters by baseline, DAgger history by seed) as the run's log printed them (read as data)."""
    tuned: dict[str, dict[str, Any]] = {}
    hist: dict[int, list[dict[str, Any]]] = {}
    for line in log.read_text(encoding="utf-8", errors="replace").replace("\r", "\n").splitlines():
        if m := _TUNED.match(line):
            for part in re.findall(r"(\w+) (\{[^{}]*(?:\{[^{}]*\}[^{}]*)*\})(?:; |$)", m.group(1)):
                tuned[part[0]] = json.loads(part[1])
        elif m := _DISTILL.match(line):
            hist.setdefault(int(m.group(1)), []).append(ast.literal_eval(m.group(3)))
    return tuned, hist


def test_look(config: str, run_dir: Path, log: Path, workers: int | None = None) -> dict[str, Any]:
    cfg = load_benchmark_config(config)
    logged, hist = logged_run(log)
    (a, run), = cfg["agents"]["runs"].items()  # the design's one run
    t0 = time.perf_counter()
    with Runner(workers or cfg["workers"]) as runner:
        tuned, tuning_split = tune_baselines(cfg, runner, lambda m: print(m, file=sys.stderr, flush=True))
        for n, params in logged.items():  # the same tuning as the run's (deterministic), or stop here
            if n != "oracle" and tuned[n]["params"] != params:
                raise SystemExit(f"tuned {n} = {tuned[n]['params']}, the run logged {params}: not the run's tuning")
        wall = {"tuning": time.perf_counter() - t0}
        res = residual_spec(run, tuned)
        students = []
        for seed in run["seeds"]:
            path = next((run_dir / "models").glob(f"{a}_v*_seed{seed}.zip"))
            students.append({"kind": "agent", "path": str(path), "residual": res,
                             "obs_norm": str(path.with_name(path.stem + "_obs_norm.npz"))})
        ens = {**ensemble_spec(students), "of": a}
        bases = [n for n in benchmark_baselines(tuned) if n != "oracle"]
        entries = [(n, {"kind": "baseline", "name": n, "params": tuned[n]["params"]}) for n in bases]
        entries.append((f"{a}_ensemble", _policy_part(ens)))
        kwargs = {**cfg["env_kwargs"], "scenario": cfg["test"].get("scenario", "test")}
        seeds = cfg["test"]["seeds"]
        jobs = [j for _, sp in entries for j in episode_jobs(cfg["env_id"], kwargs, sp, seeds)]
        t1 = time.perf_counter()
        recs = _mapped(runner, jobs, "test")
        wall["test"] = time.perf_counter() - t1
    n_t = len(seeds)
    by = {n: recs[i * n_t:(i + 1) * n_t] for i, (n, _) in enumerate(entries)}
    policies: dict[str, Any] = {n: {"kind": "baseline", "params": tuned[n]["params"], "episodes": by[n]}
                                for n in bases}
    policies[f"{a}_ensemble"] = _ensemble_record(ens, cfg["agents"]["runs"], by[f"{a}_ensemble"])
    training = {"selection": cfg["agents"]["selection"], "runs": {},  # no single student was played on test
                "ensembles": {f"{a}_ensemble": {"of": a, "models": policies[f"{a}_ensemble"]["models"],
                                                "validation_reward": None}},
                "students": {a: {"config": run["config"], "seeds": run["seeds"],
                                 "teacher": {**run["teacher"], "observation": "true env state", "models": [],
                                             "distill": [{"seed": s, "iterations": hist.get(s)} for s in run["seeds"]]},
                                 "played_on_test": "in the ensemble only (scripts/v2_test_look.py)"}}}
    splits = {"tuning": tuning_split, "validation": {"scenario": "train", "seeds": [], "well_ids": [],
                                                    "note": "not played (selection: mean needs none)"},
              "test": {"scenario": kwargs["scenario"], "seeds": seeds,
                                               "well_ids": sorted({e["well_id"] for e in by[bases[0]]})}}
    wall["total"] = time.perf_counter() - t0
    report = build_report(cfg, policies, splits, {n: {k: v for k, v in t.items() if k != "evaluated"}
                                                   for n, t in tuned.items()}, training, wall)
    report["quick"] = False
    report["test_look"] = ("scripts/v2_test_look.py: the tuned baselines (not the clairvoyant oracle) and the "
                           "ensemble; the students trained by the benchmark run, stopped before its test stage")
    report = _json_clean(report)
    _atomic_write(run_dir / "benchmark.json", json.dumps(report, indent=1))
    write_markdown(report, run_dir / "benchmark.md", None)
    return report


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("config")
    p.add_argument("--run", type=Path, required=True, help="the benchmark run's --out-dir (its models/)")
    p.add_argument("--log", type=Path, required=True, help="the run's stderr (tuned parameters, DAgger history)")
    p.add_argument("--workers", type=int)
    args = p.parse_args()
    rep = test_look(args.config, args.run, args.log, args.workers)
    print(markdown_tables(rep))
    print(verdict(rep))


if __name__ == "__main__":
    main()
