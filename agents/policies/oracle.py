"""The ``oracle`` baseline of the v1 benchmark: a perfect-model planner with the hidden well and inflow."""

from __future__ import annotations

import copy
import math
from collections.abc import Sequence
from typing import Any

import numpy as np

from .field import IDLE, _batch, _out, action_from_setpoints, interval_s_of, make_field_baseline, obs_names_of


class OraclePolicy:
    """Perfect-model planner with the hidden well and inflow schedule: the best schedule it can compute.

    At the episode's first step it deep-copies ``env.unwrapped`` - the true well, its annulus state, the
    inflow schedule ``inflow_multiplier(t)`` and the random stream: a perfect model - and searches, by
    simulating whole episodes on copies of it:

    1. every constant action of a ``n_spm x n_stroke`` grid over the whole box (plus ``anchors``, e.g. the
       tuned constant);
    2. a piecewise-constant schedule (``segments`` equal parts of the horizon) refined from the best
       constant by coordinate search: +-``step`` on each axis of each segment, step halved per round,
       ``rounds`` rounds (each trial re-simulates from the segment's start state only);
    3. the closed-loop trajectories of the tuned field baselines in ``policies`` (``[[name, params]]``).

    It then plays the best action sequence found, open loop: the model is exact and deterministic, so the
    episode it plays is the one it simulated (``planned_reward`` = the realised return; a test checks it).
    By construction it scores at least as well as every constant action of its grid and every baseline it
    was given, on every episode. Its cost is bounded and reported: ``sim_steps`` model steps.

    ``mode="lookahead"`` instead re-plans every interval greedily: each candidate (last action, +-``steps``
    around it, idle, anchors) simulated ``horizon`` intervals ahead.

    One env only (no batch): it needs the env itself, passed by ``reset(env)``.
    """

    name = "oracle"

    def __init__(self, mode: str = "plan", n_spm: int = 7, n_stroke: int = 3, segments: int = 4,
                 rounds: int = 2, step: float = 0.25, policies: Sequence[Sequence[Any]] = (),
                 anchors: Sequence[Sequence[float]] = (), steps: Sequence[float] = (0.3, 0.1),
                 horizon: int = 1) -> None:
        if mode not in ("plan", "lookahead"):
            raise ValueError(f"oracle mode = {mode!r}: expected plan or lookahead")
        if horizon < 1 or segments < 1:
            raise ValueError(f"oracle horizon = {horizon!r}, segments = {segments!r}: expected >= 1")
        self.mode = mode
        self.n_spm, self.n_stroke, self.segments, self.rounds = int(n_spm), int(n_stroke), int(segments), int(rounds)
        self.step = float(step)
        self.policies = [(str(n), dict(p)) for n, p in policies]
        self.steps = tuple(float(s) for s in steps)
        self.horizon = int(horizon)
        self.anchors = [np.clip(np.asarray(a, np.float32), -1, 1) for a in anchors]
        self._env: Any = None
        self._last: np.ndarray | None = None
        self._plan: list[np.ndarray] | None = None
        self._k = 0
        self.planned_reward = math.nan
        self.plan_source = ""
        self.sim_steps = 0  # model steps simulated (its compute cost)

    def reset(self, env: Any, index: int | None = None) -> None:
        if index not in (None, 0):
            raise ValueError("OraclePolicy drives one env (index 0), not a batch")
        self._env = env.unwrapped
        cfg = self._env.cfg
        self._last = action_from_setpoints(cfg.surface.spm, cfg.surface.stroke_length_m, cfg.control)
        self._plan, self._k = None, 0
        self.planned_reward, self.plan_source, self.sim_steps = math.nan, "", 0

    # ------------------------------------------------------------------ plan mode
    def _n_steps(self) -> int:
        env = self._env
        return max(1, math.ceil(float(env.cfg.task.episode_hours) * 3600.0 / interval_s_of(env) - 1e-6))

    def _roll(self, model: Any, actions: Sequence[np.ndarray], snapshots: dict[int, Any] | None = None,
              k0: int = 0) -> tuple[float, int]:
        """Play ``actions[k0:]`` on ``model`` (mutated); returns (reward sum, steps). Copies the model into
        ``snapshots[k]`` at each segment boundary k it passes, if given."""
        total, k = 0.0, k0
        bounds = self._bounds()
        for k in range(k0, len(actions)):
            if snapshots is not None and k in bounds and k != k0:
                snapshots[k] = (copy.deepcopy(model), total)
            _, r, terminated, truncated, _ = model.step(actions[k])
            self.sim_steps += 1
            total += float(r)
            if terminated or truncated:
                return total, k + 1
        return total, len(actions)

    def _bounds(self) -> list[int]:
        n = self._n_plan
        return [round(i * n / self.segments) for i in range(self.segments + 1)]

    def _constant_return(self, a: np.ndarray) -> float:
        return self._roll(copy.deepcopy(self._model0), [a] * self._n_plan)[0]

    def _closed_loop(self, name: str, params: dict[str, Any], obs0: np.ndarray) -> tuple[float, list[np.ndarray]]:
        model = copy.deepcopy(self._model0)
        pol = make_field_baseline(name, params, obs_names_of(model))
        if hasattr(pol, "reset"):
            pol.reset(model)
        obs, state, total, acts = obs0, None, 0.0, []
        for k in range(self._n_plan):
            a, state = pol.predict(obs, state=state, episode_start=np.array([k == 0]))
            a = np.asarray(a, np.float32)
            acts.append(a)
            obs, r, terminated, truncated, _ = model.step(a)
            self.sim_steps += 1
            total += float(r)
            if terminated or truncated:
                break
        return total, acts

    def _make_plan(self, obs0: np.ndarray) -> None:
        self._model0 = copy.deepcopy(self._env)
        self._n_plan = self._n_steps()
        cands = [np.array([a, b], np.float32) for a in np.linspace(-1, 1, self.n_spm)
                 for b in np.linspace(-1, 1, self.n_stroke)] + list(self.anchors)
        best_c, best_r = cands[0], -math.inf
        for c in cands:
            r = self._constant_return(c)
            if r > best_r:
                best_c, best_r = c, r
        plan = [best_c.copy() for _ in range(self._n_plan)]
        source = "constant"
        if self.segments > 1 and self.rounds > 0:
            plan, best_r = self._refine(plan, best_r)
            source = "schedule"
        for name, params in self.policies:
            r, acts = self._closed_loop(name, params, obs0)
            if r > best_r and len(acts) == self._n_plan:
                plan, best_r, source = acts, r, name
        self._plan, self.planned_reward, self.plan_source = plan, best_r, source

    def _refine(self, plan: list[np.ndarray], best_r: float) -> tuple[list[np.ndarray], float]:
        bounds = self._bounds()
        snaps: dict[int, Any] = {0: (copy.deepcopy(self._model0), 0.0)}
        self._roll(copy.deepcopy(self._model0), plan, snaps)
        step = self.step
        for _ in range(self.rounds):
            for s in range(self.segments):
                k0, k1 = bounds[s], bounds[s + 1]
                if k1 <= k0 or k0 not in snaps:
                    continue
                base = plan[k0]
                for d in ((step, 0.0), (-step, 0.0), (0.0, step), (0.0, -step)):
                    trial_a = np.clip(base + np.asarray(d, np.float32), -1, 1).astype(np.float32)
                    if np.allclose(trial_a, plan[k0]):
                        continue
                    trial = plan[:k0] + [trial_a] * (k1 - k0) + plan[k1:]
                    model, before = snaps[k0]
                    r = before + self._roll(copy.deepcopy(model), trial, None, k0)[0]
                    if r > best_r + 1e-9:
                        plan, best_r = trial, r
                        new_snaps = {k: v for k, v in snaps.items() if k <= k0}
                        m, b = copy.deepcopy(snaps[k0][0]), snaps[k0][1]
                        part: dict[int, Any] = {}
                        self._roll(m, plan, part, k0)
                        new_snaps.update({k: (mm, b + bb) for k, (mm, bb) in part.items()})
                        snaps = new_snaps
            step /= 2
        return plan, best_r

    # ------------------------------------------------------------------ lookahead mode
    def candidates(self) -> list[np.ndarray]:
        last = self._last
        cands = [last, np.array([IDLE, last[1]], np.float32), *self.anchors]
        for s in self.steps:
            for d in ((s, 0.0), (-s, 0.0), (0.0, s), (0.0, -s)):
                cands.append(np.clip(last + np.asarray(d, np.float32), -1.0, 1.0))
        unique: dict[tuple[float, float], np.ndarray] = {}
        for c in cands:
            unique.setdefault((round(float(c[0]), 6), round(float(c[1]), 6)), c.astype(np.float32))
        return list(unique.values())

    def score(self, action: np.ndarray) -> float:
        model = copy.deepcopy(self._env)
        total = 0.0
        for _ in range(self.horizon):
            _, r, terminated, truncated, _ = model.step(action)
            self.sim_steps += 1
            total += float(r)
            if terminated or truncated:
                break
        return total

    def predict(self, observation: Any, state: Any = None, episode_start: Any = None,
                deterministic: bool = True) -> tuple[np.ndarray, Any]:
        obs, n, batched = _batch(observation)
        if n != 1 or self._env is None:
            raise RuntimeError("OraclePolicy: one env only, and call reset(env) after env.reset")
        if self.mode == "plan":
            if self._plan is None:
                self._make_plan(obs[0].astype(np.float32))
            best = self._plan[min(self._k, len(self._plan) - 1)]
            self._k += 1
            return _out(best.reshape(1, 2), batched), state
        best, best_r = self._last, -math.inf
        for c in self.candidates():
            r = self.score(c)
            if r > best_r:
                best, best_r = c, r
        self._last = best
        return _out(best.reshape(1, 2), batched), state

    def params(self) -> dict[str, Any]:
        return {"mode": self.mode, "n_spm": self.n_spm, "n_stroke": self.n_stroke, "segments": self.segments,
                "rounds": self.rounds, "step": self.step, "policies": [list(p) for p in self.policies],
                "anchors": [a.tolist() for a in self.anchors], "steps": list(self.steps), "horizon": self.horizon}
