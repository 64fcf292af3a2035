"""A wide digest of v1 and v2 episodes, to the bit (docs/speed.md §2j): every observation, reward, flag and info,
the last stroke's whole summary, trace and figures, the annulus volume and the clock after every reset and step of
nine cases x five seeds (v2 through full speed, the VSD minimum, mid, idle and back; v2 random actions; v2 with 60x
the condition rates and the privileged observation; v2's test split; ``family:7``; v2 ``fast_stepping=False``; v2
with an economics override; v1 random; v1 ``fast_stepping``). Run it in two trees and compare the JSON lines:

    python scripts/wide_digest.py
    cd /tmp/before && PYTHONPATH=/tmp/before python /path/to/this/checkout/scripts/wide_digest.py
"""

from __future__ import annotations

import argparse
import hashlib
import json
import warnings

import numpy as np
from rl_digest import _feed

FIGURES = ("lifted_m3", "displacement_m3", "fillage", "fillage_est", "work_j", "damage", "stick_slip_j", "impact_m_s",
           "power_mean_w", "power_peak_w")
CASES = {  # name: (env id, env kwargs, actions)
    "v2_const": ("srenv/SuckerRod-v2", {}, "const"),
    "v2_rand": ("srenv/SuckerRod-v2", {}, "rand"),
    "v2_events": ("srenv/SuckerRod-v2", {"event_rate_scale": 60.0, "observation": "privileged"}, "rand"),
    "v2_test": ("srenv/SuckerRod-v2", {"scenario": "test"}, "const"),
    "v2_family": ("srenv/SuckerRod-v2", {"scenario": "family:7"}, "rand"),
    "v2_slow": ("srenv/SuckerRod-v2", {"fast_stepping": False}, "const"),
    "v1": ("srenv/SuckerRod-v1", {}, "rand"),
    "v1_fast": ("srenv/SuckerRod-v1", {"fast_stepping": True}, "const"),
    "v2_over": ("srenv/SuckerRod-v2", {"overrides": {"economics.oil_price_usd_m3": 400.0}}, "const"),
}
SEEDS = (11, 12, 40, 77, 123)
CONSTANT = [(1.0, 1.0)] * 6 + [(-0.6, 1.0)] * 8 + [(0.3, -0.4)] * 4 + [(-1.0, 0.0)] * 2 + [(1.0, 1.0)] * 3


def episode(h, env, seed: int, actions: list) -> None:
    obs, info = env.reset(seed=seed)
    _feed(h, obs)
    _feed(h, info)
    u = env.unwrapped
    for a in actions:
        obs, r, terminated, truncated, info = env.step(a)
        _feed(h, obs)
        _feed(h, float(r))
        _feed(h, [bool(terminated), bool(truncated)])
        _feed(h, info)
        _feed(h, u._last.summary)
        _feed(h, u._last.trace)
        _feed(h, [float(getattr(u._last, k)) for k in FIGURES])
        _feed(h, [float(u.sim.annulus.volume_m3), float(u.sim.time_s)])
        if terminated or truncated:
            break


def main() -> None:
    warnings.filterwarnings("ignore")
    import gymnasium as gym

    import srenv  # noqa: F401  (registers the envs)

    out = {}
    for name, (env_id, kwargs, mode) in CASES.items():
        h = hashlib.sha256()
        env = gym.make(env_id, **kwargs)
        rng = np.random.default_rng(5)
        for seed in SEEDS:
            if mode == "const":
                actions = [np.array(a, np.float32) for a in CONSTANT]
            else:
                actions = [rng.uniform(-1, 1, 2).astype(np.float32) for _ in range(14)]
            episode(h, env, seed, actions)
        out[name] = h.hexdigest()[:16]
    print(json.dumps(out))


if __name__ == "__main__":
    argparse.ArgumentParser(description=__doc__.split("\n\n")[0]).parse_args()  # no options: --help, or run
    main()
