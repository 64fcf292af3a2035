"""Argument types shared by the command lines (``srenv`` and its ``sweep`` subcommand): a bad value is one
line naming the flag, the value and what is expected (argparse turns it into exit status 2)."""

from __future__ import annotations

import argparse
import math
from collections.abc import Callable


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


def positive_int(name: str) -> Callable[[str], int]:
    def parse(text: str) -> int:
        if not text.isdigit() or int(text) <= 0:
            raise argparse.ArgumentTypeError(f"{name} = {text!r}: expected a positive integer")
        return int(text)
    return parse
