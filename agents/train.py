"""Stable-Baselines3 training from an rl-zoo3-style hyperparameter YAML.

One YAML file describes one run (read with srenv's bounded safe loader, duplicate keys refused; nothing in
it is evaluated as code, and ``env_id`` must be an id srenv registers)::

    algo: ppo                      # ppo | sac | a2c | td3
    env_kwargs: {config: default}  # passed to gymnasium.make("srenv/SuckerRod-v0", **env_kwargs)
    n_envs: null                   # null = os.cpu_count(); SubprocVecEnv when > 1
    n_timesteps: 200000
    policy: MlpPolicy
    policy_kwargs: {net_arch: [64, 64], activation_fn: tanh}
    normalize: {norm_obs: true, norm_reward: true}   # or true / false
    seed: 0
    checkpoint_freq: 20000         # environment steps between checkpoints (summed over envs)
    eval_freq: 10000               # environment steps between EvalCallback evaluations
    n_eval_episodes: 5
    eval_seed: 10000               # eval-callback episodes; keep away from the held-out test seeds
    learning_rate: lin_3.0e-4      # every other key is an algorithm keyword argument
    ...

Outputs in ``--out DIR``: ``model.zip`` + ``model_vecnormalize.json`` (the normalisation statistics are
part of the policy: without them the network sees unscaled inputs; JSON so that evaluation reads them
without unpickling, the ``.pkl`` beside it is for resuming), ``best/best_model.zip`` +
``best/best_model_vecnormalize.json`` / ``.pkl`` + ``best/best_model.json`` (EvalCallback; its best mean
reward), ``checkpoints/`` (model, VecNormalize and, for
off-policy algorithms, replay buffer every ``checkpoint_freq`` steps), ``tb/`` (TensorBoard) and
``train_config.json`` (the resolved configuration). ``--resume`` continues from the newest readable
checkpoint with its statistics and the step count carried on (``reset_num_timesteps=False``).
"""

from __future__ import annotations

import inspect
import json
import math
import os
import re
import sys
import time
from collections.abc import Callable
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

from srenv.errors import short_repr

ENV_ID = "srenv/SuckerRod-v0"
VECNORM_SUFFIX = "_vecnormalize.pkl"
CHECKPOINT_PREFIX = "rl_model"
_CHECKPOINT_RE = re.compile(rf"^{CHECKPOINT_PREFIX}_(\d+)_steps\.zip$")

# Keys of the YAML that configure the harness; every other key goes to the algorithm's constructor.
_HARNESS_KEYS = {"algo", "env_id", "env_kwargs", "n_envs", "n_timesteps", "policy", "policy_kwargs",
                 "normalize", "seed", "checkpoint_freq", "eval_freq", "n_eval_episodes", "eval_seed",
                 "save_replay_buffer", "vec_env", "backend"}


def algorithms() -> dict[str, type]:
    """Supported SB3 algorithms by YAML name (imported lazily: torch is slow to import)."""
    from stable_baselines3 import A2C, PPO, SAC, TD3

    return {"ppo": PPO, "sac": SAC, "a2c": A2C, "td3": TD3}


RESIDUAL_ENV_ID = "agents.residual_v1:ResidualSuckerRod-v1"


def allowed_env_ids() -> list[str]:
    """The Gymnasium ids srenv registers (``srenv/...``): the only ones a training YAML may name."""
    import gymnasium as gym

    import srenv  # noqa: F401  (registers its envs)

    # plus the benchmark's residual env, which this package registers itself (agents/residual_v1.py): a fixed id
    # naming our own module, never a module chosen by the YAML
    return sorted(k for k in gym.registry if k.startswith("srenv/") and ":" not in k) + [RESIDUAL_ENV_ID]


class TrainConfigError(ValueError):
    """A training YAML that cannot be used; the message names the key and what was expected."""


