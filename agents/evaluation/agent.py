"""Policies built from a *policy spec*: a picklable dict naming a baseline or trained models, so episodes can
run in worker processes that build their own env and policy:

- ``{"kind": "baseline", "name": "pump_off", "params": {...}}`` (:mod:`agents.policies.factory`),
- ``{"kind": "agent", "path": "x.zip", "obs_norm": "x_obs_norm.npz" | None}`` (an SB3 model and the
  observation normalisation it was trained with, stored as npz; both are read as data, nothing is unpickled),
  optionally with ``"residual": {"base", "params", "scale"[, "idle_scale"][, "cap"]}`` (:mod:`agents.policies.residual`)
  and, for a residual student that sees the last K observations, ``"history": K`` (:mod:`agents.policies.history`),
  and, for one whose input ends with the well file's features, ``"described": true``
  (:mod:`agents.policies.described_features`, read at ``reset`` from ``well_file(env)``),
- ``{"kind": "ensemble", "members": [{"path", "obs_norm"}, ...], "residual": ... | None}``: the mean of the
  members' actions (:mod:`agents.policies.ensemble`);
- ``{"kind": "guarded", "inner": <agent or ensemble spec>, "fallback": {"name", "params"}, "guard": {...},
  "scale": ... | None}``: the inner policy under a constraint guard (:mod:`agents.policies.guarded`).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..policies.described_features import DescribedInputs
from ..policies.ensemble import EnsemblePolicy
from ..policies.factory import make_baseline
from ..policies.field import obs_names_of
from ..policies.guarded import GuardedPolicy
from ..policies.residual import ResidualAgentPolicy
from .model_io import algorithms, detect_algo, load_policy, read_data, space_shape
from .normalizer import ObsNormalizer


class SB3Policy:
    """A trained SB3 model and the observation normaliser it was trained with (observations only: the reward
    normalisation is a training device, evaluation reports raw env rewards): any object with
    ``normalize_obs`` (:class:`agents.evaluation.normalizer.ObsNormalizer`, or a trusted ``VecNormalize``)."""

    def __init__(self, model: Any, norm: Any = None, path: str = "") -> None:
        self.model = model
        self.norm = norm
        self.path = path

    def predict(self, observation: Any, state: Any = None, episode_start: Any = None,
                deterministic: bool = True) -> tuple[np.ndarray, Any]:
        if self.norm is not None:
            observation = self.norm.normalize_obs(observation)
        return self.model.predict(observation, state=state, episode_start=episode_start,
                                  deterministic=deterministic)

    def __repr__(self) -> str:
        return f"{type(self).__name__}({type(self.model).__name__}, {self.path})"


class AgentPolicy(SB3Policy):
    """An SB3 model (PPO, SAC, ...) with its observation normaliser, deterministic by default.

    The zip is read as data (:func:`agents.evaluation.model_io.load_policy`: the network rebuilt from its plain-text
    kwargs, weights loaded tensors-only), so a model file cannot run code; the spaces are the Box shapes
    the zip records, in the action box [-1, 1] of the v1 contract.
    """

    def __init__(self, path: str, obs_norm: str | None = None) -> None:
        import gymnasium as gym

        data = read_data(path)
        obs_shape, act_shape = space_shape(data, "observation_space", path), space_shape(data, "action_space", path)
        self.observation_space = gym.spaces.Box(-np.inf, np.inf, obs_shape, np.float32)
        self.action_space = gym.spaces.Box(-1.0, 1.0, act_shape, np.float32)
        model = load_policy(path, algorithms()[detect_algo(path)], self.observation_space, self.action_space)
        norm = ObsNormalizer.load(obs_norm) if obs_norm else None
        if norm is not None and norm.mean.shape != obs_shape:
            raise ValueError(f"{obs_norm}: statistics of shape {norm.mean.shape} do not fit the model "
                             f"{path} (observation shape {obs_shape})")
        super().__init__(model, norm, path)


def build_policy(spec: dict[str, Any], env: Any) -> Any:
    if spec["kind"] == "guarded":
        return _guarded(spec, env)
    if spec["kind"] == "baseline":
        return make_baseline(spec["name"], spec.get("params", {}), obs_names_of(env))
    if spec["kind"] in ("agent", "ensemble"):
        res = spec.get("residual")
        if spec.get("history", 1) != 1 and not res:  # before any file is read: the spec itself is wrong
            raise ValueError(f"policy spec history = {spec['history']!r}: a history needs a residual student")
        described = spec.get("described", False)
        if not isinstance(described, bool):
            raise ValueError(f"policy spec described = {described!r}: expected true or false (the well file's "
                             "features appended to the model's input)")
        if spec["kind"] == "agent":
            agent: Any = AgentPolicy(spec["path"], spec.get("obs_norm"))
        else:
            agent = EnsemblePolicy([AgentPolicy(m["path"], m.get("obs_norm")) for m in spec["members"]])
        if described:
            agent = DescribedInputs(agent)
        if res:
            return ResidualAgentPolicy(agent, res["base"], res["params"], res["scale"], res.get("idle_scale"),
                                       spec.get("history", 1), res.get("cap"))
        return agent
    raise ValueError(f"policy spec kind = {spec.get('kind')!r}: expected baseline, agent, ensemble or guarded")


def _guarded(spec: dict[str, Any], env: Any) -> Any:
    """A guarded spec's policy; its ``scale`` replaces the inner residual's (0: the residual's base itself)."""
    inner, res = dict(spec["inner"]), spec["inner"].get("residual")
    if spec.get("scale") is not None and res:
        if float(spec["scale"]) == 0.0:
            inner = {"kind": "baseline", "name": res["base"], "params": res["params"]}
        else:
            inner["residual"] = {**res, "scale": float(spec["scale"])}
    fb = spec["fallback"]
    return GuardedPolicy(build_policy(inner, env), fb["name"], fb.get("params", {}), spec["guard"], obs_names_of(env))
