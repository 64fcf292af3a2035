"""Potential-based reward shaping for training on ``srenv/SuckerRod-v1`` (training only; evaluation uses the
env's own reward).

Why: the v1 reward is, up to the costs, the value of what the *reservoir* delivers (revenue + inventory =
``v q_in``), and a controller raises ``q_in`` only by drawing the annulus level down, over hours. The effect of
an action on the reward therefore arrives through an integrator, tens of intervals later, which a policy
gradient at a few hundred thousand steps does not resolve. The shaping pays that value at once:

    r'_t = r_t + Phi(s_{t+1}) - Phi(s_t),    Phi(s) = v q_in(s) t_rem(s) / h        (reward units: USD/h)

with ``v`` the well's net value of a cubic metre of liquid (USD/m3), ``q_in(s)`` the reservoir inflow at the
present annulus level and inflow schedule (m3/h, privileged state the simulator has), ``t_rem`` the well time
left in the episode (h) and ``h`` the control interval (h). ``Phi`` is the value of producing at the present
inflow for the rest of the episode, so ``r'`` is the value of the change in inflow an interval made, plus the
costs. ``Phi`` is 0 at the end of an episode (``t_rem`` = 0, or a terminal failure), so the shaped return is the
true return minus ``Phi(s_0)``, which no action changes (Ng, Harada & Russell 1999, with the undiscounted
telescoping of the evaluation metric): the policy that maximises one maximises the other.

``info["shaping"]`` carries the added term; ``info`` is otherwise the env's.
"""

from __future__ import annotations

from typing import Any

import gymnasium as gym

from ..envs import ENV_ID_V1, make_env

ENV_ID = "ShapedSuckerRod-v1"
SHAPED_ENV_ID = f"{__name__}:{ENV_ID}"  # the module as imported: agents (checkout) or srenv_agents (wheel)


def potential(env: Any) -> float:
    """``Phi(s)`` in the env's reward units (USD/h): the value of the present inflow for the time left."""
    u = env.unwrapped
    t_rem_h = max(0.0, u.horizon_s - u._elapsed()) / 3600.0
    interval_h = u.cfg.task.interval_s / 3600.0
    ann = u.sim.annulus
    # the schedule's multiplier at this moment (the env sets the annulus's at the start of the next interval)
    mult = u.inflow_multiplier(u._elapsed())
    q_m3_h = ann.inflow_m3_s() / ann.rate_multiplier * mult * 3600.0 if ann.rate_multiplier > 0 else 0.0
    return u.econ.net_value_usd_m3 * q_m3_h * t_rem_h / interval_h


class ShapedEnv(gym.Wrapper):
    """``env`` with the potential-based shaping of the module doc added to its reward."""

    def reset(self, **kwargs: Any) -> tuple[Any, dict]:
        obs, info = self.env.reset(**kwargs)
        self._phi = potential(self.env)
        return obs, info

    def step(self, action: Any) -> tuple[Any, float, bool, bool, dict]:
        obs, r, term, trunc, info = self.env.step(action)
        phi = 0.0 if term or trunc else potential(self.env)
        shaping = phi - self._phi
        self._phi = phi
        return obs, float(r) + shaping, term, trunc, {**info, "shaping": shaping}


def make_shaped_env(inner_env_id: str = ENV_ID_V1, **env_kwargs: Any) -> ShapedEnv:
    if inner_env_id != ENV_ID_V1:  # the potential reads v1's state; and no module chosen by a YAML is imported
        raise ValueError(f"shaped inner_env_id = {inner_env_id!r}: expected {ENV_ID_V1}")
    return ShapedEnv(make_env(inner_env_id, **env_kwargs))


if ENV_ID not in gym.registry:
    gym.register(ENV_ID, entry_point=make_shaped_env)
