"""Every baseline of the v1 benchmark by name: the field controllers and the oracle (which plays the field
controllers itself, so it sits between them and this factory)."""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from typing import Any

from .field import FIELD_BASELINES, make_field_baseline
from .oracle import OraclePolicy

BASELINE_NAMES = (*FIELD_BASELINES, "oracle")
# tuned and tested by a benchmark only when its config lists them (v2's field controller with alarms), so the
# v1 benchmark's policies and report stay as they were
OPTIONAL_BASELINES = ("alarm_pump_off",)
# the coordinate searches, in the order they run: an init value may name a baseline tuned before (its value)
SEARCHED_BASELINES = ("pump_off", "fillage_pi", *OPTIONAL_BASELINES)


def benchmark_baselines(configured: Iterable[str]) -> tuple[str, ...]:
    """The baselines a benchmark tunes, tests and reports: all of :data:`BASELINE_NAMES` and the optional ones
    ``configured`` (its ``baselines:`` block, or the tuned parameters' names) lists, before the oracle."""
    names = set(configured)
    return (*FIELD_BASELINES, *(n for n in OPTIONAL_BASELINES if n in names), "oracle")


def make_baseline(name: str, params: dict[str, Any], obs_names: Sequence[str]) -> Any:
    """A baseline by benchmark name from its (tuned) parameters."""
    if name == "oracle":
        return OraclePolicy(**dict(params))
    if name == "alarm_pump_off":  # v2's baselines (agents/policies/alarms.py, causal_oracle.py)
        from .alarms import make_field_controller

        return make_field_controller(name, params, obs_names)
    if name == "causal_oracle":
        from .causal_oracle import CausalOraclePolicy

        return CausalOraclePolicy(**dict(params))
    if name == "estimated_mpc":  # the causal oracle's planner on an estimated model (agents/policies/estimated_mpc.py)
        from .estimated_mpc import EstimatedMPCPolicy

        return EstimatedMPCPolicy(**dict(params))
    if name not in FIELD_BASELINES and name != "constant":
        raise ValueError(f"baseline {name!r}: expected one of {', '.join(BASELINE_NAMES)}")
    return make_field_baseline(name, params, obs_names)
