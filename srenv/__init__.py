"""srenv: exact nonsmooth finite-element sucker-rod pump simulator and Gymnasium environment."""

from .config import WellConfig, load_config
from .errors import ConfigError, SolverFailure

__all__ = ["ConfigError", "Simulator", "SolverFailure", "WellConfig", "load_config"]
__version__ = "0.2.0"

ENV_ID = "srenv/SuckerRod-v0"
ENV_ID_V1 = "srenv/SuckerRod-v1"

# Every env srenv registers: id -> (entry point, default kwargs shown by gymnasium.spec(id)). Adding an env
# is one line here. No TimeLimit (max_episode_steps) and no reward_threshold are registered on purpose:
# each env truncates itself from its config (v0: control.max_episode_s, the horizon, and
# control.max_episode_steps, a cap; v1: task.episode_hours of well time, 144 five-minute intervals by
# default), so the config stays the one source of the episode length; the returns are time integrals of
# production less penalties (v1: less costs), with no level that "solves" the task.
ENVS: dict[str, tuple[str, dict]] = {
    ENV_ID: ("srenv.envs.sucker_rod_v0:SuckerRodEnv", {"config": "default"}),
    # v1's horizon is part of its spec: 12 h of well time in 5-min control intervals (144 steps); passing these
    # kwargs (or None to keep a config's own task section) changes it
    ENV_ID_V1: ("srenv.envs.sucker_rod_v1:SuckerRodV1Env",
                {"scenario": "train", "observation": "field", "episode_hours": 12.0, "interval_s": 300.0}),
}


def register_envs() -> None:
    """Register :data:`ENVS` with gymnasium (idempotent; run on ``import srenv``)."""
    import gymnasium

    for env_id, (entry_point, kwargs) in ENVS.items():
        if env_id not in gymnasium.registry:
            # entry point by string: importing srenv stays light (the kernel compiles only when an env is made)
            gymnasium.register(id=env_id, entry_point=entry_point, kwargs=dict(kwargs),
                               max_episode_steps=None, reward_threshold=None, nondeterministic=False)
    # The registry is left as gymnasium makes it: v0 and v1 are versions of one name, so gymnasium's make of
    # v0 issues its DeprecationWarning "out of date, consider v1" (hidden by Python's default filters outside
    # __main__). v0 stays, with its numbers, for reproducibility.


register_envs()


def __getattr__(name: str) -> type:
    # lazy: importing srenv must not compile the kernel
    if name == "Simulator":
        from .simulation.simulator import Simulator

        return Simulator
    raise AttributeError(name)
