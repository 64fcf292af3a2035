"""One declaration per numeric command-line flag and per numeric field of a file a command reads: its type,
unit and range, and where a bound that follows from resources comes from.

The parsers build their argparse types from these (``Number.parse``), the file readers check with them
(``Number.check``), and ``tests/test_declared_inputs.py`` / ``test_declared_files.py`` generate their refusal
cases from them (``Number.bad_texts`` / ``bad_values``), so a flag or field added here is bounded and tested by construction; a test also
fails when a parser holds a typed flag that is not declared here. A refusal is one line: the flag or field,
the value as given (cut to a bounded length) and what is expected.
"""

from __future__ import annotations

import argparse
import math
import numbers
from dataclasses import dataclass
from typing import Any

from .errors import ConfigError, short_repr

MAX_INT_DIGITS = 18  # int() of a 100 000-digit string is itself slow; no bound here needs more digits


@dataclass(frozen=True)
class Number:
    """A bounded number: ``kind`` int or float, ``unit`` ('' for a count), range ``lo`` .. ``hi``
    (``lo`` itself refused when ``lo_open``: a positive number is ``lo=0, lo_open=True``)."""

    name: str
    kind: type
    unit: str = ""
    lo: float = 0.0
    hi: float | None = None
    lo_open: bool = True
    why: str = ""  # where the bound comes from (memory, wall time, a config field's range)

    def _fmt(self, x: float) -> str:
        return str(int(x)) if self.kind is int else f"{x:g}"

    def expected(self) -> str:
        if self.kind is int:
            what = "a positive integer" if self.lo_open and self.lo == 0 else "an integer"
        else:
            what = "a positive number" if self.lo_open and self.lo == 0 else "a number"
        if self.unit:
            what += f" in {self.unit}"
        if self.hi is not None:
            left = "(" if self.lo_open else "["
            if self.lo == 0 and self.lo_open:
                what += f" at most {self._fmt(self.hi)}"
            else:
                what += f" within {left}{self._fmt(self.lo)}, {self._fmt(self.hi)}]"
        elif not (self.lo == 0 and self.lo_open):
            what += f" {'above' if self.lo_open else 'at least'} {self._fmt(self.lo)}"
        return what

    def _in_range(self, x: float) -> bool:
        above = x > self.lo if self.lo_open else x >= self.lo
        return math.isfinite(x) and above and (self.hi is None or x <= self.hi)

    def parse(self, text: str) -> Any:
        """A command-line value (argparse ``type=``): the number, or one line naming the flag."""
        def refuse() -> argparse.ArgumentTypeError:
            return argparse.ArgumentTypeError(f"{self.name} = {short_repr(text, 60)}: expected {self.expected()}")
        s = text.strip()
        if self.kind is int:
            digits = s[1:] if s[:1] in "+-" else s
            if not digits.isdigit() or len(digits) > MAX_INT_DIGITS:
                raise refuse()
            x: Any = int(s)
        else:
            try:
                x = float(s)
            except ValueError:
                raise refuse() from None
        if not self._in_range(float(x)):
            raise refuse()
        return x

    def check(self, value: Any, field: str | None = None) -> Any:
        """A value read from a file (numpy scalars are numbers; a bool is not): the number as int or float,
        or ``ConfigError`` naming ``field`` (default: the declared name)."""
        name = field or self.name
        if isinstance(value, bool) or not isinstance(value, numbers.Real):
            raise ConfigError(name, value, self.expected())
        if self.kind is int:
            whole = isinstance(value, numbers.Integral) or (
                isinstance(value, float) and value.is_integer() and abs(value) < 2**53)
            if not whole or abs(int(value)) > 10**MAX_INT_DIGITS:
                raise ConfigError(name, value, self.expected())
            x: Any = int(value)
        else:
            try:
                x = float(value)
            except OverflowError:  # an integer beyond any float (10**400)
                raise ConfigError(name, value, self.expected()) from None
        if not self._in_range(float(x)):
            raise ConfigError(name, value, self.expected())
        return x

    def _below(self) -> float:
        """A value just out of range at the bottom (the bound itself when it is excluded)."""
        if self.lo_open:
            return self.lo
        return self.lo - 1 if self.kind is int else self.lo - (0.5 * abs(self.lo) + 1.0)

    def bad_texts(self) -> list[str]:
        """Values every declaration must refuse: not numbers, not finite, out of range on either side."""
        out = ["abc", "nan", "inf", "-inf", "1" + "0" * 400]
        if self.kind is int:
            out += ["2.5", "1e3"]
        out.append(f"{self._below():g}")
        if self.hi is not None:
            out.append(str(int(self.hi) + 1) if self.kind is int else f"{self.hi * 1.5 + 1:g}")
        return out


    def bad_values(self) -> list[Any]:
        """File values every declaration must refuse (what a YAML/JSON reader can hand over)."""
        out: list[Any] = ["abc", None, True, [1], {"a": 1}, float("nan"), float("inf"), 10**400]
        if self.kind is int:
            out.append(2.5)
        out.append(self._below())
        if self.hi is not None:
            out.append(int(self.hi) + 1 if self.kind is int else self.hi * 1.5 + 1)
        return out


def from_config_field(flag: str, key: str) -> Number:
    """The declaration of a flag that sets a config field: the field's own unit and range."""
    import dataclasses
    import typing

    from .config_sections import WellConfig

    section, name = key.split(".")
    cls = typing.get_type_hints(WellConfig)[section]
    meta = {f.name: f.metadata for f in dataclasses.fields(cls)}[name]
    check = meta.get("check", "any")
    lo = meta.get("lo", 0.0)
    return Number(flag, float, meta.get("unit", ""), float(lo), meta.get("hi"),
                  lo_open=(check == "positive" and lo == 0.0), why=f"the range of config field {key}")


