"""What an SB3 run is built from: the env factory, the vector env, the policy's keyword arguments and
rl-zoo's ``lin_<x>`` schedules."""

from __future__ import annotations

from typing import Any

from ...envs import make_env  # module-level: picklable into SubprocVecEnv workers, registers srenv there
from ..config import TrainConfig, _expect


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


def build_vec_env(cfg: TrainConfig, n_envs: int, seed: int, subproc: bool, native: bool = False) -> Any:
    """SB3's DummyVecEnv / SubprocVecEnv of ``make_env``, or (``native``) srenv's native vector env (:mod:`..native_vec`)."""
    from functools import partial

    if native:
        from ..native_vec import build_native_vec_env

        return build_native_vec_env(cfg.env_id, cfg.env_kwargs, n_envs, seed, cfg.vec_processes)

    from stable_baselines3.common.env_util import make_vec_env
    from stable_baselines3.common.vec_env import DummyVecEnv, SubprocVecEnv

    factory = partial(make_env, cfg.env_id, **cfg.env_kwargs)
    cls = SubprocVecEnv if subproc and n_envs > 1 else DummyVecEnv
    return make_vec_env(factory, n_envs=n_envs, seed=seed, vec_env_cls=cls)
