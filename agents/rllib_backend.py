"""Ray RLlib as the second backend of ``python -m agents train`` (``backend: rllib`` in the training YAML).

One YAML describes one run (read with ``yaml.safe_load``; nothing in it is evaluated as code)::

    backend: rllib
    algo: ppo                        # ppo | appo | sac
    env_id: srenv/SuckerRod-v0       # the plain id: srenv.rllib.register() makes it known to every runner
    env_kwargs: {config: default}    # gymnasium.make keyword arguments (RLlib's env_config)
    n_timesteps: 100000              # environment steps in total, resumed ones included
    num_env_runners: 2               # sampling processes (0 = sample in the driver)
    num_envs_per_env_runner: 1
    seed: 0
    checkpoint_freq: 20000           # environment steps between checkpoints
    num_cpus: null                   # local Ray only: CPUs it may schedule (null = max(cores, runners + 1))
    model_config: {fcnet_hiddens: [64, 64], fcnet_activation: tanh}   # RLlib's DefaultModelConfig
    training: {lr: 3.0e-4, gamma: 0.95, train_batch_size_per_learner: 512, minibatch_size: 64}

``training`` goes to ``AlgorithmConfig.training`` (checked against its signature). Ray runs locally,
bound to the loopback interface and without dashboard, unless ``--address`` names a cluster (``auto`` or
``ray://host:10001``): the cluster's nodes then need srenv installed. Outputs in ``--out DIR``:
``checkpoint/`` (the final algorithm checkpoint: ``python -m agents evaluate --policy DIR/checkpoint``),
``checkpoints/step_<N>/`` (every ``checkpoint_freq`` steps; ``--resume`` continues from the newest that
restores) and ``train_config.json``. Every checkpoint also holds ``srenv_progress.json`` (steps done) and
the policy as data (``srenv_policy.json`` + ``srenv_policy_weights.pt``): ``evaluate`` reads those, never
RLlib's pickles, unless ``--trust-model`` is given.
"""

from __future__ import annotations

import inspect
import json
import math
import os
import re
import shutil
import sys
import time
from collections.abc import Callable
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from .train import ENV_ID, TrainConfigError, _expect, _positive_int, _yaml12_float

BACKEND = "rllib"
PROGRESS_FILE = "srenv_progress.json"
POLICY_WEIGHTS = "srenv_policy_weights.pt"  # the policy as data (evaluate without --trust-model)
POLICY_JSON = "srenv_policy.json"
_STEP_DIR_RE = re.compile(r"^step_(\d+)$")
_HARNESS_KEYS = {"backend", "algo", "env_id", "env_kwargs", "n_timesteps", "num_env_runners",
                 "num_envs_per_env_runner", "seed", "checkpoint_freq", "num_cpus", "model_config", "training"}


def algorithm_configs() -> dict[str, type]:
    """Supported RLlib algorithms by YAML name (imported lazily: Ray is slow to import)."""
    from ray.rllib.algorithms.appo import APPOConfig
    from ray.rllib.algorithms.ppo import PPOConfig
    from ray.rllib.algorithms.sac import SACConfig

    return {"ppo": PPOConfig, "appo": APPOConfig, "sac": SACConfig}


@dataclass
class RLlibTrainConfig:
    algo: str
    env_id: str = ENV_ID
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


def _training_arguments(config_cls: type) -> set[str]:
    """Keyword arguments ``config_cls().training`` accepts: its own and those of every base class."""
    names: set[str] = set()
    for klass in config_cls.__mro__:
        fn = klass.__dict__.get("training")
        if fn is not None:
            names |= {n for n, p in inspect.signature(fn).parameters.items()
                      if p.kind in (p.KEYWORD_ONLY, p.POSITIONAL_OR_KEYWORD)}
    return names - {"self"}


