"""Soak test: run the default env for many strokes under seeded random actions and check it stays healthy.

    python scripts/soak.py --strokes 10000 [--seed 0] [--checkpoint 1000] [--config default]

Checks, every env step: observation, reward and every numeric entry of ``info`` finite; the simulator's
energy residual over the stroke <= 1e-6 of that stroke's polished-rod work. Every ``--checkpoint`` strokes
it records the resident set size (``/proc/self/statm``, current) and ``ru_maxrss`` (peak); memory is
"flat" when the RSS after warm-up (the first checkpoint) grows by less than 5 %. Prints one JSON summary
and exits 1 if any check failed.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import resource
import sys
import time
from collections.abc import Iterator
from typing import Any

import gymnasium as gym
import numpy as np

from srenv import ENV_ID  # importing srenv registers the envs
from srenv.simulation.simulator import Simulator

ENERGY_RTOL = 1e-6
RSS_GROWTH_LIMIT_PCT = 5.0
PAGE_BYTES = os.sysconf("SC_PAGE_SIZE")


def rss_mb() -> float:
    """Current resident set size (maxrss only ever grows, so it cannot show memory being given back)."""
    with open("/proc/self/statm") as fh:
        return int(fh.read().split()[1]) * PAGE_BYTES / 2**20


def maxrss_mb() -> float:
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024  # Linux reports KiB


def numeric_leaves(value: Any, path: str = "") -> Iterator[tuple[str, float]]:
    """Every number inside an info dict (nested dicts, lists, arrays), with its path."""
    if isinstance(value, dict):
        for k, v in value.items():
            yield from numeric_leaves(v, f"{path}.{k}" if path else str(k))
    elif isinstance(value, (list, tuple)):
        for i, v in enumerate(value):
            yield from numeric_leaves(v, f"{path}[{i}]")
    elif isinstance(value, np.ndarray) and value.dtype.kind in "fiub":
        for i, v in enumerate(value.ravel()):
            yield f"{path}[{i}]", float(v)
    elif isinstance(value, (int, float, np.number)) and not isinstance(value, bool):
        yield path, float(value)


def simulator_of(env: gym.Env) -> Simulator:
    """The Simulator inside the env (the env may build a new one on reset, so look it up each time)."""
    inner = env.unwrapped
    for name in ("sim", "simulator", "_sim"):
        sim = getattr(inner, name, None)
        if isinstance(sim, Simulator):
            return sim
    raise AttributeError(f"no Simulator found on {type(inner).__name__}")


def soak(strokes: int, seed: int, checkpoint: int, config: str | None) -> dict:
    env = gym.make(ENV_ID, **({"config": config} if config else {}))
    env.action_space.seed(seed)
    obs, _ = env.reset(seed=seed)
    strokes_per_step = int(simulator_of(env).cfg.control.strokes_per_step)
    problems: list[str] = []
    worst_energy_rel, episodes, failures, terminations, done_strokes, steps = 0.0, 1, 0, 0, 0, 0
    rss_log: list[tuple[int, float, float]] = []
    next_checkpoint = checkpoint
    t0 = time.perf_counter()
    while done_strokes < strokes:
        sim = simulator_of(env)
        before = sim.energy_balance()
        obs, reward, terminated, truncated, info = env.step(env.action_space.sample())
        steps += 1
        done_strokes += strokes_per_step
        after = simulator_of(env).energy_balance() if simulator_of(env) is sim else None
        if after is not None:
            # the balance is accumulated since the simulator's reset: this step's share is the difference
            work = after["polished_rod_work_j"] - before["polished_rod_work_j"]
            resid = after["residual_j"] - before["residual_j"]
            rel = abs(resid) / max(abs(work), 1e-12)
            if "failure" not in info:
                worst_energy_rel = max(worst_energy_rel, rel)
                if not rel <= ENERGY_RTOL:
                    problems.append(f"stroke {done_strokes}: energy residual {rel:.3g} of polished-rod work")
        if not np.all(np.isfinite(obs)):
            problems.append(f"stroke {done_strokes}: non-finite observation")
        if not math.isfinite(float(reward)):
            problems.append(f"stroke {done_strokes}: non-finite reward {reward}")
        bad = [k for k, v in numeric_leaves(info) if not math.isfinite(v)]
        if bad:
            problems.append(f"stroke {done_strokes}: non-finite info {bad[:5]}")
        if "failure" in info:
            failures += 1
        if terminated or truncated:
            terminations += int(terminated)
            episodes += 1
            obs, _ = env.reset()
        if done_strokes >= next_checkpoint:
            rss_log.append((done_strokes, rss_mb(), maxrss_mb()))
            next_checkpoint += checkpoint
    seconds = time.perf_counter() - t0
    env.close()
    base = rss_log[0][1] if rss_log else rss_mb()
    growth_pct = 100.0 * (max(r for _, r, _ in rss_log[1:]) - base) / base if len(rss_log) > 1 else 0.0
    if growth_pct >= RSS_GROWTH_LIMIT_PCT:
        problems.append(f"RSS grew {growth_pct:.2f} % after warm-up")
    return {
        "strokes": done_strokes, "env_steps": steps, "episodes": episodes, "terminated": terminations,
        "solver_failures": failures, "seconds": round(seconds, 1),
        "strokes_per_s": round(done_strokes / seconds, 1),
        "max_energy_residual_rel": worst_energy_rel,
        "rss_mb": [round(r, 1) for _, r, _ in rss_log], "maxrss_mb": round(maxrss_mb(), 1),
        "rss_growth_after_warmup_pct": round(growth_pct, 3),
        "checkpoint_strokes": checkpoint, "seed": seed,
        "problems": problems[:20], "n_problems": len(problems), "ok": not problems,
    }


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--strokes", type=int, default=10000)
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--checkpoint", type=int, default=1000, help="strokes between memory samples")
    p.add_argument("--config", help="well config (default: the env's default)")
    a = p.parse_args(argv)
    summary = soak(a.strokes, a.seed, a.checkpoint, a.config)
    print(json.dumps(summary))
    return 0 if summary["ok"] else 1


if __name__ == "__main__":
    sys.exit(main())
