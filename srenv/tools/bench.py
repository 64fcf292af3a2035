"""``srenv bench``: performance figures as one JSON document.

Every figure is a median over ``--repeats`` runs; ratios are measured inside one run (interleaved), so a
noisy shared machine moves both sides alike. Compile time of the kernel is excluded by a warm-up stroke.
"""

from __future__ import annotations

import json
import resource
import statistics
import sys
import time
from argparse import Namespace

import numpy as np

from ..config import load_config
from ..simulation.simulator import Simulator

CASES = ("paper_fig4_deviated", "paper_fig3_vertical")


def _time_strokes(sim: Simulator, n: int, record: bool = False) -> float:
    t = time.perf_counter()
    for _ in range(n):
        sim.run_stroke(record=record)
    return time.perf_counter() - t


def _linear_reference(cfg) -> Simulator:
    """Same mesh and time step, no friction and no valve law: a plain linear Newmark step."""
    return Simulator(cfg, linear_reference=True)


def case_figures(name: str, repeats: int, strokes: int) -> dict:
    cfg = load_config(name)
    sim, lin = Simulator(cfg), _linear_reference(cfg)
    sim.run_stroke(record=False)
    lin.run_stroke(record=False)
    rates, ratios = [], []
    for _ in range(repeats):
        t_ns = _time_strokes(sim, strokes)
        t_lin = _time_strokes(lin, strokes)
        rates.append(strokes / t_ns)
        ratios.append(t_ns / t_lin)
    res = sim.run_stroke(record=False)
    steps = res.n_steps
    return {
        "strokes_per_s": statistics.median(rates),
        "strokes_per_s_min": min(rates),
        "strokes_per_s_max": max(rates),
        "us_per_step": 1e6 / (statistics.median(rates) * steps),
        "nonsmooth_over_linear_step_cost": statistics.median(ratios),
        "steps_per_stroke": steps,
        "nodes": sim.mesh.n_nodes,
        "certified_steps_per_stroke": res.certified_steps,
        "corrected_steps_per_stroke": res.corrected_steps,
        "qp_steps_per_stroke": res.qp_steps,
        "solver_calls_per_stroke": res.qp_calls,
    }


def always_qp_figures(name: str, repeats: int) -> dict:
    """The reference path (a solver call at every step): one-shot qpsolvers vs persistent ProxSuite."""
    cfg = load_config(name)
    out = {}
    for label, persistent in (("qpsolvers_one_shot", False), ("proxsuite_persistent_warm_start", True)):
        sim = Simulator(cfg, always_qp=True, persistent_qp=persistent)
        sim.run_stroke(record=False)
        times = [_time_strokes(sim, 1) for _ in range(max(1, repeats // 2))]
        res = sim.run_stroke(record=False)
        t = statistics.median(times)
        out[label] = {"strokes_per_s": 1.0 / t, "ms_per_solver_call": 1e3 * t / max(res.qp_calls, 1),
                      "solver_calls_per_stroke": res.qp_calls}
    return out


def memory_figures(name: str, strokes: int = 1000) -> dict:
    """RSS before and after a long unrecorded run: flat memory means no per-stroke accumulation."""
    def rss_mb() -> float:
        with open("/proc/self/statm") as fh:
            return int(fh.read().split()[1]) * resource.getpagesize() / 2**20

    sim = Simulator(load_config(name))
    for _ in range(50):
        sim.run_stroke(record=False)
    before = rss_mb()
    for _ in range(strokes):
        sim.run_stroke(record=False)
    after = rss_mb()
    return {"strokes": strokes, "rss_before_mb": before, "rss_after_mb": after, "rss_growth_mb": after - before}


def env_figures(repeats: int) -> dict | None:
    try:
        from ..envs.bench_env import env_overhead
    except ImportError:
        return None
    return env_overhead(repeats=repeats)


def run(repeats: int = 5, strokes: int = 10, quick: bool = False) -> dict:
    from .bench_kernel import kernel_figures

    t_start = time.perf_counter()
    out: dict = {"repeats": repeats, "strokes_per_run": strokes, "python": sys.version.split()[0],
                 "numpy": np.__version__, "cases": {}}
    out["kernel"] = kernel_figures(CASES[0], repeats=max(repeats, 5), strokes=strokes)
    for name in CASES:
        out["cases"][name] = case_figures(name, repeats, strokes)
    out["always_qp"] = {CASES[0]: always_qp_figures(CASES[0], repeats)}
    out["memory"] = memory_figures(CASES[0])
    env = env_figures(repeats)
    if env is not None:
        out["env"] = env
    from ..envs.bench_env import v1_figures

    out["env_v1"] = v1_figures(repeats=max(1, repeats // 2))
    from .bench_cards import cards_figures  # pump conditions: srenv cards / classify

    out["cards"] = cards_figures(n_cards=40 if repeats < 5 else 200)
    from .bench_speed import speed_figures

    out.update(speed_figures(quick))
    out["wall_time_s"] = time.perf_counter() - t_start
    return out


def main(args: Namespace) -> int:
    repeats, strokes = (3, 3) if args.quick else (args.repeats, args.strokes)
    print(json.dumps(run(repeats, strokes, quick=args.quick), indent=2))
    return 0