@dataclass
class TrainConfig:
    algo: str
    env_id: str = ENV_ID
    env_kwargs: dict[str, Any] = field(default_factory=dict)
    n_envs: int = 0  # 0 = os.cpu_count()
    n_timesteps: int = 100_000
    policy: str = "MlpPolicy"
    policy_kwargs: dict[str, Any] = field(default_factory=dict)
    normalize: dict[str, Any] | None = None  # VecNormalize kwargs, None = no normalisation
    seed: int = 0
    checkpoint_freq: int = 10_000
    eval_freq: int = 10_000
    n_eval_episodes: int = 5
    eval_seed: int = 10_000
    save_replay_buffer: bool = True
    vec_env: str = "subproc"
    algo_kwargs: dict[str, Any] = field(default_factory=dict)

    @property
    def resolved_n_envs(self) -> int:
        return self.n_envs or os.cpu_count() or 1


def _expect(cond: bool, key: str, value: Any, what: str) -> None:
    if not cond:
        raise TrainConfigError(f"train config: {key} = {value!r}: expected {what}")


def _positive_int(data: dict, key: str, default: int) -> int:
    v = data.get(key, default)
    _expect(isinstance(v, int) and not isinstance(v, bool) and v > 0, key, v, "a positive integer")
    return int(v)


def _seed(data: dict, key: str, default: int) -> int:
    v = data.get(key, default)
    _expect(isinstance(v, int) and not isinstance(v, bool) and 0 <= v < 2**32, key, v,
            "an integer seed in [0, 2^32)")
    return int(v)


_FLOAT_RE = re.compile(r"^[-+]?[0-9][0-9_]*(?:\.[0-9_]*)?[eE][-+]?[0-9]+$")


def _yaml12_float(value: Any) -> Any:
    """PyYAML (YAML 1.1) reads ``1e-4`` - no dot - as a string; every other tool reads a number."""
    return float(value) if isinstance(value, str) and _FLOAT_RE.match(value) else value


def parse_train_config(data: Any, source: str = "<dict>") -> TrainConfig:
    """Validate a YAML mapping into a :class:`TrainConfig` (clear errors, no evaluation of strings)."""
    _expect(isinstance(data, dict), source, type(data).__name__, "a mapping of hyperparameters")
    _expect(data.get("backend", "sb3") == "sb3", "backend", data.get("backend"),
            "sb3 here (backend: rllib is read by agents.rllib_backend)")
    algo = str(data.get("algo", "")).lower()
    _expect(algo in algorithms(), "algo", data.get("algo"), "one of " + ", ".join(algorithms()))
    n_envs = data.get("n_envs") or 0
    _expect(isinstance(n_envs, int) and n_envs >= 0, "n_envs", n_envs, "a positive integer or null")
    normalize = data.get("normalize", False)
    _expect(isinstance(normalize, (bool, dict)), "normalize", normalize, "true, false or a mapping")
    env_kwargs = data.get("env_kwargs") or {}
    _expect(isinstance(env_kwargs, dict), "env_kwargs", env_kwargs, "a mapping")
    policy_kwargs = data.get("policy_kwargs") or {}
    _expect(isinstance(policy_kwargs, dict), "policy_kwargs", policy_kwargs,
            "a mapping (strings of Python code are not evaluated)")
    vec_env = data.get("vec_env", "subproc")
    _expect(vec_env in ("subproc", "dummy"), "vec_env", vec_env, "subproc or dummy")
    env_id = data.get("env_id", ENV_ID)
    allowed = allowed_env_ids()
    # gymnasium.make("module:Env-v0") imports `module` (from the working directory, too): only ids that
    # srenv itself registers are accepted, so a YAML can never name code to import
    _expect(isinstance(env_id, str) and env_id in allowed, "env_id", env_id, "one of " + ", ".join(allowed))
    cfg = TrainConfig(
        algo=algo, env_id=env_id, env_kwargs=dict(env_kwargs), n_envs=n_envs,
        n_timesteps=_positive_int(data, "n_timesteps", 100_000), policy=str(data.get("policy", "MlpPolicy")),
        policy_kwargs=dict(policy_kwargs),
        normalize=(dict(normalize) if isinstance(normalize, dict) else ({} if normalize else None)),
        seed=_seed(data, "seed", 0), checkpoint_freq=_positive_int(data, "checkpoint_freq", 10_000),
        eval_freq=_positive_int(data, "eval_freq", 10_000),
        n_eval_episodes=_positive_int(data, "n_eval_episodes", 5), eval_seed=_seed(data, "eval_seed", 10_000),
        save_replay_buffer=bool(data.get("save_replay_buffer", True)), vec_env=vec_env,
        algo_kwargs={k: _yaml12_float(v) for k, v in data.items() if k not in _HARNESS_KEYS},
    )
    # keywords the harness passes itself: verbose / device may override its defaults, the others may not
    for key in ("tensorboard_log", "_init_setup_model"):
        _expect(key not in cfg.algo_kwargs, key, cfg.algo_kwargs.get(key), "no value (set by the harness)")
    if "verbose" in cfg.algo_kwargs:
        v = cfg.algo_kwargs["verbose"]
        _expect(v in (0, 1, 2) and not isinstance(v, bool), "verbose", v, "0, 1 or 2")
    if "device" in cfg.algo_kwargs:
        d = cfg.algo_kwargs["device"]
        _expect(isinstance(d, str) and re.fullmatch(r"cpu|auto|cuda(:\d+)?", d) is not None, "device", d,
                "cpu, auto or cuda[:N]")
        if d.startswith("cuda"):
            import torch

            _expect(torch.cuda.is_available(), "device", d, "cpu or auto (no CUDA device here)")
    # Unknown keys would otherwise surface as a TypeError deep inside SB3, far from the YAML line.
    accepted = set(inspect.signature(algorithms()[algo].__init__).parameters) - {"self", "policy", "env"}
    for key in sorted(set(cfg.algo_kwargs) - accepted):
        _expect(False, key, cfg.algo_kwargs[key], f"a {algo.upper()} argument or one of {sorted(_HARNESS_KEYS)}")
    return cfg


