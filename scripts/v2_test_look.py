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

With a ``guarded:`` block in the config (configs/benchmark/v2_oracle_distilled_guarded.yaml) the design is the same
students' ensemble under the constraint guard (agents/policies/guarded.py), the fallback its tuned baseline; the
report goes to ``--out`` (the students copied to OUT/models, so ``replay`` and ``--evaluate-only --report`` find them):

    python scripts/v2_test_look.py configs/benchmark/v2_oracle_distilled_guarded.yaml \
        --run runs/v2_oracle_distilled --log runs/v2od.log --out runs/v2_oracle_distilled_guarded
"""

from __future__ import annotations

import argparse
import ast
import json
import re
import shutil
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

from agents.benchmark.assemble import _ensemble_record, guarded_record
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
from agents.benchmark.stages import design_guarded, run_test_episodes, tune_baselines
from agents.evaluation.rollout import Runner
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


def design(cfg: dict[str, Any], run_dir: Path, tuned: dict[str, Any], out_dir: Path) -> tuple[str, dict, dict]:
    """(policy name, spec, report record) of the design the config's judge reads: the run's students' ensemble,
    or - with a ``guarded:`` block (configs/benchmark/v2_oracle_distilled_guarded.yaml) - that ensemble under
    the constraint guard (agents/policies/guarded.py; the students copied to OUT/models, where the report's
    ``models/`` names resolve for replay and --evaluate-only)."""
    (a, run), = cfg["agents"]["runs"].items()  # the design's one run
    res = residual_spec(run, tuned)
    students = []
    for seed in run["seeds"]:
        path = next((run_dir / "models").glob(f"{a}_v*_seed{seed}.zip"))
        students.append({"kind": "agent", "path": str(path), "residual": res,
                         "obs_norm": str(path.with_name(path.stem + "_obs_norm.npz"))})
    ens = {**ensemble_spec(students), "of": a}
    g = cfg.get("guarded")
    if not g:
        return f"{a}_ensemble", _policy_part(ens), _ensemble_record(ens, cfg["agents"]["runs"], [])
    if out_dir.resolve() != run_dir.resolve():
        (out_dir / "models").mkdir(parents=True, exist_ok=True)
        for st in students:
            for f in (Path(st["path"]), Path(st["obs_norm"])):
                shutil.copyfile(f, out_dir / "models" / f.name)
    spec = design_guarded(cfg, tuned, ens, a)
    rec = guarded_record(spec, cfg["agents"]["runs"], [])
    return f"{a}_guarded", _policy_part(spec), rec


def test_look(config: str, run_dir: Path, log: Path | None, workers: int | None = None,
              out_dir: Path | None = None, built: Callable[[dict[str, Any]], tuple[str, dict, dict]] | None = None,
              expected: dict[str, dict[str, Any]] | None = None) -> dict[str, Any]:
    """The look. A caller with its own design (scripts/guard_described.py: d42's fits under a guard) hands
    ``built`` (the re-tuned baselines -> (name, spec, report record)) and ``expected`` (the tuned parameters the
    design was gated with, checked instead of the run's ``log``)."""
    cfg = load_benchmark_config(config)
    out_dir = out_dir or run_dir
    logged, hist = (expected, {}) if expected is not None else logged_run(log)
    (a, run), = cfg["agents"]["runs"].items()
    t0 = time.perf_counter()
    with Runner(workers or cfg["workers"]) as runner:
        tuned, tuning_split = tune_baselines(cfg, runner, lambda m: print(m, file=sys.stderr, flush=True))
        for n, params in logged.items():  # the same tuning as the run's (deterministic), or stop here
            if n != "oracle" and tuned[n]["params"] != params:
                raise SystemExit(f"tuned {n} = {tuned[n]['params']}, the run logged {params}: not the run's tuning")
        wall = {"tuning": time.perf_counter() - t0}
        name, spec, rec = built(tuned) if built else design(cfg, run_dir, tuned, out_dir)
        bases = [n for n in benchmark_baselines(tuned) if n != "oracle"]
        t1 = time.perf_counter()
        by_entry = run_test_episodes(cfg, runner, tuned, {name: [spec]}, -1, policies=bases)
        wall["test"] = time.perf_counter() - t1
    seeds = cfg["test"]["seeds"]
    policies: dict[str, Any] = {n: {"kind": "baseline", "params": tuned[n]["params"], "episodes": by_entry[(n, -1)]}
                                for n in bases}
    policies[name] = {**rec, "episodes": by_entry[(name, 0)]}
    training = {"selection": cfg["agents"]["selection"], "runs": {},  # no single student was played on test
                "ensembles": {name: {"of": a, "models": rec["models"], "validation_reward": None}},
                "students": {a: {"config": run["config"], "seeds": run["seeds"],
                                 "teacher": {**run["teacher"], "observation": "true env state", "models": [],
                                             "distill": [{"seed": s, "iterations": hist.get(s)} for s in run["seeds"]]},
                                 "played_on_test": f"in {name} only (scripts/v2_test_look.py)"}}}
    splits = {"tuning": tuning_split, "validation": {"scenario": "train", "seeds": [], "well_ids": [],
                                                    "note": "not played (selection: mean needs none)"},
              "test": {"scenario": cfg["test"].get("scenario", "test"), "seeds": seeds,
                       "well_ids": sorted({e["well_id"] for e in policies[bases[0]]["episodes"]})}}
    wall["total"] = time.perf_counter() - t0
    report = build_report(cfg, policies, splits, {n: {k: v for k, v in t.items() if k != "evaluated"}
                                                   for n, t in tuned.items()}, training, wall)
    report["quick"] = False
    report["test_look"] = (f"scripts/v2_test_look.py: the tuned baselines (not the clairvoyant oracle) and {name}; "
                           "the students trained by the benchmark run, stopped before its test stage")
    report = _json_clean(report)
    out_dir.mkdir(parents=True, exist_ok=True)
    _atomic_write(out_dir / "benchmark.json", json.dumps(report, indent=1))
    write_markdown(report, out_dir / "benchmark.md", None)
    return report


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("config")
    p.add_argument("--run", type=Path, required=True, help="the benchmark run's --out-dir (its models/)")
    p.add_argument("--log", type=Path, required=True, help="the run's stderr (tuned parameters, DAgger history)")
    p.add_argument("--workers", type=int)
    p.add_argument("--out", type=Path, help="where the report goes (default: --run)")
    args = p.parse_args()
    rep = test_look(args.config, args.run, args.log, args.workers, args.out)
    print(markdown_tables(rep))
    print(verdict(rep))


if __name__ == "__main__":
    main()
