"""``vec_env: native``: the training env as srenv's native vector env (srenv/envs/vector.py) behind SB3's ``VecEnv``.

``gymnasium.make_vec(inner id, num_envs=n_envs, vectorization_mode="vector_entry_point", processes=P | threads,
env_wrapper=..., **env kwargs)`` adapted by :func:`srenv.envs.vector.sb3_vec_env`. Each slot's env is wrapped where
it is built (in the worker processes too) exactly as ``vec_env: dummy`` wraps its envs, innermost first: the
potential-based shaping (the shaped id), the residual (the residual id), then SB3's ``Monitor``; VecNormalize wraps
the vector env as before. The seeds are SB3's: ``seed + i`` for slot i at the first reset, no seed after. So for
the same seed and ``n_envs`` the training is the one ``vec_env: dummy`` gives (tests/agents/test_native_vec.py);
only where the steps run changes. (SB3's ``make_vec_env`` also seeds each env's action space, which no SB3
algorithm samples: SAC/TD3's warm-up samples the model's own action space.)
"""

from __future__ import annotations

from typing import Any

from srenv import ENV_ID_V1, ENV_ID_V2, ENV_ID_V3

from .residual_env import RESIDUAL_ENV_ID
from .shaping import SHAPED_ENV_ID

NATIVE_IDS = (ENV_ID_V1, ENV_ID_V2, ENV_ID_V3)  # the ids with a vector entry point (srenv/__init__.py)


def wrap_slot(env: Any, shaped: bool, residual: dict[str, Any] | None) -> Any:
    """One slot's wrappers, in the order ``gym.make`` of the training id applies them (module-level: pickles)."""
    from stable_baselines3.common.monitor import Monitor

    if shaped:
        from .shaping import ShapedEnv

        env = ShapedEnv(env)
    if residual is not None:
        from .residual_env import ResidualEnv

        env = ResidualEnv(env, residual["base"], residual.get("base_params") or {}, residual.get("scale", 0.3),
                          residual.get("idle_scale"))
    return Monitor(env)


def native_plan(env_id: str, env_kwargs: dict[str, Any]) -> tuple[str, dict[str, Any], bool, dict | None]:
    """(inner id with a vector entry point, its kwargs, shaped?, residual kwargs or None) for a training id; a
    ValueError in the training YAML's message form for an id without one (agents.training.config re-raises it)."""
    kwargs = dict(env_kwargs)
    residual = None
    if env_id == RESIDUAL_ENV_ID:
        inner = kwargs.pop("inner_env_id", ENV_ID_V1)
        residual = {k: kwargs.pop(k) for k in ("base", "base_params", "scale", "idle_scale") if k in kwargs}
        residual.setdefault("base", "fillage_pi")
        env_id = inner
    shaped = env_id == SHAPED_ENV_ID
    if shaped:  # the potential reads v1's state (agents/training/shaping.py)
        env_id = kwargs.pop("inner_env_id", ENV_ID_V1)
        if env_id != ENV_ID_V1:
            raise ValueError(f"train config: shaped inner_env_id = {env_id!r}: expected {ENV_ID_V1}")
    if env_id not in NATIVE_IDS:
        raise ValueError(f"train config: vec_env = 'native' with env_id {env_id!r}: expected an env with a "
                               f"native vector env ({', '.join(NATIVE_IDS)}, or the residual / shaped env on one)")
    return env_id, kwargs, shaped, residual


def native_backend(vec_processes: int, n_envs: int) -> dict[str, int]:
    """make_vec's backend keywords: P >= 2 worker processes (0 = one per core), 1 = this process's threads."""
    from srenv.envs.vector import default_threads

    p = vec_processes or default_threads()
    p = min(p, n_envs)
    return {"processes": p} if p >= 2 else {"threads": default_threads()}


def build_native_vec_env(env_id: str, env_kwargs: dict[str, Any], n_envs: int, seed: int,
                         vec_processes: int = 0) -> Any:
    """The SB3 ``VecEnv`` of ``vec_env: native`` (seeded for its first reset as SB3's ``make_vec_env`` does)."""
    from functools import partial

    import gymnasium as gym

    from srenv.envs.vector import sb3_vec_env

    inner, kwargs, shaped, residual = native_plan(env_id, env_kwargs)
    venv = gym.make_vec(inner, num_envs=n_envs, vectorization_mode="vector_entry_point",
                        env_wrapper=partial(wrap_slot, shaped=shaped, residual=residual),
                        **native_backend(vec_processes, n_envs), **kwargs)
    out = sb3_vec_env(venv)
    out.seed(seed)
    return out