def parse_rllib_config(data: Any, source: str = "<dict>") -> RLlibTrainConfig:
    """Validate a YAML mapping into a :class:`RLlibTrainConfig` (one clear error naming the key)."""
    _expect(isinstance(data, dict), source, type(data).__name__, "a mapping of hyperparameters")
    unknown = sorted(set(data) - _HARNESS_KEYS)
    _expect(not unknown, unknown[0] if unknown else "", data.get(unknown[0]) if unknown else None,
            f"one of {sorted(_HARNESS_KEYS)} (algorithm arguments go under training:)")
    algo = str(data.get("algo", "")).lower()
    configs = algorithm_configs()
    _expect(algo in configs, "algo", data.get("algo"), "one of " + ", ".join(configs))
    runners = data.get("num_env_runners", 2)
    _expect(isinstance(runners, int) and not isinstance(runners, bool) and runners >= 0, "num_env_runners",
            runners, "a non-negative integer")
    num_cpus = data.get("num_cpus")
    _expect(num_cpus is None or (isinstance(num_cpus, int) and num_cpus > 0), "num_cpus", num_cpus,
            "a positive integer or null")
    for key in ("env_kwargs", "model_config", "training"):
        _expect(isinstance(data.get(key) or {}, dict), key, data.get(key), "a mapping")
    training = {k: _yaml12_float(v) for k, v in (data.get("training") or {}).items()}
    accepted = _training_arguments(configs[algo])
    for key in sorted(set(training) - accepted):
        _expect(False, f"training.{key}", training[key], f"an argument of RLlib's {algo.upper()} training()")
    return RLlibTrainConfig(
        algo=algo, env_id=str(data.get("env_id", ENV_ID)), env_kwargs=dict(data.get("env_kwargs") or {}),
        n_timesteps=_positive_int(data, "n_timesteps", 100_000), num_env_runners=runners,
        num_envs_per_env_runner=_positive_int(data, "num_envs_per_env_runner", 1),
        seed=int(data.get("seed", 0)), checkpoint_freq=_positive_int(data, "checkpoint_freq", 20_000),
        num_cpus=num_cpus, model_config=dict(data.get("model_config") or {}), training=training)


def build_algorithm_config(cfg: RLlibTrainConfig) -> Any:
    import srenv.rllib

    if cfg.env_id in srenv.rllib.srenv_ids():
        srenv.rllib.register([cfg.env_id])  # the plain id, known to every env runner of the cluster
    return (algorithm_configs()[cfg.algo]()
            .environment(cfg.env_id, env_config=dict(cfg.env_kwargs))
            .env_runners(num_env_runners=cfg.num_env_runners,
                         num_envs_per_env_runner=cfg.num_envs_per_env_runner)
            .framework("torch")
            .rl_module(model_config=dict(cfg.model_config))
            .training(**cfg.training)
            .debugging(seed=cfg.seed))


# ------------------------------------------------------------------------------------------------- Ray
def start_ray(address: str | None, num_cpus: int | None, runners: int) -> bool:
    """Connect to ``address`` or start a local Ray on the loopback interface; True if this call started it."""
    import ray

    if ray.is_initialized():
        return False
    # the driver's torch learner and the runners' envs share the cores; runners would fight over threads
    env_vars = {"OMP_NUM_THREADS": "1", "MKL_NUM_THREADS": "1"}
    if address:
        ray.init(address=address, runtime_env={"env_vars": env_vars}, log_to_driver=False)
    else:
        # every runner asks for one CPU, the driver's learner another: on a small machine Ray would wait
        # forever for CPUs it does not have, so it is told the runs' demand (they time-share the cores)
        cpus = num_cpus or max(os.cpu_count() or 1, runners + 1)
        ray.init(_node_ip_address="127.0.0.1", include_dashboard=False, num_cpus=cpus,
                 runtime_env={"env_vars": env_vars}, log_to_driver=False, configure_logging=False)
    return True


# ------------------------------------------------------------------------------------------- checkpoints
def step_checkpoints(out_dir: str | Path) -> list[tuple[int, Path]]:
    """(timesteps, path) of ``out_dir/checkpoints/step_<N>``, newest first."""
    d = Path(out_dir) / "checkpoints"
    found = [(int(m.group(1)), p) for p in d.glob("step_*") if p.is_dir() and (m := _STEP_DIR_RE.match(p.name))]
    return sorted(found, reverse=True)


