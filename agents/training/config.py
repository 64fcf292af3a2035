"""The SB3 training YAML: its schema, validation and reading (``python -m agents train CONFIG.yaml``).

One YAML file describes one run (read with srenv's bounded safe loader, duplicate keys refused; nothing in
it is evaluated as code, and ``env_id`` must be an id srenv registers)::

    algo: ppo                      # ppo | sac | a2c | td3
    env_kwargs: {config: default}  # passed to gymnasium.make("srenv/SuckerRod-v0", **env_kwargs)
    n_envs: null                   # null = os.cpu_count(); SubprocVecEnv when > 1
    vec_env: subproc               # subproc | dummy (SB3's) | native (srenv's vector env, v1/v2 and wrappers;
                                   # the RLlib YAML takes sync | native: agents.training.rllib.config)
    vec_processes: 0               # native only: worker processes, 0 = one per core, 1 = threads in this process
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

The checks shared with the RLlib backend's YAML (:mod:`agents.training.rllib.config`) live here too.
"""

from __future__ import annotations

import inspect
import os
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from srenv.errors import short_repr
from srenv.safe_yaml import yaml_kind

from ..envs import ENV_ID_V0
from ..evaluation.model_io import algorithms
from .residual_env import RESIDUAL_ENV_ID

# Keys of the YAML that configure the harness; every other key goes to the algorithm's constructor.
_HARNESS_KEYS = {"algo", "env_id", "env_kwargs", "n_envs", "n_timesteps", "policy", "policy_kwargs",
                 "normalize", "seed", "checkpoint_freq", "eval_freq", "n_eval_episodes", "eval_seed",
                 "save_replay_buffer", "vec_env", "vec_processes", "backend"}


def allowed_env_ids() -> list[str]:
    """The Gymnasium ids srenv registers (``srenv/...``): the only ones a training YAML may name."""
    import gymnasium as gym

    import srenv  # noqa: F401  (registers its envs)

    # plus the benchmark's residual env, which this package registers itself (agents/training/residual_env.py): a fixed id
    # naming our own module, never a module chosen by the YAML
    return sorted(k for k in gym.registry if k.startswith("srenv/") and ":" not in k) + [RESIDUAL_ENV_ID]


class TrainConfigError(ValueError):
    """A training YAML that cannot be used; the message names the key and what was expected."""


@dataclass
class TrainConfig:
    algo: str
    env_id: str = ENV_ID_V0
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
    vec_processes: int = 0  # vec_env native: 0 = one worker process per core (capped at n_envs), 1 = threads
    algo_kwargs: dict[str, Any] = field(default_factory=dict)

    @property
    def resolved_n_envs(self) -> int:
        return self.n_envs or os.cpu_count() or 1


def _expect(cond: bool, key: str, value: Any, what: str) -> None:
    if not cond:
        raise TrainConfigError(f"train config: {key} = {value!r}: expected {what}")


def declared(key: str, value: Any) -> int:
    """A field declared in agents/inputs.py (type and bound), refused as a TrainConfigError."""
    from srenv.errors import ConfigError, short_repr

    from ..inputs import FIELDS

    try:
        return FIELDS["train"][key].check(value, key)
    except ConfigError as exc:  # the training YAML's own message form: "train config: key = value: expected ..."
        raise TrainConfigError(f"train config: {key} = {short_repr(value)}: expected {exc.expected}") from None


def _positive_int(data: dict, key: str, default: int) -> int:
    from ..inputs import FIELDS

    v = data.get(key, default)
    if key in FIELDS["train"]:  # declared with a bound (agents/inputs.py)
        return declared(key, v)
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


# vec_env's values per backend, the default first: SB3's own vector envs or RLlib's (gymnasium's sync), or srenv's
VEC_ENVS = {"sb3": ("subproc", "dummy", "native"), "rllib": ("sync", "native")}


def vec_env_keys(data: dict, backend: str, env_id: str, env_kwargs: dict) -> tuple[str, int]:
    """``vec_env`` and ``vec_processes`` of a training YAML of either backend, checked (one TrainConfigError line).

    ``native`` needs an env with srenv's vector entry point (v1, v2; with SB3 also the residual / shaped env on
    one, whose wrappers go inside each slot); ``vec_processes`` is for ``native`` only.
    """
    values = VEC_ENVS[backend]
    vec_env = data.get("vec_env", values[0])
    _expect(vec_env in values, "vec_env", vec_env, ", ".join(values[:-1]) + " or " + values[-1])
    vec_processes = declared("vec_processes", data.get("vec_processes", 0))
    _expect(vec_env == "native" or "vec_processes" not in data, "vec_processes", data.get("vec_processes"),
            "no value unless vec_env: native")
    if vec_env == "native":
        from .native_vec import NATIVE_IDS, native_plan

        try:
            inner = native_plan(env_id, env_kwargs)[0]
        except ValueError as exc:
            raise TrainConfigError(str(exc)) from None
        _expect(backend == "sb3" or inner == env_id, "env_id", env_id,
                f"{' or '.join(NATIVE_IDS)} with vec_env: native and backend: {backend} (the residual and shaped "
                "envs take it with sb3)")
    return vec_env, vec_processes


