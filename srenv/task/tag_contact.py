"""``srenv/SuckerRod-v3``'s tagging damage from the contact: how hard the plunger hits the pump's end.

The tagging law (srenv.physics.laws.pump_conditions) is a one-sided spring between the plunger and the pump's
top (bottom) end, placed ``tag_*_overtravel_m`` inside the plunger's free travel of the first stroke after the
condition starts. In v3 the end stays where it was placed for the rest of the episode
(``Simulator.fixed_contact_ends``: a spacing drift is a fixed position, not one relative to today's stroke).

A stroke's contact is its **impact speed**: the plunger's speed when it reaches the end (the largest of the
stroke's contacts; the trace is taken as periodic, so a contact that starts at the stroke's boundary counts).
The speed, not the contact spring's peak force, is what the rods deliver: the spring is a numerical device
(``pump.tag_stiffness_n_m``, soft enough for the explicit step), the force of a hit on a steel end is the rod's
impedance times that speed. The damage of a stroke, in workovers, is

    d = TAG_WORKOVER_SHARE_PER_STROKE x (v_impact / TAG_REFERENCE_SPEED_M_S)^TAG_EXPONENT

with ``TAG_EXPONENT = 2`` (the hit's kinetic energy, as fluid pound's ``reward_pound``) and the reference speed
set so that the training wells' median hit at their installed point and severity 0.6 (the middle of the drawn
range) costs v2's share per stroke at that severity, 0.6e-6 (docs/task.md, "v3"). It is 0 without contact and
continuous in the action: a stroke that grazes the end meets it at a speed near 0.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from .events import TAG_WORKOVER_SHARE_PER_STROKE

TAG_EXPONENT = 2.0
TAG_REFERENCE_SPEED_M_S = 0.36  # 0.277 m/s (median, 20 training wells) / sqrt(0.6)


def _entry_speeds(x: np.ndarray, v: np.ndarray, inside: np.ndarray, edge: float) -> np.ndarray:
    """The speeds (|v| interpolated at the crossing of ``edge``) where the periodic trace enters ``inside``."""
    nxt = np.roll(np.arange(x.size), -1)
    k = np.flatnonzero(~inside & inside[nxt])
    if k.size == 0:
        return np.zeros(0)
    x0, x1, v0, v1 = x[k], x[nxt[k]], v[k], v[nxt[k]]
    span = np.where(x1 != x0, x1 - x0, 1.0)
    w = np.clip((edge - x0) / span, 0.0, 1.0)
    return np.abs(v0 + w * (v1 - v0))


def impact_speed_m_s(pump_position_m: np.ndarray, pump_velocity_m_s: np.ndarray, ends: Mapping[str, float]) -> float:
    """The stroke's impact speed (m/s) on the placed ends (``Simulator.contact_ends``, kernel sign: positive
    down) from its trace (upward positive); 0 when no end is placed or the plunger stays clear."""
    x = np.asarray(pump_position_m, dtype=np.float64)
    v = np.asarray(pump_velocity_m_s, dtype=np.float64)
    if x.size < 2:
        return 0.0
    speeds = [0.0]
    if ends["tag_bottom_set"]:  # the end at kernel ub = tag_bottom_m, the trace's x = -tag_bottom_m
        edge = -float(ends["tag_bottom_m"])
        speeds.extend(_entry_speeds(x, v, x < edge, edge))
    if ends["tag_top_set"]:
        edge = -float(ends["tag_top_m"])
        speeds.extend(_entry_speeds(x, v, x > edge, edge))
    return float(max(speeds))


def stroke_impact_m_s(trace: Mapping[str, np.ndarray], ends: Mapping[str, float]) -> float:
    """:func:`impact_speed_m_s` of a stroke's trace (a simulator's ``pump_position_m`` / ``pump_velocity_m_s``)."""
    return impact_speed_m_s(trace["pump_position_m"], trace["pump_velocity_m_s"], ends)


def damage_per_stroke(impact_m_s: float) -> float:
    """Workovers' worth of damage of one stroke with that impact speed (module docstring)."""
    if impact_m_s <= 0.0:
        return 0.0
    return TAG_WORKOVER_SHARE_PER_STROKE * (impact_m_s / TAG_REFERENCE_SPEED_M_S) ** TAG_EXPONENT
