"""A native vector env: N wells (each its own mesh) stepped across threads, for any srenv task env class.

``gymnasium.make_vec("srenv/SuckerRod-v1", num_envs=N, vectorization_mode="vector_entry_point", ...)`` builds a
:class:`KernelVectorEnv` of N :class:`~srenv.envs.sucker_rod_v1.SuckerRodV1Env`. The exact strokes run in the
compiled kernel, which releases the GIL (``nogil=True``), so the wells' strokes run in parallel on a thread pool
(``threads``, default: the cores this process may use); the Python around them (the env's bookkeeping, the card
features) takes turns. The results are those of N single envs stepped one by one (tests/test_speed.py): each env
owns its simulator and random stream, and a thread steps one env at a time.

Autoreset is gymnasium's NEXT_STEP mode (``metadata["autoreset_mode"]``): the step after an episode ends resets
that env (its action is ignored, reward 0). ``reset(seed=s)`` seeds env i with s + i (gymnasium's convention).
Another task version uses it with one line: ``vector_entry(SuckerRodV2Env)``. :class:`SB3VecEnv` adapts it to
stable-baselines3 (which resets in the same step and hands the final observation in ``infos``).
"""

from __future__ import annotations

import os
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from typing import Any, ClassVar

import numpy as np
from gymnasium.vector import AutoresetMode, VectorEnv
from gymnasium.vector.utils import batch_space


def default_threads() -> int:
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # not Linux
        return os.cpu_count() or 1


class KernelVectorEnv(VectorEnv):
    """N instances of ``env_cls`` (built with ``env_kwargs``) stepped on ``threads`` threads."""

    metadata: ClassVar[dict[str, Any]] = {"autoreset_mode": AutoresetMode.NEXT_STEP, "render_modes": []}

    def __init__(self, env_cls: type, num_envs: int, threads: int | None = None, **env_kwargs: Any) -> None:
        if int(num_envs) < 1:
            raise ValueError(f"num_envs = {num_envs!r}: expected an integer >= 1")
        env_kwargs.pop("max_episode_steps", None)  # gymnasium passes the spec's; the envs truncate themselves
        self.envs = [env_cls(**env_kwargs) for _ in range(int(num_envs))]
        self.num_envs = len(self.envs)
        first = self.envs[0]
        self.single_observation_space = first.observation_space
        self.single_action_space = first.action_space
        self.observation_space = batch_space(first.observation_space, self.num_envs)
        self.action_space = batch_space(first.action_space, self.num_envs)
        self.threads = max(1, min(int(threads or default_threads()), self.num_envs))
        self._pool = ThreadPoolExecutor(self.threads) if self.threads > 1 else None
        self._done = np.zeros(self.num_envs, dtype=bool)
        self.render_mode = None

    def map(self, fn: Callable[[int], Any]) -> list:
        """fn(i) for every env, on the pool (each call touches env i only)."""
        idx = range(self.num_envs)
        return list(self._pool.map(fn, idx)) if self._pool is not None else [fn(i) for i in idx]

    def reset(self, *, seed: int | list | None = None, options: dict | None = None) -> tuple[np.ndarray, dict]:
        seeds = seed if isinstance(seed, (list, tuple)) else [
            None if seed is None else int(seed) + i for i in range(self.num_envs)]
        res = self.map(lambda i: self.envs[i].reset(seed=seeds[i], options=options))
        self._done[:] = False
        infos: dict = {}
        for i, (_, info) in enumerate(res):
            infos = self._add_info(infos, info, i)
        return np.stack([o for o, _ in res]), infos

    def step(self, actions: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, dict]:
        actions = np.asarray(actions)

        def one(i: int) -> tuple:
            if self._done[i]:  # NEXT_STEP autoreset: this step only resets env i
                obs, info = self.envs[i].reset()
                return obs, 0.0, False, False, info
            return self.envs[i].step(actions[i])

        res = self.map(one)
        infos: dict = {}
        for i, r in enumerate(res):
            infos = self._add_info(infos, r[4], i)
        term = np.array([r[2] for r in res], dtype=bool)
        trunc = np.array([r[3] for r in res], dtype=bool)
        self._done = term | trunc
        return (np.stack([r[0] for r in res]), np.array([r[1] for r in res], dtype=np.float64), term, trunc,
                infos)

    def close_extras(self, **kwargs: Any) -> None:
        if self._pool is not None:
            self._pool.shutdown()
            self._pool = None
        for env in self.envs:
            env.close()


