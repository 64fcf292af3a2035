"""What ProxSuite in the loop costs: strokes/s of the bare simulator and env steps/s, per step path.

    PYTHONPATH=. python scripts/qp_in_the_loop.py [CONFIG ...]      # default: default paper_fig4_deviated

Modes (all exact: the trajectories agree to 1e-8, tests/srenv/simulation/test_simulator.py): the default certified reuse
with up to ``simulation.max_corrections`` exact corrections; ``simulation.max_corrections: 0`` (a ProxSuite
solve at every stick/slip pattern change); ``simulation.always_qp: true`` (a ProxSuite solve every step).
Medians of 3 rounds, modes interleaved in each round (a shared machine slows all alike), after a warm-up
stroke (kernel compile). Env steps use seeded random actions, so more pattern changes than a policy's.
Prints one JSON document.
"""

from __future__ import annotations

import argparse
import json
import statistics
import time

import gymnasium as gym
import numpy as np

from srenv import ENV_ID  # importing srenv registers the envs
from srenv.config import load_config
from srenv.simulation.simulator import Simulator

MODES = {"default": {}, "max_corrections_0": {"simulation.max_corrections": 0},
         "always_qp": {"simulation.always_qp": True}}
STROKES = {"default": 10, "max_corrections_0": 5, "always_qp": 1}  # per round: ~0.02-0.5 s each


def _rounds(run: dict, n: dict) -> dict:
    rates: dict = {m: [] for m in run}
    for _ in range(3):
        for m, f in run.items():
            t = time.perf_counter()
            for _ in range(n[m]):
                f()
            rates[m].append(n[m] / (time.perf_counter() - t))
    return {m: statistics.median(r) for m, r in rates.items()}


def simulator_figures(name: str) -> dict:
    sims = {m: Simulator(load_config(name, overrides=o)) for m, o in MODES.items()}
    for s in sims.values():
        s.run_stroke(record=False)
    rates = _rounds({m: (lambda s=s: s.run_stroke(record=False)) for m, s in sims.items()}, STROKES)
    out = {}
    for m, s in sims.items():
        r = s.run_stroke(record=False)
        out[m] = {"strokes_per_s": round(rates[m], 2), "solver_calls_per_stroke": r.qp_calls,
                  "certified_steps_per_stroke": r.certified_steps, "corrected_steps_per_stroke": r.corrected_steps}
    return out


def env_figures(name: str) -> dict:
    envs = {m: gym.make(ENV_ID, config=name, overrides=o) for m, o in MODES.items()}
    rng = np.random.default_rng(0)
    calls: dict = {m: [] for m in MODES}

    def step(m: str) -> None:
        _, _, terminated, truncated, info = envs[m].step(rng.uniform(-1, 1, 2).astype(np.float32))
        calls[m].append(info["solver_calls"])
        if terminated or truncated:
            envs[m].reset()

    for m, e in envs.items():
        e.reset(seed=0)
        step(m)
    rates = _rounds({m: (lambda m=m: step(m)) for m in envs}, STROKES)
    return {m: {"env_steps_per_s": round(rates[m], 2), "solver_calls_per_step": round(float(np.mean(calls[m])), 1)}
            for m in envs}


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("configs", nargs="*", metavar="CONFIG", help="well YAML or shipped name "
                    "(default: default paper_fig4_deviated)")
    names = ap.parse_args().configs or ["default", "paper_fig4_deviated"]
    print(json.dumps({"simulator": {n: simulator_figures(n) for n in names}, "env": env_figures(names[0])},
                     indent=1))