def load_train_config(path: str | Path, overrides: dict[str, Any] | None = None) -> TrainConfig:
    """Read a training YAML with srenv's bounded safe loader: bad syntax, a key given twice, a file too
    large or unreadable are each one TrainConfigError line."""
    from srenv.config import load_yaml_file
    from srenv.errors import ConfigError

    try:
        data = load_yaml_file(path, "train config")
    except ConfigError as exc:
        raise TrainConfigError(f"train config {short_repr(str(path))}: expected {exc.expected}") from None
    if isinstance(data, dict) and overrides:
        data = {**data, **overrides}
    return parse_train_config(data, str(path))


# --------------------------------------------------------------------------------------------- builders
def schedule(value: Any) -> Any:
    """rl-zoo's ``lin_<x>`` strings become a linear decay from x to 0 over training; numbers pass through."""
    if isinstance(value, str) and value.startswith("lin_"):
        start = float(value[4:])

        def linear(progress_remaining: float) -> float:
            return progress_remaining * start

        return linear
    return value


def _activation(name: Any) -> type:
    from torch import nn

    key = str(name).removeprefix("nn.").lower().replace("_", "")
    by_name = {n.lower(): c for n, c in vars(nn).items() if isinstance(c, type) and issubclass(c, nn.Module)}
    _expect(key in by_name, "policy_kwargs.activation_fn", name, "a torch.nn activation name, e.g. tanh, relu")
    return by_name[key]


def build_policy_kwargs(policy_kwargs: dict[str, Any]) -> dict[str, Any]:
    out = dict(policy_kwargs)
    if "activation_fn" in out:
        out["activation_fn"] = _activation(out["activation_fn"])
    return out


def make_env(env_id: str = ENV_ID, **env_kwargs: Any) -> Any:
    """Module-level env factory: picklable into SubprocVecEnv workers, and registers srenv there."""
    import gymnasium as gym

    import srenv  # noqa: F401  (registers srenv/SuckerRod-v0 in this process)

    return gym.make(env_id, **env_kwargs)


