"""``alarm_pump_off``: the field's pump-off controller WITH the alarms field controllers have (for v2).

A rod-pump controller does more than stop on low fillage: it shuts the well in on a **parted-rod** signature
(the polished-rod load collapses to the buoyant rod weight: the card's load range falls far below the
well's normal) or a **tubing-leak** signature (the fluid load fades over hours: the load range falls below
normal while the card still looks full), and it **slows down on gas** (gas interference: the pump fills
partly with gas, and pounding the gas wastes strokes). It reads only the field observation:

- the card's load range ``pprl - mprl`` (by name), against the range of the episode's first card (the well
  as found; v2's conditions start after the episode does);
- the classifier's probabilities ``prob_parted_rods``, ``prob_tubing_leak``, ``prob_gas_interference`` when the
  observation has them (v2's field observation; uniform 1/12 until the conditions branch's classifier is wired,
  so these alarms then never fire on them: ``alarm_prob`` > 1/12).

Actions: a shut-in alarm (parted rods or tubing leak) idles the well for the rest of the episode; the gas alarm
runs at ``a_spm - gas_slowdown`` while it holds; otherwise :class:`agents.policies.field.PumpOffPolicy`.
Every threshold is a parameter, tuned like pump-off's on the training wells only (``baselines.alarm_pump_off`` of
``configs/benchmark/v2.yaml``: from pump-off's tuned set point; :func:`agents.training.tuning.refuse_test_split`
refuses the test, validation and fresh ``family:`` wells).

``state`` per row: (idle intervals left, pumped last, shut in, reference load range).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from .field import IDLE, PumpOffPolicy, _batch, _out, _starts, make_field_baseline, name_index


def slowed(rate: np.ndarray, alarm: np.ndarray, slowdown: float) -> np.ndarray:
    """The rate entries of a batch slowed by ``slowdown`` where ``alarm`` holds, never below idle (an idle
    interval stays idle): the alarm controller's slow-down, for any alarm that slows it."""
    return np.where(alarm & (rate > IDLE), np.maximum(rate - slowdown, IDLE), rate)


class AlarmPumpOffPolicy(PumpOffPolicy):
    name = "alarm_pump_off"

    def __init__(self, obs_names: Sequence[str], threshold: float = 0.8, idle_time_s: float = 1800.0,
                 a_spm: float = 0.5, a_stroke: float = 1.0, interval_s: float = 300.0, load_drop: float = 0.5,
                 alarm_prob: float = 0.6, gas_slowdown: float = 0.3) -> None:
        super().__init__(obs_names, threshold, idle_time_s, a_spm, a_stroke, interval_s)
        if not 0.0 < load_drop < 1.0:
            raise ValueError(f"alarm_pump_off load_drop = {load_drop!r}: expected a fraction in (0, 1)")
        if not 1.0 / 12.0 < alarm_prob <= 1.0:
            raise ValueError(f"alarm_pump_off alarm_prob = {alarm_prob!r}: expected a probability in (1/12, 1]")
        if not 0.0 <= gas_slowdown <= 2.0:
            raise ValueError(f"alarm_pump_off gas_slowdown = {gas_slowdown!r}: expected [0, 2] action units")
        self.i_pprl, self.i_mprl = name_index(obs_names, "pprl"), name_index(obs_names, "mprl")
        names = list(obs_names)
        self.i_prob = {k: names.index(f"prob_{k}") for k in ("parted_rods", "tubing_leak", "gas_interference")
                       if f"prob_{k}" in names}
        self.load_drop, self.alarm_prob, self.gas_slowdown = float(load_drop), float(alarm_prob), float(gas_slowdown)

    def _prob(self, obs: np.ndarray, label: str) -> np.ndarray:
        i = self.i_prob.get(label)
        return obs[:, i] if i is not None else np.zeros(len(obs))

    def gas_alarm(self, observation: Any) -> np.ndarray:
        """Whether the gas alarm holds on each row's last card (the slow-down's condition)."""
        return self._prob(np.atleast_2d(np.asarray(observation, np.float64)), "gas_interference") > self.alarm_prob

    def predict(self, observation: Any, state: Any = None, episode_start: Any = None,
                deterministic: bool = True) -> tuple[np.ndarray, Any]:
        obs, n, batched = _batch(observation)
        starts = _starts(episode_start, n, state)
        st = np.zeros((n, 4)) if state is None else np.array(state, np.float64).reshape(n, 4)
        load_range = obs[:, self.i_pprl] - obs[:, self.i_mprl]
        st[starts] = 0.0
        st[starts, 3] = load_range[starts]
        action, st_po = super().predict(obs, st[:, :2], np.zeros(n, bool), deterministic)
        action = np.array(action, np.float64).reshape(n, 2)
        st[:, :2] = st_po
        # a card that was pumped (not an idle stretch's stale one) with the load range collapsed, or the classifier
        signature = (st[:, 1] > 0.5) & (load_range < (1.0 - self.load_drop) * st[:, 3])
        shut = (st[:, 2] > 0.5) | signature | (self._prob(obs, "parted_rods") > self.alarm_prob) \
            | (self._prob(obs, "tubing_leak") > self.alarm_prob)
        gas = self.gas_alarm(obs)
        action[:, 0] = slowed(action[:, 0], gas, self.gas_slowdown)
        action[:, 0] = np.where(shut, IDLE, action[:, 0])
        st[:, 2] = shut.astype(np.float64)
        return _out(action, batched), st

    def params(self) -> dict[str, Any]:
        return {**super().params(), "load_drop": self.load_drop, "alarm_prob": self.alarm_prob,
                "gas_slowdown": self.gas_slowdown}


def make_field_controller(name: str, params: dict[str, Any], obs_names: Sequence[str]) -> Any:
    """A field controller by benchmark name - the field baselines and ``alarm_pump_off`` - from its (tuned)
    parameters: the one builder of :func:`agents.policies.factory.make_baseline` and of the estimated MPC's
    fallback."""
    if name == "alarm_pump_off":
        return AlarmPumpOffPolicy(obs_names, **dict(params))
    return make_field_baseline(name, params, obs_names)
