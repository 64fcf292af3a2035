"""``python -m agents train | evaluate | quickstart | benchmark | replay``.

Each command prints a JSON summary as its last stdout line (progress and notes go to stderr; ``evaluate``
with several policies prints a markdown comparison table before the JSON). Bad input prints one line
``agents: error: ...`` on stderr and exits with status 2.
"""

from __future__ import annotations

import argparse
import json
import math
import numbers
import signal
import sys
from pathlib import Path
from typing import Any

import yaml

from srenv.cli_types import EXIT_BAD_INPUT, command_parser
from srenv.shipped import shipped_dir

QUICK_BENCHMARK = shipped_dir("benchmark") / "v1_quick.yaml"  # the checkout's configs/, or the wheel's


# the usage names the command that runs this copy: a checkout's package `agents`, the wheel's `srenv_agents`
PROG = "python -m agents" if __name__.split(".")[0] == "agents" else "srenv-agents"


def _flag(command: str, flag: str) -> Any:
    """The argparse type of a declared flag (agents/inputs.py: type, unit, range)."""
    from .inputs import FLAGS

    return FLAGS[command][flag].parse


def _key_value(text: str) -> tuple[str, Any]:
    """``key=value`` with the value read as YAML (numbers, booleans, lists); never evaluated as code."""
    key, sep, value = text.partition("=")
    if not sep or not key:
        raise argparse.ArgumentTypeError(f"{text!r}: expected KEY=VALUE")
    from srenv.safe_yaml import _yaml_load

    try:
        return key, _yaml_load(value)
    except yaml.YAMLError:
        return key, value  # a plain string, as --set reads one


def _json_default(x: Any) -> Any:
    return float(x) if isinstance(x, (int, float)) else str(x)


def _print_json(obj: dict) -> None:
    # NaN/inf are not JSON: report them as null so every reader can parse the line
    def clean(v: Any) -> Any:
        if isinstance(v, numbers.Real) and not isinstance(v, (bool, numbers.Integral)):  # numpy floats too
            return float(v) if math.isfinite(float(v)) else None
        if isinstance(v, dict):
            return {k: clean(w) for k, w in v.items()}
        if isinstance(v, (list, tuple)):
            return [clean(w) for w in v]
        return v

    print(json.dumps(clean(obj), default=_json_default, allow_nan=False), flush=True)


