"""How a config field declares itself: ``num`` (a number with its unit, validity check and physical range),
``choice`` and ``opt``; the sections (``srenv.config_sections``, ``srenv.config_unit``) are built from these, the
loader checks them and ``docs/config.md`` is generated from them."""

from __future__ import annotations

import dataclasses
import typing
from dataclasses import field
from typing import Any

# check name -> (predicate, phrase used in the error message)
_CHECKS: dict[str, tuple[typing.Callable[[float], bool], str]] = {
    "positive": (lambda x: x > 0, "a positive number"),
    "nonneg": (lambda x: x >= 0, "a non-negative number"),
    "any": (lambda x: True, "a finite number"),
    "unit_interval": (lambda x: 0 <= x <= 1, "a number in [0, 1]"),
    "angle": (lambda x: 0 <= x <= 180, "an angle in [0, 180]"),
    "azimuth": (lambda x: -360 <= x <= 360, "an angle in [-360, 360]"),
}


def num(default: Any = dataclasses.MISSING, *, unit: str, check: str = "positive", doc: str = "",
        lo: float | None = None, hi: float | None = None) -> Any:
    """A numeric config field with its unit, validity check and physical range [lo, hi] (both inclusive).

    Every numeric field has a finite upper bound: a value far outside any physical range (1e308 N, a
    1e-300 m element) either overflows to NaN or asks for unbounded memory, so it is refused at load time.
    """
    meta = {"unit": unit, "check": check, "doc": doc}
    if lo is not None:
        meta["lo"] = lo
    if hi is not None:
        meta["hi"] = hi
    return field(default=default, metadata=meta)


def choice(default: str, options: tuple[str, ...], doc: str = "") -> Any:
    return field(default=default, metadata={"options": options, "doc": doc})


def opt(default: Any = None, doc: str = "", **kw: Any) -> Any:
    return field(default=default, metadata={"doc": doc, **kw})