def export_policy(algo: Any, cfg: RLlibTrainConfig, directory: Path) -> None:
    """The policy as data beside RLlib's pickles: the module's tensors (``torch.save`` of a state dict,
    read back with ``weights_only=True``) and a JSON description to rebuild the module from, so that
    ``evaluate`` needs no ``--trust-model`` for a checkpoint this backend wrote."""
    import torch
    from ray.rllib.core import DEFAULT_MODULE_ID

    module = algo.get_module(DEFAULT_MODULE_ID)  # the env runners' copy: inference-only for PPO
    torch.save({k: v.detach().cpu() for k, v in module.state_dict().items()}, directory / POLICY_WEIGHTS)
    obs, act = module.observation_space, module.action_space
    # the model config the module was built with: the YAML's merged with the algorithm's own defaults
    model_config = dict(algo.config.model_config)
    json.dumps(model_config)  # plain data only, or this export cannot be read back as data
    (directory / POLICY_JSON).write_text(json.dumps({
        "algo": cfg.algo, "model_config": model_config, "inference_only": bool(module.inference_only),
        "module_class": type(module).__name__,
        "observation_shape": list(obs.shape), "action_shape": list(act.shape),
        "action_low": np.asarray(act.low).tolist(), "action_high": np.asarray(act.high).tolist()}, indent=1))


def save_checkpoint(algo: Any, cfg: RLlibTrainConfig, path: Path, num_timesteps: int, iterations: int) -> Path:
    """Atomic: written beside ``path`` and renamed, so a kill never leaves a half checkpoint under its name."""
    tmp = path.with_name(f".tmp_{path.name}")
    shutil.rmtree(tmp, ignore_errors=True)
    algo.save_to_path(str(tmp.resolve()))
    export_policy(algo, cfg, tmp)
    (tmp / PROGRESS_FILE).write_text(json.dumps({"num_timesteps": num_timesteps, "iterations": iterations}))
    old = path.with_name(f".old_{path.name}")
    if path.exists():
        os.replace(path, old)
    os.replace(tmp, path)
    shutil.rmtree(old, ignore_errors=True)
    return path


def _restore(algo: Any, out: Path, log: Callable[[str], None]) -> tuple[int, int, Path] | None:
    """Restore the newest checkpoint that loads; (timesteps, iterations, path) or None."""
    for _, path in step_checkpoints(out):
        try:
            progress = json.loads((path / PROGRESS_FILE).read_text())
            algo.restore_from_path(str(path.resolve()))
        except Exception as exc:  # noqa: BLE001 - an unreadable checkpoint: fall back to the previous one
            log(f"resume: skipping checkpoint {path.name} ({exc})")
            continue
        return int(progress["num_timesteps"]), int(progress["iterations"]), path
    return None


def _env_steps(result: dict) -> int:
    """Environment steps sampled in one ``train()`` result (summed over runners)."""
    from ray.rllib.utils.metrics import ENV_RUNNER_RESULTS, NUM_ENV_STEPS_SAMPLED

    return int(result.get(ENV_RUNNER_RESULTS, {}).get(NUM_ENV_STEPS_SAMPLED, 0))


def _episode_return(result: dict) -> float | None:
    from ray.rllib.utils.metrics import ENV_RUNNER_RESULTS, EPISODE_RETURN_MEAN

    v = result.get(ENV_RUNNER_RESULTS, {}).get(EPISODE_RETURN_MEAN)
    return float(v) if v is not None and math.isfinite(float(v)) else None


