"""Where an env step's CPU time goes, on the acceptance's protocol (docs/speed.md, issue 25).

    python scripts/step_profile.py [--action -0.6] [--env srenv/SuckerRod-v2]
    python scripts/step_profile.py --trees /tmp/before . --repeats 3     # interleaved, each tree its own process
    python scripts/step_profile.py --random --steps 40 --trees /tmp/rl_before . --repeats 6   # an RL agent's actions

The protocol of ``acceptance/speed``: ``scenario="train"``, a constant action [a, 1], a warm-up episode (seed 3,
one step), then seeds 11 and 12, 12 steps each, in CPU time (``time.process_time``). ``--random``: a new uniform
action every step from a fixed seed instead (``srenv bench``'s ``random_actions``: what an RL agent does; the
same actions in every tree), ``--steps`` steps per seed. Prints one JSON line: the
resets' and the steps' CPU ms, the compiled kernel's share of each (``kernel.run`` timed around), the steps'
Python per step and ``python_per_kernel`` (the steps' Python over their kernel time: the figure that survives a
loaded machine, both sides slowing alike), ``exact_strokes_per_step`` (the steps' ``info["exact_strokes"]``), and with ``--functions`` the self time of the step's main Python
parts (wrapped with a timer: their own time, the wrapped callees' taken out; the wrappers add ~1 µs a call).
"""

from __future__ import annotations

import argparse
import functools
import importlib
import json
import os
import statistics
import subprocess
import sys
import time
import warnings
from collections import defaultdict

PARTS = (  # (module, qualified name): the step's Python, timed by self time with --functions
    ("srenv.simulation.simulator", "Simulator.run_stroke"),
    ("srenv.simulation.simulator", "Simulator._run"),
    ("srenv.numerics.kernel", "run"),
    ("srenv.surface_unit.surface", "SurfaceMotion.stroke_motion"),
    ("srenv.surface_unit.inline_unit", "unit_for_stroke"),
    ("srenv.analysis.card_features", "stick_slip_energy_j"),
    ("srenv.analysis.card_features", "impact_speed_m_s"),
    ("srenv.analysis.card_shape", "features"),
    ("srenv.task.interval", "IntervalRunner._repeat_stroke"),
    ("srenv.task.interval", "stroke_figures"),
    ("srenv.analysis.stroke_summary", "summarize"),
    ("srenv.surface_unit.surface", "SurfaceMotion.gearbox_report"),
    ("srenv.surface_unit.gearbox", "analyse_runs"),
    ("srenv.surface_unit.gearbox", "optimal_counterbalance_nm"),
    ("srenv.task.interval", "IntervalRunner.run"),
    ("srenv.simulation.pump_cycle", "PumpCycle.fast_forward"),
    ("srenv.envs.sucker_rod_v1", "SuckerRodV1Env.reset"),
    ("srenv.config", "load_config"),
    ("srenv.config", "config_from_dict"),
    ("srenv.envs.sucker_rod_v2", "SuckerRodV2Env._card_probabilities"),
    ("srenv.envs.sucker_rod_v2", "SuckerRodV2Env._observe"),
    ("srenv.envs.sucker_rod_v1", "SuckerRodV1Env.step"),
)


class SelfTimer:
    """Wraps functions with a CPU-time accumulator that keeps each one's own time (wrapped callees out)."""

    def __init__(self) -> None:
        self.ms: dict[str, float] = defaultdict(float)
        self.calls: dict[str, int] = defaultdict(int)
        self._stack: list[float] = []

    def wrap(self, module: str, qualname: str) -> None:
        try:
            mod = importlib.import_module(module)
        except ModuleNotFoundError:  # an older tree without it
            return
        *path, name = qualname.split(".")
        owner = functools.reduce(getattr, path, mod)
        fn = getattr(owner, name, None)
        if fn is None:
            return
        stack, ms, calls = self._stack, self.ms, self.calls

        @functools.wraps(fn)
        def timed(*a, **k):
            t0 = time.process_time()
            stack.append(0.0)
            try:
                return fn(*a, **k)
            finally:
                dt = time.process_time() - t0
                ms[qualname] += 1e3 * (dt - stack.pop())
                calls[qualname] += 1
                if stack:
                    stack[-1] += dt

        setattr(owner, name, timed)
        if not path:  # a module function imported by name elsewhere
            for m in list(sys.modules.values()):
                if m is not None and getattr(m, name, None) is fn:
                    setattr(m, name, timed)


def _actions(action: float, random: bool):
    import numpy as np

    rng = np.random.default_rng(0)  # srenv bench's RANDOM_ACTIONS_SEED (the old trees have no such mode)
    while True:
        yield rng.uniform(-1.0, 1.0, 2).astype(np.float32) if random else np.array([action, 1.0], np.float32)


