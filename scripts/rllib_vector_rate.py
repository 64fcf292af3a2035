"""Sampled env steps/s of one RLlib env runner: RLlib's ``sync`` vector env against srenv's native one.

One local ``SingleAgentEnvRunner`` per mode (built from the training YAML as ``python -m agents train`` builds it:
PPO's default module, ``explore=True``, torch on one thread as in a Ray runner), ``num_envs_per_env_runner = N``
wells of each env (the default train scenario and horizon). Modes: ``sync`` (``vec_env: sync``, the default),
``native_t1`` / ``native_t2`` (``vec_env: native``, the vector env's pool on 1 / 2 threads) and ``native_p2``
(``vec_processes: 2``, two worker processes). After a warm-up sample (resets, compilation) the modes are sampled in
turn, ``--rounds`` times, the order rotated every round, each time ``N * --steps-per-env`` env steps with the same
weights and torch's exploration noise seeded alike (so every mode samples the same episodes - the same work -
``same_episodes`` checks it on the rewards); a mode's rate is
its best round and its median (env steps over wall time), with its CPU seconds per wall second (the process and its
threads; workers not counted) and ``env_step_share``, the share of the wall time spent in the vector env's ``step``
(the rest is RLlib: the module, the connectors, the episodes). Ratios are native over sync, as measured (gains or losses)::

    PYTHONPATH=. nice python scripts/rllib_vector_rate.py --json docs/archive/rllib_vector_rate.json
"""

from __future__ import annotations

import json
import os
import statistics
import sys
import time
from pathlib import Path
from typing import Any

from srenv.cli_types import OneLineParser
from srenv.declarations import Number
from srenv.errors import ConfigError
from srenv.outputs import atomic_write, check_outputs

MODES = {"sync": {"vec_env": "sync"}, "native_t1": {"vec_env": "native", "vec_processes": 1, "threads": 1},
         "native_t2": {"vec_env": "native", "vec_processes": 1, "threads": 2},
         "native_p2": {"vec_env": "native", "vec_processes": 2}}
ENV_IDS = ("srenv/SuckerRod-v2", "srenv/SuckerRod-v1")


def runner(env_id: str, n: int, mode: str, seed: int = 0) -> Any:
    from ray.rllib.env.single_agent_env_runner import SingleAgentEnvRunner

    from agents.training.rllib.config import build_algorithm_config, parse_rllib_config

    spec = dict(MODES[mode])
    threads = spec.pop("threads", None)
    cfg = parse_rllib_config({"backend": "rllib", "algo": "ppo", "env_id": env_id, "num_env_runners": 0,
                              "num_envs_per_env_runner": n, "seed": seed, **spec})
    algo_config = build_algorithm_config(cfg)
    if threads is not None:  # the pool's size (native_backend gives the cores)
        algo_config.env_config = {**algo_config.env_config, "threads": threads}
    return SingleAgentEnvRunner(config=algo_config)


def timed_steps(venv: Any) -> list[float]:
    """Accumulate the wall time of ``venv.step`` (the vector env's share of a sample) in the returned list."""
    spent, step = [0.0], venv.step

    def timed(actions: Any) -> Any:
        t0 = time.perf_counter()
        try:
            return step(actions)
        finally:
            spent[0] += time.perf_counter() - t0
    venv.step = timed  # the runner's DictInfoToList calls the instance's step
    return spent


def one_sample(r: Any, steps: int, seed: int, spent: list[float]) -> tuple[int, float, float, float, float]:
    """(env steps, wall s, CPU s of this process, sum of the rewards, wall s in the vector env's step) of one
    ``sample``, its exploration noise drawn from torch seeded with ``seed``: every mode samples the same actions, so
    the same episodes (the same work)."""
    import torch

    torch.manual_seed(seed)
    s0, w0, c0 = spent[0], time.perf_counter(), time.process_time()
    episodes = r.sample(num_timesteps=steps, explore=True)
    wall, cpu = time.perf_counter() - w0, time.process_time() - c0
    return (sum(len(e) for e in episodes), wall, cpu, float(sum(sum(e.get_rewards()) for e in episodes)),
            spent[0] - s0)


