"""Digests of v1 (default and ``fast_stepping``) and v2 episodes under changing (random) and constant actions:
observations, rewards and infos to the bit (issue 25, docs/speed.md §2d).

    python scripts/rl_digest.py            # prints {case: sha256} as JSON
    PYTHONPATH=/tmp/rl_before python scripts/rl_digest.py   # the same from another tree

tests/srenv/envs/test_rl_digest.py holds the digests of 25d9225 and compares them with ``==``; the acceptance
protocol's (``acceptance_*``: seeds 11 and 12, 12 steps at a constant action, after a warm-up step on seed 3) are
those of 67d2e08 (issue 25's fifth round, docs/speed.md §2e).
"""

from __future__ import annotations

import hashlib
import json
import warnings

import numpy as np

CASES = {  # name: (env id, env kwargs)
    "v1": ("srenv/SuckerRod-v1", {}),
    "v1_fast": ("srenv/SuckerRod-v1", {"fast_stepping": True}),
    "v2": ("srenv/SuckerRod-v2", {}),
}
SEEDS = (1, 2, 3)
STEPS = 20


def _feed(h, value) -> None:
    """Every number of an info, in a fixed order, by its bytes."""
    if isinstance(value, dict):
        for k in sorted(value):
            h.update(str(k).encode())
            _feed(h, value[k])
    elif isinstance(value, (list, tuple)):
        for v in value:
            _feed(h, v)
    elif isinstance(value, np.ndarray):
        h.update(str(value.dtype).encode() + np.ascontiguousarray(value).tobytes())
    elif isinstance(value, (float, np.floating)):
        h.update(float(value).hex().encode())
    else:
        h.update(repr(value).encode())


def digest(env_id: str, kwargs: dict, policy: str, seeds=SEEDS, steps: int = STEPS) -> str:
    import gymnasium as gym

    import srenv  # noqa: F401  (registers the envs)

    h = hashlib.sha256()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        env = gym.make(env_id, scenario="train", **kwargs)
        rng = np.random.default_rng(0)
        for seed in seeds:
            obs, info = env.reset(seed=seed)
            _feed(h, obs)
            _feed(h, info)
            for i in range(steps):
                if policy == "random":
                    a = rng.uniform(-1.0, 1.0, 2).astype(np.float32)
                else:
                    a = np.array([1.0 if i < steps // 2 else -0.6, 1.0], np.float32)
                obs, reward, term, trunc, info = env.step(a)
                _feed(h, [obs, float(reward), term, trunc, info])
        env.close()
    return h.hexdigest()


def acceptance_digest(env_id: str, a0: float, seeds=(11, 12), steps: int = 12) -> str:
    """The acceptance's speed protocol (``acceptance/speed``): a warm-up reset (seed 3) and step, then ``steps``
    steps at the constant action [a0, 1] on each of ``seeds``; every observation, reward and info by its bits."""
    import gymnasium as gym

    import srenv  # noqa: F401  (registers the envs)

    h = hashlib.sha256()
    a = np.array([a0, 1.0], np.float32)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        env = gym.make(env_id, scenario="train")
        _feed(h, list(env.reset(seed=3)))
        _feed(h, list(env.step(a)))
        for seed in seeds:
            _feed(h, list(env.reset(seed=seed)))
            for _ in range(steps):
                obs, reward, term, trunc, info = env.step(a)
                _feed(h, [obs, float(reward), term, trunc, info])
        env.close()
    return h.hexdigest()


ACCEPTANCE_ACTIONS = {"full_speed": 1.0, "vsd_minimum": -0.6}


def all_digests() -> dict:
    out = {f"{name}/{policy}": digest(env_id, kw, policy)
           for name, (env_id, kw) in CASES.items() for policy in ("random", "constant")}
    for env_name, env_id in (("v1", "srenv/SuckerRod-v1"), ("v2", "srenv/SuckerRod-v2")):
        for label, a0 in ACCEPTANCE_ACTIONS.items():
            out[f"{env_name}/acceptance_{label}"] = acceptance_digest(env_id, a0)
    return out


if __name__ == "__main__":
    print(json.dumps(all_digests(), indent=1))
