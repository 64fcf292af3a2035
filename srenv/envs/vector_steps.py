"""One env's step and attribute access, as both vector-env backends run them (threads in
:mod:`srenv.envs.vector`, worker processes in :mod:`srenv.envs.vector_procs`): one function per convention, so the
backends give the same results."""

from __future__ import annotations

from typing import Any

import numpy as np


def slot_env(env_cls: type, env_kwargs: dict, env_wrapper: Any = None) -> Any:
    """One slot's env: ``env_cls(**env_kwargs)``, wrapped by ``env_wrapper(env)`` when one is given."""
    env = env_cls(**env_kwargs)
    return env if env_wrapper is None else env_wrapper(env)


def next_step(env: Any, done: bool, action: np.ndarray) -> tuple:
    """One env's step under NEXT_STEP autoreset: the step after its episode ended only resets it."""
    if done:
        obs, info = env.reset()
        return obs, 0.0, False, False, info
    return env.step(action)


def same_step(env: Any, action: np.ndarray) -> tuple:
    """One env's step under SB3's convention: reset in the same step, the final observation in the info."""
    obs, rew, term, trunc, info = env.step(action)
    info = dict(info)
    done = term or trunc
    if done:
        info["TimeLimit.truncated"] = trunc and not term
        info["terminal_observation"] = obs
        obs = env.reset()[0]
    return obs, rew, done, info


def env_op(env: Any, what: str, name: str, args: tuple, kwargs: dict) -> Any:
    """get / set / call / isinstance on one env (the SB3 adapter's get_attr, set_attr, env_method, ...)."""
    if what == "get":  # through wrappers as SB3's DummyVecEnv reads (a bare env: getattr)
        return env.get_wrapper_attr(name) if hasattr(env, "get_wrapper_attr") else getattr(env, name)
    if what == "set":
        setattr(env, name, args[0])
        return None
    if what == "call":
        fn = env.get_wrapper_attr(name) if hasattr(env, "get_wrapper_attr") else getattr(env, name)
        return fn(*args, **kwargs)
    if what == "isinstance":  # the env or any wrapper under it (SB3's env_is_wrapped)
        while env is not None:
            if isinstance(env, args[0]):
                return True
            env = getattr(env, "env", None)
        return False
    raise ValueError(f"env operation {what!r}: expected get, set, call or isinstance")