def build_parser() -> argparse.ArgumentParser:
    p, sub = command_parser("agents", PROG, "Baselines, SB3 training and evaluation for srenv.")

    t = sub.add_parser("train", help="train PPO/SAC from a hyperparameter YAML (SB3, or RLlib with backend: rllib)")
    t.add_argument("config", help="training YAML, e.g. configs/train/ppo_default.yaml")
    t.add_argument("--total-timesteps", type=_flag("train", "--total-timesteps"),
                   help="override n_timesteps (total, incl. resumed)")
    t.add_argument("--out", help="output directory (default runs/<config name>)")
    t.add_argument("--resume", action="store_true", help="continue from the newest checkpoint in --out")
    t.add_argument("--n-envs", type=_flag("train", "--n-envs"),
                   help="override n_envs (default: all cores); num_env_runners for backend: rllib")
    t.add_argument("--address", help="backend: rllib: Ray cluster to join (auto, ray://host:10001); "
                                     "default a local Ray on 127.0.0.1")
    t.add_argument("--progress", action=argparse.BooleanOptionalAction, default=None,
                   help="progress bar (default: when stdout is a terminal)")

    e = sub.add_parser("evaluate", help="evaluate baselines and/or saved models on held-out seeds")
    e.add_argument("--policy", action="append", required=True,
                   help="rocking, fillage, an SB3 model .zip or an RLlib checkpoint directory; repeat to compare")
    e.add_argument("--episodes", type=_flag("evaluate", "--episodes"), default=20)
    e.add_argument("--seed", type=_flag("evaluate", "--seed"), default=1000,
                   help="first held-out seed (episodes use S..S+N-1)")
    e.add_argument("--config", default="default", help="well config name or YAML path")
    e.add_argument("--env-kwarg", type=_key_value, action="append", default=[], metavar="KEY=VALUE",
                   help="extra keyword for gymnasium.make (value read as YAML)")
    e.add_argument("--plot", help="PNG of a sample episode's cards and controls per policy")
    e.add_argument("--trust-model", action="store_true",
                   help="load model zips and *_vecnormalize.pkl through SB3/pickle, which runs any code they "
                   "contain: only for files you made yourself (default: read as data, nothing unpickled)")

    c = sub.add_parser("convert-stats", help="convert trusted *_vecnormalize.pkl files to the JSON that "
                       "evaluation reads without unpickling")
    c.add_argument("pickles", nargs="+", help="VecNormalize pickles you made yourself (they are unpickled)")

    q = sub.add_parser("quickstart", help="the shipped benchmarked agent vs the tuned baselines on a few test "
                       "wells, with a verdict; --train: a short training demo instead")
    q.add_argument("--train", action="store_true", help="the training demo: the v1 benchmark on a small scale "
                   "(tune baselines, train PPO/SAC for a minute)")
    q.add_argument("--workers", type=_flag("quickstart", "--workers"), default=2, help="processes (default 2)")
    q.add_argument("--env", choices=("v1", "v2"), default="v2",
                   help="whose shipped agent: srenv/SuckerRod-v2's (default) or v1's")
    q.add_argument("--config", default=str(QUICK_BENCHMARK), help="--train: benchmark YAML (default v1_quick.yaml)")
    q.add_argument("--out", default="runs/quickstart")
    q.add_argument("--total-timesteps", type=_flag("quickstart", "--total-timesteps"),
                   help="override every agent run's n_timesteps")
    q.add_argument("--episodes", type=_flag("quickstart", "--episodes"),
                   help="number of test episodes (default 3; --train: the config's)")
    q.add_argument("--seed", type=_flag("quickstart", "--seed"), help="--train: first test seed (S..S+N-1)")

    b = sub.add_parser("benchmark", help="tune baselines, train PPO/SAC, test all on unseen wells (v1, v2 or v3: "
                       "the YAML's env)")
    b.add_argument("config", help="benchmark YAML, e.g. configs/benchmark/v1.yaml")
    b.add_argument("--quick", action="store_true", help="apply the config's quick: block (minutes, for CI)")
    b.add_argument("--out-dir", help="output directory (default: the env version's shipped report folder, docs for v1 and docs/v2 for v2, with the models in models/; runs/benchmark_quick with --quick)")
    b.add_argument("--evaluate-only", action="store_true", help="no training or tuning: the shipped models and "
                   "tuned baselines on --episodes fresh family wells drawn from --fresh-seed")
    b.add_argument("--fresh-seed", type=_flag("benchmark", "--fresh-seed"),
                   help="--evaluate-only: seed of the fresh wells (recorded)")
    b.add_argument("--episodes", type=_flag("benchmark", "--episodes"), help="--evaluate-only: number of fresh wells")
    b.add_argument("--workers", type=_flag("benchmark", "--workers"),
                   help="--evaluate-only: processes (default the config's)")
    b.add_argument("--report", help="--evaluate-only: the benchmark report whose tuned baselines and agents are "
                   "evaluated, models read next to it (default: the shipped v1 report, models/MANIFEST.json)")

    r = sub.add_parser("replay", help="re-run a benchmark report's test episodes from its own record (v1, v2 or v3); "
                       "exit 1 if a return differs")
    r.add_argument("report", help="benchmark JSON, e.g. docs/benchmark.json (models are read next to it)")
    r.add_argument("--policy", action="append", help="a policy of the report; repeat (default: all but the oracle)")
    r.add_argument("--episodes", type=_flag("replay", "--episodes"), default=3,
                   help="the first N test episodes (default 3)")
    r.add_argument("--tol", type=_flag("replay", "--tol"), default=1e-9,
                   help="relative difference a return may have (default 1e-9: exact; a trained agent on another "
                   "CPU kind: torch's round-off, 0.05 covers it)")
    return p


def cmd_replay(args: argparse.Namespace) -> dict:
    from .evaluation.replay import replay

    return replay(args.report, args.policy, args.episodes, args.tol)


def cmd_train(args: argparse.Namespace) -> dict:
    from .inputs import check_output_dir
    from .training.config import load_train_config
    from .training.rllib.config import read_backend
    from .training.sb3.train import train

    out = args.out or str(Path("runs") / Path(args.config).stem)
    check_output_dir(Path(out), (), "--out")  # a file there, or under a file: refused before any work
    if read_backend(args.config) == "rllib":
        from .training.rllib import backend as rllib_backend
        from .training.rllib.config import load_rllib_config

        rcfg = load_rllib_config(args.config,
                                 {"num_env_runners": args.n_envs} if args.n_envs else None)
        return rllib_backend.train(rcfg, out, total_timesteps=args.total_timesteps, resume=args.resume,
                                   address=args.address)
    if args.address:
        raise ValueError(f"--address {args.address}: only for backend: rllib configs")
    cfg = load_train_config(args.config, {"n_envs": args.n_envs} if args.n_envs else None)
    progress = sys.stdout.isatty() if args.progress is None else args.progress
    return train(cfg, out, total_timesteps=args.total_timesteps, resume=args.resume, progress_bar=progress)