# rl-zoo3's hyperparameter files (configs/train/zoo_ppo.yml) are keyed by env id: a top-level key of that form
_ENV_ID_KEY = re.compile(r"^(?:[\w.:-]+/)?[\w.:-]+-v\d+$")
_FLAT = "python -m agents train reads the flat layout: algo, env_id, ... at the top level"
_ZOO = "rl-zoo3's layout, read by python -m rl_zoo3.train -conf"


def require_mapping(data: Any, source: str) -> dict:
    """A training YAML (either backend) is a mapping at the top level, not in rl-zoo3's layout (a mapping under
    each env id): otherwise one TrainConfigError line naming the file or the env id, the value and its type, and
    what is expected."""
    if not isinstance(data, dict):
        raise TrainConfigError(f"train config {source} = {short_repr(data, 80)} ({yaml_kind(data)}): expected a "
                               "mapping of hyperparameters (key: value lines)")
    key = next((k for k in data if isinstance(k, str) and k not in _HARNESS_KEYS and _ENV_ID_KEY.match(k)), None)
    if key is not None:
        value = data[key]
        expected = (f"the flat layout, not {_ZOO} ({_FLAT})" if isinstance(value, dict)
                    else f"a mapping of hyperparameters under the env id ({_ZOO}; {_FLAT})")
        raise TrainConfigError(f"train config {source}: {key[:80]} = {short_repr(value, 80)} ({yaml_kind(value)}): "
                               f"expected {expected}")
    return data


def parse_train_config(data: Any, source: str = "<dict>") -> TrainConfig:
    """Validate a YAML mapping into a :class:`TrainConfig` (clear errors, no evaluation of strings)."""
    require_mapping(data, source)
    _expect(data.get("backend", "sb3") == "sb3", "backend", data.get("backend"),
            "sb3 here (backend: rllib is read by agents.training.rllib.config)")
    algo = str(data.get("algo", "")).lower()
    _expect(algo in algorithms(), "algo", data.get("algo"), "one of " + ", ".join(algorithms()))
    n_envs = declared("n_envs", data.get("n_envs") or 0)
    normalize = data.get("normalize", False)
    _expect(isinstance(normalize, (bool, dict)), "normalize", normalize, "true, false or a mapping")
    env_kwargs = data.get("env_kwargs") or {}
    _expect(isinstance(env_kwargs, dict), "env_kwargs", env_kwargs, "a mapping")
    policy_kwargs = data.get("policy_kwargs") or {}
    _expect(isinstance(policy_kwargs, dict), "policy_kwargs", policy_kwargs,
            "a mapping (strings of Python code are not evaluated)")
    env_id = data.get("env_id", ENV_ID_V0)
    allowed = allowed_env_ids()
    # gymnasium.make("module:Env-v0") imports `module` (from the working directory, too): only ids that
    # srenv itself registers are accepted, so a YAML can never name code to import
    _expect(isinstance(env_id, str) and env_id in allowed, "env_id", env_id, "one of " + ", ".join(allowed))
    vec_env, vec_processes = vec_env_keys(data, "sb3", env_id, env_kwargs)
    cfg = TrainConfig(
        algo=algo, env_id=env_id, env_kwargs=dict(env_kwargs), n_envs=n_envs,
        n_timesteps=_positive_int(data, "n_timesteps", 100_000), policy=str(data.get("policy", "MlpPolicy")),
        policy_kwargs=dict(policy_kwargs),
        normalize=(dict(normalize) if isinstance(normalize, dict) else ({} if normalize else None)),
        seed=_seed(data, "seed", 0), checkpoint_freq=_positive_int(data, "checkpoint_freq", 10_000),
        eval_freq=_positive_int(data, "eval_freq", 10_000),
        n_eval_episodes=_positive_int(data, "n_eval_episodes", 5), eval_seed=_seed(data, "eval_seed", 10_000),
        save_replay_buffer=bool(data.get("save_replay_buffer", True)), vec_env=vec_env, vec_processes=vec_processes,
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


def read_train_yaml(path: str | Path, overrides: dict[str, Any] | None = None) -> Any:
    """A training YAML (either backend) read with srenv's bounded safe loader, ``overrides`` applied: bad
    syntax, a key given twice, a file too large or unreadable are each one TrainConfigError line."""
    from srenv.config import load_yaml_file
    from srenv.errors import ConfigError

    try:
        data = load_yaml_file(path, "train config")
    except ConfigError as exc:
        raise TrainConfigError(f"train config {short_repr(str(path))}: expected {exc.expected}") from None
    if isinstance(data, dict) and overrides:
        data = {**data, **overrides}
    return data


def load_train_config(path: str | Path, overrides: dict[str, Any] | None = None) -> TrainConfig:
    """Read and validate an SB3 training YAML."""
    return parse_train_config(read_train_yaml(path, overrides), str(path))
