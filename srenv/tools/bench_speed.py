"""``srenv bench``'s task-env figures: env steps/s per core of every task version (and of v1 with the fast
stepping option) at full speed, at the VSD minimum and idle, and the native vector env's steps/s at N = 1, 8, 32
on all the cores this process may use (docs/speed.md).

Per-core rates are env steps over this process's CPU time (a shared machine's other jobs do not count); the
vector env's are over wall time with its CPU time beside it (cpu_per_wall: how many cores it kept busy).
"""

from __future__ import annotations

import time
import warnings

import numpy as np

from .. import ENV_ID, ENV_ID_V1, ENVS

# the acceptance's operating points: a0 = 1 full speed, a0 = -0.6 an average rate at or below the VSD minimum
MODES = {"full_speed": (1.0, 1.0), "vsd_minimum": (-0.6, 1.0), "idle": (-1.0, -1.0)}
# what an RL agent does: a new action every step, uniform in the action box (a fixed seed: the same actions in
# every run and every tree)
RANDOM_MODE = "random_actions"
RANDOM_ACTIONS_SEED = 0


def mode_actions(label: str):
    """The actions of a bench mode, one per step: a constant one, or uniform random ones from a fixed seed."""
    if label == RANDOM_MODE:
        rng = np.random.default_rng(RANDOM_ACTIONS_SEED)
        while True:
            yield rng.uniform(-1.0, 1.0, 2).astype(np.float32)
    a = np.array(MODES[label], np.float32)
    while True:
        yield a


def task_env_ids() -> list[str]:
    """The control-task envs (every registered version after v0; importing srenv registered them)."""
    return sorted(i for i in ENVS if i != ENV_ID)


def env_rates(env_id: str, steps: int, seeds: tuple = (11, 12), **kwargs) -> dict:
    """Env steps per CPU second in each mode (the constant actions of ``MODES`` and ``random_actions``): a
    warm-up step on seed 3, then `steps` steps on each seed."""
    import gymnasium as gym

    out = {}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        env = gym.make(env_id, scenario="train", **kwargs)
        for label in (*MODES, RANDOM_MODE):
            actions = mode_actions(label)
            env.reset(seed=3)
            env.step(next(actions))
            n, exact, t_step, t_reset = 0, 0, 0.0, 0.0
            for seed in seeds:
                t0 = time.process_time()
                env.reset(seed=seed)
                t_reset += time.process_time() - t0
                for _ in range(steps):
                    a = next(actions)
                    t0 = time.process_time()
                    exact += env.step(a)[4]["exact_strokes"]
                    t_step += time.process_time() - t0
                    n += 1
            # the acceptance's rate counts the resets' CPU time too: both are given
            out[label] = {"env_steps_per_cpu_s": n / t_step, "with_resets_env_steps_per_cpu_s": n / (t_step + t_reset),
                          "reset_cpu_ms": 1e3 * t_reset / len(seeds), "exact_strokes_per_step": exact / n}
        env.close()
    return out


def vector_actions(mode: str, n: int, steps: int) -> np.ndarray:
    """(steps, n, 2) actions of a bench mode for n wells: its constant action, or uniform ones from a fixed seed."""
    actions = mode_actions(mode)  # one stream per mode: the wells of a step take its next n actions in turn
    return np.array([next(actions) for _ in range(steps * n)], np.float32).reshape(steps, n, 2)


def _vector_rate(env_id: str, n: int, steps: int, mode: str = "full_speed", **kwargs) -> dict:
    """One vector env in a bench mode (default full speed): env steps/s over wall time (and per CPU second of
    this process: a process backend's workers are not in it) over `steps` steps after a reset and one step."""
    import gymnasium as gym

    venv = gym.make_vec(env_id, num_envs=n, vectorization_mode="vector_entry_point", **kwargs)
    try:
        acts = vector_actions(mode, n, steps + 1)
        venv.reset(seed=0)
        venv.step(acts[0])
        t, c = time.perf_counter(), time.process_time()
        for a in acts[1:]:
            venv.step(a)
        wall, cpu = time.perf_counter() - t, time.process_time() - c
    finally:
        venv.close()
    return {"env_steps_per_s": n * steps / wall, "env_steps_per_cpu_s": n * steps / max(cpu, 1e-9),
            "cpu_per_wall": cpu / wall}


