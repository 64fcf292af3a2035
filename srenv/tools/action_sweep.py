"""Reward of one v1 control step along one action axis, from the same well and state each time.

``srenv sweep`` studies the simulator; this studies the *reward*: it resets a v1 env with a fixed seed and
takes one step at each setpoint, so neighbouring setpoints see the same well, level and inflow. Used by the
continuity test (``tests/srenv/envs/test_env_v1.py``) and by ``scripts/reward_sweep.py`` (the figure in docs/task.md).
"""

from __future__ import annotations

import numpy as np

from ..envs.sucker_rod_v1 import SuckerRodV1Env, action_from_setpoints


def sweep(scenario: str, seed: int, axis: str, step: float, **env_kwargs) -> dict[str, np.ndarray]:
    """axis 'spm' (average SPM, stroke at mid-range) or 'stroke' (m, SPM at the installed point)."""
    env = SuckerRodV1Env(scenario=scenario, **env_kwargs)
    env.reset(seed=seed)
    ctl, surf = env.cfg.control, env.cfg.surface
    if axis == "spm":
        values = np.arange(step, ctl.spm_max + 1e-9, step)
        actions = action_from_setpoints(values, np.full_like(values, 0.5 * (ctl.stroke_min_m + ctl.stroke_max_m)),
                                        ctl)
    elif axis == "stroke":
        values = np.arange(ctl.stroke_min_m, ctl.stroke_max_m + 1e-9, step)
        actions = action_from_setpoints(np.full_like(values, surf.spm), values, ctl)
    else:
        raise ValueError(f"axis = {axis!r}: expected 'spm' or 'stroke'")
    out: dict[str, list] = {"value": [], "reward": [], "stick_slip_energy_j": [], "fillage": [], "cost": []}
    terms: dict[str, list] = {}
    for v, a in zip(values, actions):
        env.reset(seed=seed)
        _, r, _, _, info = env.step(a)
        out["value"].append(v)
        out["reward"].append(r)
        for k in ("stick_slip_energy_j", "fillage", "cost"):
            out[k].append(info[k])
        for k, x in info.items():
            if k.startswith("reward_"):
                terms.setdefault(k, []).append(x)
    res = {k: np.asarray(v, dtype=float) for k, v in out.items()}
    res.update({k: np.asarray(v, dtype=float) for k, v in terms.items()})
    res["well_id"] = env.well.well_id
    return res
