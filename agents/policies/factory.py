"""Every baseline of the v1 benchmark by name: the field controllers and the oracle (which plays the field
controllers itself, so it sits between them and this factory)."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

from .field import FIELD_BASELINES, make_field_baseline
from .oracle import OraclePolicy

BASELINE_NAMES = (*FIELD_BASELINES, "oracle")


def make_baseline(name: str, params: dict[str, Any], obs_names: Sequence[str]) -> Any:
    """A baseline by benchmark name from its (tuned) parameters."""
    if name == "oracle":
        return OraclePolicy(**dict(params))
    if name not in FIELD_BASELINES and name != "constant":
        raise ValueError(f"baseline {name!r}: expected one of {', '.join(BASELINE_NAMES)}")
    return make_field_baseline(name, params, obs_names)
