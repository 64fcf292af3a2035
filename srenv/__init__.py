"""srenv: exact nonsmooth finite-element sucker-rod pump simulator and Gymnasium environment."""

from .config import WellConfig, load_config
from .errors import ConfigError, SolverFailure

__all__ = ["ConfigError", "SolverFailure", "WellConfig", "load_config", "Simulator"]
__version__ = "0.1.0"


def __getattr__(name: str):  # noqa: ANN202 - lazy: importing srenv must not compile the kernel
    if name == "Simulator":
        from .simulator import Simulator

        return Simulator
    raise AttributeError(name)
