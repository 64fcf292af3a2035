"""Env overhead for ``srenv bench``: env.step versus the bare simulator running the same strokes."""

from __future__ import annotations

import statistics
import time

import numpy as np

from .. import ENV_ID


def env_overhead(repeats: int = 5, n_strokes: int = 50) -> dict:
    """Two identical envs, reset alike: one steps through the env API, the other's simulator runs the very
    same strokes bare (``run_stroke(record=False)``), interleaved stroke by stroke so that machine noise
    hits both sides alike. Medians over `repeats` of the summed CPU times of this thread."""
    import gymnasium as gym

    action = np.zeros(2, dtype=np.float32)
    env = gym.make(ENV_ID).unwrapped
    bare = gym.make(ENV_ID).unwrapped
    t_env, t_sim = [], []
    for rep in range(repeats + 1):  # the first repeat warms up (kernel compilation, caches)
        env.reset(seed=0, options={"randomize": False})
        bare.reset(seed=0, options={"randomize": False})
        te = ts = 0.0
        for _ in range(n_strokes):
            # CPU time of this thread: on a shared machine, wall time charges either side for the other jobs
            t = time.thread_time()
            env.step(action)
            te += time.thread_time() - t
            t = time.thread_time()
            bare.sim.run_stroke(env._spm, env._stroke, record=False)
            ts += time.thread_time() - t
        if rep:
            t_env.append(te)
            t_sim.append(ts)
    te, ts = statistics.median(t_env), statistics.median(t_sim)
    return {"env_steps_per_s": n_strokes / te, "bare_strokes_per_s": n_strokes / ts,
            "env_overhead_pct": 100.0 * (te - ts) / ts, "strokes_per_env_step": env.cfg.control.strokes_per_step}


def v1_figures(repeats: int = 3, steps: int = 48) -> dict:
    """srenv/SuckerRod-v1 for ``srenv bench``: env steps/s at full speed, at the VSD minimum and idle, on the
    same train well (medians over `repeats`), and what an interval costs in exact strokes."""
    from .sucker_rod_v1 import SuckerRodV1Env, action_from_setpoints

    env = SuckerRodV1Env(scenario="train")
    env.reset(seed=0)
    ctl = env.cfg.control
    modes = {"pumping_full_speed": action_from_setpoints(ctl.spm_max, ctl.stroke_max_m, ctl),
             "pumping_vsd_minimum": action_from_setpoints(ctl.spm_min, ctl.stroke_min_m, ctl),
             "intermittent_half_duty": action_from_setpoints(0.5 * ctl.spm_min, ctl.stroke_max_m, ctl),
             "idle": action_from_setpoints(0.0, ctl.stroke_min_m, ctl)}
    out: dict = {"well": env.well.well_id, "interval_s": env.cfg.task.interval_s, "steps": steps}
    for name, action in modes.items():
        rates, exact, ff = [], 0, 0.0
        for rep in range(repeats + 1):
            env.reset(seed=0)
            t = time.perf_counter()
            for _ in range(steps):
                info = env.step(action)[4]
                exact += info["exact_strokes"] if rep else 0
                ff += info["fast_forward_strokes"] if rep else 0.0
            if rep:
                rates.append(steps / (time.perf_counter() - t))
        out[name] = {"env_steps_per_s": statistics.median(rates),
                     "well_hours_per_wall_s": statistics.median(rates) * env.cfg.task.interval_s / 3600.0,
                     "exact_strokes_per_step": exact / (repeats * steps),
                     "fast_forward_strokes_per_step": ff / (repeats * steps)}
    out["idle_vs_full_speed_cost_ratio"] = (out["pumping_full_speed"]["env_steps_per_s"]
                                            / out["idle"]["env_steps_per_s"])
    return out
