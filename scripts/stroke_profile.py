"""Where one exact stroke's CPU time goes in v2's env (docs/speed.md §2e): a train well with v2's per-well physics,
recorded strokes at one setpoint (12 SPM, 1.6 m) each summarised as the interval does (``IntervalRunner._figures``);
the self time of the stroke's Python parts (scripts/step_profile.py's timer, ~1-3 µs a call of its own).

    python scripts/stroke_profile.py [--well 11] [--strokes 60]
"""

from __future__ import annotations

import argparse
import json
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
    ("srenv.task.interval", "stroke_figures"),
)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--well", type=int, default=11, help="train split index")
    ap.add_argument("--strokes", type=int, default=60)
    args = ap.parse_args()
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
    for _ in range(3):  # the setpoint's linkage and caches, numba's cache loaded
        runner._figures(sim.run_stroke(12.0, 1.6, record=True))
    timer.ms.clear()
    timer.calls.clear()
    t0 = time.process_time()
    for _ in range(args.strokes):
        runner._figures(sim.run_stroke(12.0, 1.6, record=True))
    n = args.strokes
    print(json.dumps({"ms_per_stroke": 1e3 * (time.process_time() - t0) / n,
                      "self_us_per_stroke": {k: round(1e3 * v / n, 1)
                                             for k, v in sorted(timer.ms.items(), key=lambda kv: -kv[1])}}))


if __name__ == "__main__":
    main()
