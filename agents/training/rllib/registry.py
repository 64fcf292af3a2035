"""Ray RLlib support: srenv's env ids in Ray Tune's registry, so RLlib's env runners find them.

An RLlib env runner is a separate process that never ran ``import srenv``, so the plain id fails there with
``NamespaceNotFound``. Three ways that work (``python -m agents train`` with ``backend: rllib`` uses the
second):

1. ``config.environment("srenv:srenv/SuckerRod-v0", env_config={...})``: gymnasium's ``module:id`` form
   imports srenv in each runner before it makes the env. Nothing to run in the driver.
2. ``from agents.training.rllib import registry; registry.register()`` once in the driver, then the plain id
   ``config.environment("srenv/SuckerRod-v0", env_config={...})``: every srenv id is put in Ray Tune's
   cluster-wide registry with a creator that imports srenv in the runner.
3. ``ray.tune.register_env("any-name", registry.env_creator)``, then
   ``config.environment("any-name", env_config={"env_id": "srenv/SuckerRod-v0", ...})``: the creator
   itself, under a name of your choice (RLlib takes a creator only through its registry).

``env_config`` holds the ``gymnasium.make`` keyword arguments (``config``, ``overrides``, ...). With RLlib's
``gym_env_vectorize_mode="vector_entry_point"`` (``vec_env: native`` in the training YAML) a runner calls the creator
once with ``num_envs``: it returns srenv's native vector env (``gymnasium.make_vec(id, num_envs=N,
vectorization_mode="vector_entry_point", **env_config)``, so ``threads`` / ``processes`` may be in ``env_config``)
for an id that has one (v1, v2), gymnasium's ``SyncVectorEnv`` of single envs for the others. A creator
must return one env per call: ``lambda c: gym.make(...)`` fails in the runners (srenv not imported there),
and one that returns a vector env where RLlib expects a single one fails later with an ``IndexError``.
Ray is imported only by :func:`register`, so this module is importable without Ray.
"""

from __future__ import annotations

from functools import partial
from typing import Any

from srenv import ENV_ID

__all__ = ["env_creator", "register", "srenv_ids"]


def srenv_ids() -> list[str]:
    """Every id in gymnasium's registry under the ``srenv/`` namespace (after ``import srenv``)."""
    import gymnasium as gym

    return sorted(i for i in gym.registry if i.startswith("srenv/"))


def _make(env_id: str, env_config: Any) -> Any:
    import gymnasium as gym

    import srenv  # noqa: F401  (registers the srenv ids in this process: the runner's, not the driver's)

    kwargs = dict(env_config)  # an RLlib EnvContext is a dict; worker_index etc. are attributes, not items
    kwargs.pop("env_id", None)
    num_envs = kwargs.pop("num_envs", None)  # RLlib's gym_env_vectorize_mode="vector_entry_point"
    if num_envs is not None:  # srenv's native vector env where the id has one, else gymnasium's sync
        mode = "vector_entry_point" if gym.spec(env_id).vector_entry_point is not None else "sync"
        return gym.make_vec(env_id, num_envs=int(num_envs), vectorization_mode=mode, **kwargs)
    return gym.make(env_id, **kwargs)


def env_creator(env_config: Any) -> Any:
    """RLlib env creator: ``env_config`` = ``gymnasium.make`` kwargs plus ``env_id`` (default v0)."""
    return _make(str(dict(env_config).get("env_id", ENV_ID)), env_config)


def register(env_ids: list[str] | None = None) -> list[str]:
    """Put srenv's ids (default: all of :func:`srenv_ids`) in Ray Tune's registry; returns them.

    Call before (or after) ``ray.init``; Ray ships the registration to every process of the cluster.
    """
    from ray.tune.registry import register_env

    known = srenv_ids()
    ids = known if env_ids is None else list(env_ids)
    for env_id in ids:
        if env_id not in known:
            raise ValueError(f"env_id = {env_id!r}: expected one of srenv's envs: {', '.join(known)}")
        # a partial of a module-level function pickles by reference: the runner imports this module
        register_env(env_id, partial(_make, env_id))
    return ids
