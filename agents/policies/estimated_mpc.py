"""``estimated_mpc``: the causal oracle's planner on a model a field controller could have (issue 24).

:class:`agents.policies.causal_oracle.CausalOraclePolicy` plans on a deep copy of the TRUE env: the hidden well,
its annulus level, the reservoir's deliverability and the active condition. This policy plays the same planner
(candidates around the last action, idle, anchors, the tuned field baselines closed loop; ``horizon`` intervals,
replan every ``replan_every``) on a **twin**: a v2 env of the *training* well whose first field card is nearest
the episode's first card (:class:`WellLibrary`, shipped as data in ``agents/policies/estimated_mpc_library.npz``, built from
training wells 16..199 by ``scripts/estimated_mpc_library.py``; wells 0..15 - the tuning and validation wells -
are left out so validation measures the estimator on wells it has not seen). The twin runs without conditions
(``event_rate_scale`` 0) at the reservoir's nominal deliverability (multiplier 1), and is stepped with every action
played. Its annulus level is the only state it is corrected on, from the field observation alone:

* at the first card and at every new acoustic shot, the level is the shot's (``level_shot``: level / pump depth,
  times the twin's pump depth);
* a pumped-off card on the real well (``fillage_est`` < ``POUNDED``) while the twin is full empties the twin's
  annulus; a full card while the twin pounds lifts it to ``REFILL`` of its depth (the pump is submerged again).

Options (issue 24, helper s24; off by default, which is m24's policy): ``observer`` - the twin's level is instead
:class:`agents.policies.level_observer.LevelObserver`'s (an inflow balance on the twin's IPR and pump
displacement times the real card's fillage, its deliverability estimated from successive shots, corrected at
shots and pounding cards), the twin's deliverability the observer's (from each shot on: the plans made at a shot
draw at its new estimate), ``observer_gain`` the weight of each shot's deliverability estimate (default 0.5;
helper t24c); ``condition_prob`` - the twin carries the
classifier's most probable non-normal label above that probability at a mid severity (``condition_estimate``).
Option ``twin`` (issue 24, helper t24b): ``library`` (default: the nearest training well, as above) or
``described`` - the twin is the played well as its operator's file describes it
(:mod:`srenv.task.well_file`: its equipment, the family's nominal reservoir, friction and damping;
:mod:`agents.policies.described_twin`), the file handed over at ``reset`` by ``well_file(env)``. Guard option
``pound_prob``: the classifier's ``prob_fluid_pound`` at or above it also hands the interval to the fallback.

What it reads of the env: the observation names and the task's clock (``horizon_s``, ``cfg.task.interval_s``) at
``reset`` (and, with ``twin: described``, the operator's file); nothing else of the well, its annulus, the reservoir or the condition (tests/agents/test_estimated_mpc.py
swaps them out after ``reset`` and shows the same actions). The field baselines it weighs are reset on a view that
holds the twin's control range and the installed point read off the first observation.
"""

from __future__ import annotations

import copy
import math
from collections.abc import Sequence
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import numpy as np

from srenv.task.events import NORMAL

from .alarms import make_field_controller
from .causal_oracle import CausalOraclePolicy, freeze_future
from .described_twin import DescribedTwinEnv, check_twin
from .field import make_field_baseline, obs_names_of
from .level_observer import PROD_GAIN, LevelObserver, check_gain, condition_estimate

LIBRARY = Path(__file__).resolve().parent / "estimated_mpc_library.npz"  # data beside the code: not a trained model
SCALARS = ("spm", "pprl", "mprl", "power_mean", "power_peak", "fillage_est", "level_shot")
POUNDED, FULL, REFILL = 0.9, 0.98, 0.1
FLOOR_M = 1.0  # observer: a full card means liquid above the intake - no more (0.02 x depth, ~18 m, sent a twin
#               whose real level was 0.2 m pumping into a pound: validation 20006, 30.6 against 89.2 USD/h)


def feature_names(obs_names: Sequence[str]) -> list[str]:
    """The matched features: the 64 card loads and :data:`SCALARS` (all in the field observation)."""
    return [n for n in obs_names if n.startswith("card_")] + list(SCALARS)


