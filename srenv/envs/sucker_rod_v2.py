"""``srenv/SuckerRod-v2``: run a beam-pumped well for profit while the conditions real wells develop come and go.

v2 is the v1 task (:mod:`srenv.envs.sucker_rod_v1`: the well family, in-episode inflow changes, intermittent
pumping, the USD/h reward, the constraint cost) plus **field conditions as events within an episode**
(:mod:`srenv.task.events`: gas slugs, valve leaks that develop, a tubing leak, tagging after a spacing drift,
heavy-oil periods, flow through the pump, rods that part), a reward that prices what each does, the
classifier's label probabilities in the field observation, the true condition in the privileged one, a fixed
``validation`` split and ``family:SEED`` wells outside every split.

Constructor
-----------
| kwarg | default | meaning |
|---|---|---|
| ``scenario`` | ``"train"`` | ``"train"`` / ``"validation"`` / ``"test"`` (200 / 50 / 50 wells; validation for model selection, test for the final evaluation), ``"family:SEED"`` (well SEED of the family, outside every split; id ``family-SEED``), or a shipped well name / YAML path |
| ``observation`` | ``"field"`` | ``"field"`` or ``"privileged"`` |
| ``episode_hours`` | ``12.0`` (spec) | horizon in hours of well time (``task.episode_hours``) |
| ``interval_s`` | ``300.0`` (spec) | control interval in s of well time (``task.interval_s``) |
| ``event_rate_scale`` | ``1.0`` | multiplies every condition's rate (0: no conditions, the v1 task on v2's spaces) |
| ``classifier`` | ``None`` | callable(trace dict of the last stroke) -> 12 label probabilities in :data:`LABELS` order; ``None``: :func:`default_classifier` (run 2's model, pinned); called once per card |
| ``fast_stepping`` | ``True`` | v2's stepping (docs/speed.md): an interval reuses the stroke an earlier interval at its setpoint converged to, carried to the pump's intake pressure; ``False``: v1's stepping |
| ``render_mode`` | ``None`` | ``"rgb_array"`` or ``"human"`` |
| ``overrides`` / ``**kwargs`` | ``None`` | config overrides, as v1 |

``reset(seed=S)``: on a split, well ``S mod N`` of the split; the episode's inflow schedule and its conditions
(:func:`srenv.task.events.draw_schedule`) from the seeded ``np_random``. ``info["well_id"]`` names the well
(``"validation-004"``, ``"family-7777777"``); the ``family-`` ids cannot collide with a split's.

Conditions (rates per hour of well time while the well runs normally; severities in [0, 1] drawn per episode)
------------------------------------------------------------------------------------------------------------
| condition | rate (1/h) | severity | lasts |
|---|---|---|---|
| ``gas_interference`` (gas slug) | 0.020 | 0.2-1.0 | 0.5-3 h |
| ``heavy_oil`` (period) | 0.008 | 0.3-1.0 | 1-4 h |
| ``flowing`` (flow through the pump) | 0.004 | 0.3-1.0 | 0.5-2 h |
| ``travelling_valve_leak`` / ``standing_valve_leak`` | 0.008 / 0.006 | 0.1-0.6 | to the end, developing over 4 h |
| ``tubing_leak`` | 0.004 | 0.05-0.4 | to the end |
| ``tagging_down`` (after a spacing drift) | 0.008 | 0.2-1.0 | to the end |
| ``parted_rods`` | 1e-4 x (G / 60 %)^4 x fraction pumped | 1 | ends the episode (a workover) |

G is the interval's peak Goodman loading of the rods: how hard a controller runs them moves the parting hazard
(:class:`srenv.task.events.PartingClock`).

They change the physics at interval boundaries (``srenv.physics.conditions.condition_overrides``: the card of
each condition); the lost liquid of leaks, tagging damage and parted rods are booked by the env, since the
simulator's volume accounting does not see them (:data:`srenv.task.events.BOOKED`, see there).

Action space
------------
As v1: ``Box(-1, 1, (2,), float32)``, average stroke rate and stroke length.

Observation space
-----------------
Flat float32 ``Box(-10, 10)``; names in ``FIELD_OBS_NAMES`` / ``PRIVILEGED_OBS_NAMES``. Field (89): v1's field
observation (77: the last stroke's surface card and the controller's figures) + the classifier's probabilities
of the 12 labels for the last card (``prob_<label>``; run 2's model, pinned, via :func:`default_classifier`,
uniform 1/12 for a card it cannot read). Privileged (113): v1's privileged (88) + the 12 probabilities + the
true condition of the last interval one-hot (``true_<label>``; ``full`` / ``fluid_pound`` by the true fillage
when no event is active) + its severity.

Reward
------
USD per hour of well time, the sum of ``info["reward_*"]``: v1's terms (:data:`srenv.task.economics.REWARD_TERMS`,
revenue, inventory, energy, fatigue, stick-slip, peak load, fluid pound, ramp, failure) and

| term | USD/h | meaning |
|---|---|---|
| ``reward_lost_production`` | ``-v V_lost / h`` | liquid a leak (valves, tubing) or parted rods lose; it falls back to the annulus |
| ``reward_tagging`` | ``-workover_usd d_tag / h`` | tagging damage, ``d_tag`` = 1e-6 workovers per stroke x severity |
| ``reward_workover`` | ``-workover_usd / h`` | the rod job after parted rods (the interval they part in) |

with ``v`` the net value of a m3 of liquid and ``h`` the interval in hours; pounding damage is v1's
``reward_pound`` (continuous in the impact speed). ``info["cost"]`` >= 0 sums v1's parts and
``cost_tagging`` (severity x fraction of the interval pumped) and ``cost_parted_rods`` (1 in the interval they
part). ``info["condition"]`` and ``info["condition_severity"]`` name the interval's true condition.

Episode end
-----------
terminated: parted rods, a rod failure or an unrecoverable step-QP failure (as v1). truncated: the horizon.

Version history
---------------
* v2: conditions as events with their costs, classifier probabilities and the true condition in the
  observations, the validation split and ``family:`` wells; the native vector env (srenv/envs/vector.py: N wells in threads,
  equal to N single envs); the speed branch's stepping (``fast_stepping=True`` by default: converged strokes
  reused across intervals and carried to the intake pressure; its error against every stroke in
  docs/speed.md; its fast-forward draws a stroke's liquid at the upstroke's end as an exact stroke does).
  Fixed before release: a condition switched on mid-episode now acts in the exact
  strokes (``Simulator.switch_config`` starts the chamber's spring state: a gas slug's transfer had stayed rigid
  while only the bookkeeping counted the gas), the fast-forward draws what the gas leaves of the displacement,
  and a condition no longer touches the well's annulus (the card set's full column stays out of episodes).
  Added before release: the realism branch's physics per well (:func:`physics_overrides`: a conventional /
  Mark II / air-balanced unit drawn per well and scaled to its unit stroke, its crank following the stroke
  action; Kelvin-Voigt damping with zeta_1 = 0.08 on every well's fundamental). Planned before release: the
  conditions branch's physics of every condition and its classifier.
* v1 / v0: unchanged (see their modules).
* v3 (:mod:`srenv.envs.sucker_rod_v3`): the leaks' volumes and the tagging damage from the physics, run 7's
  classifier; v2 keeps every number.
"""

