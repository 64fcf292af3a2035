"""A native vector env: N wells (each its own mesh) stepped across threads, for any srenv task env class.

``gymnasium.make_vec("srenv/SuckerRod-v1", num_envs=N, vectorization_mode="vector_entry_point", ...)`` builds a
:class:`KernelVectorEnv` of N :class:`~srenv.envs.sucker_rod_v1.SuckerRodV1Env`. The exact strokes run in the
compiled kernel, which releases the GIL (``nogil=True``), so the wells' strokes run in parallel on a thread pool
(``threads``, default: the cores this process may use); the Python around them (the env's bookkeeping, the card
features) takes turns. The results are those of N single envs stepped one by one (tests/test_speed.py): each env
owns its simulator and random stream, and a thread steps one env at a time.

``processes=P`` (P >= 2) moves the envs into P worker processes instead, a contiguous block of wells each
(:mod:`srenv.envs.vector_procs`): the whole step - kernel and Python - then runs on P cores, and the results are
still those of the single envs (the same per-env step functions run in the workers).

Autoreset is gymnasium's NEXT_STEP mode (``metadata["autoreset_mode"]``): the step after an episode ends resets
that env (its action is ignored, reward 0). ``reset(seed=s)`` seeds env i with s + i (gymnasium's convention).
Another task version uses it with one line: ``vector_entry(SuckerRodV2Env)``. :class:`SB3VecEnv` adapts it to
stable-baselines3 (which resets in the same step and hands the final observation in ``infos``).

``env_wrapper=f`` wraps every slot's env as ``f(env)`` where it is built (in the workers too, so ``f`` must pickle:
a module-level function or a ``functools.partial`` of one): how ``python -m agents train`` with ``vec_env: native``
puts its residual, reward-shaping and ``Monitor`` wrappers inside each slot (gymnasium's own ``wrappers=`` is
refused in this vectorization mode). Without it the slots are the bare envs, as before.
"""

from __future__ import annotations

import os
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from typing import Any, ClassVar

import numpy as np
from gymnasium.vector import AutoresetMode, VectorEnv
from gymnasium.vector.utils import batch_space

from .vector_steps import env_op, next_step, same_step, slot_env


def default_threads() -> int:
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # not Linux
        return os.cpu_count() or 1


class KernelVectorEnv(VectorEnv):
    """N instances of ``env_cls`` (built with ``env_kwargs``) stepped on ``threads`` threads."""

    metadata: ClassVar[dict[str, Any]] = {"autoreset_mode": AutoresetMode.NEXT_STEP, "render_modes": []}

    def __init__(self, env_cls: type, num_envs: int, threads: int | None = None, processes: int | None = None,
                 env_wrapper: Callable[[Any], Any] | None = None, **env_kwargs: Any) -> None:
        self._pool = self._procs = None  # close() (also from __del__) works when the arguments or envs fail
        self.envs = []
        if isinstance(num_envs, bool) or not isinstance(num_envs, (int, np.integer)) or int(num_envs) < 1:
            raise ValueError(f"num_envs = {num_envs!r}: expected an integer >= 1")
        if processes is not None and (isinstance(processes, bool) or not isinstance(processes, (int, np.integer))
                                      or int(processes) < 1):
            raise ValueError(f"processes = {processes!r}: expected an integer >= 1 (or None: threads)")
        env_kwargs.pop("max_episode_steps", None)  # gymnasium passes the spec's; the envs truncate themselves
        self.num_envs = int(num_envs)
        self.processes = min(int(processes or 1), self.num_envs)
        if self.processes > 1:
            from .vector_procs import ProcessShards

            self.envs = []  # the envs live in the workers
            self._procs = ProcessShards(env_cls, self.num_envs, self.processes, env_kwargs, env_wrapper)
            obs_space, act_space = self._procs.spaces
            self.threads = 1
        else:
            self.envs = [slot_env(env_cls, env_kwargs, env_wrapper) for _ in range(self.num_envs)]
            obs_space, act_space = self.envs[0].observation_space, self.envs[0].action_space
            self.threads = max(1, min(int(threads or default_threads()), self.num_envs))
        self.single_observation_space = obs_space
        self.single_action_space = act_space
        self.observation_space = batch_space(obs_space, self.num_envs)
        self.action_space = batch_space(act_space, self.num_envs)
        self._pool = ThreadPoolExecutor(self.threads) if self.threads > 1 else None
        self._done = np.zeros(self.num_envs, dtype=bool)
        self.render_mode = None

    def map(self, fn: Callable[[int], Any]) -> list:
        """fn(i) for every env, on the pool (each call touches env i only); in-process envs only."""
        idx = range(self.num_envs)
        return list(self._pool.map(fn, idx)) if self._pool is not None else [fn(i) for i in idx]

    # the three operations both backends provide (the SB3 adapter uses them too)
    def reset_envs(self, seeds: list, options: dict | None = None) -> list:
        """[(obs, info)] of every env reset with its seed."""
        if self._procs is not None:
            return self._procs.run("reset", [(s, options) for s in seeds])
        return self.map(lambda i: self.envs[i].reset(seed=seeds[i], options=options))

    def step_envs(self, actions: np.ndarray, same: bool = False) -> list:
        """Every env's step: NEXT_STEP autoreset (``done`` flags kept here), or SB3's same-step reset."""
        if self._procs is not None:
            if same:
                return self._procs.run("same", list(actions))
            return self._procs.run("next", list(zip(self._done.tolist(), actions)))
        if same:
            return self.map(lambda i: same_step(self.envs[i], actions[i]))
        return self.map(lambda i: next_step(self.envs[i], bool(self._done[i]), actions[i]))

    def env_call(self, what: str, name: str, indices: list, *args: Any, **kwargs: Any) -> list:
        """get (an attribute), set (``args[0]``), call (a method with args) or isinstance on envs ``indices``."""
        if self._procs is not None:
            return self._procs.call(what, name, list(indices), args, kwargs)
        return [env_op(self.envs[i], what, name, args, kwargs) for i in indices]

    def reset(self, *, seed: int | list | None = None, options: dict | None = None) -> tuple[np.ndarray, dict]:
        seeds = list(seed) if isinstance(seed, (list, tuple)) else [
            None if seed is None else int(seed) + i for i in range(self.num_envs)]
        res = self.reset_envs(seeds, options)
        self._done[:] = False
        infos: dict = {}
        for i, (_, info) in enumerate(res):
            infos = self._add_info(infos, info, i)
        return np.stack([o for o, _ in res]), infos

    def step(self, actions: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, dict]:
        actions = np.asarray(actions)
        if self._procs is not None:  # block by block: the driver's infos merge while the workers still step
            parts = self._procs.run_parts("next", list(zip(self._done.tolist(), actions)))
        else:
            parts = [self.step_envs(actions)]
        res: list = []
        infos: dict = {}
        for part in parts:
            for r in part:
                infos = self._add_info(infos, r[4], len(res))
                res.append(r)
        term = np.array([r[2] for r in res], dtype=bool)
        trunc = np.array([r[3] for r in res], dtype=bool)
        self._done = term | trunc
        return (np.stack([r[0] for r in res]), np.array([r[1] for r in res], dtype=np.float64), term, trunc,
                infos)

    def close_extras(self, **kwargs: Any) -> None:
        if self._procs is not None:
            self._procs.close()
            self._procs = None
        if self._pool is not None:
            self._pool.shutdown()
            self._pool = None
        for env in self.envs:
            env.close()