def profile(env_id: str, action: float, functions: bool, random: bool = False, n_steps: int = 12) -> dict:
    warnings.filterwarnings("ignore")
    import gymnasium as gym

    import srenv  # noqa: F401  (registers the envs)
    from srenv.numerics import kernel

    spent = [0.0]
    run = kernel.run

    def timed_run(*a):
        t0 = time.process_time()
        try:
            return run(*a)
        finally:
            spent[0] += time.process_time() - t0

    kernel.run = timed_run
    timer = SelfTimer()
    if functions:
        for module, qualname in PARTS:
            timer.wrap(module, qualname)
    actions = _actions(action, random)
    env = gym.make(env_id, scenario="train")
    env.reset(seed=3)
    env.step(next(actions))
    timer.ms.clear()
    timer.calls.clear()
    reset = steps = k_reset = k_steps = 0.0
    exact = 0
    for seed in (11, 12):
        k0, t0 = spent[0], time.process_time()
        env.reset(seed=seed)
        reset += time.process_time() - t0
        k_reset += spent[0] - k0
        for _ in range(n_steps):
            a = next(actions)
            k0, t0 = spent[0], time.process_time()
            info = env.step(a)[4]
            steps += time.process_time() - t0
            k_steps += spent[0] - k0
            exact += info.get("exact_strokes", 0)  # the interval's strokes simulated exactly (0 in an old tree)
    n = 2 * n_steps
    out = {"env": env_id, "action": "random" if random else action, "env_steps_per_cpu_s": n / (reset + steps),
           "reset_ms": 1e3 * reset, "reset_kernel_ms": 1e3 * k_reset, "steps_ms": 1e3 * steps,
           "steps_kernel_ms": 1e3 * k_steps, "steps_python_ms_per_step": 1e3 * (steps - k_steps) / n,
           "python_per_kernel": (steps - k_steps) / k_steps, "exact_strokes_per_step": exact / n}
    if functions:
        out["self_ms"] = {k: [round(v, 2), timer.calls[k]] for k, v in sorted(timer.ms.items(), key=lambda kv: -kv[1])}
    return out


def interleaved(trees: list[str], repeats: int, argv: list[str]) -> dict:
    """Each tree in its own process, alternating, ``repeats`` rounds; medians and per-round ratios to the first."""
    rows: dict[str, list[dict]] = {t: [] for t in trees}
    for _ in range(repeats):
        for tree in trees:
            env = dict(os.environ, PYTHONPATH=os.path.abspath(tree))
            p = subprocess.run([sys.executable, os.path.abspath(__file__), *argv], capture_output=True, text=True,
                               env=env, cwd=os.path.abspath(tree), check=True)
            rows[tree].append(json.loads(p.stdout.strip().splitlines()[-1]))
    keys = ("env_steps_per_cpu_s", "steps_python_ms_per_step", "python_per_kernel", "reset_ms")
    summary = {t: {k: statistics.median(r[k] for r in rs) for k in keys} for t, rs in rows.items()}
    for t, rs in rows.items():
        summary[t]["env_steps_per_cpu_s_per_round"] = [round(r["env_steps_per_cpu_s"], 1) for r in rs]
    base = rows[trees[0]]
    for t in trees[1:]:
        summary[t]["python_per_kernel_ratio_to_first"] = [round(r["python_per_kernel"] / b["python_per_kernel"], 3)
                                                          for r, b in zip(rows[t], base)]
        ratios = [r["env_steps_per_cpu_s"] / b["env_steps_per_cpu_s"] for r, b in zip(rows[t], base)]
        summary[t]["rate_ratio_to_first"] = [round(x, 3) for x in ratios]
        summary[t]["rate_ratio_min_median_max"] = [round(f(ratios), 3) for f in (min, statistics.median, max)]
    return summary


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--env", default="srenv/SuckerRod-v2")
    ap.add_argument("--action", type=float, default=1.0, help="the stroke-rate action (1: full speed, -0.6: VSD min)")
    ap.add_argument("--functions", action="store_true", help="self time of the step's main Python parts")
    ap.add_argument("--trees", nargs="+", help="project trees to compare, interleaved (the first is the base)")
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--random", action="store_true", help="a new uniform random action every step (fixed seed)")
    ap.add_argument("--steps", type=int, default=12, help="steps per seed (seeds 11 and 12)")
    args = ap.parse_args()
    if args.trees:
        child = ["--env", args.env, "--action", str(args.action), "--steps", str(args.steps)] \
            + (["--random"] if args.random else [])
        print(json.dumps(interleaved(args.trees, args.repeats, child), indent=1))
        return
    print(json.dumps(profile(args.env, args.action, args.functions, args.random, args.steps)))


if __name__ == "__main__":
    main()
