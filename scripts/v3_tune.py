"""Issue 24: the tuned baselines of ``srenv/SuckerRod-v3`` by the benchmark's own tuning code
(:func:`agents.benchmark.stages.tune_baselines`, as v2's were) on v3's TRAINING wells with v2.yaml's tuning seeds
(``configs/benchmark/v3.yaml``: train, seeds 0..9), beside v2's (``docs/v2/benchmark.json`` ``tuned``).

    PYTHONPATH=. nice -n 5 python scripts/v3_tune.py        # ~30 min on 2 loaded cores -> docs/v3/tuned.json

No flags. Writes ``docs/v3/tuned.json`` atomically (checked before the work): ``env_id``, ``config``, ``tuning``
(scenario, seeds, well_ids), ``tuned`` (every baseline's parameters and training score, the tuning history),
``v2_tuned`` and ``wall_time_s``. Only training wells are played; nothing is tested.
"""

from __future__ import annotations

import json
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
sys.path.insert(0, str(Path(__file__).resolve().parent))
from v3_mechanism import no_arguments

from agents.benchmark.config import load_benchmark_config
from agents.benchmark.report import _atomic_write, _json_clean
from agents.benchmark.stages import tune_baselines
from agents.evaluation.replay import load_report
from agents.evaluation.rollout import Runner
from agents.inputs import check_output_dir

ROOT = Path(__file__).resolve().parents[1]
CONFIG = ROOT / "configs" / "benchmark" / "v3.yaml"
OUT = ROOT / "docs" / "v3" / "tuned.json"
V2_REPORT = ROOT / "docs" / "v2" / "benchmark.json"


def main(argv: list[str] | None = None) -> None:
    no_arguments("v3_tune.py", argv)
    check_output_dir(OUT.parent, (OUT.name,))
    cfg = load_benchmark_config(CONFIG)
    t0 = time.perf_counter()
    with Runner(cfg["workers"]) as runner:
        tuned, split = tune_baselines(cfg, runner, lambda m: print(m, file=sys.stderr, flush=True))
    v2 = load_report(V2_REPORT)["tuned"]
    rec = {"env_id": cfg["env_id"], "config": str(CONFIG.relative_to(ROOT)), "tuning": split,
           "tuned": {n: {k: v for k, v in t.items() if k != "evaluated"} for n, t in tuned.items()},
           "tuning_history": {n: t.get("evaluated", []) for n, t in tuned.items()},
           "v2_tuned": {n: t.get("params") for n, t in v2.items()},
           "wall_time_s": time.perf_counter() - t0}
    _atomic_write(OUT, json.dumps(_json_clean(rec), indent=1))
    print(json.dumps({n: t["params"] for n, t in rec["tuned"].items() if n != "oracle"}))


if __name__ == "__main__":
    main()
