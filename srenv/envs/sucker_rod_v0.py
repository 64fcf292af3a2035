"""``srenv/SuckerRod-v0``: choose the stroke rate and length of a beam-pumped well, stroke by stroke.

The physical system is :class:`srenv.simulation.simulator.Simulator` (exact nonsmooth FE rod string, valve law,
friction, inflow and fillage); the reward and the rod-failure monitor live in :mod:`srenv.task.reward`; the
cards are drawn by :mod:`srenv.analysis.render`. This module only composes them.

Constructor
-----------
| kwarg | default | meaning |
|---|---|---|
| ``config`` | ``"default"`` | well YAML path, shipped name (``configs/wells``) or a ``WellConfig`` |
| ``overrides`` | ``None`` | ``{"key.path": value}`` applied to the config |
| ``render_mode`` | ``None`` | ``"rgb_array"`` (card image) or ``"human"`` (matplotlib window) |
| ``card_points`` | ``32`` | points per card branch in the observation |
| ``**kwargs`` | | further overrides, ``section__field=value`` (e.g. ``control__spm_max=8``) |

Action space
------------
``Box(-1, 1, (2,), float32)``: ``a[0]`` → SPM linearly in [``control.spm_min``, ``control.spm_max``],
``a[1]`` → stroke length in [``control.stroke_min_m``, ``control.stroke_max_m``]. Out-of-range actions are
clipped to [-1, 1]; a NaN or infinite action raises ``ValueError``. With ``control.spm_rate_limit`` > 0 the
SPM moves at most that much per step. A conventional beam unit fixes the stroke by its crank hole
(``a[1]`` then has no effect).

Observation space
-----------------
``Box(-10, 10, (2 * card_points + 8,), float32)`` (values clipped into the box):

| index | value |
|---|---|
| ``0 : P`` | last stroke's surface card, up branch: load / ``reward.pprl_rating_n`` on a normalised position grid |
| ``P : 2P`` | the down branch, same grid |
| ``2P`` | SPM, mapped to [-1, 1] over the control range |
| ``2P+1`` | stroke length, mapped to [-1, 1] |
| ``2P+2`` | annulus liquid level above the pump / 100 m |
| ``2P+3`` | pump intake pressure / 10 MPa |
| ``2P+4`` | pump fillage of the last stroke (0..1) |
| ``2P+5`` | PPRL / ``pprl_rating_n`` |
| ``2P+6`` | max Goodman loading / 100 % |
| ``2P+7`` | stick-slip index / 10 |

``FILLAGE_INDEX`` (module constant function :func:`obs_index`) gives positions by name.

Reward
------
See :mod:`srenv.task.reward`: ``reward_production - stick-slip - peak-load (- failure)``; each term is in
``info`` as ``reward_production``, ``reward_stick_slip``, ``reward_peak_load``, ``reward_failure`` and
they sum to the reward.

Info
----
The stroke metrics of :func:`srenv.analysis.stroke_summary.summarize` (``pprl_n``, ``mprl_n``, ``fillage``,
``production_m3_day``, ``goodman_pct``, ``goodman_max_pct``, ``stick_slip_index``,
``plunger_extra_stick_episodes``, ``certified_steps``, ``corrected_steps``, ``qp_steps``,
``solver_calls``, ...), ``spm``, ``stroke_length_m``, ``fluid_level_m``, the reward terms, and
``failure`` (text) when the episode ended on a failure. ``fluid_level_m`` is 0.0 for a well without an inflow model.

Episode end
-----------
terminated: rod failure (Goodman loading above ``reward.failure_goodman_pct``) or an unrecoverable step-QP
failure (``info["failure"]``, never raised from ``step``); truncated: ``control.max_episode_s`` of simulated
time (the horizon: returns are time integrals, see :mod:`srenv.task.reward`) or ``control.max_episode_steps``.
If the solver fails before any stroke of the step completed, the metrics in ``info`` are the previous
step's and only ``reward_failure`` is non-zero (nothing was produced or loaded in that step).

Randomisation
-------------
With ``control.randomize``, each ``reset`` draws from ``self.np_random`` (never the global RNG): within
± ``control.randomize_fraction`` the reservoir pressure, maximum rate and productivity index, the fluid
density and the rod–tubing friction coefficient; the initial liquid level within ×[0.5, 1.5] (wider, so the
time to pump-off varies from episode to episode). ``reset(options={"randomize": False})`` uses the config
as is. If the warm-up stroke of ``reset`` cannot be solved, a randomised reset draws another well (up to 5
times, from ``np_random``); only if every draw fails (or without randomisation) does ``reset`` raise
:class:`~srenv.errors.SolverFailure`: the configured operating point itself cannot be run.

Version history
---------------
* v0 (kept for reproducibility; fixes only): ``info["fluid_level_m"]`` is 0.0, not NaN, for a well without an
  inflow model (NaN made the checkers' determinism test fail on four shipped configs); a pull-out config is
  refused at construction with a ``ConfigError`` instead of failing in ``reset``. The control task is
  ``srenv/SuckerRod-v1`` (:mod:`srenv.envs.sucker_rod_v1`).
"""

