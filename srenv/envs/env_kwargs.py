"""The keyword arguments every srenv env reads besides its own: ``overrides`` and ``section__field=value``,
checked before use so that a wrong one is one line naming ``overrides`` (or the keyword) and the value,
never a raw ``ValueError``/``AttributeError`` from deep inside; and ``card_points``, declared with its range."""

from __future__ import annotations

from typing import Any

from ..declarations import Number
from ..errors import ConfigError

# points per card branch in the v0 observation: its size is 2 * card_points + 8 floats per step
CARD_POINTS = Number("card_points", int, lo=2, hi=512, lo_open=False, why="observation size (2 * n + 8 floats)")


def merged_overrides(overrides: Any, kwargs: dict[str, Any]) -> dict[str, Any]:
    """``overrides`` (a mapping of 'section.field' strings, or None) updated by ``section__field`` keywords."""
    if overrides is None:
        merged: dict[str, Any] = {}
    elif isinstance(overrides, dict):
        for key in overrides:
            if not isinstance(key, str) or not key:
                raise ConfigError("overrides", key, "'section.field' strings as keys")
        merged = dict(overrides)
    else:
        raise ConfigError("overrides", overrides, "a mapping {'section.field': value}, e.g. "
                          "{'task.interval_s': 600}")
    for key, value in kwargs.items():
        if "__" not in key:
            raise ConfigError(key, value, "a keyword of the env or a config field as section__field=value")
        merged[key.replace("__", ".")] = value
    return merged


APPLIED_CACHE_SIZE = 512  # wells whose overridden config an env keeps (every well of the largest split)


def restates(cfg: Any, key: str, value: Any) -> bool:
    """True when the override ``key = value`` already holds in ``cfg`` (same type and value: the config
    parsed with it would be equal), so it need not be applied."""
    cur: Any = cfg
    for part in key.split("."):
        if not hasattr(cur, part):
            return False  # not a field: load_config names it in its error
        cur = getattr(cur, part)
    return type(cur) is type(value) and cur == value
