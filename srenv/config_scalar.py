"""One scalar config value checked against its field's declaration (type, options, check, range): used by the
loader (``srenv.config``) and by the ``units:`` conversion (``srenv.config_units``), which checks a converted
value against the same SI bounds."""

from __future__ import annotations

import math
from typing import Any

from .config_fields import _CHECKS
from .errors import ConfigError


def _parse_scalar(tp: Any, value: Any, path: str, meta: dict) -> Any:
    if tp is bool:
        if isinstance(value, bool):
            return value
        raise ConfigError(path, value, "true or false")
    if tp is str:
        if not isinstance(value, str):
            raise ConfigError(path, value, "a string")
        opts = meta.get("options")
        if opts and value not in opts:
            raise ConfigError(path, value, "one of " + ", ".join(opts))
        return value
    if tp in (int, float):
        check = meta.get("check", "any")
        pred = _CHECKS[check][0]
        value = _plain_number(value)
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise ConfigError(path, value, _expected(tp, meta))
        if isinstance(value, int):
            # compare exactly before any float(): float(10**400) overflows (and no field is that large)
            if abs(value) > _MAX_INT_MAGNITUDE:
                raise ConfigError(path, value, _expected(tp, meta))
        elif not math.isfinite(value) or (tp is int and not value.is_integer()):
            raise ConfigError(path, value, _expected(tp, meta))
        x = tp(value)
        lo, hi = meta.get("lo"), meta.get("hi")
        if not pred(float(x)) or (lo is not None and x < lo) or (hi is not None and x > hi):
            raise ConfigError(path, value, _expected(tp, meta))
        return x
    raise TypeError(f"unsupported config type {tp} at {path}")  # programming error, not user input


def _expected(tp: type, meta: dict) -> str:
    """What a numeric field expects, as its refusal says it (built only for a refusal: an env reset parses
    ~300 fields)."""
    unit, check = meta.get("unit", ""), meta.get("check", "any")
    phrase = _CHECKS[check][1]
    what = f"{'an integer' if tp is int else phrase} in {unit}" if unit and unit != "-" else (
        "an integer" if tp is int else phrase)
    if tp is int:
        what = f"{'a non-negative' if check == 'nonneg' else 'a positive'} integer" + (
            f" in {unit}" if unit not in ("", "-") else "")
    return what + _range_phrase(meta.get("lo"), meta.get("hi"))


def _plain_number(value: Any) -> Any:
    """numpy scalars (np.float32(5.0), np.int64(5): what a training loop hands the env) are numbers."""
    import numbers

    if type(value) in (float, int):  # the common case, returned as is (as the checks below would)
        return value
    if isinstance(value, numbers.Integral) and not isinstance(value, (bool, int)):
        return int(value)
    if isinstance(value, numbers.Real) and not isinstance(value, (bool, int, float)):
        return float(value)
    return value


# integers beyond this are refused before any conversion to float (every bound is far below it)
_MAX_INT_MAGNITUDE = 10**15


def _range_phrase(lo: float | None, hi: float | None) -> str:
    if lo is not None and hi is not None:
        return f" within [{lo:g}, {hi:g}]"
    if hi is not None:
        return f" at most {hi:g}"
    return f" at least {lo:g}" if lo is not None else ""
