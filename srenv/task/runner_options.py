"""The interval runner's opt-in stepping options, declared once (docs/speed.md §2g-§2i): each option's kind, bounds
and meaning, and the one check every caller uses (the runner, the error tool). An integer option out of its bounds is
a ValueError, a switch that is not True/False a TypeError, each naming the option, its value and what is expected."""

from __future__ import annotations

BOUNDARY_STROKES_MAX = 16  # beyond ~16 a 5-min interval at 12 SPM is mostly simulated: use exact_min instead

# name -> (kind, lowest, highest or None, meaning)
OPTIONS: dict[str, tuple[type, int, int | None, str]] = {
    "exact_min": (int, 0, None, "exact strokes per interval"),
    "boundary_strokes": (int, 0, BOUNDARY_STROKES_MAX,
                         "exact strokes an interval may add at regime boundaries; 0 is off"),
    "follow_drift": (bool, 0, 1, "the fast-forward's figures follow the carry's slopes"),
    "draw_follows_pump": (bool, 0, 1, ("the fast-forward's draw follows the pump's displacement at the current "
                                       "intake pressure")),
}


def check_option(name: str, value):
    """``value`` of option ``name``, validated against its declaration."""
    kind, lo, hi, meaning = OPTIONS[name]
    if kind is bool:
        if not isinstance(value, bool):
            raise TypeError(f"{name} = {value!r}: expected True or False ({meaning})")
        return value
    if isinstance(value, bool) or not isinstance(value, int) or value < lo or (hi is not None and value > hi):
        span = f"in {lo}..{hi}" if hi is not None else f">= {lo}"
        raise ValueError(f"{name} = {value!r}: expected an integer {span} ({meaning})")
    return value