def vector_entry(env_cls: type) -> Callable[..., KernelVectorEnv]:
    """A gymnasium ``vector_entry_point`` for ``env_cls``."""
    def make(num_envs: int = 1, threads: int | None = None, **env_kwargs: Any) -> KernelVectorEnv:
        return KernelVectorEnv(env_cls, num_envs, threads=threads, **env_kwargs)
    return make


def make_v1(num_envs: int = 1, threads: int | None = None, **env_kwargs: Any) -> KernelVectorEnv:
    """srenv/SuckerRod-v1's vector entry point."""
    from .sucker_rod_v1 import SuckerRodV1Env

    return KernelVectorEnv(SuckerRodV1Env, num_envs, threads=threads, **env_kwargs)


def make_v2(num_envs: int = 1, threads: int | None = None, **env_kwargs: Any) -> KernelVectorEnv:
    """srenv/SuckerRod-v2's vector entry point (its events and classifier run per well, in the same threads)."""
    from .sucker_rod_v2 import SuckerRodV2Env

    return KernelVectorEnv(SuckerRodV2Env, num_envs, threads=threads, **env_kwargs)


def sb3_vec_env(venv: KernelVectorEnv):
    """The vector env as a stable-baselines3 ``VecEnv`` (imports SB3 only when called)."""
    from stable_baselines3.common.vec_env.base_vec_env import VecEnv

    class SB3VecEnv(VecEnv):
        """SB3's conventions: reset in the same step, the final observation in infos["terminal_observation"],
        infos["TimeLimit.truncated"] for a truncation."""

        def __init__(self, v: KernelVectorEnv) -> None:
            self.venv = v
            self._actions = None
            self._seeds: list = [None] * v.num_envs
            super().__init__(v.num_envs, v.single_observation_space, v.single_action_space)

        def reset(self) -> np.ndarray:
            envs = self.venv.envs
            obs = self.venv.map(lambda i: envs[i].reset(seed=self._seeds[i])[0])
            self._seeds = [None] * self.num_envs
            return np.stack(obs)

        def step_async(self, actions: np.ndarray) -> None:
            self._actions = np.asarray(actions)

        def step_wait(self):
            envs = self.venv.envs

            def one(i: int) -> tuple:
                obs, rew, term, trunc, info = envs[i].step(self._actions[i])
                info = dict(info)
                done = term or trunc
                if done:
                    info["TimeLimit.truncated"] = trunc and not term
                    info["terminal_observation"] = obs
                    obs = envs[i].reset()[0]
                return obs, rew, done, info

            res = self.venv.map(one)
            return (np.stack([r[0] for r in res]), np.array([r[1] for r in res], dtype=np.float32),
                    np.array([r[2] for r in res], dtype=bool), [r[3] for r in res])

        def seed(self, seed: int | None = None) -> list:
            self._seeds = [None if seed is None else seed + i for i in range(self.num_envs)]
            return self._seeds

        def close(self) -> None:
            self.venv.close()

        def get_attr(self, attr_name: str, indices=None) -> list:
            return [getattr(self.venv.envs[i], attr_name) for i in self._get_indices(indices)]

        def set_attr(self, attr_name: str, value: Any, indices=None) -> None:
            for i in self._get_indices(indices):
                setattr(self.venv.envs[i], attr_name, value)

        def env_method(self, method_name: str, *args: Any, indices=None, **kwargs: Any) -> list:
            return [getattr(self.venv.envs[i], method_name)(*args, **kwargs) for i in self._get_indices(indices)]

        def env_is_wrapped(self, wrapper_class: type, indices=None) -> list:
            return [isinstance(self.venv.envs[i], wrapper_class) for i in self._get_indices(indices)]

    return SB3VecEnv(venv)


__all__ = ["KernelVectorEnv", "make_v1", "sb3_vec_env", "vector_entry"]
