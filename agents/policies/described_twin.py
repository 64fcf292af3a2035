"""The twin of ``estimated_mpc``'s option ``twin: described`` (issue 24): a v2 env of the well its operator's file
describes (:func:`srenv.task.well_file.twin_config`: the file's equipment, the family's nominal reservoir, friction
and damping), with no conditions. The policy gets the file at ``reset`` through
:func:`srenv.task.well_file.well_file` - the one hook by which the played env hands anything of its well - and
builds this twin from the file alone."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from srenv.envs.sucker_rod_v2 import SuckerRodV2Env
from srenv.task.well_family import WellSpec
from srenv.task.well_file import twin_config

TWINS = ("library", "described")


class DescribedTwinEnv(SuckerRodV2Env):
    """A v2 env whose one well is the described twin (the env's own fixed-well path, as for a YAML scenario), at
    the played task's clock, without conditions (``event_rate_scale`` 0)."""

    def __init__(self, file: Mapping[str, Any], episode_hours: float, interval_s: float) -> None:
        super().__init__(scenario="train", event_rate_scale=0.0, episode_hours=episode_hours, interval_s=interval_s)
        cfg = twin_config(file)
        self.split = None  # one fixed well (v1's path for a config scenario): the twin
        self._fixed = self._apply(WellSpec("described_twin", None, cfg, cfg.inflow.max_rate_m3_day))


def check_twin(twin: Any) -> str:
    if twin not in TWINS:
        raise ValueError(f"estimated_mpc twin = {twin!r}: expected one of {list(TWINS)}")
    return str(twin)