def build_vec_env(cfg: TrainConfig, n_envs: int, seed: int, subproc: bool) -> Any:
    from functools import partial

    from stable_baselines3.common.env_util import make_vec_env
    from stable_baselines3.common.vec_env import DummyVecEnv, SubprocVecEnv

    factory = partial(make_env, cfg.env_id, **cfg.env_kwargs)
    cls = SubprocVecEnv if subproc and n_envs > 1 else DummyVecEnv
    return make_vec_env(factory, n_envs=n_envs, seed=seed, vec_env_cls=cls)


# ------------------------------------------------------------------------------------------- checkpoints
def vecnormalize_path(model_path: str | Path) -> Path | None:
    """The VecNormalize statistics that belong to a saved model, if any.

    Conventions, in order: ``X.zip`` -> ``X_vecnormalize.pkl`` (this package), SB3 checkpoints
    ``rl_model_N_steps.zip`` -> ``rl_model_vecnormalize_N_steps.pkl``, rl-zoo's ``vecnormalize.pkl``.
    """
    p = Path(model_path)
    stem = p.name.removesuffix(".zip")
    m = re.match(r"^(.*)_(\d+)_steps$", stem)
    candidates = [p.with_name(stem + VECNORM_SUFFIX), p.with_name("vecnormalize.pkl")]
    if m:
        candidates.insert(1, p.with_name(f"{m.group(1)}_vecnormalize_{m.group(2)}_steps.pkl"))
    return next((c for c in candidates if c.is_file()), None)


def checkpoints(out_dir: str | Path) -> list[tuple[int, Path]]:
    """(timesteps, path) of the checkpoints in ``out_dir/checkpoints``, newest first."""
    d = Path(out_dir) / "checkpoints"
    found = [(int(m.group(1)), p) for p in d.glob("*.zip") if (m := _CHECKPOINT_RE.match(p.name))]
    return sorted(found, reverse=True)


BEST_RECORD = "best_model.json"


def _save_vecnormalize_callback(path: Path) -> Any:
    """EvalCallback's ``callback_on_new_best``: keep the statistics that the best model was evaluated with
    (pickle for resuming, JSON for evaluation) and the best mean reward, so that a resumed run whose eval
    history is lost still does not overwrite a better best_model with a worse one."""
    from stable_baselines3.common.callbacks import BaseCallback

    from .model_io import stats_path, write_stats

    class SaveVecNormalize(BaseCallback):
        def _on_step(self) -> bool:
            vn = self.model.get_vec_normalize_env()
            if vn is not None:
                vn.save(str(path))
                write_stats(vn, stats_path(path.parent / "best_model.zip"))
            best = float(self.parent.best_mean_reward)
            record = {"best_mean_reward": best, "num_timesteps": int(self.num_timesteps)}
            (path.parent / BEST_RECORD).write_text(json.dumps(record))
            return True

    return SaveVecNormalize()


def _recorded_best(best_dir: Path) -> float:
    """Best mean reward of an earlier run into the same directory (-inf when none is readable)."""
    try:
        value = float(json.loads((best_dir / BEST_RECORD).read_text())["best_mean_reward"])
    except (OSError, ValueError, KeyError, TypeError):
        return -math.inf
    return value if math.isfinite(value) else -math.inf


def _eval_reporter() -> Any:
    """One line per evaluation on stderr: stdout stays for the JSON summary."""
    from stable_baselines3.common.callbacks import BaseCallback

    class Report(BaseCallback):
        def _on_step(self) -> bool:
            parent = self.parent
            print(f"eval @ {self.num_timesteps} steps: mean reward {parent.last_mean_reward:.3f} "
                  f"(best {parent.best_mean_reward:.3f})", file=sys.stderr, flush=True)
            return True

    return Report()


