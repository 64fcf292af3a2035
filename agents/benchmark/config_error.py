"""The one error of a benchmark YAML (its own module: the config and its split checks both raise it)."""

from __future__ import annotations

Declared = dict[str, tuple[tuple[type, ...], str]]  # a block's keys -> (the YAML types each takes, what that is)


class BenchmarkConfigError(ValueError):
    """A benchmark YAML that cannot be used; the message names the key, the value and what is expected."""
