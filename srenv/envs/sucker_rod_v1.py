"""``srenv/SuckerRod-v1``: run a beam-pumped well for profit, from what a rod-pump controller measures.

A family of wells (:mod:`srenv.task.well_family`: depth, tapered rod design, pump, survey, friction, water cut,
inflow) with fixed train and test splits; the reservoir's inflow changes within an episode; one step is a
control interval of well time (default 5 min) in which the unit pumps at an average stroke rate, intermittently
below the VSD's minimum speed, down to idle; the reward is the well's profit rate in USD per hour of well time
(:mod:`srenv.task.economics`). The physical system is the exact nonsmooth FE simulator
(:class:`srenv.simulation.simulator.Simulator`) run interval by interval by :class:`srenv.task.interval.IntervalRunner`
(exact strokes + a quasi-steady fast-forward whose error is measured); this module composes them.

Constructor
-----------
| kwarg | default | meaning |
|---|---|---|
| ``scenario`` | ``"train"`` | ``"train"`` / ``"test"``: the split's wells (200 / 50); or a shipped well name / YAML path |
| ``observation`` | ``"field"`` | ``"field"`` (what a controller measures) or ``"privileged"`` (adds the hidden truth) |
| ``episode_hours`` | ``12.0`` (spec) | horizon in hours of well time (``task.episode_hours``); ``None`` keeps the config's; an override of ``task.episode_hours`` wins |
| ``interval_s`` | ``300.0`` (spec) | control interval in s of well time (``task.interval_s``); ``None`` keeps the config's; an override of ``task.interval_s`` wins |
| ``render_mode`` | ``None`` | ``"rgb_array"`` or ``"human"`` (surface and pump cards of the last stroke) |
| ``fast_stepping`` | ``False`` | ``True``: an interval at an earlier interval's setpoint reuses its converged stroke (``IntervalRunner(reuse_periodic=True)``, docs/speed.md); off keeps v1's numbers |
| ``overrides`` | ``None`` | ``{"key.path": value}`` applied to every well's config (e.g. ``economics.oil_price_usd_m3``) |
| ``**kwargs`` | | further overrides as ``section__field=value`` (e.g. ``task__interval_s=600``) |

``reset(seed=S)`` on a split draws well number ``S mod N`` of that split (so a test episode is reproduced by
its seed) and the episode's randomness (initial fluid level, inflow step) from the seeded ``np_random``;
``reset()`` without a seed draws the well from ``np_random``. ``info["well_id"]`` names the well
(``"train-017"``). The test split is for final evaluation only: :func:`srenv.task.well_family.check_split` refuses it
to tuning and training code.

Action space
------------
``Box(-1, 1, (2,), float32)``: ``a[0]`` -> average stroke rate in [0, ``control.spm_max``] (linear; -1 = idle the
whole interval). Below ``control.spm_min`` (the VSD's minimum speed) the unit runs at ``spm_min`` for the fraction
``avg / spm_min`` of the interval and stands still for the rest (intermittent pumping, the field's pump-off
practice, continuous in the action). ``a[1]`` -> stroke length in [``control.stroke_min_m``,
``control.stroke_max_m``]. Ranges are per well. Out-of-range actions are clipped; NaN raises ``ValueError``.

Observation space
-----------------
Flat float32 ``Box(-10, 10)``; names in ``FIELD_OBS_NAMES`` / ``PRIVILEGED_OBS_NAMES`` (``env.obs_names``,
:func:`obs_index`). Field (77): the last pumped stroke's surface card (load-cell load / the unit's PPRL rating on
32 positions per branch), the running SPM and average SPM (/ ``spm_max``), stroke (-1..1 over its range), duty
(fraction of the last interval pumped), idle time since the pump last ran (h), the controller's fillage
estimate read off the downhole card (``task.fillage_estimator``: :func:`srenv.task.fillage_reading.controller_fillage`), mean and peak polished-rod power (/ rating x max speed), PPRL and
MPRL (/ rating), time remaining (fraction of the horizon), the last acoustic fluid-level shot (level above the
pump / pump depth, every ``task.level_shot_interval_h``) and its age (/ horizon). Privileged (88) adds the true
annulus level, intake pressure, true fillage, current inflow (/ nominal) and the hidden well parameters.

Reward
------
USD per hour of well time, the sum of ``info["reward_*"]`` (:data:`srenv.task.economics.REWARD_TERMS`): revenue,
inventory (the value of the change in annulus liquid, so draining it earns nothing net: the horizon cannot
reward it), energy, fatigue, stick-slip, peak load, fluid pound, VSD ramp, failure. ``info["cost"]`` >= 0 is the
constraint cost (overload, compression, pound; parts in ``info["cost_*"]``).

Episode end
-----------
terminated: rod failure (Goodman above ``task.failure_goodman_pct``) or an unrecoverable step-QP failure
(``info["failure"]``; never raised from ``step``). truncated: after ``task.episode_hours`` of well time.

Version history
---------------
* v1: well family with splits, in-episode inflow changes, idle/intermittent pumping, USD/h reward with
  constraint cost, field observation. v0 (one well, stroke-per-step, unitless reward) is kept unchanged.
  Since: the opt-in ``fast_stepping`` kwarg (default off, numbers unchanged) and a native vector env
  (``gymnasium.make_vec(..., vectorization_mode="vector_entry_point")``, srenv/envs/vector.py).
  Later: ``info["condition"]`` names the pump condition (srenv.physics.conditions.LABELS); observation,
  reward and dynamics unchanged.
* v1, no change of results: the episode's well, and what happens before and after each interval, are methods
  (``_episode_spec``, ``_before_interval``, ``_after_interval``; no-ops here) that v2 overrides.
"""