from __future__ import annotations

import functools
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
from gymnasium import spaces

from ..config import apply_overrides, config_from_dict
from ..task import events as ev
from ..task import v2_physics
from ..task import well_family as wf
from ..task.interval import IntervalResult, IntervalRunner
from .env_kwargs import restates
from .sucker_rod_v1 import FIELD_OBS_NAMES as V1_FIELD
from .sucker_rod_v1 import OBS_BOUND, SuckerRodV1Env
from .sucker_rod_v1 import PRIVILEGED_OBS_NAMES as V1_PRIVILEGED

LABELS = ev.LABELS
PROB_NAMES = tuple(f"prob_{k}" for k in LABELS)
TRUE_NAMES = tuple(f"true_{k}" for k in LABELS) + ("true_severity",)
FIELD_OBS_NAMES = V1_FIELD + PROB_NAMES
PRIVILEGED_OBS_NAMES = V1_PRIVILEGED + PROB_NAMES + TRUE_NAMES
V2_REWARD_TERMS = ("reward_lost_production", "reward_tagging", "reward_workover")
V2_COST_TERMS = ("cost_tagging", "cost_parted_rods")
Classifier = Callable[[dict], np.ndarray]


@functools.lru_cache(maxsize=4)
def default_classifier(model: Path | None = None) -> Classifier | None:
    """The card classifier v2 was released with (:mod:`srenv.analysis.card_classifier`, run 2's model, pinned
    as ``srenv/models/classifier_run2.npz`` so v2 keeps its numbers when ``srenv classify`` ships a newer one;
    trained on simulated cards only) as a callable: the last stroke's trace -> 12 probabilities in :data:`LABELS` order;
    a card it cannot read gives the uniform vector. ``None`` (the uniform vector) when no model is shipped.
    ``model``: another surface model file (no config) read the same way (scripts/episode_card_confusion.py)."""
    from ..analysis.card_classifier import V2_MODEL, CardClassifier
    from ..analysis.card_shape import BadCard, features

    model = model or V2_MODEL
    if not model.is_file():
        return None
    clf = CardClassifier.load(model)
    order = [clf.labels.index(k) for k in LABELS]

    def classify(trace: dict) -> np.ndarray:
        try:
            f = features(trace["polished_rod_position_m"], trace["polished_rod_load_n"])
        except BadCard:
            return uniform_probabilities(trace)
        return np.asarray(clf.proba_features(f[None, :])[0], np.float64)[order]

    return classify


