"""Where one exact stroke's CPU time goes in v2's env (docs/speed.md §2e): a train well with v2's per-well physics,
recorded strokes at one setpoint (12 SPM, 1.6 m) each summarised as the interval does (``IntervalRunner._figures``);
the self time of the stroke's Python parts (scripts/step_profile.py's timer, ~1-3 µs a call of its own).

    python scripts/stroke_profile.py [--well 11] [--strokes 60]
    python scripts/stroke_profile.py --trees /tmp/before . --repeats 6   # interleaved, each tree its own process

``--trees``: each tree in its own process (``PYTHONPATH``), alternating which runs first, ``--repeats`` rounds; the
per-round ratios of ``ms_per_stroke`` and of the stroke's Python (``python_us_per_stroke``: the whole stroke less
the compiled kernel's ``run``) to the first tree's.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import time
import warnings

from step_profile import SelfTimer

PARTS = (
    ("srenv.numerics.kernel", "run"), ("srenv.numerics.kernel_layout", "build"),
    ("srenv.simulation.simulator", "Simulator._stepper"), ("srenv.simulation.simulator", "Simulator._run"),
    ("srenv.simulation.simulator", "Simulator.run_stroke"), ("srenv.simulation.simulator", "Simulator.energy_balance"),
    ("srenv.simulation.pump_cycle", "PumpCycle._on_event"), ("srenv.simulation.pump_cycle", "PumpCycle._cond_keep"),
    ("srenv.simulation.run_result", "trace_from_record"), ("srenv.analysis.stroke_summary", "summarize"),
    ("srenv.analysis.stroke_summary", "_stroke_figures"), ("srenv.analysis.stroke_summary", "goodman_per_taper"),
    ("srenv.surface_unit.surface", "SurfaceMotion.gearbox_report"), ("srenv.surface_unit.gearbox", "analyse_runs"),
    ("srenv.surface_unit.gearbox", "analyse"), ("srenv.surface_unit.gearbox", "stroke_crank_angle_rad"),
    ("srenv.surface_unit.gearbox", "_optimal"), ("srenv.surface_unit.gearbox", "GearboxReport.summary"),
    ("srenv.surface_unit.surface", "SurfaceMotion.stroke_motion"), ("srenv.analysis.card_features", "impact_speed_m_s"),
    ("srenv.analysis.card_features", "polished_rod_power_w"), ("srenv.analysis.card_features", "stick_slip_energy_j"),
    ("srenv.task.interval", "stroke_figures"), ("srenv.simulation.kernel_args", "KernelArgs.stepper"),
    ("srenv.numerics.kernel_layout", "for_run"), ("srenv.surface_unit.gearbox", "stroke_columns"),
)


def interleaved(trees: list[str], repeats: int, argv: list[str]) -> dict:
    """Each tree in its own process, the order alternating round by round; medians and per-round ratios."""
    rows: dict[str, list[dict]] = {t: [] for t in trees}
    for r in range(repeats):
        for tree in (trees if r % 2 == 0 else trees[::-1]):
            env = dict(os.environ, PYTHONPATH=os.path.abspath(tree))
            p = subprocess.run([sys.executable, os.path.abspath(__file__), *argv], capture_output=True, text=True,
                               env=env, cwd=os.path.abspath(tree), check=True)
            rows[tree].append(json.loads(p.stdout.strip().splitlines()[-1]))
    out = {}
    for t, rs in rows.items():
        out[t] = {k: round(statistics.median(x[k] for x in rs), 4) for k in ("ms_per_stroke", "python_us_per_stroke")}
        if t != trees[0]:
            for k in ("ms_per_stroke", "python_us_per_stroke"):
                ratios = [a[k] / b[k] for a, b in zip(rs, rows[trees[0]])]
                out[t][f"{k}_ratio_min_median_max"] = [round(f(ratios), 3) for f in (min, statistics.median, max)]
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--well", type=int, default=11, help="train split index")
    ap.add_argument("--strokes", type=int, default=60)
    ap.add_argument("--defer", action="store_true", help="summaries as an interval's strokes that are not its last "
                    "(the gearbox's optimal counterbalance and powers deferred, never completed; this tree's option)")
    ap.add_argument("--trees", nargs="+", help="project trees to compare, interleaved (the first is the base)")
    ap.add_argument("--repeats", type=int, default=6)
    args = ap.parse_args()
    if args.trees:
        print(json.dumps(interleaved(args.trees, args.repeats, ["--well", str(args.well), "--strokes",
                                                                   str(args.strokes)]), indent=1))
        return
    warnings.filterwarnings("ignore")
    from srenv.config import load_config
    from srenv.envs.sucker_rod_v2 import physics_overrides
    from srenv.simulation.simulator import Simulator
    from srenv.task import well_family as wf
    from srenv.task.interval import IntervalRunner

    timer = SelfTimer()
    for module, qualname in PARTS:
        timer.wrap(module, qualname)
    spec = wf.build_spec("train", args.well)
    sim = Simulator(load_config(spec.cfg, physics_overrides(spec)))
    sim.reset(fluid_level_m=500.0)
    runner = IntervalRunner(sim)
    kw = {"defer": True} if args.defer else {}
    for _ in range(3):  # the setpoint's linkage and caches, numba's cache loaded
        runner._figures(sim.run_stroke(12.0, 1.6, record=True), **kw)
    timer.ms.clear()
    timer.calls.clear()
    t0 = time.process_time()
    for _ in range(args.strokes):
        runner._figures(sim.run_stroke(12.0, 1.6, record=True), **kw)
    n = args.strokes
    ms = 1e3 * (time.process_time() - t0) / n
    print(json.dumps({"ms_per_stroke": ms, "python_us_per_stroke": 1e3 * ms - 1e3 * timer.ms.get("run", 0.0) / n,
                      "self_us_per_stroke": {k: round(1e3 * v / n, 1)
                                             for k, v in sorted(timer.ms.items(), key=lambda kv: -kv[1])}}))


if __name__ == "__main__":
    main()