from __future__ import annotations

from typing import Any, ClassVar

import gymnasium as gym
import numpy as np
from gymnasium import spaces

from ..analysis.metrics import resample_prescribed_card
from ..analysis.render import CardWindow
from ..analysis.stroke_summary import summarize
from ..config import ControlConfig, WellConfig, check_stroke_steps, field_bounds, load_config
from ..errors import ConfigError, SolverFailure
from ..simulation.simulator import Simulator
from ..task.reward import RodFailureMonitor, SuckerRodReward
from .action_check import checked_action
from .env_kwargs import CARD_POINTS, merged_overrides

OBS_TAIL = ("spm", "stroke", "fluid_level", "intake_pressure", "fillage", "pprl", "goodman", "stick_slip")
OBS_BOUND = 10.0
RESET_ATTEMPTS = 5


def _from_unit(a: Any, lo: float, hi: float) -> Any:
    """Action coordinate in [-1, 1] -> physical value in [lo, hi]: v0's linear map (floats or arrays alike)."""
    return lo + 0.5 * (a + 1.0) * (hi - lo)


def setpoints_from_action(action: np.ndarray, control: ControlConfig) -> tuple[np.ndarray, np.ndarray]:
    """(SPM, stroke length in m) commanded by action(s) of shape (..., 2), before the SPM rate limit."""
    a = np.clip(np.asarray(action, dtype=np.float64), -1.0, 1.0)
    return (_from_unit(a[..., 0], control.spm_min, control.spm_max),
            _from_unit(a[..., 1], control.stroke_min_m, control.stroke_max_m))


def action_from_setpoints(spm: np.ndarray | float, stroke_length_m: np.ndarray | float,
                          control: ControlConfig) -> np.ndarray:
    """Action(s) of shape (..., 2) for the given SPM and stroke length (clipped into the control range)."""
    def to_unit(x: Any, lo: float, hi: float) -> np.ndarray:
        return np.clip(2.0 * (np.asarray(x, dtype=np.float64) - lo) / (hi - lo) - 1.0, -1.0, 1.0)

    a_spm, a_stroke = np.broadcast_arrays(to_unit(spm, control.spm_min, control.spm_max),
                                          to_unit(stroke_length_m, control.stroke_min_m, control.stroke_max_m))
    return np.stack([a_spm, a_stroke], axis=-1).astype(np.float32)


def obs_index(name: str, card_points: int = 32) -> int:
    """Index of a named scalar in the observation vector."""
    return 2 * card_points + OBS_TAIL.index(name)