# ------------------------------------------------------------------------------------------------ train
def train(cfg: RLlibTrainConfig, out_dir: str | Path, total_timesteps: int | None = None, resume: bool = False,
          address: str | None = None, log: Callable[[str], None] | None = None) -> dict[str, Any]:
    """Train (or continue) one RLlib run; returns the JSON-ready summary."""
    log = log or (lambda msg: print(msg, file=sys.stderr, flush=True))
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    target = int(total_timesteps or cfg.n_timesteps)
    t_start = time.perf_counter()
    started = start_ray(address, cfg.num_cpus, cfg.num_env_runners)
    algo = None
    try:
        algo = build_algorithm_config(cfg).build_algo()
        steps, iterations, resumed_from = 0, 0, None
        if resume:
            restored = _restore(algo, out, log)
            if restored is None:
                log(f"resume: no checkpoint in {out / 'checkpoints'}, starting from scratch")
            else:
                steps, iterations, path = restored
                resumed_from = str(path)
                log(f"resume: {path.name} at {steps} steps")
        (out / "train_config.json").write_text(json.dumps(asdict(cfg), indent=2, default=str))
        last_return = None
        next_ckpt = (steps // cfg.checkpoint_freq + 1) * cfg.checkpoint_freq
        while steps < target:
            result = algo.train()
            sampled = _env_steps(result)
            if sampled <= 0:
                raise RuntimeError("RLlib sampled no environment steps in a training iteration")
            steps += sampled
            iterations += 1
            last_return = _episode_return(result) if _episode_return(result) is not None else last_return
            log(f"rllib iteration {iterations}: {steps} steps, episode return mean {last_return}")
            if steps >= next_ckpt and steps < target:
                save_checkpoint(algo, cfg, out / "checkpoints" / f"step_{steps}", steps, iterations)
                next_ckpt = (steps // cfg.checkpoint_freq + 1) * cfg.checkpoint_freq
        (out / "checkpoints").mkdir(exist_ok=True)
        save_checkpoint(algo, cfg, out / "checkpoints" / f"step_{steps}", steps, iterations)
        final = save_checkpoint(algo, cfg, out / "checkpoint", steps, iterations)
    finally:
        if algo is not None:
            algo.stop()
        if started:
            import ray

            ray.shutdown()
    return {
        "backend": BACKEND,
        "algo": cfg.algo,
        "num_timesteps": steps,
        "target_timesteps": target,
        "iterations": iterations,
        "num_env_runners": cfg.num_env_runners,
        "num_envs_per_env_runner": cfg.num_envs_per_env_runner,
        "wall_time_s": round(time.perf_counter() - t_start, 2),
        "resumed_from": resumed_from,
        "model": str(final),
        "last_episode_return_mean": last_return,
    }


# --------------------------------------------------------------------------------------------- evaluate
def is_rllib_checkpoint(path: str | Path) -> bool:
    """A directory written by ``Algorithm.save_to_path`` (this backend's ``checkpoint/`` or ``step_<N>/``)."""
    p = Path(path)
    return p.is_dir() and (p / "learner_group").is_dir()


class RLlibPolicy:
    """The RL module of an RLlib checkpoint with SB3's ``predict`` interface (no Ray process needed).

    Deterministic actions are the mode of the module's action distribution (the Gaussian mean for PPO),
    clipped into the env's action box as RLlib's env runners do.
    """

    def __init__(self, module: Any, action_space: Any, path: str = "") -> None:
        self.module = module
        self.action_space = action_space
        self.path = path

    def predict(self, observation: np.ndarray, state: Any = None, episode_start: np.ndarray | None = None,
                deterministic: bool = True) -> tuple[np.ndarray, Any]:
        import torch

        obs = torch.as_tensor(np.asarray(observation, dtype=np.float32)[None])
        with torch.no_grad():
            out = self.module.forward_inference({"obs": obs})
            dist = self.module.get_inference_action_dist_cls().from_logits(out["action_dist_inputs"])
            action = (dist.to_deterministic() if deterministic else dist).sample()
        a = np.asarray(action[0].numpy(), dtype=self.action_space.dtype)
        return np.clip(a, self.action_space.low, self.action_space.high), state

    def __repr__(self) -> str:
        return f"RLlibPolicy({type(self.module).__name__}, {self.path})"


def _module_from_data(p: Path, env: Any) -> Any:
    """Rebuild the module from ``srenv_policy.json`` (plain JSON) and load its tensors with
    ``torch.load(weights_only=True)``, which refuses anything but tensors and plain containers."""
    import torch

    from .evaluate import check_spaces

    meta = json.loads((p / POLICY_JSON).read_text())
    configs = algorithm_configs()
    if meta.get("algo") not in configs or not isinstance(meta.get("model_config"), dict):
        raise ValueError(f"{p / POLICY_JSON}: expected algo one of {', '.join(configs)} and a model_config mapping")
    saved_obs, saved_act = tuple(meta["observation_shape"]), tuple(meta["action_shape"])
    check_spaces(saved_obs, saved_act, env.observation_space.shape, env.action_space.shape, p)
    if not (np.allclose(meta["action_low"], env.action_space.low)
            and np.allclose(meta["action_high"], env.action_space.high)):
        raise ValueError(f"{p} does not fit this env: action bounds {meta['action_low']}..{meta['action_high']} "
                         f"vs {env.action_space}")
    spec = configs[meta["algo"]]().rl_module(model_config=meta["model_config"]).get_default_rl_module_spec()
    spec.observation_space, spec.action_space = env.observation_space, env.action_space
    spec.model_config, spec.inference_only = meta["model_config"], bool(meta.get("inference_only", False))
    module = spec.build()
    module.load_state_dict(torch.load(p / POLICY_WEIGHTS, weights_only=True, map_location="cpu"))
    module.eval()
    return module


def load_rllib_policy(path: str | Path, env: Any, trust: bool = False) -> RLlibPolicy:
    """The default policy of an RLlib checkpoint directory, checked against ``env``'s spaces.

    By default read as data (``srenv_policy.json`` + ``srenv_policy_weights.pt``, written by this backend);
    ``trust=True`` (``--trust-model``) loads RLlib's own pickled module instead - pickles can run code when
    read, so only for checkpoints you made (e.g. written by RLlib outside this backend).
    """
    p = Path(path)
    if not trust:
        if not ((p / POLICY_JSON).is_file() and (p / POLICY_WEIGHTS).is_file()):
            raise ValueError(f"--policy {p}: an RLlib checkpoint without {POLICY_JSON} / {POLICY_WEIGHTS} holds "
                             "only pickles, which can run arbitrary code when loaded; pass --trust-model if you "
                             "made it yourself")
        return RLlibPolicy(_module_from_data(p, env), env.action_space, str(p))
    from ray.rllib.core import (
        COMPONENT_LEARNER,
        COMPONENT_LEARNER_GROUP,
        COMPONENT_RL_MODULE,
        DEFAULT_MODULE_ID,
    )
    from ray.rllib.core.rl_module.rl_module import RLModule

    from .evaluate import check_spaces

    module_dir = p / COMPONENT_LEARNER_GROUP / COMPONENT_LEARNER / COMPONENT_RL_MODULE / DEFAULT_MODULE_ID
    if not module_dir.is_dir():
        raise FileNotFoundError(f"--policy {p}: an RLlib checkpoint without {module_dir.relative_to(p)}")
    module = RLModule.from_checkpoint(str(module_dir.resolve()))
    check_spaces(module.observation_space, module.action_space, env.observation_space, env.action_space, p)
    return RLlibPolicy(module, env.action_space, str(p))


def _read_yaml(path: str | Path) -> Any:
    """srenv's bounded safe loader, its problems as one TrainConfigError line (as agents.train does)."""
    from srenv.config import load_yaml_file
    from srenv.errors import ConfigError, short_repr

    try:
        return load_yaml_file(path, "train config")
    except ConfigError as exc:
        raise TrainConfigError(f"train config {short_repr(str(path))}: expected {exc.expected}") from None


def read_backend(path: str | Path) -> str:
    """The ``backend`` key of a training YAML (``sb3`` when absent)."""
    data = _read_yaml(path)
    backend = data.get("backend", "sb3") if isinstance(data, dict) else "sb3"
    if backend not in ("sb3", BACKEND):
        raise TrainConfigError(f"train config: backend = {backend!r}: expected sb3 or rllib")
    return str(backend)


def load_rllib_config(path: str | Path, overrides: dict[str, Any] | None = None) -> RLlibTrainConfig:
    data = _read_yaml(path)
    if isinstance(data, dict) and overrides:
        data = {**data, **overrides}
    return parse_rllib_config(data, str(path))