from __future__ import annotations

import functools
import math
from pathlib import Path
from typing import Any, ClassVar

import gymnasium as gym
import numpy as np
from gymnasium import spaces

from ..analysis.metrics import resample_prescribed_card
from ..analysis.render import CardWindow
from ..config import ControlConfig, WellConfig, load_config
from ..errors import ConfigError, SolverFailure
from ..physics.conditions import condition_name
from ..simulation.simulator import Simulator
from ..task import well_family as wf
from ..task.economics import COST_TERMS, REWARD_TERMS, EconomicReward
from ..task.interval import IntervalResult, IntervalRunner, StrokeFigures
from .action_check import checked_action
from .env_kwargs import APPLIED_CACHE_SIZE, merged_overrides, restates

CARD_POINTS = 32
OBS_BOUND = 10.0
FIELD_TAIL = ("spm", "avg_spm", "stroke", "duty", "idle_s", "fillage_est", "power_mean", "power_peak", "pprl",
              "mprl", "time_remaining", "level_shot", "level_shot_age")
PRIVILEGED_TAIL = ("level", "intake_pressure", "fillage", "inflow", "depth", "plunger_diameter", "productivity",
                   "reservoir_pressure", "water_cut", "friction", "decline")
CARD_NAMES = tuple(f"card_up_{i:02d}" for i in range(CARD_POINTS)) + tuple(
    f"card_down_{i:02d}" for i in range(CARD_POINTS))
FIELD_OBS_NAMES = CARD_NAMES + FIELD_TAIL
PRIVILEGED_OBS_NAMES = FIELD_OBS_NAMES + PRIVILEGED_TAIL
OBSERVATIONS = ("field", "privileged")


def obs_index(name: str, observation: str = "field") -> int:
    names = FIELD_OBS_NAMES if observation == "field" else PRIVILEGED_OBS_NAMES
    return names.index(name)


def setpoints_from_action(action: np.ndarray, control: ControlConfig) -> tuple[np.ndarray, np.ndarray]:
    a = np.clip(np.asarray(action, dtype=np.float64), -1.0, 1.0)
    avg = 0.5 * (a[..., 0] + 1.0) * control.spm_max
    stroke = control.stroke_min_m + 0.5 * (a[..., 1] + 1.0) * (control.stroke_max_m - control.stroke_min_m)
    return avg, stroke


