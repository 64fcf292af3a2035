"""Env overhead for ``srenv bench``: env.step versus the bare simulator running the same strokes."""

from __future__ import annotations

import statistics
import time

import numpy as np


def env_overhead(repeats: int = 5, n_strokes: int = 50) -> dict:
    """Median over `repeats` of the time for `n_strokes` env steps and for the same strokes run bare
    (``Simulator.run_stroke(record=False)`` at the same SPM and stroke), interleaved."""
    import gymnasium as gym

    from ..simulator import Simulator

    env = gym.make("srenv/SuckerRod-v0").unwrapped
    action = np.zeros(2, dtype=np.float32)
    env.reset(seed=0, options={"randomize": False})
    env.step(action)
    spm, stroke = env._spm, env._stroke
    sim = Simulator(env.cfg)
    sim.run_stroke(spm, stroke, record=False)
    t_env, t_sim = [], []
    for _ in range(repeats):
        env.reset(seed=0, options={"randomize": False})
        t = time.perf_counter()
        for _ in range(n_strokes):
            env.step(action)
        t_env.append(time.perf_counter() - t)
        sim.reset()
        t = time.perf_counter()
        for _ in range(n_strokes):
            sim.run_stroke(spm, stroke, record=False)
        t_sim.append(time.perf_counter() - t)
    te, ts = statistics.median(t_env), statistics.median(t_sim)
    return {"env_steps_per_s": n_strokes / te, "bare_strokes_per_s": n_strokes / ts,
            "env_overhead_pct": 100.0 * (te - ts) / ts, "strokes_per_env_step": env.cfg.control.strokes_per_step}
