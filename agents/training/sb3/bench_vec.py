"""PPO training speed by vector env (docs/agents.md, "Vector envs"): ``python -m agents.training.sb3.bench_vec``.

The v2 residual run's settings (configs/train/ppo_residual_v2.yaml on the residual env, here with the
``fillage_pi`` base) trained for ``--steps`` environment steps with ``vec_env: dummy``, ``native`` (worker
processes) and ``subproc``, each ``n_envs`` wide, each in a fresh process, in alternating order over ``--rounds``
rounds (the machine's load shifts between rounds, not within a round's comparison). Per run: the setup time
(building the vector env and the model) and the training rate, ``steps / model.learn's wall time`` (rollouts and
the PPO updates). Per round: each backend's rate over dummy's; the JSON on stdout has min/median/max.
"""

from __future__ import annotations

import argparse
import json
import statistics
import subprocess
import sys
import time

CONFIG = "configs/train/ppo_residual_v2.yaml"
RESIDUAL = {"inner_env_id": "srenv/SuckerRod-v2", "base": "fillage_pi", "scale": 0.5}


def one_run(vec_env: str, n_envs: int, steps: int, processes: int) -> dict:
    """Set up and train one run in this process; its setup time and training rate."""
    import torch
    from stable_baselines3.common.vec_env import VecNormalize

    from ...evaluation.model_io import algorithms
    from ..config import load_train_config
    from ..residual_env import RESIDUAL_ENV_ID
    from .builders import build_policy_kwargs, build_vec_env, schedule

    torch.set_num_threads(1)  # as agents.training.sb3.train does
    t0 = time.perf_counter()
    base = load_train_config(CONFIG)
    over = {"env_id": RESIDUAL_ENV_ID, "env_kwargs": {**base.env_kwargs, **RESIDUAL}, "n_envs": n_envs,
            "vec_env": vec_env, **({"vec_processes": processes} if vec_env == "native" else {})}
    cfg = load_train_config(CONFIG, over)
    venv = build_vec_env(cfg, n_envs, cfg.seed, subproc=vec_env == "subproc", native=vec_env == "native")
    venv = VecNormalize(venv, **cfg.normalize)
    kwargs = {"device": "cpu", "verbose": 0, **{k: schedule(v) for k, v in cfg.algo_kwargs.items()}}
    model = algorithms()[cfg.algo](cfg.policy, venv, policy_kwargs=build_policy_kwargs(cfg.policy_kwargs),
                                   seed=cfg.seed, **kwargs)
    t1 = time.perf_counter()
    model.learn(total_timesteps=steps)
    t2 = time.perf_counter()
    venv.close()
    return {"vec_env": vec_env, "setup_s": round(t1 - t0, 2), "learn_s": round(t2 - t1, 2),
            "steps": int(model.num_timesteps), "steps_per_s": round(model.num_timesteps / (t2 - t1), 2)}


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--steps", type=int, default=3072)
    p.add_argument("--n-envs", type=int, default=2)
    p.add_argument("--rounds", type=int, default=3)
    p.add_argument("--processes", type=int, default=2, help="vec_processes of the native runs")
    p.add_argument("--one", help=argparse.SUPPRESS)  # internal: run one backend in this process
    a = p.parse_args(argv)
    if a.one:
        print(json.dumps(one_run(a.one, a.n_envs, a.steps, a.processes)))
        return 0
    backends = ["dummy", "native", "subproc"]
    rounds = []
    for r in range(a.rounds):
        order = backends[r % 3:] + backends[:r % 3]  # alternate which backend runs first
        runs = {}
        for b in order:
            cmd = [sys.executable, "-m", "agents.training.sb3.bench_vec", "--one", b, "--steps", str(a.steps),
                   "--n-envs", str(a.n_envs), "--processes", str(a.processes)]
            out = subprocess.run(cmd, check=True, capture_output=True, text=True).stdout
            runs[b] = json.loads(out.strip().splitlines()[-1])
            print(json.dumps({"round": r, **runs[b]}), file=sys.stderr, flush=True)
        rounds.append(runs)
    ratios = {b: [rd[b]["steps_per_s"] / rd["dummy"]["steps_per_s"] for rd in rounds] for b in backends[1:]}
    summary = {"config": CONFIG, "residual": RESIDUAL, "steps": a.steps, "n_envs": a.n_envs,
               "native_processes": a.processes, "rounds": rounds,
               "ratio_over_dummy": {b: {"min": round(min(v), 3), "median": round(statistics.median(v), 3),
                                        "max": round(max(v), 3)} for b, v in ratios.items()}}
    print(json.dumps(summary))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
