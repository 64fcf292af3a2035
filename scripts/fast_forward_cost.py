"""CPU µs of one interval's fast-forward (``IntervalRunner._repeat_stroke``) by stroke count, the compiled loop
against the Python one it replaced (docs/speed.md §2e): a train well of v2's scenario at 12 SPM.

    python scripts/fast_forward_cost.py
"""

from __future__ import annotations

import copy
import json
import time
import warnings


def cost_us(compiled: bool, strokes: int, calls: int = 200) -> float:
    from srenv.simulation.simulator import Simulator
    from srenv.task import interval
    from srenv.task import well_family as wf
    from srenv.task.interval import IntervalResult, IntervalRunner

    sim = Simulator(wf.build_spec("train", 11).cfg)
    sim.reset(fluid_level_m=300.0)
    runner = IntervalRunner(sim, draw_at_top=True)
    f = runner._figures(sim.run_stroke(12.0, 1.6, record=True))
    applies = interval.compiled_applies
    interval.compiled_applies = applies if compiled else (lambda s: False)
    try:
        runner.sim = copy.deepcopy(sim)
        res = IntervalResult(duration_s=1e9)
        runner._repeat_stroke(res, f, 5.0, strokes, 0.0, 1e12, 2, 4, False)  # loads numba's cache
        t0 = time.process_time()
        for _ in range(calls):
            runner._repeat_stroke(res, f, 5.0, strokes, 0.0, 1e12, 2, 4, False)
        return 1e6 * (time.process_time() - t0) / calls
    finally:
        interval.compiled_applies = applies


if __name__ == "__main__":
    warnings.filterwarnings("ignore")
    print(json.dumps({f"{n}_strokes": {"python_us": round(cost_us(False, n), 1), "compiled_us": round(cost_us(True, n), 1)}
                      for n in (1, 5, 60)}))