# the lower bound each config check implies where a field gives none (config_sections._CHECKS)
_CHECK_LO = {"positive": (0.0, True), "nonneg": (0.0, False), "unit_interval": (0.0, False),
             "angle": (0.0, False), "azimuth": (-360.0, False)}
_CHECK_HI = {"unit_interval": 1.0, "angle": 180.0, "azimuth": 360.0}


def config_fields() -> dict[str, tuple[Number, bool]]:
    """Every numeric field of a well config (sections; lists at their first item, ``rod.tapers.0.x``) as a
    declaration with the range the loader checks, and whether null is accepted (an optional field): the
    generated bad-value tests (tests/test_declared_files.py) cover a field added to config_sections by
    construction."""
    import dataclasses
    import types
    import typing

    from .config_sections import WellConfig

    out: dict[str, tuple[Number, bool]] = {}

    def walk(cls: type, prefix: str) -> None:
        hints = typing.get_type_hints(cls)
        for f in dataclasses.fields(cls):
            tp, key = hints[f.name], prefix + f.name
            optional = typing.get_origin(tp) in (typing.Union, types.UnionType) and type(None) in typing.get_args(tp)
            if optional:
                tp = next(a for a in typing.get_args(tp) if a is not type(None))
            if dataclasses.is_dataclass(tp):
                walk(tp, key + ".")
            elif typing.get_origin(tp) is tuple:
                walk(typing.get_args(tp)[0], key + ".0.")
            elif tp in (int, float) and "check" in f.metadata:
                m = f.metadata
                lo, lo_open = _CHECK_LO.get(m["check"], (-math.inf, False))
                if "lo" in m:
                    lo, lo_open = float(m["lo"]), False
                hi = m.get("hi", _CHECK_HI.get(m["check"]))
                out[key] = (Number(key, tp, m.get("unit", ""), lo, hi, lo_open), optional)

    walk(WellConfig, "")
    return out


# ------------------------------------------------------------------------------------ resource bounds
MAX_STROKES = 100_000      # simulate --strokes; the recorded samples are bounded too (MAX_RUN_SAMPLES)
MAX_DURATION_S = 1.0e6     # --duration-s (the recorded samples bound it first at any real time step)
MAX_HARMONICS = 1000       # diagnose: the march holds 2 * harmonics + 4 samples per segment (memory,
#                            and a measured card's sensor bandwidth is far below 1000 harmonics)
MAX_FIT_STROKES = 100      # fit: strokes simulated per evaluation, times up to MAX_FIT_EVALUATIONS
MAX_FIT_EVALUATIONS = 2000  # fit: evaluations of least_squares (wall time: ~0.1-1 s each)
MAX_SWEEP_WORKERS = 256
MAX_CARDS = 200_000  # srenv cards: the set is held in memory: 200 000 cards x 4 arrays x 256 points x 8 B = 1.6 GB


def _flags(*decls: Number) -> dict[str, Number]:
    return {d.name: d for d in decls}


def _command_flags() -> dict[str, dict[str, Number]]:
    duration = Number("--duration-s", float, "s", hi=MAX_DURATION_S)
    return {
        "simulate": _flags(
            Number("--strokes", int, hi=MAX_STROKES, why="wall time; samples bounded by MAX_RUN_SAMPLES"),
            duration,
            from_config_field("--spm", "surface.spm"),
            from_config_field("--stroke-length-m", "surface.stroke_length_m"),
            from_config_field("--pull-velocity-m-s", "surface.pull_velocity_m_s")),
        "bench": _flags(Number("--repeats", int, hi=1000, why="wall time"),
                        Number("--strokes", int, hi=1000, why="wall time")),
        "sweep": _flags(duration,
                        Number("--settle-fraction", float, "", lo=0.0, hi=0.99, lo_open=False),
                        Number("--workers", int, hi=MAX_SWEEP_WORKERS, why="processes")),
        "diagnose": _flags(from_config_field("--spm", "surface.spm"),
                           Number("--harmonics", int, hi=MAX_HARMONICS, why="memory of the march")),
        "fit": _flags(Number("--strokes", int, hi=MAX_FIT_STROKES, why="wall time per evaluation"),
                      Number("--max-evaluations", int, hi=MAX_FIT_EVALUATIONS, why="wall time")),
        "validate": _flags(Number("--strokes", int, hi=50, why="wall time (strokes from the static state)")),
        "cards": _flags(Number("--n", int, hi=MAX_CARDS, why="memory of the set"),
                        Number("--seed", int, lo=0, hi=2**31 - 1, lo_open=False),
                        Number("--workers", int, hi=MAX_SWEEP_WORKERS, why="processes")),
    }


FLAGS = _command_flags()

# the output files of each command: flag -> accepted suffixes (checked before any work, srenv.outputs)
OUTPUTS: dict[str, dict[str, tuple[str, ...]]] = {
    "simulate": {"--out": (".csv",), "--plot": (".png",)},
    "sweep": {"--out": (".csv",), "--plot": (".png",)},
    "diagnose": {"--out": (".csv",), "--plot": (".png",)},
    "fit": {"--out": (".yaml", ".yml")},
    "validate": {"--plot": (".png",)},
}


def add_number(parser: argparse.ArgumentParser, command: str, flag: str, **kwargs: Any) -> None:
    """``parser.add_argument(flag, type=<its declaration>)``: the one way a numeric flag is added."""
    decl = FLAGS[command][flag]
    parser.add_argument(flag, type=decl.parse, **kwargs)