def measure(env_id: str, n: int, modes: list[str], steps_per_env: int, rounds: int) -> dict[str, Any]:
    runners = {m: runner(env_id, n, m) for m in modes}
    out: dict[str, Any] = {}
    spent: dict[str, list[float]] = {}
    try:
        first = next(iter(runners.values()))
        for m, r in runners.items():
            r.module.set_state(first.module.get_state())  # the same weights everywhere
            venv = r.env.unwrapped
            out[m] = {"vector_env": type(venv).__name__, "threads": getattr(venv, "threads", 1),
                      "processes": getattr(venv, "processes", 1)}
            spent[m] = timed_steps(venv)
            one_sample(r, 2 * n, 0, spent[m])  # warm-up: resets, compilation, the first exact strokes
        runs: dict[str, list] = {m: [] for m in modes}
        for k in range(rounds):
            for m in modes[k % len(modes):] + modes[:k % len(modes)]:
                runs[m].append(one_sample(runners[m], n * steps_per_env, 1 + k, spent[m]))
    finally:
        for r in runners.values():
            r.stop()
    for m, rs in runs.items():
        rates = [s / w for s, w, *_ in rs]
        wall = sum(w for _, w, *_ in rs)
        out[m].update({
            "env_steps_per_s_best": round(max(rates), 1), "env_steps_per_s_median": round(statistics.median(rates), 1),
            "cpu_per_wall": round(sum(c for _, _, c, *_ in rs) / wall, 2),
            "env_step_share": round(sum(x[4] for x in rs) / wall, 3),
            "env_steps": [s for s, *_ in rs], "reward_sums": [round(x[3], 9) for x in rs]})
    out["same_episodes"] = len({tuple(o["reward_sums"]) for m, o in out.items() if m in runs}) == 1
    if "sync" in out:
        for m in (m for m in modes if m != "sync"):
            for stat in ("best", "median"):
                key = f"env_steps_per_s_{stat}"
                out[m][f"over_sync_{stat}"] = round(out[m][key] / out["sync"][key], 3)
    return out


def main(argv: list[str] | None = None) -> int:
    ap = OneLineParser(prog="rllib_vector_rate.py", description=__doc__.splitlines()[0])
    ap.tool = "rllib_vector_rate.py"
    ap.add_argument("--json", help="write the results here (.json)")
    ap.add_argument("--env-id", action="append", choices=ENV_IDS, help="default: both (v2, then v1)")
    ap.add_argument("--n", action="append", type=Number("--n", int, hi=256, why="processes' memory").parse,
                    help="num_envs_per_env_runner (repeatable; default 8)")
    ap.add_argument("--mode", action="append", choices=list(MODES), help="default: all")
    ap.add_argument("--steps-per-env", type=Number("--steps-per-env", int, hi=10_000, why="wall time").parse,
                    default=8)
    ap.add_argument("--rounds", type=Number("--rounds", int, hi=100, why="wall time").parse, default=3)
    args = ap.parse_args(argv)
    try:
        check_outputs({"--json": (args.json, (".json",))})
    except ConfigError as exc:
        ap.error(f"{exc.field} = {args.json!r}: expected {exc.expected}")
    import torch

    torch.set_num_threads(1)  # as in a Ray runner (OMP_NUM_THREADS=1, agents/training/rllib/backend.py)
    modes = args.mode or list(MODES)
    result: dict[str, Any] = {"started_utc": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()),
                              "load_avg_start": os.getloadavg(), "cores": os.cpu_count(),
                              "steps_per_env": args.steps_per_env, "rounds": args.rounds, "results": {}}
    for env_id in args.env_id or list(ENV_IDS):
        for n in args.n or [8]:
            res = measure(env_id, n, modes, args.steps_per_env, args.rounds)
            result["results"][f"{env_id} N={n}"] = res
            print(json.dumps({f"{env_id} N={n}": res}), file=sys.stderr, flush=True)
    result["load_avg_end"] = os.getloadavg()
    text = json.dumps(result, indent=1)
    if args.json:
        atomic_write(args.json, lambda tmp: Path(tmp).write_text(text + "\n"))
    print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