def report_evaluation(results: dict[str, dict], episodes: int, seed: int, config: str) -> dict:
    """Print the comparison table (several policies) and return the JSON summary."""
    from .evaluation.evaluate import markdown_table

    head = {"episodes": episodes, "seeds": [seed, seed + episodes - 1], "config": config}
    if len(results) == 1:
        return {**head, **next(iter(results.values()))}
    print(markdown_table(results), flush=True)
    best = max(results, key=lambda k: results[k]["mean_reward"])
    return {**head, "best_by_mean_reward": best, "policies": results}


def cmd_evaluate(args: argparse.Namespace) -> dict:
    from .evaluation.evaluate import evaluate

    results = evaluate(args.policy, args.episodes, args.seed, args.config, dict(args.env_kwarg), args.plot,
                       trust_model=args.trust_model)
    return report_evaluation(results, args.episodes, args.seed, args.config)


def cmd_convert_stats(args: argparse.Namespace) -> dict:
    """X_vecnormalize.pkl -> X_vecnormalize.json (the pickle is trusted: the user says they made it)."""
    import pickle

    from .evaluation.model_io import STATS_SUFFIX, write_stats

    written = []
    for name in args.pickles:
        src = Path(name)
        if not src.name.endswith("_vecnormalize.pkl") or not src.is_file():
            raise FileNotFoundError(f"{name}: expected an existing <model>_vecnormalize.pkl")
        with open(src, "rb") as fh:
            vn = pickle.load(fh)  # explicitly trusted by the caller
        dst = src.with_name(src.name.removesuffix("_vecnormalize.pkl") + STATS_SUFFIX)
        write_stats(vn, dst)
        written.append(str(dst))
    return {"written": written}


def cmd_quickstart(args: argparse.Namespace) -> dict:
    if not args.train:  # prints its table, verdict and file locations itself: no JSON after them
        from .benchmark.shipped_quickstart import quickstart_shipped

        quickstart_shipped(args.out, args.episodes or 3, workers=args.workers, version=args.env)
        return {"_printed": True}
    from .benchmark.run import quickstart

    return quickstart(args.config, args.out, args.total_timesteps, args.episodes, args.seed)


def cmd_benchmark(args: argparse.Namespace) -> dict:
    if args.evaluate_only or args.fresh_seed is not None or args.episodes or args.report is not None:
        if not (args.evaluate_only and args.fresh_seed is not None and args.episodes and not args.quick):
            raise ValueError("--evaluate-only, --fresh-seed S and --episodes N go together (and without --quick)")
        from .benchmark.fresh import evaluate_fresh

        return evaluate_fresh(args.config, args.fresh_seed, args.episodes, args.out_dir or "runs/fresh",
                              args.workers, report=args.report)
    from .benchmark.run import benchmark_main

    return benchmark_main(args.config, args.quick, args.out_dir)


def _eval_env_kwargs(train_env_kwargs: dict) -> dict:
    """Evaluate on the env the model was trained on, except the well config, which evaluate() sets."""
    return {k: v for k, v in train_env_kwargs.items() if k != "config"}


def main(argv: list[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    from srenv.errors import ConfigError

    from .training.config import TrainConfigError

    commands = {"train": cmd_train, "evaluate": cmd_evaluate, "quickstart": cmd_quickstart,
                "convert-stats": cmd_convert_stats, "benchmark": cmd_benchmark,
                "replay": cmd_replay}
    from srenv.interrupts import EXIT_INTERRUPTED, raise_on_sigterm

    previous = signal.signal(signal.SIGTERM, raise_on_sigterm) if argv is None else None
    try:
        result = commands[args.command](args)
    except (ConfigError, TrainConfigError, ValueError, FileNotFoundError) as exc:
        print(f"agents: error: {exc}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except KeyboardInterrupt:  # Ctrl-C or SIGTERM: one line, status 130 (no traceback)
        print("agents: interrupted", file=sys.stderr)
        return EXIT_INTERRUPTED
    finally:
        if previous is not None:
            signal.signal(signal.SIGTERM, previous)
    if not result.pop("_printed", False):  # the quick start printed its table, verdict and file locations
        _print_json(result)
    return 1 if result.get("reproduced") is False else 0  # replay: a return differs from the report's


if __name__ == "__main__":
    sys.exit(main())
