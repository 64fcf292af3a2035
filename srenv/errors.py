"""Typed errors shared by the config loader, the simulator and the CLI."""

from __future__ import annotations


class ConfigError(ValueError):
    """A config value is invalid. The message names the field, the value and the expected unit."""

    def __init__(self, field: str, value: object, expected: str) -> None:
        self.field = field
        self.value = value
        self.expected = expected
        super().__init__(f"config field '{field}' = {value!r}: expected {expected}")


class SolverFailure(RuntimeError):
    """The step QP could not be solved by any backend in the retry chain."""

    def __init__(self, step: int, time_s: float, detail: str) -> None:
        self.step = step
        self.time_s = time_s
        self.detail = detail
        super().__init__(f"step QP failed at step {step} (t = {time_s:.4f} s): {detail}")
