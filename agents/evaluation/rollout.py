"""Episodes of ``srenv/SuckerRod-v1`` for any policy, one process or a small pool.

A job names its policy by a picklable *policy spec* (:mod:`agents.evaluation.agent`), so episodes can run in
worker processes that build their own env and policy.

An *episode record* (:func:`run_episode`) holds ``well_id``, ``seed``, ``reward`` (the episode return: the
sum of the per-interval rewards, as Gymnasium and SB3 count it; each interval's reward is a rate in USD
per hour of well time), ``reward_rate_usd_h`` (return / intervals: the time-mean rate, intervals are
equal), ``cost`` (sum of ``info["cost"]``), the sums of every ``reward_*`` / ``cost_*`` term, interval
means of a few operating quantities, ``steps`` and ``failure``.
"""

from __future__ import annotations

import json
import math
from collections.abc import Callable, Iterable, Iterator, Sequence
from concurrent.futures import ProcessPoolExecutor
from multiprocessing import get_context
from typing import TYPE_CHECKING, Any

import numpy as np

from ..envs import make_env
from .agent import build_policy

if TYPE_CHECKING:
    from typing_extensions import Self  # typing.Self from Python 3.11 only

# info keys averaged over an episode's intervals (the env's units, in their names)
MEAN_KEYS = ("production_m3_day", "oil_m3_day", "inflow_m3_day", "avg_spm", "duty", "stroke_length_m",
             "fillage", "fillage_est", "fluid_level_m")
# info keys recorded per interval for the "what it learned" figure
TRACE_KEYS = ("avg_spm", "spm", "duty", "stroke_length_m", "fillage_est", "fillage", "fluid_level_m",
              "production_m3_day", "inflow_m3_day", "cost")


# ------------------------------------------------------------------------------------------ episodes
Step = tuple[Any, float, bool, bool, dict]  # what env.step returns: obs, reward, terminated, truncated, info


def play(env: Any, policy: Any, seed: int) -> tuple[dict, Iterator[Step]]:
    """The one episode loop: ``env.reset(seed=seed)``, then deterministic actions until the episode ends.

    Returns the reset's info and an iterator over the steps (each as ``env.step`` returned it). A policy with
    ``reset(env)`` is reset with the env; one whose ``needs_info`` is true is fed each step's info through
    ``observe(info)`` (v0's pump-off controller on an observation without the fillage).
    """
    obs, info = env.reset(seed=int(seed))
    if hasattr(policy, "reset"):
        policy.reset(env)
    return info, _steps(env, policy, obs)


def _steps(env: Any, policy: Any, obs: Any) -> Iterator[Step]:
    feed_info = getattr(policy, "needs_info", False)
    state, start = None, True
    while True:
        action, state = policy.predict(obs, state=state, episode_start=np.array([start]), deterministic=True)
        start = False
        step = env.step(action)
        obs, info = step[0], step[4]
        if feed_info:
            policy.observe(info)
        yield step
        if step[2] or step[3]:
            return