class SuckerRodEnv(CardWindow, gym.Env):
    metadata: ClassVar[dict[str, Any]] = {"render_modes": ["rgb_array", "human"], "render_fps": 2}

    def __init__(self, config: str | WellConfig = "default", overrides: dict | None = None,
                 render_mode: str | None = None, card_points: int = 32, **kwargs: Any) -> None:
        merged = merged_overrides(overrides, kwargs)
        self.base_cfg = load_config(config, merged or None)
        if self.base_cfg.surface.motion == "pullout":
            raise ConfigError("surface.motion", "pullout",
                              "'harmonic' or 'conventional' for the env (a pull-out has no strokes to control; "
                              "run it with `srenv simulate --duration-s`)")
        # the slowest stroke the agent can command must fit the per-stroke bound (refused here, not in step)
        check_stroke_steps(self.base_cfg, self.base_cfg.control.spm_min, "control.spm_min")
        if render_mode is not None and render_mode not in self.metadata["render_modes"]:
            raise ValueError(f"render_mode = {render_mode!r}: expected one of {self.metadata['render_modes']}")
        self.render_mode = render_mode
        self.card_points = CARD_POINTS.check(card_points)
        self.action_space = spaces.Box(-1.0, 1.0, (2,), np.float32)
        n_obs = 2 * self.card_points + len(OBS_TAIL)
        self.observation_space = spaces.Box(-OBS_BOUND, OBS_BOUND, (n_obs,), np.float32)
        self.reward_fn = SuckerRodReward(self.base_cfg.reward)
        self.monitor = RodFailureMonitor(self.base_cfg.reward)
        self.cfg = self.base_cfg
        self.sim: Simulator | None = None
        self._trace: dict | None = None
        self._fig = None

    # -------------------------------------------------------------------------------- helpers
    def _randomized_config(self) -> WellConfig:
        c = self.base_cfg
        f = c.control.randomize_fraction
        rng = self.np_random

        def jitter(x: float) -> float:
            return float(x * (1.0 + f * rng.uniform(-1.0, 1.0)))

        o = {"fluid.density_kg_m3": jitter(c.fluid.density_kg_m3),
             "friction.coefficient": jitter(c.friction.coefficient)}
        if c.friction.law == "nonmonotone":
            o["friction.kinetic_coefficient"] = min(jitter(c.friction.kinetic_coefficient), o["friction.coefficient"])
        if c.inflow.model != "none":
            o["inflow.initial_fluid_level_m"] = float(c.inflow.initial_fluid_level_m * rng.uniform(0.5, 1.5))
            o["inflow.reservoir_pressure_pa"] = jitter(c.inflow.reservoir_pressure_pa)
            o["inflow.max_rate_m3_day"] = jitter(c.inflow.max_rate_m3_day)
            o["inflow.productivity_index_m3_day_pa"] = jitter(c.inflow.productivity_index_m3_day_pa)
        # a base value near a field's bound must not be jittered past it (reset would then refuse it)
        o = {k: float(np.clip(v, *field_bounds(k))) for k, v in o.items()}
        return load_config(c, o)

    def _to_operating_point(self, action: np.ndarray) -> tuple[float, float]:
        c = self.cfg.control
        # clipped to [-1, 1] in Python floats (the same IEEE arithmetic as numpy scalars, at a fraction of the cost)
        a0, a1 = (min(max(float(x), -1.0), 1.0) for x in action)
        spm, stroke = _from_unit(a0, c.spm_min, c.spm_max), _from_unit(a1, c.stroke_min_m, c.stroke_max_m)
        if c.spm_rate_limit > 0 and self._spm is not None:
            spm = min(max(spm, self._spm - c.spm_rate_limit), self._spm + c.spm_rate_limit)
        return float(spm), float(stroke)

    def _observe(self, m: dict) -> np.ndarray:
        c, tr = self.cfg, self._trace
        rating = c.reward.pprl_rating_n
        card = resample_prescribed_card(tr["polished_rod_position_m"], tr["polished_rod_load_n"], self.card_points) / rating
        ctl = c.control

        def unit(x: float, lo: float, hi: float) -> float:
            return 2.0 * (x - lo) / (hi - lo) - 1.0 if hi > lo else 0.0

        level = self.sim.annulus.level_m if self.sim.annulus is not None else 0.0
        tail = [unit(self._spm, ctl.spm_min, ctl.spm_max), unit(self._stroke, ctl.stroke_min_m, ctl.stroke_max_m),
                level / 100.0, m["intake_pressure_pa"] / 1e7, m["fillage"], m["pprl_n"] / rating,
                m["goodman_max_pct"] / 100.0, m["stick_slip_index"] / 10.0]
        obs = np.empty(card.size + len(tail), dtype=np.float32)  # filled in place: no concatenated temporaries
        obs[:card.size] = card
        obs[card.size:] = tail
        return np.clip(obs, -OBS_BOUND, OBS_BOUND, out=obs)  # every term is finite by construction

    def _run_strokes(self) -> tuple[dict, str | None]:
        results = []
        try:
            for _ in range(self.cfg.control.strokes_per_step):
                results.append(self.sim.run_stroke(self._spm, self._stroke, record=True))
        except SolverFailure as exc:
            if not results:
                return {}, str(exc)
            m = summarize(self.sim, results)
            return m, str(exc)
        self._trace = results[-1].trace
        m = summarize(self.sim, results)
        return m, self.monitor.failure(m)

    def _info(self, m: dict, failure: str | None) -> dict:
        info = dict(m)
        # a well without an inflow model has no annulus: report no level (0.0), never NaN (NaN != NaN breaks every
        # determinism check on info)
        info.update(spm=self._spm, stroke_length_m=self._stroke,
                    fluid_level_m=self.sim.annulus.level_m if self.sim.annulus is not None else 0.0)
        if failure:
            info["failure"] = failure
        return info

    # -------------------------------------------------------------------------------- gym API
    def reset(self, *, seed: int | None = None, options: dict | None = None) -> tuple[np.ndarray, dict]:
        super().reset(seed=seed)
        randomize = self.base_cfg.control.randomize if not options or "randomize" not in options \
            else bool(options["randomize"])
        # A training loop resets automatically and must not crash: if the warm-up stroke of a randomised
        # well cannot be solved, draw another well (from np_random, so still reproducible).
        for _attempt in range(RESET_ATTEMPTS if randomize else 1):
            self.cfg = self._randomized_config() if randomize else self.base_cfg
            self.sim = Simulator(self.cfg)
            self._steps = 0
            s = self.cfg.surface
            self._spm, self._stroke = float(s.spm), float(self.sim.surface.stroke_length_m(s.stroke_length_m))
            m, failure = self._run_strokes()
            if m:
                break
        self._t0 = self.sim.time_s  # the warm-up stroke is not part of the episode's horizon
        if failure and not m:
            raise SolverFailure(0, 0.0, failure)  # the configured operating point itself cannot be run
        self._last = m
        return self._observe(m), self._info(m, failure)

    def step(self, action: np.ndarray) -> tuple[np.ndarray, float, bool, bool, dict]:
        if self.sim is None:
            raise RuntimeError("call reset() before step()")
        action = checked_action(action, "SPM, stroke")
        self._spm, stroke = self._to_operating_point(action)
        self._stroke = self.sim.surface.stroke_length_m(stroke)
        m, failure = self._run_strokes()
        if m:
            terms = self.reward_fn.terms(m, failed=failure is not None)
        else:
            # solver failure on the first stroke of the step: the last metrics keep the observation valid,
            # but they must not earn production (or cost load) a second time
            m = dict(self._last)
            terms = {k: 0.0 for k in self.reward_fn.terms(m, failed=True)}
            terms["reward_failure"] = -self.cfg.reward.failure_penalty
        self._last = m
        reward = float(sum(terms.values()))
        self._steps += 1
        terminated = failure is not None
        ctl = self.cfg.control
        truncated = not terminated and (self._steps >= ctl.max_episode_steps
                                        or self.sim.time_s - self._t0 >= ctl.max_episode_s - 1e-9)
        info = self._info(m, failure)
        info.update(terms)
        if self.render_mode == "human":
            self.render()
        return self._observe(m), reward, terminated, truncated, info

    def render(self) -> np.ndarray | None:
        if self._trace is None:
            return None
        from ..analysis.render import card_figure, card_rgb

        title = f"{self.cfg.name}: {self._spm:.2f} SPM, {self._stroke:.2f} m"
        if self.render_mode == "rgb_array":
            return card_rgb(self._trace, title)
        if self.render_mode == "human":
            import matplotlib.pyplot as plt

            if self._fig is None:
                plt.ion()
                self._fig = plt.figure(figsize=(9, 3.8))
            self._fig.clf()
            src = card_figure(self._trace, title)
            for ax_src, pos in zip(src.axes, (121, 122)):
                ax = self._fig.add_subplot(pos)
                for line in ax_src.get_lines():
                    ax.plot(*line.get_data(), color=line.get_color(), lw=1.0)
                ax.set(xlabel=ax_src.get_xlabel(), ylabel=ax_src.get_ylabel(), title=ax_src.get_title())
            self._fig.suptitle(title)
            plt.pause(0.001)
        return None
