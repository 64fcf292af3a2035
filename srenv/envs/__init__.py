"""Gymnasium environments of srenv (one env per module)."""

from .sucker_rod_v0 import SuckerRodEnv, obs_index

__all__ = ["SuckerRodEnv", "obs_index"]