def run_episode(env: Any, policy: Any, seed: int, trace: bool = False) -> dict[str, Any]:
    """One deterministic episode (:func:`play`); the record described in the module doc."""
    info, steps = play(env, policy, seed)
    rec: dict[str, Any] = {"well_id": str(info.get("well_id", getattr(env.unwrapped.well, "well_id", "?"))),
                           "seed": int(seed)}
    sums: dict[str, float] = {}
    means: dict[str, list[float]] = {k: [] for k in MEAN_KEYS}
    tr: dict[str, list] = {k: [] for k in (*TRACE_KEYS, "reward", "card", "condition")} if trace else {}
    ret, n, failure = 0.0, 0, None
    for obs, reward, terminated, _, info in steps:
        ret += float(reward)
        n += 1
        for k, v in info.items():
            if (k.startswith(("reward_", "cost_")) or k == "cost") and _is_number(v):
                sums[k] = sums.get(k, 0.0) + float(v)
        for k in MEAN_KEYS:
            if k in info and _is_number(info[k]):
                means[k].append(float(info[k]))
        if trace:
            for k in TRACE_KEYS:
                tr[k].append(float(info[k]) if k in info and _is_number(info[k]) else math.nan)
            tr["reward"].append(float(reward))
            tr["card"].append(np.asarray(obs, np.float64)[:64].round(4).tolist())
            tr["condition"].append(str(info.get("condition", "")))  # v2's true condition ("" before v2)
        failure = info.get("failure") if terminated else None
    rec.update(reward=ret, cost=sums.pop("cost", 0.0), steps=n, reward_rate_usd_h=ret / max(n, 1))
    rec.update(sorted(sums.items()))
    rec.update({f"mean_{k}": float(np.mean(v)) for k, v in means.items() if v})
    rec["failure"] = str(failure) if failure else None
    if hasattr(policy, "sim_steps"):  # the oracle: its compute, and which plan it played
        rec["model_steps"] = int(policy.sim_steps)
        rec["plan_source"] = getattr(policy, "plan_source", "")
    if trace:
        rec["trace"] = tr
    return rec


def _is_number(v: Any) -> bool:
    return isinstance(v, (int, float, np.floating, np.integer)) and not isinstance(v, bool) \
        and math.isfinite(float(v))


# -------------------------------------------------------------------------------------------- jobs
_ENV_CACHE: dict[str, Any] = {}


def _cached_env(env_id: str, env_kwargs: dict[str, Any]) -> Any:
    key = json.dumps([env_id, env_kwargs], sort_keys=True, default=str)
    if key not in _ENV_CACHE:
        _ENV_CACHE[key] = make_env(env_id, **env_kwargs)
    return _ENV_CACHE[key]


def episode_job(job: dict[str, Any]) -> dict[str, Any]:
    """Worker entry: ``{"env_id", "env_kwargs", "policy": spec, "seed", "trace"}`` -> episode record."""
    import torch

    torch.set_num_threads(1)  # one core per worker
    env = _cached_env(job["env_id"], job["env_kwargs"])
    policy = build_policy(job["policy"], env)
    return run_episode(env, policy, job["seed"], trace=job.get("trace", False))


class Runner:
    """Runs episode jobs in ``workers`` processes (1 = in this process), in submission order.

    Workers start by ``spawn`` (no torch state forked; they get this sys.path) and keep their envs between jobs.
    """

    def __init__(self, workers: int = 1) -> None:
        self.workers = max(1, int(workers))
        self._pool: ProcessPoolExecutor | None = None

    def __enter__(self) -> Self:
        if self.workers > 1:
            self._pool = ProcessPoolExecutor(self.workers, mp_context=get_context("spawn"))
        return self

    def __exit__(self, *exc: object) -> None:
        if self._pool is not None:
            if exc[0] is not None:  # an error or Ctrl-C: stop the running episodes too, not only the queued ones
                for proc in list(getattr(self._pool, "_processes", {}).values()):
                    proc.terminate()
            self._pool.shutdown(cancel_futures=True)
            self._pool = None

    def map(self, jobs: Sequence[dict[str, Any]], progress: Callable[[int], None] | None = None,
            fn: Callable[[dict[str, Any]], Any] = episode_job) -> list[Any]:
        if self._pool is None:
            out = []
            for j in jobs:
                out.append(fn(j))
                if progress:
                    progress(1)
            return out
        from srenv.interrupts import workers_ignore_sigint

        with workers_ignore_sigint():  # workers start on submit; Ctrl-C is reported by this driver alone
            futures = [self._pool.submit(fn, j) for j in jobs]
        out = []
        for f in futures:
            out.append(f.result())
            if progress:
                progress(1)
        return out


def episode_jobs(env_id: str, env_kwargs: dict[str, Any], policy: dict[str, Any],
                 seeds: Iterable[int]) -> list[dict[str, Any]]:
    return [{"env_id": env_id, "env_kwargs": env_kwargs, "policy": policy, "seed": int(s)} for s in seeds]
