"""Issue 24: srenv/SuckerRod-v3's mechanism figures against v2's (docs/task.md, "v3"), training wells only.

    PYTHONPATH=. python scripts/v3_mechanism.py > v3_mechanism.json

One JSON object on stdout, no flags and no files written:

* ``tag_reference``: the plunger's impact speed at each of training wells 0..19 (``train`` seeds 0..19) at its
  installed point, tagging_down at severity 0.6 (the middle of the drawn range), and their median: the reference
  speed of srenv.task.tag_contact is that median / sqrt(0.6).
* ``tagging``: on training well train-003 (seed 3), tagging_down at severity 0.6 (and 0), the interval after the
  onset one (the onset at the installed point): ``reward_tagging`` (USD/h) and ``cost_tagging`` in v2 and v3 at
  8 / 6 / 3 SPM on the full stroke and at 6 SPM on 2.0 and 1.6 m; and v3's SPM sweep 2..9 by 0.25.
* ``leaks``: the same well, each leak at severity 0.2: the lost share of the lifted liquid
  (``reward_lost_production / reward_revenue``) in v2 and v3 at 3 / 5 / 8 SPM.
"""

from __future__ import annotations

import json
import math
import sys

import gymnasium as gym
import numpy as np

import srenv  # noqa: F401 - registers the envs
from srenv.envs.sucker_rod_v1 import action_from_setpoints
from srenv.task import events as ev
from srenv.task import tag_contact

SEED = 3
VERSIONS = ("srenv/SuckerRod-v2", "srenv/SuckerRod-v3")


def forced(env_id: str, label: str, severity: float, seed: int = SEED, interval_s: float = 300.0):
    env = gym.make(env_id, scenario="train", episode_hours=1.0, interval_s=interval_s).unwrapped
    env.reset(seed=seed)
    env._schedule = ev.Schedule([ev.Event(label, 0.0, math.inf, severity)])
    return env


def act(env, spm: float, stroke_m: float | None = None) -> np.ndarray:
    stroke = env.cfg.surface.stroke_length_m if stroke_m is None else stroke_m
    return action_from_setpoints(spm, stroke, env.cfg.control).astype(np.float32)


def after_onset(env_id: str, label: str, severity: float, spm: float, stroke_m: float | None = None) -> dict:
    """The info of the interval after the onset interval (run at the well's installed point)."""
    env = forced(env_id, label, severity)
    env.step(act(env, env.cfg.surface.spm))
    return env.step(act(env, spm, stroke_m))[4]


def tag_reference() -> dict:
    speeds = []
    for seed in range(20):
        env = forced(VERSIONS[1], "tagging_down", 0.6, seed)
        env.step(act(env, env.cfg.surface.spm))
        speeds.append(tag_contact.stroke_impact_m_s(env._last.trace, env.sim.contact_ends()))
    median = float(np.median(speeds))
    return {"impact_m_s": [round(s, 4) for s in speeds], "median_m_s": median,
            "reference_m_s": median / math.sqrt(0.6), "shipped_reference_m_s": tag_contact.TAG_REFERENCE_SPEED_M_S}


def tagging() -> dict:
    out: dict = {}
    cases = [(0.6, 8.0, None), (0.6, 6.0, None), (0.6, 3.0, None), (0.6, 6.0, 2.0), (0.6, 6.0, 1.6), (0.0, 8.0, None)]
    for env_id in VERSIONS:
        rows = []
        for sev, spm, stroke in cases:
            info = after_onset(env_id, "tagging_down", sev, spm, stroke)
            rows.append({"severity": sev, "spm": spm, "stroke_m": stroke or "installed",
                         "reward_tagging_usd_h": info["reward_tagging"], "cost_tagging": info["cost_tagging"]})
        out[env_id] = rows
    sweep = []
    for spm in np.arange(2.0, 9.01, 0.25):
        env = forced(VERSIONS[1], "tagging_down", 0.6, interval_s=60.0)
        sweep.append([round(float(spm), 2), env.step(act(env, float(spm)))[4]["reward_tagging"]])
    out["v3_sweep_spm_reward_tagging_usd_h"] = sweep
    return out


def leaks() -> dict:
    out: dict = {}
    for env_id in VERSIONS:
        for label in ("travelling_valve_leak", "standing_valve_leak", "tubing_leak"):
            shares = {}
            for spm in (3.0, 5.0, 8.0):
                info = after_onset(env_id, label, 0.2, spm)
                shares[str(spm)] = -info["reward_lost_production"] / info["reward_revenue"]
            out.setdefault(env_id, {})[label] = shares
    return out


def no_arguments(script: str, argv: list[str] | None) -> None:
    """A script of fixed figures refuses any argument: one line naming it, exit 2 (before any work)."""
    args = sys.argv[1:] if argv is None else argv
    if args:
        print(f"{script}: {args[0]!r}: expected no arguments (the figures are fixed; see the docstring)",
              file=sys.stderr)
        raise SystemExit(2)


def main(argv: list[str] | None = None) -> None:
    no_arguments("v3_mechanism", argv)
    print(json.dumps({"well_seed": SEED, "tag_reference": tag_reference(), "tagging": tagging(), "leaks": leaks()}))


if __name__ == "__main__":
    main()