class WellLibrary:
    """Training wells by the features of their first card: ``nearest(obs)`` -> a training-well index. The card's
    64 points and the 7 scalars weigh the same in total (each card point by sqrt(7/64)), on standardised
    features."""

    def __init__(self, wells: np.ndarray, features: np.ndarray, names: Sequence[str]) -> None:
        self.wells = np.asarray(wells, np.int64)
        self.names = [str(n) for n in names]
        x = np.asarray(features, np.float64)
        if x.ndim != 2 or x.shape != (len(self.wells), len(self.names)) or not np.all(np.isfinite(x)):
            raise ValueError(f"well library: features {x.shape}: expected ({len(self.wells)}, {len(self.names)}) "
                             "finite numbers")
        self.mean, self.scale = x.mean(0), np.maximum(x.std(0), 1e-6)
        n_card = sum(n.startswith("card_") for n in self.names)
        self.weight = np.array([math.sqrt(len(SCALARS) / max(n_card, 1)) if n.startswith("card_") else 1.0
                                for n in self.names])
        self._z = self._standard(x)

    def _standard(self, x: np.ndarray) -> np.ndarray:
        return (x - self.mean) / self.scale * self.weight

    @classmethod
    def load(cls, path: str | Path = LIBRARY) -> WellLibrary:
        try:
            with np.load(Path(path), allow_pickle=False) as d:  # data, never pickle
                return cls(d["wells"], d["features"], d["names"])
        except (OSError, KeyError, ValueError) as exc:
            raise ValueError(f"estimated_mpc library = {str(path)!r}: expected an .npz of wells, features and names "
                             f"(scripts/estimated_mpc_library.py): {str(exc).splitlines()[0]}") from None

    def nearest(self, obs: np.ndarray, obs_names: Sequence[str]) -> int:
        idx = [list(obs_names).index(n) for n in self.names]
        z = self._standard(np.asarray(obs, np.float64)[idx])
        return int(self.wells[int(np.argmin(np.sum((self._z - z) ** 2, axis=1)))])


def _installed_view(cfg: Any, a0: np.ndarray, names: Sequence[str]) -> Any:
    """What a field baseline's ``reset(env)`` reads (the installed point, the control range, the interval),
    from the twin's config and the installed point of the first observation, not from the real env."""
    from srenv.envs.sucker_rod_v1 import setpoints_from_action

    spm, stroke = setpoints_from_action(a0, cfg.control)
    view = SimpleNamespace(surface=SimpleNamespace(spm=float(spm), stroke_length_m=float(stroke)),
                           control=cfg.control, task=cfg.task)
    return SimpleNamespace(unwrapped=SimpleNamespace(cfg=view, obs_names=tuple(names)))