def _load_checkpoint(cfg: TrainConfig, venv_raw: Any, out_dir: Path) -> tuple[Any, Any, Path] | None:
    """Newest checkpoint that loads (a kill during a save can leave the newest one truncated)."""
    from stable_baselines3.common.vec_env import VecNormalize

    algo = algorithms()[cfg.algo]
    for steps, path in checkpoints(out_dir):
        try:
            venv = venv_raw
            if cfg.normalize is not None:
                stats = vecnormalize_path(path)
                if stats is None:
                    raise FileNotFoundError(f"no VecNormalize statistics next to {path}")
                venv = VecNormalize.load(str(stats), venv_raw)
                venv.training = True
            model = algo.load(str(path), env=venv, device="cpu",
                              custom_objects=_schedule_objects(cfg))
        except Exception as exc:  # noqa: BLE001 - any unreadable checkpoint: fall back to the previous one
            print(f"resume: skipping checkpoint {path.name} ({exc})", file=sys.stderr)
            continue
        buffer = path.with_name(f"{CHECKPOINT_PREFIX}_replay_buffer_{steps}_steps.pkl")
        if buffer.is_file() and hasattr(model, "load_replay_buffer"):
            try:
                model.load_replay_buffer(str(buffer))
            except Exception as exc:  # noqa: BLE001 - a truncated buffer: continue with an empty one
                print(f"resume: skipping replay buffer {buffer.name} ({type(exc).__name__}: "
                      f"{str(exc)[:120]}); continuing with an empty buffer", file=sys.stderr)
        return model, venv, path
    return None


def _restore_eval_history(eval_cb: Any, npz_path: Path, upto_steps: int) -> None:
    """Carry the evaluations before the checkpoint into the resumed EvalCallback.

    A fresh callback starts from best = -inf and rewrites evaluations.npz with its own results only, so
    after a resume the first evaluation would overwrite a better ``best_model`` and the history be lost.
    """
    import numpy as np

    if not npz_path.is_file():
        return
    try:
        with np.load(npz_path, allow_pickle=False) as h:
            keep = h["timesteps"] <= upto_steps
            timesteps = h["timesteps"][keep].tolist()
            results = h["results"][keep].tolist()
            lengths = h["ep_lengths"][keep].tolist()
    except Exception as exc:  # noqa: BLE001 - truncated / not an npz: resume without the history
        print(f"resume: skipping evaluation history {npz_path.name} ({type(exc).__name__}: {str(exc)[:120]})",
              file=sys.stderr)
        return
    eval_cb.evaluations_timesteps, eval_cb.evaluations_results, eval_cb.evaluations_length = (
        timesteps, results, lengths)
    if eval_cb.evaluations_results:
        eval_cb.best_mean_reward = float(max(np.mean(r) for r in eval_cb.evaluations_results))


def _schedule_objects(cfg: TrainConfig) -> dict[str, Any]:
    """Schedules are pickled closures; re-create them from the YAML so a checkpoint loads on any install."""
    return {k: schedule(cfg.algo_kwargs[k]) for k in ("learning_rate", "clip_range")
            if k in cfg.algo_kwargs}