def action_from_setpoints(avg_spm: Any, stroke_m: Any, control: ControlConfig) -> np.ndarray:
    a0 = 2.0 * np.asarray(avg_spm, dtype=np.float64) / control.spm_max - 1.0
    span = control.stroke_max_m - control.stroke_min_m
    a1 = (2.0 * (np.asarray(stroke_m, dtype=np.float64) - control.stroke_min_m) / span - 1.0) if span > 0 else \
        np.zeros_like(a0)
    return np.clip(np.stack([a0, a1], axis=-1), -1.0, 1.0).astype(np.float32)


@functools.lru_cache(maxsize=512)
def _spec(split: str, index: int) -> wf.WellSpec:
    return wf.build_spec(split, index)


class SuckerRodV1Env(CardWindow, gym.Env):
    metadata: ClassVar[dict[str, Any]] = {"render_modes": ["rgb_array", "human"], "render_fps": 2}

    def __init__(self, scenario: str = "train", observation: str = "field", render_mode: str | None = None,
                 overrides: dict | None = None, episode_hours: float | None = None, interval_s: float | None = None,
                 fast_stepping: bool = False, **kwargs: Any) -> None:
        if observation not in OBSERVATIONS:
            raise ConfigError("observation", observation, "one of " + ", ".join(OBSERVATIONS))
        if render_mode is not None and render_mode not in self.metadata["render_modes"]:
            raise ConfigError("render_mode", render_mode, "one of " + ", ".join(self.metadata["render_modes"]))
        self.scenario = str(scenario)
        self.fast_stepping = bool(fast_stepping)  # IntervalRunner(reuse_periodic=...): off keeps v1's numbers
        self.observation = observation
        self.render_mode = render_mode
        self.overrides = merged_overrides(overrides, kwargs)
        # the registered spec always passes episode_hours and interval_s; an override of the same field
        # (``overrides={"task.interval_s": ...}`` or ``task__interval_s=...``) is the more specific request
        for key, value in (("task.episode_hours", episode_hours), ("task.interval_s", interval_s)):
            if value is not None:
                self.overrides.setdefault(key, value)
        self.split = self.scenario if self.scenario in wf.SPLITS else None
        self._fixed: wf.WellSpec | None = None
        self._applied: dict[str, tuple[wf.WellSpec, wf.WellSpec]] = {}
        if self.split is None:
            cfg = load_config(self.scenario, self.overrides or None)
            self._fixed = self._spec_from_config(cfg)
        else:
            self._apply(_spec(self.split, 0))  # validates the overrides once, up front
        self.obs_names = FIELD_OBS_NAMES if observation == "field" else PRIVILEGED_OBS_NAMES
        self.action_space = spaces.Box(-1.0, 1.0, (2,), np.float32)
        self.observation_space = spaces.Box(-OBS_BOUND, OBS_BOUND, (len(self.obs_names),), np.float32)
        self.well: wf.WellSpec | None = None
        self.sim: Simulator | None = None
        self._fig = None

    # ------------------------------------------------------------------------------------------ wells
    def _spec_from_config(self, cfg: WellConfig) -> wf.WellSpec:
        if cfg.inflow.model == "none":
            raise ConfigError("inflow.model", cfg.inflow.model,
                              "'linear' or 'vogel': the v1 task is about running a well against its inflow")
        if cfg.surface.motion == "pullout":
            raise ConfigError("surface.motion", cfg.surface.motion, "'harmonic' or 'conventional' for the env")
        name = Path(self.scenario).stem
        return wf.WellSpec(well_id=name, params=None, cfg=cfg, nominal_rate_m3_day=cfg.inflow.max_rate_m3_day)

    def _apply(self, spec: wf.WellSpec) -> wf.WellSpec:
        """The well with the env's overrides; the config is parsed again only when an override changes it (the
        registered episode_hours and interval_s usually restate the well's own), once per well of the split."""
        if not self.overrides or all(restates(spec.cfg, k, v) for k, v in self.overrides.items()):
            return spec
        seen = self._applied.get(spec.well_id)
        if seen is not None and seen[0] is spec:
            return seen[1]
        cfg = load_config(spec.cfg, self.overrides)
        out = wf.WellSpec(spec.well_id, spec.params, cfg, spec.nominal_rate_m3_day, spec.design)
        self._applied[spec.well_id] = (spec, out)
        while len(self._applied) > APPLIED_CACHE_SIZE:
            self._applied.pop(next(iter(self._applied)))
        return out

    def _episode_spec(self, seed: int | None, rng: np.random.Generator) -> wf.WellSpec:
        """The episode's well: number ``seed mod N`` of the split (drawn when no seed), or the fixed well."""
        if self.split is None:
            return self._fixed
        n = wf.split_size(self.split)
        index = seed % n if seed is not None else int(rng.integers(n))
        return self._split_well(int(index))

    def _split_well(self, index: int) -> wf.WellSpec:
        """Well number ``index`` of the split, with the env's overrides."""
        return self._apply(_spec(self.split, index))

    def inflow_multiplier(self, t_s: float) -> float:
        """The reservoir's deliverability relative to the well's IPR at well time t_s since the episode start."""
        days = t_s / 86400.0
        m = math.exp(-self._decline * days)
        if t_s >= self._step_time_s:
            m *= 1.0 + self._step_fraction
        return m

    # ------------------------------------------------------------------------------------------ gym API
    def reset(self, *, seed: int | None = None, options: dict | None = None) -> tuple[np.ndarray, dict]:
        super().reset(seed=seed)
        rng = self.np_random
        spec = self._episode_spec(seed, rng)
        self.well = spec
        cfg = spec.cfg
        self.cfg = cfg
        task = cfg.task
        self.horizon_s = task.episode_hours * 3600.0
        self._decline = task.inflow_decline_per_day
        if self.split is not None:
            self._step_fraction = float(rng.uniform(-0.4, 0.3)) if rng.uniform() < 0.8 else 0.0
            self._step_time_s = float(rng.uniform(0.2, 0.8)) * self.horizon_s
            static = spec.design.get("static_level_m", cfg.inflow.initial_fluid_level_m)
            level0 = float(rng.uniform(0.02, 1.0)) * static
        else:
            self._step_fraction = task.inflow_step_fraction
            self._step_time_s = 0.5 * self.horizon_s
            level0 = cfg.inflow.initial_fluid_level_m
        self.sim = Simulator(cfg, fluid_level_m=level0)  # one reset, at the episode's level
        self.runner = self._interval_runner()
        self.econ = EconomicReward(cfg.economics)
        s = cfg.surface
        self._spm = float(s.spm)
        self._avg_spm = float(s.spm)
        self._stroke = float(self.sim.surface.stroke_length_m(s.stroke_length_m))
        self._duty = 1.0
        self._idle_s = 0.0
        try:
            self._last: StrokeFigures = self.runner.warm_up(self._spm, self._stroke)
        except SolverFailure as exc:  # the configured operating point itself cannot be run
            raise SolverFailure(0, 0.0, f"{spec.well_id}: warm-up stroke failed: {exc}") from None
        self._t0 = self.sim.time_s
        self._shot_level = self.sim.annulus.level_m
        self._shot_time = 0.0
        self._result: IntervalResult | None = None
        info = self._info(None, {}, {})
        return self._observe(), info

    def _elapsed(self) -> float:
        return self.sim.time_s - self._t0

    def step(self, action: np.ndarray) -> tuple[np.ndarray, float, bool, bool, dict]:
        if self.sim is None:
            raise RuntimeError("call reset() before step()")
        action = checked_action(action, "avg SPM, stroke")
        ctl = self.cfg.control
        avg, stroke = setpoints_from_action(action, ctl)
        avg, stroke = float(avg), float(stroke)
        if ctl.spm_rate_limit > 0:
            avg = float(np.clip(avg, self._avg_spm - ctl.spm_rate_limit, self._avg_spm + ctl.spm_rate_limit))
        d_avg = avg - self._avg_spm
        self.sim.set_inflow_multiplier(self.inflow_multiplier(self._elapsed()))
        self._setpoints = (avg, stroke)  # the interval's requested setpoints (v3's conditions read them)
        self._before_interval()
        failure = None
        duration = min(self.cfg.task.interval_s, self.horizon_s - self._elapsed())
        duration = max(duration, 1e-3)
        try:
            r = self.runner.run(avg, stroke, duration)
        except SolverFailure as exc:
            failure = str(exc)
            r = IntervalResult(duration_s=duration)
        if r.last is not None:
            self._last = r.last
            self._spm, self._stroke = r.spm, r.stroke_length_m
        if failure is None and r.strokes > 0 and r.goodman_max_pct > self.cfg.task.failure_goodman_pct:
            failure = (f"rod failure: Goodman loading {r.goodman_max_pct:.1f} % > "
                       f"{self.cfg.task.failure_goodman_pct:.1f} %")
        self._avg_spm, self._duty = avg, r.pumping_fraction
        self._idle_s = 0.0 if r.pumping_s >= r.duration_s - 1e-9 else self._idle_s * (r.pumping_s <= 0) + (
            r.duration_s - r.pumping_s)
        terms = self.econ.terms(r, d_avg, failed=failure is not None)
        costs = self.econ.costs(r)
        ended = self._after_interval(r, terms, costs)
        reward = float(sum(terms.values()))
        if self._elapsed() - self._shot_time >= self.cfg.task.level_shot_interval_h * 3600.0 - 1e-6:
            self._shot_level, self._shot_time = self.sim.annulus.level_m, self._elapsed()
        self._result = r
        terminated = failure is not None or ended
        truncated = not terminated and self._elapsed() >= self.horizon_s - 1e-6
        info = self._info(r, terms, costs)
        if failure:
            info["failure"] = failure
        if self.render_mode == "human":
            self.render()
        return self._observe(), reward, terminated, truncated, info

    # hooks for later versions (v2's conditions and stepping); v1 has none
    def _interval_runner(self) -> IntervalRunner:
        """The runner of the episode's intervals on ``self.sim``."""
        return IntervalRunner(self.sim, reuse_periodic=self.fast_stepping)

    def _before_interval(self) -> None:
        """Called before each interval is run."""

    def _after_interval(self, r: IntervalResult, terms: dict, costs: dict) -> bool:
        """Called with the interval's reward terms and costs (may add to both); True ends the episode."""
        return False

    # ------------------------------------------------------------------------------------------ obs / info
    def _observe(self) -> np.ndarray:
        cfg, f = self.cfg, self._last
        ctl, econ = cfg.control, cfg.economics
        rating = econ.pprl_rating_n
        tr = f.trace
        card = resample_prescribed_card(tr["polished_rod_position_m"], tr["polished_rod_load_n"], CARD_POINTS) / rating
        span = ctl.stroke_max_m - ctl.stroke_min_m
        power_ref = rating * ctl.stroke_max_m * math.pi * ctl.spm_max / 60.0  # rating x peak harmonic speed
        depth = self.sim.mesh.x_m[-1]
        m = f.summary
        tail = [self._spm / ctl.spm_max, self._avg_spm / ctl.spm_max,
                2.0 * (self._stroke - ctl.stroke_min_m) / span - 1.0 if span > 0 else 0.0,
                self._duty, self._idle_s / 3600.0, f.fillage_est, f.power_mean_w / power_ref,
                f.power_peak_w / power_ref, m["pprl_n"] / rating, m["mprl_n"] / rating,
                max(0.0, 1.0 - self._elapsed() / self.horizon_s), self._shot_level / depth,
                (self._elapsed() - self._shot_time) / 3600.0 / self.cfg.task.episode_hours]
        if self.observation == "privileged":
            ann = self.sim.annulus
            hidden = self.well.params.hidden() if self.well.params is not None else {}
            q_now = ann.inflow_m3_s() * 86400.0
            tail += [ann.level_m / depth, ann.intake_pressure_pa() / 1e7, f.fillage,
                     q_now / max(self.well.nominal_rate_m3_day, 1e-9),
                     hidden.get("depth_m", depth) / 2500.0,
                     hidden.get("plunger_diameter_mm", cfg.pump.plunger_diameter_mm) / 63.5,
                     hidden.get("productivity", 1.0) / 3.0, cfg.inflow.reservoir_pressure_pa / 2e7,
                     cfg.economics.water_cut, cfg.friction.coefficient / 0.3, self._decline / 0.3]
        obs = np.concatenate([card, np.asarray(tail, dtype=np.float64)]).astype(np.float32)
        obs = np.nan_to_num(obs, nan=0.0, posinf=OBS_BOUND, neginf=-OBS_BOUND)
        return np.clip(obs, -OBS_BOUND, OBS_BOUND, out=obs)

    def _info(self, r: IntervalResult | None, terms: dict, costs: dict) -> dict:
        ann = self.sim.annulus
        f = self._last
        info: dict[str, Any] = {"well_id": self.well.well_id}
        info.update({k: float(terms.get(k, 0.0)) for k in REWARD_TERMS})
        info.update({k: float(costs.get(k, 0.0)) for k in COST_TERMS})
        info["cost"] = float(sum(info[k] for k in COST_TERMS))
        dur = r.duration_s if r is not None else 1.0
        lifted = r.lifted_m3 if r is not None else 0.0
        wc = self.cfg.economics.water_cut
        info.update(
            time_h=self._elapsed() / 3600.0, spm=self._spm, avg_spm=self._avg_spm, duty=self._duty,
            stroke_length_m=self._stroke, idle_s=self._idle_s,
            fillage=float(r.fillage) if r is not None and r.displaced_m3 > 0 else float(f.fillage),
            fillage_est=float(f.fillage_est),
            production_m3_day=86400.0 * lifted / dur, oil_m3_day=86400.0 * lifted * (1.0 - wc) / dur,
            inflow_m3_day=86400.0 * (r.inflow_m3 if r is not None else 0.0) / dur,
            inflow_multiplier=float(ann.rate_multiplier), fluid_level_m=float(ann.level_m),
            pprl_n=float(r.pprl_n if r is not None and r.strokes > 0 else f.summary["pprl_n"]),
            mprl_n=float(r.mprl_n if r is not None and r.strokes > 0 else f.summary["mprl_n"]),
            goodman_max_pct=float(r.goodman_max_pct if r is not None and r.strokes > 0
                                  else f.summary["goodman_max_pct"]),
            strokes=float(r.strokes if r is not None else 0.0),
            exact_strokes=int(r.exact_strokes if r is not None else 1),
            fast_forward_strokes=float(r.fast_forward_strokes if r is not None else 0.0),
            stick_slip_energy_j=float(r.stick_slip_j if r is not None else f.stick_slip_j),
            impact_speed_m_s=float(f.impact_m_s),
            condition=condition_name(self.sim.cfg, f.summary.get("card_class", "full")),
        )
        solver = r.solver if r is not None else {k: int(f.summary[k]) for k in
                                                 ("certified_steps", "corrected_steps", "qp_steps", "solver_calls")}
        info.update({k: int(v) for k, v in solver.items()})
        return info

    # ------------------------------------------------------------------------------------------ render
    def render(self) -> np.ndarray | None:
        if self.sim is None:
            return None
        from ..analysis.render import card_figure, card_rgb

        title = f"{self.well.well_id}: {self._spm:.2f} SPM, {self._stroke:.2f} m, duty {self._duty:.2f}"
        if self.render_mode == "rgb_array":
            return card_rgb(self._last.trace, title)
        if self.render_mode == "human":
            import matplotlib.pyplot as plt

            if self._fig is not None:
                plt.close(self._fig)
            plt.ion()
            self._fig = card_figure(self._last.trace, title)
            plt.pause(0.001)
        return None