class EstimatedMPCPolicy(CausalOraclePolicy):
    name = "estimated_mpc"

    def __init__(self, horizon: int = 6, replan_every: int = 3, steps: Sequence[float] = (0.3, 0.1),
                 anchors: Sequence[Sequence[float]] = (), policies: Sequence[Sequence[Any]] = (),
                 library: str | None = None, guard: dict[str, Any] | None = None, observer: bool = False,
                 condition_prob: float | None = None, twin: str = "library", observer_gain: float | None = None) -> None:
        if not (isinstance(horizon, int) and not isinstance(horizon, bool) and 1 <= horizon <= 144):
            raise ValueError(f"estimated_mpc horizon = {horizon!r}: expected an integer in [1, 144] intervals")
        super().__init__(horizon=horizon, replan_every=replan_every, steps=steps, anchors=anchors, policies=policies)
        self.library_path = library
        self.library = WellLibrary.load(library or LIBRARY)
        self.guard = check_guard(guard)
        if observer is not True and observer is not False:
            raise ValueError(f"estimated_mpc observer = {observer!r}: expected true or false")
        if condition_prob is not None and (isinstance(condition_prob, bool) or not isinstance(condition_prob, (int, float))
                                           or not 0.0 < condition_prob < 1.0):
            raise ValueError(f"estimated_mpc condition_prob = {condition_prob!r}: expected None or a number in (0, 1)")
        self.observer, self.condition_prob = observer, condition_prob
        if observer_gain is not None and not observer:
            raise ValueError(f"estimated_mpc observer_gain = {observer_gain!r}: expected None without observer: true")
        self.observer_gain = None if observer_gain is None else check_gain(observer_gain, "estimated_mpc observer_gain")
        self.twin = check_twin(twin)
        self._file: dict[str, Any] | None = None
        self._obs_level: LevelObserver | None = None
        self._twin: Any = None
        self._fallback: list[Any] | None = None

    def reset(self, env: Any, index: int | None = None) -> None:
        if index not in (None, 0):
            raise ValueError("EstimatedMPCPolicy drives one env (index 0), not a batch")
        u = env.unwrapped
        self._names = obs_names_of(env)
        self._clock = (float(u.horizon_s) / 3600.0, float(u.cfg.task.interval_s))  # the task's, not the well's
        self._env = self._twin = None
        self._plan, self._k, self._since, self._follow, self._live = None, 0, 0, None, {}
        self.planned_reward, self.plan_source, self.sim_steps = math.nan, "", 0
        self.model_well = -1
        self.guarded_intervals = 0
        self._fallback = None
        self._shot_age = math.inf
        self._obs_level, self._pumped = None, None
        if self.twin == "described":  # the operator's file of the played well: the one thing read of it
            from srenv.task.well_file import well_file

            self._file = well_file(env)

    def _start(self, obs: np.ndarray) -> None:
        """At the first observation: the twin (the nearest training well, or the described well), at the observed
        level."""
        from srenv.envs.sucker_rod_v2 import SuckerRodV2Env

        hours, interval = self._clock
        if self.twin == "described":
            twin = DescribedTwinEnv(self._file, hours, interval)
            twin.reset(seed=0)
        else:
            self.model_well = self.library.nearest(obs, self._names)
            twin = SuckerRodV2Env(scenario="train", event_rate_scale=0.0, episode_hours=hours, interval_s=interval)
            twin.reset(seed=self.model_well)
        twin.inflow_multiplier = lambda t_s: 1.0  # the reservoir as designed: its draw is unknown
        self._twin = self._env = twin
        if self.observer:  # the twin's annulus and IPR are the observer's model; its level and draw the estimate's
            ann, depth = twin.sim.annulus, float(twin.sim.mesh.x_m[-1])
            self._obs_level = LevelObserver(ann.area_m2, ann.pump_md_m, ann.nominal_inflow_m3_s,
                                            float(obs[self._names.index("level_shot")]) * depth,
                                            floor_m=FLOOR_M, gain=self.observer_gain or PROD_GAIN)
            twin.inflow_multiplier = lambda t_s: self._obs_level.prod
        i = self._names.index
        self._last = np.clip(np.array([2.0 * obs[i("avg_spm")] - 1.0, obs[i("stroke")]], np.float32), -1, 1)
        view = _installed_view(twin.cfg, self._last, self._names)
        for name, params in self.policies:
            pol = make_field_baseline(name, params, self._names)
            if hasattr(pol, "reset"):
                pol.reset(view)
            self._live[name] = [pol, None, True]
        if self.guard is not None:
            pol = make_field_controller(*self.guard["fallback"], self._names)  # alarm_pump_off or a field one
            if hasattr(pol, "reset"):
                pol.reset(view)
            self._fallback = [pol, None, True]

    def _set_level(self, level_m: float) -> None:
        """The twin's annulus to ``level_m`` through its own methods: liquid given back or drawn, no time passing."""
        ann = self._twin.sim.annulus
        dv = ann.area_m2 * (float(np.clip(level_m, 0.0, ann.pump_md_m)) - ann.level_m)
        if dv > 0:
            ann.give_back(dv)
        elif dv < 0:
            ann.draw(-dv, ann.last_time_s)

    def _correct(self, obs: np.ndarray) -> None:
        """The twin's annulus from what the field shows (module doc)."""
        if self.condition_prob is not None:
            self._set_condition(*condition_estimate(obs, self._names, self.condition_prob))
        if self._obs_level is not None:
            return self._observe(obs)
        i = self._names.index
        depth = float(self._twin.sim.mesh.x_m[-1])
        age = float(obs[i("level_shot_age")])
        if age < self._shot_age:  # a new shot (or the first card)
            self._set_level(float(obs[i("level_shot")]) * depth)
        self._shot_age = age
        real, model = float(obs[i("fillage_est")]), float(self._twin._last.fillage_est)
        if real < POUNDED <= model:
            self._set_level(0.0)
        elif real >= FULL > model:
            self._set_level(max(self._twin.sim.annulus.level_m, REFILL * depth))

    def _observe(self, obs: np.ndarray) -> None:
        """The level observer (agents/policies/level_observer.py) over the last interval, then the twin set to it."""
        i, ob = self._names.index, self._obs_level
        if self._pumped is not None:  # the twin's pump displacement for the action played x the real card's fillage
            dt, displaced = self._pumped
            ob.advance(dt, displaced * float(np.clip(obs[i("fillage_est")], 0.0, 1.0)))
        age = float(obs[i("level_shot_age")])
        if age < self._shot_age:
            ob.shot(float(obs[i("level_shot")]) * float(self._twin.sim.mesh.x_m[-1]))
            self._twin.sim.set_inflow_multiplier(ob.prod)  # the plans from this shot on draw at the new estimate
        elif self._pumped is not None and obs[i("duty")] > 0:  # a card of this interval (pumping came first)
            ob.card(float(obs[i("fillage_est")]), (1.0 - float(obs[i("duty")])) * self._pumped[0], POUNDED, FULL)
        self._shot_age = age
        self._set_level(ob.level_m)

    def _set_condition(self, label: str | None, severity: float) -> None:
        """The twin on the estimated condition's physics (persisting in its plans: freeze_future)."""
        from srenv.task.events import Event, Schedule

        if (label, severity) != self._twin._condition:
            self._twin._schedule = Schedule([Event(label, 0.0, math.inf, severity)] if label is not None else [])
            self._twin._before_interval()

    def _alarmed(self, obs: np.ndarray) -> bool:
        """The guard (:func:`check_guard`) on the real card: pounding (the fillage estimate, or the classifier's
        ``prob_fluid_pound`` with ``pound_prob``), near overload, or an abnormal condition."""
        g, i = self.guard, self._names.index
        probs = [obs[i(n)] for n in self._names if n.startswith("prob_") and n[5:] not in NORMAL]
        pound = g.get("pound_prob") is not None and obs[i("prob_fluid_pound")] >= g["pound_prob"]
        return bool(obs[i("fillage_est")] < g["pound_below"] or obs[i("pprl")] > g["load_above"]
                    or (probs and max(probs) > g["condition_prob"]) or pound)

    def _model(self) -> Any:
        return freeze_future(copy.deepcopy(self._twin))

    def predict(self, observation: Any, state: Any = None, episode_start: Any = None,
                deterministic: bool = True) -> tuple[np.ndarray, Any]:
        obs = np.asarray(observation, np.float64)
        if obs.ndim != 1 and obs.shape[0] != 1:
            raise RuntimeError("EstimatedMPCPolicy: one env only")
        row = obs.reshape(-1)
        self.track(row)
        action, state = super().predict(observation, state, episode_start, deterministic)
        if self._fallback is not None:  # the fallback runs all episode on the real observations (its state)
            fb = self._fallback
            a_fb, fb[1] = fb[0].predict(row, state=fb[1], episode_start=np.array([fb[2]]))
            fb[2] = False
            if self._alarmed(row):
                action = np.asarray(a_fb, np.float32).reshape(np.shape(action))
                self.guarded_intervals += 1
        self.played(action)
        return action, state

    def track(self, row: np.ndarray) -> None:
        """The state estimate at a new observation (the twin started at the first): what ``predict`` plans on;
        scripts/level_observer_pilot.py calls it (and :meth:`played`) to measure the estimate without planning."""
        if self._twin is None:
            self._start(row)
        self._correct(row)

    def played(self, action: Any) -> None:
        """The twin stepped with the action played; its pump displacement kept for the observer."""
        self._twin.step(np.asarray(action, np.float32).reshape(2))
        r = self._twin._result
        self._pumped = (float(r.duration_s), float(r.displaced_m3))
        self.sim_steps += 1

    def params(self) -> dict[str, Any]:
        return {**super().params(), **({"library": self.library_path} if self.library_path else {}),
                **({"guard": self.guard} if self.guard is not None else {}),
                **({"observer": True} if self.observer else {}),
                **({"observer_gain": self.observer_gain} if self.observer_gain is not None else {}),
                **({"condition_prob": self.condition_prob} if self.condition_prob is not None else {}),
                **({"twin": self.twin} if self.twin != "library" else {})}