# ------------------------------------------------------------------------------------------------ train
def train(cfg: TrainConfig, out_dir: str | Path, total_timesteps: int | None = None, resume: bool = False,
          progress_bar: bool = False, log: Callable[[str], None] | None = None) -> dict[str, Any]:
    """Train (or continue) one run; returns the JSON-ready summary."""
    import torch
    from stable_baselines3.common.callbacks import CallbackList, CheckpointCallback, EvalCallback
    from stable_baselines3.common.vec_env import VecNormalize

    log = log or (lambda msg: print(msg, file=sys.stderr, flush=True))
    # The env workers take the cores; a multi-threaded torch in the learner would only fight them.
    torch.set_num_threads(1)
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    target = int(total_timesteps or cfg.n_timesteps)
    n_envs = cfg.resolved_n_envs
    t_start = time.perf_counter()
    venv_raw = build_vec_env(cfg, n_envs, cfg.seed, subproc=cfg.vec_env == "subproc")
    eval_env = build_vec_env(cfg, 1, cfg.eval_seed, subproc=False)
    loaded = _load_checkpoint(cfg, venv_raw, out) if resume else None
    resumed_from = None
    if loaded is not None:
        model, venv, path = loaded
        resumed_from = str(path)
        log(f"resume: {path.name} at {model.num_timesteps} steps")
    else:
        if resume:
            log(f"resume: no checkpoint in {out / 'checkpoints'}, starting from scratch")
        venv = VecNormalize(venv_raw, **cfg.normalize) if cfg.normalize is not None else venv_raw
        kwargs = {"device": "cpu", "verbose": 0, **{k: schedule(v) for k, v in cfg.algo_kwargs.items()}}
        model = algorithms()[cfg.algo](cfg.policy, venv, policy_kwargs=build_policy_kwargs(cfg.policy_kwargs),
                                       tensorboard_log=str(out / "tb"), seed=cfg.seed, **kwargs)
    if cfg.normalize is not None:
        # evaluation sees normalised observations but raw rewards; EvalCallback syncs the statistics
        eval_env = VecNormalize(eval_env, training=False, norm_obs=cfg.normalize.get("norm_obs", True),
                                norm_reward=False)
    (out / "train_config.json").write_text(json.dumps(asdict(cfg), indent=2, default=str))
    best_dir = out / "best"
    eval_cb = EvalCallback(
        eval_env, n_eval_episodes=cfg.n_eval_episodes, eval_freq=max(cfg.eval_freq // n_envs, 1),
        best_model_save_path=str(best_dir), log_path=str(out / "eval"), deterministic=True, verbose=0,
        callback_on_new_best=_save_vecnormalize_callback(best_dir / ("best_model" + VECNORM_SUFFIX)),
        callback_after_eval=_eval_reporter())
    if resumed_from is not None:
        _restore_eval_history(eval_cb, out / "eval" / "evaluations.npz", model.num_timesteps)
    if (best_dir / "best_model.zip").is_file():
        # whatever the history says, never replace an existing best_model by a worse one
        eval_cb.best_mean_reward = max(eval_cb.best_mean_reward, _recorded_best(best_dir))
    ckpt_cb = CheckpointCallback(
        save_freq=max(cfg.checkpoint_freq // n_envs, 1), save_path=str(out / "checkpoints"),
        name_prefix=CHECKPOINT_PREFIX, save_vecnormalize=True, save_replay_buffer=cfg.save_replay_buffer)
    remaining = target - model.num_timesteps
    if remaining > 0:
        model.learn(total_timesteps=remaining, callback=CallbackList([ckpt_cb, eval_cb]),
                    reset_num_timesteps=resumed_from is None, tb_log_name=cfg.algo, progress_bar=progress_bar)
    model_path = out / "model.zip"
    model.save(str(model_path))
    stats_path = None
    if model.get_vec_normalize_env() is not None:
        from .model_io import stats_path as json_stats_path
        from .model_io import write_stats

        stats_path = out / ("model" + VECNORM_SUFFIX)
        model.get_vec_normalize_env().save(str(stats_path))  # pickle: what SB3 needs to resume
        write_stats(model.get_vec_normalize_env(), json_stats_path(model_path))  # JSON: what evaluation reads
    venv.close()
    eval_env.close()
    best = best_dir / "best_model.zip"
    return {
        "algo": cfg.algo,
        "num_timesteps": int(model.num_timesteps),
        "target_timesteps": target,
        "n_envs": n_envs,
        "wall_time_s": round(time.perf_counter() - t_start, 2),
        "resumed_from": resumed_from,
        "model": str(model_path),
        "vecnormalize": str(stats_path) if stats_path else None,
        "best_model": str(best) if best.is_file() else None,
        "best_eval_mean_reward": _finite_or_none(eval_cb.best_mean_reward),
        "last_eval_mean_reward": _finite_or_none(eval_cb.last_mean_reward),
        "tensorboard": str(out / "tb"),
    }


def _finite_or_none(x: float) -> float | None:
    return float(x) if math.isfinite(x) else None
