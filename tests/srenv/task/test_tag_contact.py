"""srenv.task.tag_contact (v3): the plunger's impact speed on the pump's end from a stroke's trace, and the
damage it does."""

from __future__ import annotations

import numpy as np
import pytest

from srenv.task import tag_contact as tc

UNSET = {"tag_top_m": 0.0, "tag_bottom_m": 0.0, "tag_top_set": 0, "tag_bottom_set": 0}


def _stroke(amplitude: float, n: int = 2001) -> tuple[np.ndarray, np.ndarray]:
    """One harmonic stroke of the plunger (upward positive), starting at the bottom, period 1 s."""
    t = np.linspace(0.0, 1.0, n, endpoint=False)
    w = 2 * np.pi
    return -amplitude * np.cos(w * t), amplitude * w * np.sin(w * t)


def test_impact_speed_is_the_speed_at_the_end() -> None:
    x, v = _stroke(1.0)
    ends = {**UNSET, "tag_bottom_m": 0.6, "tag_bottom_set": 1}  # kernel sign: 0.6 m down = x -0.6
    expected = 2 * np.pi * np.sqrt(1.0 - 0.6 ** 2)  # harmonic: |v| at x = -0.6
    assert tc.impact_speed_m_s(x, v, ends) == pytest.approx(expected, rel=1e-4)
    top = {**UNSET, "tag_top_m": -0.6, "tag_top_set": 1}
    assert tc.impact_speed_m_s(x, v, top) == pytest.approx(expected, rel=1e-4)
    assert tc.impact_speed_m_s(x, v, UNSET) == 0.0
    clear = {**UNSET, "tag_bottom_m": 1.2, "tag_bottom_set": 1}
    assert tc.impact_speed_m_s(x, v, clear) == 0.0


def test_impact_speed_is_continuous_down_to_grazing_and_across_the_stroke_boundary() -> None:
    ends = {**UNSET, "tag_bottom_m": 0.999, "tag_bottom_set": 1}
    x, v = _stroke(1.0)
    assert 0.0 < tc.impact_speed_m_s(x, v, ends) < 0.3  # a graze: near 0
    end = {**UNSET, "tag_bottom_m": 0.8, "tag_bottom_set": 1}
    near = [tc.impact_speed_m_s(*_stroke(0.8 + eps, 20001), end) for eps in (1e-2, 1e-4, 1e-6)]
    assert near[0] > near[1] > near[2] and near[2] < 0.01  # -> 0 as the stroke reaches the end: no jump
    damage = [tc.damage_per_stroke(tc.impact_speed_m_s(*_stroke(a), end)) for a in np.linspace(0.7, 1.0, 61)]
    assert damage[0] == 0.0 and damage[-1] > 0.0
    assert np.max(np.abs(np.diff(damage))) < 0.05 * damage[-1]  # the damage (speed squared) has no step
    # the stroke starts inside the contact (the trace's first samples at the bottom): the entry at its end counts
    assert tc.impact_speed_m_s(x, v, {**UNSET, "tag_bottom_m": 0.9999999, "tag_bottom_set": 1}) >= 0.0


def test_damage_is_zero_without_contact_and_grows_with_the_square_of_the_speed() -> None:
    assert tc.damage_per_stroke(0.0) == 0.0
    ref = tc.TAG_REFERENCE_SPEED_M_S
    assert tc.damage_per_stroke(ref) == pytest.approx(tc.TAG_WORKOVER_SHARE_PER_STROKE)
    assert tc.damage_per_stroke(2 * ref) == pytest.approx(4 * tc.TAG_WORKOVER_SHARE_PER_STROKE)
