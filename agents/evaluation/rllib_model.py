"""Evaluating an RLlib checkpoint: its policy with SB3's ``predict`` interface, read as data by default
(``srenv_policy.json`` + ``srenv_policy_weights.pt``), RLlib's own pickles only when trusted."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from srenv.input_files import read_json

from .model_io import check_spaces
from .normalizer import OBS_NORMALIZER_KEY, ObsNormalizer

MAX_POLICY_JSON_BYTES = 1_000_000  # algo, model config, shapes: a few hundred bytes in practice

POLICY_WEIGHTS = "srenv_policy_weights.pt"  # the policy as data (evaluate without --trust-model)
POLICY_JSON = "srenv_policy.json"


def algorithm_configs() -> dict[str, type]:
    """Supported RLlib algorithms by YAML name (imported lazily: Ray is slow to import)."""
    from ray.rllib.algorithms.appo import APPOConfig
    from ray.rllib.algorithms.ppo import PPOConfig
    from ray.rllib.algorithms.sac import SACConfig

    return {"ppo": PPOConfig, "appo": APPOConfig, "sac": SACConfig}


def is_rllib_checkpoint(path: str | Path) -> bool:
    """A directory written by ``Algorithm.save_to_path`` (this backend's ``checkpoint/`` or ``step_<N>/``)."""
    p = Path(path)
    return p.is_dir() and (p / "learner_group").is_dir()


class RLlibPolicy:
    """The RL module of an RLlib checkpoint with SB3's ``predict`` interface (no Ray process needed).

    Deterministic actions are the mode of the module's action distribution (the Gaussian mean for PPO),
    clipped into the env's action box as RLlib's env runners do. ``obs_filter`` is the observation
    normaliser the module was trained behind (frozen statistics), None when training had none.
    """

    def __init__(self, module: Any, action_space: Any, path: str = "", obs_filter: Any = None) -> None:
        self.module = module
        self.action_space = action_space
        self.path = path
        self.obs_filter = obs_filter

    def predict(self, observation: np.ndarray, state: Any = None, episode_start: np.ndarray | None = None,
                deterministic: bool = True) -> tuple[np.ndarray, Any]:
        import torch

        x = np.asarray(observation, dtype=np.float32)
        obs = torch.as_tensor((self.obs_filter(x) if self.obs_filter is not None else x)[None])
        with torch.no_grad():
            out = self.module.forward_inference({"obs": obs})
            dist = self.module.get_inference_action_dist_cls().from_logits(out["action_dist_inputs"])
            action = (dist.to_deterministic() if deterministic else dist).sample()
        a = np.asarray(action[0].numpy(), dtype=self.action_space.dtype)
        return np.clip(a, self.action_space.low, self.action_space.high), state

    def __repr__(self) -> str:
        return f"RLlibPolicy({type(self.module).__name__}, {self.path})"


def _module_from_data(p: Path, env: Any) -> tuple[Any, Any]:
    """Rebuild the module from ``srenv_policy.json`` (plain JSON) and load its tensors with
    ``torch.load(weights_only=True)``, which refuses anything but tensors and plain containers; with the
    observation normaliser recorded there (None when training had none)."""
    import gymnasium as gym
    import torch

    from ..inputs import policy_json

    meta = policy_json(read_json(p / POLICY_JSON, str(p / POLICY_JSON), "policy file", MAX_POLICY_JSON_BYTES),
                       p / POLICY_JSON)
    configs = algorithm_configs()
    if meta.get("algo") not in configs or not isinstance(meta.get("model_config"), dict):
        raise ValueError(f"{p / POLICY_JSON}: expected algo one of {', '.join(configs)} and a model_config mapping")
    saved_obs, saved_act = tuple(meta["observation_shape"]), tuple(meta["action_shape"])
    check_spaces(saved_obs, saved_act, env.observation_space.shape, env.action_space.shape, p)
    if not (np.allclose(meta["action_low"], env.action_space.low)
            and np.allclose(meta["action_high"], env.action_space.high)):
        raise ValueError(f"{p} does not fit this env: action bounds {meta['action_low']}..{meta['action_high']} "
                         f"vs {env.action_space}")
    obs_space, normalizer = env.observation_space, None
    if meta.get(OBS_NORMALIZER_KEY) is not None:
        normalizer = ObsNormalizer.from_rllib(meta[OBS_NORMALIZER_KEY], obs_space.shape, p / POLICY_JSON)
        # the module was built on the normaliser's output space (as RLlib's MeanStdFilter states it)
        obs_space = gym.spaces.Box(-normalizer.clip_std, normalizer.clip_std, obs_space.shape, obs_space.dtype)
    spec = configs[meta["algo"]]().rl_module(model_config=meta["model_config"]).get_default_rl_module_spec()
    spec.observation_space, spec.action_space = obs_space, env.action_space
    spec.model_config, spec.inference_only = meta["model_config"], bool(meta.get("inference_only", False))
    module = spec.build()
    module.load_state_dict(torch.load(p / POLICY_WEIGHTS, weights_only=True, map_location="cpu"))
    module.eval()
    return module, normalizer


def load_rllib_policy(path: str | Path, env: Any, trust: bool = False) -> RLlibPolicy:
    """The default policy of an RLlib checkpoint directory, checked against ``env``'s spaces.

    By default read as data (``srenv_policy.json`` + ``srenv_policy_weights.pt``, written by this backend);
    ``trust=True`` (``--trust-model``) loads RLlib's own pickled module instead - pickles can run code when
    read, so only for checkpoints you made (e.g. written by RLlib outside this backend).
    """
    p = Path(path)
    if not trust:
        if not ((p / POLICY_JSON).is_file() and (p / POLICY_WEIGHTS).is_file()):
            raise ValueError(f"--policy {p}: an RLlib checkpoint without {POLICY_JSON} / {POLICY_WEIGHTS} holds "
                             "only pickles, which can run arbitrary code when loaded; pass --trust-model if you "
                             "made it yourself")
        module, normalizer = _module_from_data(p, env)
        return RLlibPolicy(module, env.action_space, str(p), obs_filter=normalizer)
    from ray.rllib.core import (
        COMPONENT_LEARNER,
        COMPONENT_LEARNER_GROUP,
        COMPONENT_RL_MODULE,
        DEFAULT_MODULE_ID,
    )
    from ray.rllib.core.rl_module.rl_module import RLModule

    module_dir = p / COMPONENT_LEARNER_GROUP / COMPONENT_LEARNER / COMPONENT_RL_MODULE / DEFAULT_MODULE_ID
    if not module_dir.is_dir():
        raise FileNotFoundError(f"--policy {p}: an RLlib checkpoint without {module_dir.relative_to(p)}")
    module = RLModule.from_checkpoint(str(module_dir.resolve()))
    obs_filter = RLlibObsFilter.from_checkpoint(p, env.observation_space, env.action_space)
    # behind a normaliser the module's input space is the normaliser's output (a clipped box)
    expected_obs = obs_filter.observation_space if obs_filter is not None else env.observation_space
    check_spaces(module.observation_space, module.action_space, expected_obs, env.action_space, p)
    return RLlibPolicy(module, env.action_space, str(p), obs_filter=obs_filter)


class RLlibObsFilter:
    """The trusted route: the normaliser RLlib pickled in a checkpoint, run as RLlib runs it (a frozen copy
    of the ``MeanStdFilter`` applied to a one-observation episode)."""

    def __init__(self, connector: Any, env_obs_space: Any, env_act_space: Any) -> None:
        frozen = type(connector)(update_stats=False, clip_by_value=connector.clip_by_value,
                                 de_mean_to_zero=connector.de_mean_to_zero, de_std_to_one=connector.de_std_to_one)
        # spaces after construction: MeanStdFilter(input_observation_space=...) fails in ray 2.60 (it derives
        # its output space before it has set clip_by_value)
        frozen.input_action_space, frozen.input_observation_space = env_act_space, env_obs_space
        frozen.set_state(connector.get_state())
        self.connector = frozen
        self.observation_space = frozen.observation_space  # the module's input space (clipped box)

    @classmethod
    def from_checkpoint(cls, path: Path, env_obs_space: Any, env_act_space: Any) -> RLlibObsFilter | None:
        """The checkpoint's MeanStdFilter (a local env runner's, or the algorithm's own pipeline), or None."""
        from ray.rllib.connectors.connector_v2 import ConnectorV2
        from ray.rllib.connectors.env_to_module import MeanStdFilter
        from ray.rllib.core import COMPONENT_ENV_RUNNER, COMPONENT_ENV_TO_MODULE_CONNECTOR

        runner_dir = path / COMPONENT_ENV_RUNNER / COMPONENT_ENV_TO_MODULE_CONNECTOR
        for d in (runner_dir, path / COMPONENT_ENV_TO_MODULE_CONNECTOR):
            if d.is_dir():
                pipeline = ConnectorV2.from_checkpoint(str(d.resolve()))  # unpickles: trusted only
                found = [c for c in pipeline.connectors if isinstance(c, MeanStdFilter)]
                return cls(found[0], env_obs_space, env_act_space) if found else None
        return None

    def __call__(self, obs: np.ndarray) -> np.ndarray:
        from ray.rllib.env.single_agent_episode import SingleAgentEpisode

        episode = SingleAgentEpisode(observations=[np.asarray(obs, dtype=np.float32)])
        self.connector(rl_module=None, batch={}, episodes=[episode])
        return np.asarray(episode.get_observations(-1), dtype=np.float32)