def physics_overrides(spec: wf.WellSpec) -> dict[str, Any]:
    """v2's per-well physics on top of the family's config, the one place the realism branch's features are
    switched on for v2 (:mod:`srenv.task.v2_physics`, dotted keys so the family's other damping fields stay):

    * ``surface.motion: beam_unit``: a conventional / Mark II / air-balanced unit (60 / 25 / 15 %) drawn from
      the well's own seed and scaled so its longest stroke is the well's ``unit_stroke_m``; its crank radius
      follows the stroke action (``crank_follows_stroke``), the VSD sets the SPM as before; counterbalance and
      gearbox rating at the installed point. Why: real wells are driven by a four-bar linkage, not a cosine
      (PPRL +2-3 %, asymmetric up/down stroke, a gearbox that limits speeding up; docs/surface_unit.md).
    * ``damping.stiffness_proportional_s`` = 2 x 0.08 / omega_1: Kelvin-Voigt damping, the same ratio zeta_1 =
      0.08 on every well's fundamental (modes k: (2k - 1) x 0.08). Why: real strings damp their high modes
      (docs/realism.md); a fixed tau = 0.03 s would give a 600-m well zeta_1 = 0.2 (over-damped) and a 2.5-km
      one 0.05 (docs/task.md, "v2's per-well physics")."""
    return v2_physics.overrides(spec)


def uniform_probabilities(_: dict) -> np.ndarray:
    """The classifier of no model: 1/12 for every label."""
    return np.full(len(LABELS), 1.0 / len(LABELS))