def vector_rates(env_id: str, sizes: tuple = (1, 8, 32), steps: int = 2, speedup_sizes: tuple = (8,),
                 mode: str = "full_speed", **kwargs) -> dict:
    """The native vector env in a bench mode (default full speed; `random_actions`: RL's case) on threads
    (N = `sizes`), and at each N of `speedup_sizes` its process backend on every core against the same N wells in
    one process on one thread, measured alternately (`process_speedup`: the ratio of wall rates, the issue's "2
    cores against one core's rate"; `processes` keeps N = 8's figures under their first names). More wells per
    process balance the steps' bimodal cost (an interval that needs exact strokes against one that reuses its
    stroke), which a vector step waits for."""
    from ..envs.vector import default_threads

    cores = default_threads()
    out: dict = {"threads": cores}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for n in sizes:
            out[f"n{n}"] = _vector_rate(env_id, n, steps, mode, **kwargs)
        if cores > 1:
            by_n = {}
            for n in speedup_sizes:
                one, many = [], []
                for _ in range(2):  # alternated: the machine's load moves both alike
                    one.append(_vector_rate(env_id, n, steps, mode, threads=1, **kwargs)["env_steps_per_s"])
                    many.append(_vector_rate(env_id, n, steps, mode, processes=cores, **kwargs)["env_steps_per_s"])
                by_n[n] = {"processes": cores, f"n{n}_env_steps_per_s": max(many),
                           f"n{n}_one_core_env_steps_per_s": max(one), "process_speedup": max(many) / max(one)}
            if 8 in by_n:
                out["processes"] = by_n[8]
            out["process_speedup_by_n"] = {str(n): f["process_speedup"] for n, f in by_n.items()}
    return out


def split_bound(env_id: str, n: int, steps: int, blocks: int = 2, seed: int = 0) -> dict:
    """The most a static split of N wells into `blocks` can give, with free communication: N single envs (seeded
    as the vector env seeds them) stepped one by one at full speed, each step's wall time kept, and
    serial time / sum over steps of the slowest block's time, for the process backend's contiguous blocks and for
    the best split in hindsight by each env's total (greedy, largest first). A vector step waits for its slowest
    block, so v2's bimodal steps cap the process speedup below `blocks` however cheap the pipes are."""
    import gymnasium as gym

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        envs = [gym.make(env_id, scenario="train").unwrapped for _ in range(n)]
        a = np.float32(MODES["full_speed"])
        for i, env in enumerate(envs):
            env.reset(seed=seed + i)
            env.step(a)
        t = np.zeros((steps, n))
        for s in range(steps):
            for i, env in enumerate(envs):
                t0 = time.perf_counter()
                env.step(a)
                t[s, i] = time.perf_counter() - t0
        for env in envs:
            env.close()
    load = np.zeros(blocks)
    best: list = [[] for _ in range(blocks)]
    for i in np.argsort(-t.sum(0)):  # largest first onto the least loaded block
        k = int(np.argmin(load))
        best[k].append(i)
        load[k] += t[:, i].sum()

    def bound(split: list) -> float:
        return float(t.sum() / np.max([t[:, b].sum(1) for b in split], axis=0).sum())

    contiguous = [b.tolist() for b in np.array_split(np.arange(n), blocks)]
    return {"serial_ms_per_step": float(1e3 * t.sum() / steps), "contiguous_bound": bound(contiguous),
            "hindsight_bound": bound(best)}


def speed_figures(quick: bool) -> dict:
    steps = 6 if quick else 12
    out: dict = {"env_per_core": {}}
    for env_id in task_env_ids():
        out["env_per_core"][env_id] = env_rates(env_id, steps)
    out["env_per_core"][f"{ENV_ID_V1} fast_stepping"] = env_rates(ENV_ID_V1, steps, fast_stepping=True)
    out["vector_env"] = {ENV_ID_V1: vector_rates(ENV_ID_V1, steps=2 if quick else 3)}
    if not quick:  # the newest version too, and the speedup where the blocks are large enough to balance
        for env_id in task_env_ids()[-1:]:
            out["vector_env"][env_id] = vector_rates(env_id, steps=6, speedup_sizes=(8, 32))
            # RL's case: every well changes its action every step (most well-steps simulate exact strokes)
            out["vector_env"][f"{env_id} {RANDOM_MODE}"] = vector_rates(env_id, sizes=(), steps=6,
                                                                          speedup_sizes=(8, 32), mode=RANDOM_MODE)
    return out
