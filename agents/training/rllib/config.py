"""The RLlib training YAML (``backend: rllib``): its schema, validation and the AlgorithmConfig it builds.

One YAML describes one run (read with srenv's bounded safe loader; nothing in it is evaluated as code)::

    backend: rllib
    algo: ppo                        # ppo | appo | sac
    env_id: srenv/SuckerRod-v0       # the plain id: agents.training.rllib.registry.register() makes it known to every runner
    env_kwargs: {config: default}    # gymnasium.make keyword arguments (RLlib's env_config)
    n_timesteps: 100000              # environment steps in total, resumed ones included
    num_env_runners: 2               # sampling processes (0 = sample in the driver)
    num_envs_per_env_runner: 1
    vec_env: sync                    # sync (RLlib's: gymnasium's SyncVectorEnv) | native (srenv's vector env, v1/v2)
    vec_processes: 0                 # native only: worker processes per runner, 0 = one per core, 1 = threads
    seed: 0
    checkpoint_freq: 20000           # environment steps between checkpoints
    num_cpus: null                   # local Ray only: CPUs it may schedule (null = max(cores, runners + 1))
    model_config: {fcnet_hiddens: [64, 64], fcnet_activation: tanh}   # RLlib's DefaultModelConfig
    training: {lr: 3.0e-4, gamma: 0.95, train_batch_size_per_learner: 512, minibatch_size: 64}
    normalize: {clip_std: 10}        # or true (clip_std 10) / false (default): observation mean-std filter

``vec_env: native`` makes each env runner step its ``num_envs_per_env_runner`` wells through srenv's vector entry
point (RLlib's ``gym_env_vectorize_mode="vector_entry_point"``; the creator of
:mod:`agents.training.rllib.registry` builds ``gymnasium.make_vec(id, num_envs=N,
vectorization_mode="vector_entry_point", threads=cores | processes=P)``), with the backend keywords SB3's
``vec_env: native`` uses (:func:`agents.training.native_vec.native_backend`). Same episodes as ``sync`` for the
same seeds and weights (tests/agents/test_rllib_native.py); the normaliser below applies to both alike.

``training`` goes to ``AlgorithmConfig.training`` (checked against its signature). ``normalize`` puts
:class:`agents.training.rllib.obs_filter.ObsMeanStdFilter` first in the env runners' env-to-module pipeline:
observations minus their running mean, over their running standard deviation, clipped to
``+-clip_std`` standard deviations (rewards are not normalised).
"""

from __future__ import annotations

import inspect
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from ...envs import ENV_ID_V0
from ...evaluation.rllib_model import algorithm_configs
from ..config import (
    TrainConfigError,
    _expect,
    _positive_int,
    _yaml12_float,
    declared,
    read_train_yaml,
    require_mapping,
    vec_env_keys,
)

BACKEND = "rllib"
_HARNESS_KEYS = {"backend", "algo", "env_id", "env_kwargs", "n_timesteps", "num_env_runners",
                 "num_envs_per_env_runner", "seed", "checkpoint_freq", "num_cpus", "model_config", "training",
                 "normalize", "vec_env", "vec_processes"}
DEFAULT_CLIP_STD = 10.0  # RLlib's and SB3's default clip of normalised observations


@dataclass
class RLlibTrainConfig:
    algo: str
    env_id: str = ENV_ID_V0
    env_kwargs: dict[str, Any] = field(default_factory=dict)
    n_timesteps: int = 100_000
    num_env_runners: int = 2
    num_envs_per_env_runner: int = 1
    seed: int = 0
    checkpoint_freq: int = 20_000
    num_cpus: int | None = None
    model_config: dict[str, Any] = field(default_factory=dict)
    training: dict[str, Any] = field(default_factory=dict)
    backend: str = BACKEND
    normalize: dict[str, Any] | None = None  # {"clip_std": c}; None = observations as the env gives them
    vec_env: str = "sync"  # sync: RLlib's vector env of single envs; native: srenv's (agents.training.config.VEC_ENVS)
    vec_processes: int = 0  # vec_env native: worker processes per env runner, 0 = one per core, 1 = threads


def _training_arguments(config_cls: type) -> set[str]:
    """Keyword arguments ``config_cls().training`` accepts: its own and those of every base class."""
    names: set[str] = set()
    for klass in config_cls.__mro__:
        fn = klass.__dict__.get("training")
        if fn is not None:
            names |= {n for n, p in inspect.signature(fn).parameters.items()
                      if p.kind in (p.KEYWORD_ONLY, p.POSITIONAL_OR_KEYWORD)}
    return names - {"self"}


