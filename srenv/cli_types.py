"""Argument types shared by the command lines (``srenv`` and its ``sweep``, ``diagnose`` and ``fit``
subcommands, and ``python -m agents``): a bad value is one line naming the flag, the value and what is expected (argparse turns it
into exit status 2)."""

from __future__ import annotations

import argparse
import math
from collections.abc import Callable

MAX_DURATION_S = 1.0e6  # --duration-s


def positive(name: str, unit: str) -> Callable[[str], float]:
    def parse(text: str) -> float:
        try:
            x = float(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{name} = {text!r}: expected a positive number in {unit}") from None
        if not math.isfinite(x) or x <= 0:
            raise argparse.ArgumentTypeError(f"{name} = {text!r}: expected a positive number in {unit}")
        return x
    return parse


def positive_int(name: str, hi: int | None = None) -> Callable[[str], int]:
    def parse(text: str) -> int:
        limit = f" at most {hi}" if hi is not None else ""
        # digits only, and few of them: int() of a 100 000-digit string is itself slow
        if not text.isdigit() or len(text) > 18 or int(text) <= 0 or (hi is not None and int(text) > hi):
            raise argparse.ArgumentTypeError(f"{name} = {text[:40]!r}: expected a positive integer{limit}")
        return int(text)
    return parse


def nonneg_int(name: str) -> Callable[[str], int]:
    def parse(text: str) -> int:
        if not text.isdigit() or len(text) > 18:
            raise argparse.ArgumentTypeError(f"{name} = {text[:40]!r}: expected a non-negative integer")
        return int(text)
    return parse


def bounded(parse: Callable[[str], float], name: str, unit: str, hi: float) -> Callable[[str], float]:
    def check(text: str) -> float:
        x = parse(text)
        if x > hi:
            raise argparse.ArgumentTypeError(f"{name} = {text[:40]!r}: expected a positive number in {unit} "
                                             f"at most {hi:g}")
        return x
    return check
