"""Env overhead for ``srenv bench``: env.step versus the bare simulator running the same strokes."""

from __future__ import annotations

import statistics
import time

import numpy as np


def env_overhead(repeats: int = 5, n_strokes: int = 50) -> dict:
    """Two identical envs, reset alike: one steps through the env API, the other's simulator runs the very
    same strokes bare (``run_stroke(record=False)``), interleaved stroke by stroke so that machine noise
    hits both sides alike. Medians over `repeats` of the summed times."""
    import gymnasium as gym

    action = np.zeros(2, dtype=np.float32)
    env = gym.make("srenv/SuckerRod-v0").unwrapped
    bare = gym.make("srenv/SuckerRod-v0").unwrapped
    t_env, t_sim = [], []
    for rep in range(repeats + 1):  # the first repeat warms up (kernel compilation, caches)
        env.reset(seed=0, options={"randomize": False})
        bare.reset(seed=0, options={"randomize": False})
        te = ts = 0.0
        for _ in range(n_strokes):
            t = time.perf_counter()
            env.step(action)
            te += time.perf_counter() - t
            t = time.perf_counter()
            bare.sim.run_stroke(env._spm, env._stroke, record=False)
            ts += time.perf_counter() - t
        if rep:
            t_env.append(te)
            t_sim.append(ts)
    te, ts = statistics.median(t_env), statistics.median(t_sim)
    return {"env_steps_per_s": n_strokes / te, "bare_strokes_per_s": n_strokes / ts,
            "env_overhead_pct": 100.0 * (te - ts) / ts, "strokes_per_env_step": env.cfg.control.strokes_per_step}