def _normalize(value: Any) -> dict[str, Any] | None:
    """``normalize: true | false | {clip_std: c}`` -> ``{"clip_std": c}`` or None."""
    if value is None or value is False:
        return None
    if value is True:
        return {"clip_std": DEFAULT_CLIP_STD}
    _expect(isinstance(value, dict) and set(value) <= {"clip_std"}, "normalize", value,
            "true, false or a mapping {clip_std: <standard deviations>}")
    clip = _yaml12_float(value.get("clip_std", DEFAULT_CLIP_STD))
    _expect(isinstance(clip, (int, float)) and not isinstance(clip, bool) and 0 < clip < float("inf"),
            "normalize.clip_std", clip, "a positive number of standard deviations")
    return {"clip_std": float(clip)}


def parse_rllib_config(data: Any, source: str = "<dict>") -> RLlibTrainConfig:
    """Validate a YAML mapping into a :class:`RLlibTrainConfig` (one clear error naming the key)."""
    require_mapping(data, source)
    unknown = sorted(set(data) - _HARNESS_KEYS)
    _expect(not unknown, unknown[0] if unknown else "", data.get(unknown[0]) if unknown else None,
            f"one of {sorted(_HARNESS_KEYS)} (algorithm arguments go under training:)")
    algo = str(data.get("algo", "")).lower()
    configs = algorithm_configs()
    _expect(algo in configs, "algo", data.get("algo"), "one of " + ", ".join(configs))
    runners = declared("num_env_runners", data.get("num_env_runners", 2))
    num_cpus = data.get("num_cpus")
    _expect(num_cpus is None or (isinstance(num_cpus, int) and num_cpus > 0), "num_cpus", num_cpus,
            "a positive integer or null")
    for key in ("env_kwargs", "model_config", "training"):
        _expect(isinstance(data.get(key) or {}, dict), key, data.get(key), "a mapping")
    training = {k: _yaml12_float(v) for k, v in (data.get("training") or {}).items()}
    accepted = _training_arguments(configs[algo])
    for key in sorted(set(training) - accepted):
        _expect(False, f"training.{key}", training[key], f"an argument of RLlib's {algo.upper()} training()")
    env_id, env_kwargs = str(data.get("env_id", ENV_ID_V0)), dict(data.get("env_kwargs") or {})
    vec_env, vec_processes = vec_env_keys(data, BACKEND, env_id, env_kwargs)
    return RLlibTrainConfig(
        algo=algo, env_id=env_id, env_kwargs=env_kwargs, vec_env=vec_env, vec_processes=vec_processes,
        n_timesteps=_positive_int(data, "n_timesteps", 100_000), num_env_runners=runners,
        num_envs_per_env_runner=_positive_int(data, "num_envs_per_env_runner", 1),
        seed=int(data.get("seed", 0)), checkpoint_freq=_positive_int(data, "checkpoint_freq", 20_000),
        num_cpus=num_cpus, model_config=dict(data.get("model_config") or {}), training=training,
        normalize=_normalize(data.get("normalize")))


def build_algorithm_config(cfg: RLlibTrainConfig) -> Any:
    from . import registry

    if cfg.env_id in registry.srenv_ids():
        registry.register([cfg.env_id])  # the plain id, known to every env runner of the cluster
    runners: dict[str, Any] = {"num_env_runners": cfg.num_env_runners,
                               "num_envs_per_env_runner": cfg.num_envs_per_env_runner}
    env_config = dict(cfg.env_kwargs)
    if cfg.vec_env == "native":  # the runners call the creator once with num_envs: srenv's vector entry point
        from ..native_vec import native_backend

        runners["gym_env_vectorize_mode"] = "vector_entry_point"
        env_config.update(native_backend(cfg.vec_processes, cfg.num_envs_per_env_runner))
    if cfg.normalize is not None:
        from .obs_filter import connector_factory

        runners["env_to_module_connector"] = connector_factory(cfg.normalize["clip_std"])
    return (algorithm_configs()[cfg.algo]()
            .environment(cfg.env_id, env_config=env_config)
            .env_runners(**runners)
            .framework("torch")
            .rl_module(model_config=dict(cfg.model_config))
            .training(**cfg.training)
            .debugging(seed=cfg.seed))


def read_backend(path: str | Path) -> str:
    """The ``backend`` key of a training YAML (``sb3`` when absent)."""
    data = read_train_yaml(path)
    backend = data.get("backend", "sb3") if isinstance(data, dict) else "sb3"
    if backend not in ("sb3", BACKEND):
        raise TrainConfigError(f"train config: backend = {backend!r}: expected sb3 or rllib")
    return str(backend)


def load_rllib_config(path: str | Path, overrides: dict[str, Any] | None = None) -> RLlibTrainConfig:
    return parse_rllib_config(read_train_yaml(path, overrides), str(path))