class SuckerRodV2Env(SuckerRodV1Env):
    def __init__(self, scenario: str = "train", observation: str = "field", render_mode: str | None = None,
                 overrides: dict | None = None, episode_hours: float | None = None, interval_s: float | None = None,
                 event_rate_scale: float = 1.0, classifier: Classifier | None = None, fast_stepping: bool = True,
                 **kwargs: Any) -> None:
        scenario = str(scenario)
        family = scenario.startswith("family:")
        v2_only = family or scenario == "validation"
        rate = float(event_rate_scale)
        if not 0.0 <= rate <= 1e3:
            raise ValueError(f"event_rate_scale = {event_rate_scale!r}: expected a number in [0, 1000]")
        super().__init__("train" if v2_only else scenario, observation, render_mode, overrides, episode_hours,
                         interval_s, fast_stepping, **kwargs)
        self.scenario = scenario
        if family:
            text = scenario.partition(":")[2]
            if not text.isdigit():
                raise ValueError(f"scenario = {scenario!r}: expected family:SEED with SEED a non-negative integer")
            self._fixed = self._apply(wf.family_spec(int(text)))
            self.split = "family"
        elif scenario == "validation":
            self.split = "validation"
        self.event_rate_scale = rate
        self.classifier = classifier or default_classifier() or uniform_probabilities
        self._probs: tuple[Any, np.ndarray] = (None, np.zeros(0))  # (the stroke classified, its probabilities)
        self.obs_names = FIELD_OBS_NAMES if observation == "field" else PRIVILEGED_OBS_NAMES
        self.observation_space = spaces.Box(-OBS_BOUND, OBS_BOUND, (len(self.obs_names),), np.float32)

    # ------------------------------------------------------------------------------------------ episode
    def _episode_spec(self, seed: int | None, rng: np.random.Generator) -> wf.WellSpec:
        spec = self._fixed if self.split == "family" else super()._episode_spec(seed, rng)
        spec = self._with_physics(spec)
        # the conditions from their own stream, seeded by the episode's: v1's draws keep their meaning
        erng = np.random.default_rng(int(rng.integers(2**63)))
        self._schedule = ev.draw_schedule(erng, spec.cfg.task.episode_hours, self.event_rate_scale)
        self._parting = ev.PartingClock.draw(erng)
        self._condition: tuple[str | None, float] = (None, 0.0)
        self._true = ("full", 0.0)
        return spec

    def _interval_runner(self) -> IntervalRunner:
        # fast stepping (the default): earlier intervals' strokes reused, carried to the intake pressure
        return IntervalRunner(self.sim, reuse_periodic=self.fast_stepping, carry=self.fast_stepping, draw_at_top=True)

    def _physics_cache(self) -> dict[str, wf.WellSpec]:
        """Each well with v2's physics, by name, built once (filled by :meth:`_split_well` and
        :meth:`_with_physics`; made on first use)."""
        return self.__dict__.setdefault("_physics_specs", {})

    def _split_well(self, index: int) -> wf.WellSpec:
        """A split's well with v2's per-well physics. Not seen before and with overrides that only restate task
        fields (the registered ``episode_hours`` and ``interval_s``: the physics never touches the task section),
        its config is parsed once, the physics applied to the family's mapping (v1's way parses the family's
        config, then that config with the physics: the same config, tests/srenv/envs/test_v2_one_parse.py)."""
        cache = self._physics_cache()
        well_id = wf.well_name(self.split, index)
        if well_id in cache:
            return cache[well_id]
        if not all(k.startswith("task.") for k in self.overrides):
            return super()._split_well(index)
        pre = wf.build_spec(self.split, index, parse=False)
        over = v2_physics.yield_to(physics_overrides(pre), self.overrides)
        cfg = config_from_dict(apply_overrides(pre.raw, over, owned=True))  # pre is this call's own
        if not all(restates(cfg, k, v) for k, v in self.overrides.items()):
            return super()._split_well(index)  # the env's overrides change the well: v1's way applies them first
        cache[well_id] = wf.WellSpec(well_id, pre.params, cfg, pre.nominal_rate_m3_day, pre.design)
        return cache[well_id]

    def _with_physics(self, spec: wf.WellSpec) -> wf.WellSpec:
        """The well with v2's per-well physics (the caller's overrides win), built once per well: a well's unit
        and damping are its own, the same in every episode."""
        cache = self._physics_cache()
        if spec.well_id not in cache:
            over = v2_physics.yield_to(physics_overrides(spec), self.overrides)
            if over:
                from ..config import load_config

                spec = wf.WellSpec(spec.well_id, spec.params, load_config(spec.cfg, over), spec.nominal_rate_m3_day,
                                   spec.design)
            cache[spec.well_id] = spec
        return cache[spec.well_id]

    def _before_interval(self) -> None:
        label, sev = self._schedule.active(self._elapsed() / 3600.0)
        if (label, sev) != self._condition:
            ev.apply_condition(self.sim, self.cfg, label, sev)
            self._condition = (label, sev)

    def _after_interval(self, r: IntervalResult, terms: dict, costs: dict) -> bool:
        label, sev = self._condition
        if label != "parted_rods" and self._parting.advance(r.duration_s / 3600.0, r.pumping_fraction,
                                                            r.goodman_max_pct, self.event_rate_scale):
            label, sev = "parted_rods", 1.0  # they part at the end of this interval: its liquid was lifted
            self._condition = (label, sev)
            b, tag_cost = ev.Booking(), 0.0
        else:
            b, tag_cost = self._booking(label, sev, r)
        if b.lost_m3 > 0:
            self.sim.return_liquid(b.lost_m3)  # the lost liquid falls back: it can be pumped again
        hours = r.duration_s / 3600.0
        workover = self.cfg.economics.workover_usd
        parted = label == "parted_rods"
        terms["reward_lost_production"] = -self.econ.net_value_usd_m3 * b.lost_m3 / hours
        terms["reward_tagging"] = -workover * b.tag_damage / hours
        terms["reward_workover"] = -workover / hours if parted else 0.0
        costs["cost_tagging"] = tag_cost
        costs["cost_parted_rods"] = 1.0 if parted else 0.0
        fill = r.fillage if r.displaced_m3 > 0 else self._last.fillage
        self._true = (ev.true_label(label, fill), sev)
        return parted

    def _booking(self, label: str | None, sev: float, r: IntervalResult) -> tuple[ev.Booking, float]:
        """What the env books for the interval's condition (:func:`srenv.task.events.bookkeeping`: v2's fixed
        shares) and the interval's ``cost_tagging`` (severity x fraction pumped); v3 books from the physics."""
        tagging = label in ("tagging_down", "tagging_up")
        return ev.bookkeeping(label, sev, r.lifted_m3, r.strokes), (sev * r.pumping_fraction if tagging else 0.0)

    # ------------------------------------------------------------------------------------------ obs / info
    def _observe(self) -> np.ndarray:
        base = super()._observe()
        parts = [base, self._card_probabilities().astype(np.float32)]
        if self.observation == "privileged":
            onehot = np.zeros(len(LABELS) + 1, np.float32)
            onehot[LABELS.index(self._true[0])] = 1.0
            onehot[-1] = self._true[1]
            parts.append(onehot)
        return np.clip(np.concatenate(parts), -OBS_BOUND, OBS_BOUND).astype(np.float32)

    def _card_probabilities(self) -> np.ndarray:
        """The classifier's probabilities for the last stroke's card; an interval that reused a stroke (fast
        stepping) shows the same card (trace), so its probabilities are not computed again."""
        if self._probs[0] is not self._last.trace:
            probs = np.asarray(self.classifier(self._last.trace), dtype=np.float64).reshape(-1)
            if probs.shape != (len(LABELS),) or not np.all(np.isfinite(probs)):
                raise ValueError(f"classifier returned {probs.shape} values: expected {len(LABELS)} finite "
                                 "probabilities")
            self._probs = (self._last.trace, probs)
        return self._probs[1]

    def _info(self, r: IntervalResult | None, terms: dict, costs: dict) -> dict:
        info = super()._info(r, terms, costs)
        info.update({k: float(terms.get(k, 0.0)) for k in V2_REWARD_TERMS})
        info.update({k: float(costs.get(k, 0.0)) for k in V2_COST_TERMS})
        info["cost"] += sum(info[k] for k in V2_COST_TERMS)
        info["condition"], info["condition_severity"] = self._true[0], float(self._true[1])
        return info
