"""srenv: exact nonsmooth finite-element sucker-rod pump simulator and Gymnasium environment."""

from .config import WellConfig, load_config
from .errors import ConfigError, SolverFailure

__all__ = ["ConfigError", "Simulator", "SolverFailure", "WellConfig", "load_config"]
__version__ = "0.1.0"

ENV_ID = "srenv/SuckerRod-v0"
ENV_ID_V1 = "srenv/SuckerRod-v1"


def _register() -> None:
    import gymnasium

    if ENV_ID not in gymnasium.registry:
        # entry point by string: importing srenv stays light (the kernel compiles only when an env is made)
        gymnasium.register(id=ENV_ID, entry_point="srenv.envs.sucker_rod_v0:SuckerRodEnv")
    if ENV_ID_V1 not in gymnasium.registry:
        # the horizon is in well time (task.episode_hours = 12 h of 5-min intervals = 144 steps); the env
        # truncates itself, so no TimeLimit wrapper is added
        gymnasium.register(id=ENV_ID_V1, entry_point="srenv.envs.sucker_rod_v1:SuckerRodV1Env",
                           kwargs={"scenario": "train", "observation": "field"})


_register()


def __getattr__(name: str) -> type:
    # lazy: importing srenv must not compile the kernel
    if name == "Simulator":
        from .simulator import Simulator

        return Simulator
    raise AttributeError(name)