def vector_entry(env_cls: type) -> Callable[..., KernelVectorEnv]:
    """A gymnasium ``vector_entry_point`` for ``env_cls``."""
    def make(num_envs: int = 1, threads: int | None = None, processes: int | None = None,
             env_wrapper: Callable[[Any], Any] | None = None, **env_kwargs: Any) -> KernelVectorEnv:
        return KernelVectorEnv(env_cls, num_envs, threads=threads, processes=processes, env_wrapper=env_wrapper,
                               **env_kwargs)
    return make


def make_v1(num_envs: int = 1, threads: int | None = None, processes: int | None = None,
            env_wrapper: Callable[[Any], Any] | None = None, **env_kwargs: Any) -> KernelVectorEnv:
    """srenv/SuckerRod-v1's vector entry point."""
    from .sucker_rod_v1 import SuckerRodV1Env

    return KernelVectorEnv(SuckerRodV1Env, num_envs, threads=threads, processes=processes,
                           env_wrapper=env_wrapper, **env_kwargs)


def make_v2(num_envs: int = 1, threads: int | None = None, processes: int | None = None,
            env_wrapper: Callable[[Any], Any] | None = None, **env_kwargs: Any) -> KernelVectorEnv:
    """srenv/SuckerRod-v2's vector entry point (its events and classifier run per well, in the same threads)."""
    from .sucker_rod_v2 import SuckerRodV2Env

    return KernelVectorEnv(SuckerRodV2Env, num_envs, threads=threads, processes=processes,
                           env_wrapper=env_wrapper, **env_kwargs)


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
            obs = [o for o, _ in self.venv.reset_envs(self._seeds)]
            self._seeds = [None] * self.num_envs
            return np.stack(obs)

        def step_async(self, actions: np.ndarray) -> None:
            self._actions = np.asarray(actions)

        def step_wait(self):
            res = self.venv.step_envs(self._actions, same=True)
            return (np.stack([r[0] for r in res]), np.array([r[1] for r in res], dtype=np.float32),
                    np.array([r[2] for r in res], dtype=bool), [r[3] for r in res])

        def seed(self, seed: int | None = None) -> list:
            self._seeds = [None if seed is None else seed + i for i in range(self.num_envs)]
            return self._seeds

        def close(self) -> None:
            self.venv.close()

        def get_attr(self, attr_name: str, indices=None) -> list:
            return self.venv.env_call("get", attr_name, self._get_indices(indices))

        def set_attr(self, attr_name: str, value: Any, indices=None) -> None:
            self.venv.env_call("set", attr_name, self._get_indices(indices), value)

        def env_method(self, method_name: str, *args: Any, indices=None, **kwargs: Any) -> list:
            return self.venv.env_call("call", method_name, self._get_indices(indices), *args, **kwargs)

        def env_is_wrapped(self, wrapper_class: type, indices=None) -> list:
            return self.venv.env_call("isinstance", "", self._get_indices(indices), wrapper_class)

    return SB3VecEnv(venv)


__all__ = ["KernelVectorEnv", "make_v1", "sb3_vec_env", "vector_entry"]
