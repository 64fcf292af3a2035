"""``srenv bench``'s ``kernel`` block: the exact step against its floor, measured in one run.

The kernel's µs/step is what a caller pays per time step of an unrecorded exact stroke
(``Simulator.run_stroke(record=False)``: the kernel calls, its event returns and the per-stroke set-up). The
floor (srenv.numerics.floor) steps the same mesh with the same time step and top motion. The two alternate
repeat by repeat and are timed in CPU time of this process, so a shared machine's load hits both alike; the
ratio is the median of the per-repeat ratios.
"""

from __future__ import annotations

import math
import statistics
import time

import numpy as np

from ..config import load_config
from ..numerics.floor import factor, floor_steps
from ..simulation.simulator import Simulator


class FloorRun:
    """The floor program set up on a simulator's mesh for one stroke at the config's operating point."""

    def __init__(self, sim: Simulator) -> None:
        cfg, s = sim.cfg, sim.cfg.simulation
        spm = sim.surface.default_spm(cfg.surface.spm)
        stroke = sim.surface.stroke_length_m(cfg.surface.stroke_length_m)
        period = 60.0 / spm
        self.n_steps = max(1, math.ceil(period / s.time_step_s - 1e-9))
        self.dt = period / self.n_steps
        self.va = sim.surface.stroke_velocity(spm, stroke, self.n_steps)
        ksd, kso = sim._kstar(self.dt)
        cp, inv = factor(ksd, kso)
        (kd, ko), (md, mo) = sim._k, sim._m
        self.model = (kd[1:].copy(), ko[1:].copy(), md[1:].copy(), mo[1:].copy(), sim._f_all[1:].copy(), kso,
                      cp, inv)
        self.coupling = (float(ko[0]), float(mo[0]))
        self.newmark = (s.newmark_beta, s.newmark_gamma)
        n = sim.n_free
        self.state = (sim.u.copy(), np.zeros(n), np.zeros(n), np.zeros(4))
        self.scratch = np.zeros(n)

    def stroke(self) -> None:
        floor_steps(*self.model, *self.state, self.va, self.dt, *self.newmark, *self.coupling, self.scratch)


def kernel_figures(name: str = "paper_fig4_deviated", repeats: int = 5, strokes: int = 10) -> dict:
    """µs/step of the exact stroke and of the floor program on one well, and their ratio."""
    sim = Simulator(load_config(name))
    floor = FloorRun(sim)
    sim.run_stroke(record=False)  # compiles and warms up both
    floor.stroke()
    t_kernel, t_floor, ratios = [], [], []
    steps = sim.run_stroke(record=False).n_steps
    for _ in range(repeats):
        t = time.process_time()
        for _ in range(strokes):
            sim.run_stroke(record=False)
        tk = (time.process_time() - t) / (strokes * steps)
        t = time.process_time()
        for _ in range(strokes * 4):  # the floor is fast: more strokes for a measurable time
            floor.stroke()
        tf = (time.process_time() - t) / (4 * strokes * floor.n_steps)
        t_kernel.append(tk)
        t_floor.append(tf)
        ratios.append(tk / tf)
    return {"case": name, "nodes": sim.mesh.n_nodes, "steps_per_stroke": steps,
            "us_per_step": 1e6 * statistics.median(t_kernel), "floor_us_per_step": 1e6 * statistics.median(t_floor),
            "floor_ratio": statistics.median(ratios), "floor_ratio_min": min(ratios),
            "floor_ratio_max": max(ratios)}
