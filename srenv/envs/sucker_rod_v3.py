"""``srenv/SuckerRod-v3``: v2's task (:mod:`srenv.envs.sucker_rod_v2`) with the conditions' volumes and damage
from their physics, and run 7's card classifier in the field observation.

What v3 changes (everything else, spaces included, is v2's)
-----------------------------------------------------------
* **Tagging damage from the contact** (:mod:`srenv.task.tag_contact`). The pump's end is placed once, in the
  first stroke after the spacing drift, and stays there (``Simulator.fixed_contact_ends``; v2 places it again
  after every stop, relative to the stroke that follows). Each interval's damage is its strokes x the damage of
  its last (or reused) stroke, ``1e-6 x (v_impact / 0.36 m/s)^2`` workovers with ``v_impact`` the plunger's speed
  when it reaches the end: 0 without contact, continuous in the action, smaller from 8 to 3 SPM and with a
  shorter stroke on the wells measured (not monotone in SPM: the rods' response; docs/task.md) (v2: 1e-6 x
  severity per stroke, whatever the stroke).
* **Leaks from the law's own model** (:mod:`srenv.task.leaks`). A leaking valve's speed ``v_leak = C dp / A_pl``
  is fixed in m/s at the onset; the config's ``v_leak / v_peak`` follows each interval's SPM and stroke; the
  liquid lost is the share of the displacement the leak passes while the valve is closed (pumping faster
  loses a smaller share). A hole in the tubing drains a fixed rate in m3/h. (v2: a fixed share of the lifted
  liquid, ``0.5 x severity``, whatever the pump does.) Parted rods as v2.
* **The field observation's ``prob_<label>``** from run 7's model (the shipped ``srenv classify`` model when v3
  was made), pinned as ``srenv/models/classifier_run7.npz``: it raises tagging on 0.7 % of v2's non-tagging
  episode cards, run 2 (v2's) on ~15 % (docs/conditions.md).

Constructor
-----------
| kwarg | default | meaning |
|---|---|---|
| ``scenario`` | ``"train"`` | ``"train"`` / ``"validation"`` / ``"test"``, ``"family:SEED"`` or a shipped well name / YAML path (as v2) |
| ``observation`` | ``"field"`` | ``"field"`` (89) or ``"privileged"`` (113), v2's names (``FIELD_OBS_NAMES`` / ``PRIVILEGED_OBS_NAMES``) |
| ``episode_hours`` | ``12.0`` (spec) | horizon in hours of well time |
| ``interval_s`` | ``300.0`` (spec) | control interval in s of well time |
| ``event_rate_scale`` | ``1.0`` | multiplies every condition's rate (as v2) |
| ``classifier`` | ``None`` | callable(trace dict) -> 12 probabilities; ``None``: run 7's model, pinned (:func:`default_classifier`) |
| ``fast_stepping`` | ``True`` | v2's stepping |
| ``render_mode`` | ``None`` | ``"rgb_array"`` or ``"human"`` |
| ``overrides`` / ``**kwargs`` | ``None`` | config overrides, as v1 |

Spaces
------
Action ``Box(-1, 1, (2,), float32)`` (average SPM, stroke); observation flat float32 ``Box(-10, 10)``, v2's.

Reward
------
USD per hour of well time, the sum of ``info["reward_*"]``: v1's terms and

| term | USD/h | meaning |
|---|---|---|
| ``reward_lost_production`` | ``-v V_lost / h`` | a leaking valve's passed share of the lifted liquid; a hole's ``min(lifted, Q_hole h)``; parted rods as v2 |
| ``reward_tagging`` | ``-workover_usd d_tag / h`` | ``d_tag`` = strokes x ``1e-6 (v_impact / 0.36 m/s)^2`` workovers |
| ``reward_workover`` | ``-workover_usd / h`` | the rod job after parted rods (as v2) |

``info["cost"]`` >= 0 sums v1's parts, ``cost_tagging`` (fraction pumped x ``v_impact / 0.36 m/s``, unitless) and
``cost_parted_rods`` (as v2).

Version history
---------------
* v3: tagging damage from the contact with the end fixed at onset, valve and tubing leaks' lost liquid from
  the leak's model, run 7's classifier pinned in the field observation. Why: in v2 no control but idling moved
  the tagging or leak costs (a shorter or slower stroke left a tagging well's cost where it was; docs/agents.md),
  and run 2's classifier raised tagging on ~15 % of non-tagging cards.
* v2 / v1 / v0: unchanged (see their modules).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..analysis.card_classifier import V3_MODEL
from ..task import events as ev
from ..task import leaks, tag_contact
from ..task import well_family as wf
from ..task.interval import IntervalResult, IntervalRunner
from . import sucker_rod_v2 as v2
from .vector import vector_entry

FIELD_OBS_NAMES = v2.FIELD_OBS_NAMES
PRIVILEGED_OBS_NAMES = v2.PRIVILEGED_OBS_NAMES
TAGGING = ("tagging_down", "tagging_up")


def default_classifier() -> v2.Classifier | None:
    """Run 7's card classifier, pinned as ``srenv/models/classifier_run7.npz`` (v2's reader of a surface model)."""
    return v2.default_classifier(V3_MODEL)


class SuckerRodV3Env(v2.SuckerRodV2Env):
    def __init__(self, scenario: str = "train", observation: str = "field", render_mode: str | None = None,
                 overrides: dict | None = None, episode_hours: float | None = None, interval_s: float | None = None,
                 event_rate_scale: float = 1.0, classifier: v2.Classifier | None = None, fast_stepping: bool = True,
                 **kwargs: Any) -> None:
        super().__init__(scenario, observation, render_mode, overrides, episode_hours, interval_s, event_rate_scale,
                         classifier or default_classifier() or v2.uniform_probabilities, fast_stepping, **kwargs)

    def _episode_spec(self, seed: int | None, rng: np.random.Generator) -> wf.WellSpec:
        spec = super()._episode_spec(seed, rng)
        self._running_condition: tuple = (None, 0.0, ())  # the condition, severity and extra overrides running
        self._onset = (0.0, 0.0)  # the setpoints (SPM, stroke m) the current condition started at
        self._hole_m3_h = 0.0
        return spec

    def _interval_runner(self) -> IntervalRunner:
        self.sim.fix_contact_ends()  # a spacing drift is a fixed position (srenv.task.tag_contact)
        return super()._interval_runner()

    def _running_setpoints(self) -> tuple[float, float]:
        """(SPM, stroke m) the coming interval runs at; an idle one keeps the last running SPM."""
        avg, stroke = self._setpoints
        spm = max(avg, self.cfg.control.spm_min) if avg > 1e-9 else self._spm
        return spm, float(self.sim.surface.stroke_length_m(stroke))

    def _before_interval(self) -> None:
        label, sev = self._schedule.active(self._elapsed() / 3600.0)
        now = self._running_setpoints()
        over = ev.condition_overrides(label, sev, self.cfg) if label in leaks.ACCOUNTED else {}
        if label != self._condition[0]:  # a new condition: its leak is fixed at these setpoints
            self._onset = now
            self._hole_m3_h = leaks.hole_rate_m3_h(over, self.cfg.pump, now)
        extra = leaks.valve_overrides(label, over, self._onset, now)
        key = (label, sev, tuple(sorted(extra.items())))
        if key != self._running_condition:
            ev.apply_condition(self.sim, self.cfg, label, sev, extra)
            self._running_condition = key
        self._condition = (label, sev)

    def _booking(self, label: str | None, sev: float, r: IntervalResult) -> tuple[ev.Booking, float]:
        """The interval's lost liquid and tagging damage from the physics (module docstring); v2's for the rest."""
        if label in leaks.VALVE_KEYS:
            return ev.Booking(lost_m3=leaks.valve_lost_m3(self.sim.cfg.pump, r.lifted_m3)), 0.0
        if label == "tubing_leak":
            return ev.Booking(lost_m3=leaks.hole_lost_m3(self._hole_m3_h, r.duration_s / 3600.0, r.lifted_m3)), 0.0
        if label in TAGGING:
            if r.strokes <= 0 or r.last is None:
                return ev.Booking(), 0.0
            speed = tag_contact.stroke_impact_m_s(r.last.trace, self.sim.contact_ends())
            damage = tag_contact.damage_per_stroke(speed) * r.strokes
            cost = r.pumping_fraction * speed / tag_contact.TAG_REFERENCE_SPEED_M_S
            return ev.Booking(tag_damage=damage, tag_strokes=r.strokes), cost
        return super()._booking(label, sev, r)


make_vec = vector_entry(SuckerRodV3Env)  # the vector entry point (srenv/envs/vector.py: N wells in threads)
