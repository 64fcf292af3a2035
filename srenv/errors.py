"""Typed errors shared by the config loader, the simulator and the CLI."""

from __future__ import annotations

import reprlib

# An error message shows at most this many characters of the offending value: a value can be huge (a
# 400-digit integer, a list expanded from YAML aliases) and must not turn one line into megabytes.
VALUE_REPR_CHARS = 240  # long enough for a file path, short enough for one line

_repr = reprlib.Repr()
_repr.maxlevel = 3          # nested containers beyond this depth print as [...]: bounded work, not only text
_repr.maxlist = _repr.maxtuple = _repr.maxdict = _repr.maxset = 6
_repr.maxstring = _repr.maxother = VALUE_REPR_CHARS
_repr.maxlong = 40


def short_repr(value: object, limit: int = VALUE_REPR_CHARS) -> str:
    """``repr(value)``, bounded in work and capped at ``limit`` characters (``...`` marks a cut)."""
    if isinstance(value, int) and not isinstance(value, bool) and abs(value) >= 10**30:
        # str() of a huge int is slow (and refused beyond 4300 digits): say how big it is instead
        digits = int(abs(value).bit_length() * 0.30103) + 1
        return f"<{'-' if value < 0 else ''}integer of about {digits} digits>"
    try:
        text = _repr.repr(value)
    except Exception:  # noqa: BLE001 - a value whose repr fails must not hide the error being reported
        text = f"<{type(value).__name__}>"
    return text if len(text) <= limit else text[: limit - 3] + "..."


class _Fields:
    """An error made of named fields (``_fields``, ``__init__``'s arguments in order): pickling rebuilds it from
    them, so an error raised in a worker process reaches the parent whole. Exception's own pickling would call
    ``__init__`` with the message alone, which these signatures refuse (the pool then reports a broken worker)."""

    _fields: tuple[str, ...] = ()

    def __reduce__(self) -> tuple:
        return type(self), tuple(getattr(self, name) for name in self._fields)


class ConfigError(_Fields, ValueError):
    """A config value is invalid. The message names the field, the value and the expected unit."""

    _fields = ("field", "value", "expected")

    def __init__(self, field: str, value: object, expected: str) -> None:
        self.field, self.value, self.expected = field, value, expected
        super().__init__(f"config field '{field}' = {short_repr(value)}: expected {expected}")


class NumericFailure(_Fields, RuntimeError):
    """A run produced non-finite numbers (the config's magnitudes are outside what the model can handle)."""

    _fields = ("what", "detail")

    def __init__(self, what: str, detail: str) -> None:
        self.what, self.detail = what, detail
        super().__init__(f"non-finite result in '{what}': {detail}")


class SolverFailure(_Fields, RuntimeError):
    """The step QP could not be solved by any backend in the retry chain."""

    _fields = ("step", "time_s", "detail")

    def __init__(self, step: int, time_s: float, detail: str) -> None:
        self.step, self.time_s, self.detail = step, time_s, detail
        super().__init__(f"step QP failed at step {step} (t = {time_s:.4f} s): {detail}")