GUARD_KEYS = ("fallback", "pound_below", "load_above", "condition_prob")
POUND_PROB = "pound_prob"  # optional (t24b): absent, the guard is m24's bit for bit


def check_guard(guard: Any) -> dict[str, Any] | None:
    """``guard``: None, or ``{fallback: [field baseline, params], pound_below, load_above, condition_prob}`` and
    optionally ``pound_prob``: on an interval whose real card pounds (``fillage_est`` < pound_below, or
    ``prob_fluid_pound`` >= pound_prob), nears overload (``pprl`` > load_above) or shows a condition (a classifier
    probability of a label other than full / fluid_pound > condition_prob), the fallback's action is played - where
    the twin, which has no conditions and an estimated level and well, is least to be trusted."""
    if guard is None:
        return None
    if not isinstance(guard, dict) or set(guard) - {POUND_PROB} != set(GUARD_KEYS):
        raise ValueError(f"estimated_mpc guard = {guard!r}: expected None or a mapping of exactly {list(GUARD_KEYS)} "
                         f"(and optionally {POUND_PROB})")
    fb = guard["fallback"]
    if not (isinstance(fb, (list, tuple)) and len(fb) == 2 and isinstance(fb[0], str) and isinstance(fb[1], dict)):
        raise ValueError(f"estimated_mpc guard.fallback = {fb!r}: expected [field baseline name, params]")
    for k in GUARD_KEYS[1:]:
        v = guard[k]
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not 0.0 <= v <= 1.5:
            raise ValueError(f"estimated_mpc guard.{k} = {v!r}: expected a number in [0, 1.5]")
    out = {"fallback": [fb[0], dict(fb[1])], **{k: float(guard[k]) for k in GUARD_KEYS[1:]}}
    if POUND_PROB in guard:
        v = guard[POUND_PROB]
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not 0.0 < v <= 1.0:
            raise ValueError(f"estimated_mpc guard.{POUND_PROB} = {v!r}: expected a number in (0, 1]")
        out[POUND_PROB] = float(v)
    return out
