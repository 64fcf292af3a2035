"""Measured surface motion and measured cards: reading dynamometer CSV files, finding one stroke in them,
and the periodic spline that turns one stroke's position samples into the prescribed top motion.

File format (``docs/field.md``): a CSV with a header row naming its columns; ``t_s`` (s) and
``polished_rod_position_m`` (m, measured upward from the bottom of the stroke, as ``srenv simulate``
writes it), optionally ``polished_rod_load_n`` (N, tension positive) and any other columns (ignored).
Without a ``t_s`` column the samples are taken as equally spaced over one stroke at
``surface.measured_spm``.

Period of the card: ``surface.measured_spm`` when given; otherwise, if the file holds several strokes,
the median spacing of the upward mean-crossings of the position (the last full stroke is used), and for a
single stroke the sampled span plus one sample spacing (samples at t_0, ..., t_0 + T - dt: the file does not
repeat its first sample one period later; if yours does, give ``surface.measured_spm``).
"""

from __future__ import annotations

import csv
import io
import math
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path

import numpy as np

from ..errors import ConfigError, short_repr
from ..input_files import read_regular
from .card_checks import MAX_ABS_CARD_VALUE, MAX_CARD_BYTES, check_card, check_magnitude, check_period

MIN_SAMPLES = 16


def read_card_csv(path: str | Path, field: str, required: tuple[str, ...],
                  optional: tuple[str, ...] = (), reverse: bool = False) -> dict[str, np.ndarray]:
    """Named numeric columns of a CSV with a header row (and optionally a unit row under it, field units
    converted to the SI unit the column's name ends in); one ConfigError naming `field` on any defect. A card
    (with ``polished_rod_position_m``) passes ``card_checks.check_card``; `reverse` reverses it in time."""
    p = Path(path)
    if not str(path):
        raise ConfigError(field, str(path), "a path to a CSV file")
    if not p.is_file():
        raise ConfigError(field, str(path), "an existing CSV file")
    raw = read_regular(p, field, "CSV file", MAX_CARD_BYTES)  # a FIFO is refused, a huge file not read
    try:
        rows = [r for r in csv.reader(io.StringIO(raw.decode("utf-8"), newline="")) if r and any(c.strip() for c in r)]
    except (UnicodeDecodeError, csv.Error) as exc:  # csv.Error: a field over csv's limit, a broken quote
        raise ConfigError(field, str(path), f"a readable UTF-8 text CSV file ({type(exc).__name__}: "
                          f"{short_repr(str(exc), 80)})") from None
    if not rows:
        raise ConfigError(field, str(path), "a CSV file with a header row and data rows (it is empty)")
    header = [c.strip() for c in rows[0]]
    missing = [c for c in required if c not in header]
    if missing:
        raise ConfigError(field, str(path), "a CSV whose header names the columns " + ", ".join(required)
                          + f" (missing {', '.join(missing)}; found {', '.join(header) or 'none'})")
    data = rows[1:]
    units = _unit_row(data[0], header, field, str(path)) if data else {}
    if units:
        data = data[1:]
    if len(data) < MIN_SAMPLES:
        raise ConfigError(field, str(path), f"at least {MIN_SAMPLES} data rows (found {len(data)})")
    out: dict[str, np.ndarray] = {}
    for name in required + tuple(c for c in optional if c in header):
        j = header.index(name)
        col = np.empty(len(data))
        for i, r in enumerate(data):
            try:
                col[i] = float(r[j])
            except (ValueError, IndexError):
                cell = r[j] if j < len(r) else "<missing>"
                raise ConfigError(field, str(path), f"a number in column {name} on data row {i + 1} "
                                  f"(found {cell!r})") from None
        check_magnitude(col, field, str(path), f"numbers in column {name}", "row",
                        math.inf if name == "t_s" else MAX_ABS_CARD_VALUE)
        out[name] = col * units.get(name, 1.0)
    with np.errstate(over="ignore", invalid="ignore"):  # times of 1e308: inf steps and periods, refused below
        steps = np.diff(out["t_s"]) if "t_s" in out else None
        if steps is not None and not np.all(steps > 0):
            i = int(np.argmax(steps <= 0)) + 2
            raise ConfigError(field, str(path), f"strictly increasing t_s (data row {i} does not advance)")
        if "t_s" in out and "polished_rod_position_m" in out:
            check_period(stroke_period_s(out["t_s"], out["polished_rod_position_m"]), field, str(path))
    if "polished_rod_position_m" in out:
        x, f = check_card(out["polished_rod_position_m"], out.get("polished_rod_load_n"), field, str(path), reverse)
        out["polished_rod_position_m"] = x
        if f is not None:
            out["polished_rod_load_n"] = f
        if reverse:  # the samples run backwards in time; their time stamps stay as they were
            for k in out:
                if k not in ("t_s", "polished_rod_position_m", "polished_rod_load_n"):
                    out[k] = out[k][::-1].copy()
    return out


_SI_SUFFIX = {"_m": "m", "_n": "N", "_s": "s", "_pa": "Pa", "_kg_m": "kg/m", "_m3_day": "m^3/day"}


def _unit_row(row: list[str], header: list[str], field: str, source: str) -> dict[str, float]:
    """{column: factor to SI} of a unit row (the first row under the header, all of it non-numeric), or {}."""
    from ..field_units import same_dimension

    cells = [c.strip() for c in row]
    def numeric(c: str) -> bool:
        try:
            float(c)
            return True
        except ValueError:
            return False
    if not cells or any(numeric(c) for c in cells if c):
        return {}
    out = {}
    for name, unit in zip(header, cells):
        si = next((u for suf, u in sorted(_SI_SUFFIX.items(), key=lambda kv: -len(kv[0]))
                   if name.endswith(suf)), None)
        if si is None or not unit:
            continue
        out[name] = same_dimension(unit, si, f"{field} unit row, column {name}")
    return out


def stroke_period_s(t_s: np.ndarray, position_m: np.ndarray) -> float:
    """Stroke period of sampled positions: upward mean-crossings if the record holds several strokes,
    else the span plus one (median) sample spacing."""
    dt = float(np.median(np.diff(t_s)))
    x = position_m - 0.5 * (position_m.max() + position_m.min())
    up = np.flatnonzero((x[:-1] < 0) & (x[1:] >= 0))
    if len(up) >= 2:
        # crossing times interpolated inside the sample interval
        tc = t_s[up] + (t_s[up + 1] - t_s[up]) * (-x[up]) / (x[up + 1] - x[up])
        period = float(np.median(np.diff(tc)))
        if t_s[-1] - t_s[0] + dt >= 1.5 * period:  # really several strokes, not noise near the middle
            return period
    return float(t_s[-1] - t_s[0] + dt)


def last_stroke(t_s: np.ndarray, period_s: float) -> np.ndarray:
    """Mask of the samples of the last `period_s` of a record (all of it if shorter)."""
    dt = float(np.median(np.diff(t_s)))
    return t_s > t_s[-1] - period_s + 0.5 * dt


@dataclass(frozen=True)
class MeasuredMotion:
    """One stroke of measured polished-rod position as a periodic cubic spline, re-timed to start at the
    bottom of the stroke (the simulator's strokes start there, from the static state)."""

    spline: object          # scipy CubicSpline of the upward position over card time, periodic
    period_s: float          # the card's own stroke period
    t_bottom_s: float        # card time of the bottom of the stroke
    stroke_m: float
    bottom_m: float

    @property
    def spm(self) -> float:
        return 60.0 / self.period_s

    def velocity_down_m_s(self, t_s: np.ndarray, spm: float) -> np.ndarray:
        """Top velocity, positive down, at times since the bottom for a stroke run at `spm` (the card is
        re-timed as a beam unit at another crank speed: same position at the same phase)."""
        r = self.period_s * spm / 60.0
        return -r * self.spline(self.t_bottom_s + r * np.asarray(t_s, dtype=float), 1)

    def acceleration_down_m_s2(self, t_s: float, spm: float) -> float:
        r = self.period_s * spm / 60.0
        return float(-r * r * self.spline(self.t_bottom_s + r * t_s, 2))

    def position_m(self, t_s: np.ndarray, spm: float | None = None) -> np.ndarray:
        """Upward position above the bottom at times since the bottom."""
        r = 1.0 if spm is None else self.period_s * spm / 60.0
        return self.spline(self.t_bottom_s + r * np.asarray(t_s, dtype=float)) - self.bottom_m


def motion_from_samples(t_s: np.ndarray, position_m: np.ndarray, period_s: float,
                        field: str = "surface.measured_card_csv", source: str = "") -> MeasuredMotion:
    from scipy.interpolate import CubicSpline

    keep = last_stroke(t_s, period_s)
    t, x = t_s[keep], position_m[keep]
    if len(t) < MIN_SAMPLES:
        raise ConfigError(field, source, f"at least {MIN_SAMPLES} samples in one stroke (found {len(t)})")
    if t[-1] - t[0] >= period_s - 1e-9 * period_s:
        raise ConfigError(field, source, f"samples spanning less than one stroke period ({period_s:.6g} s)")
    stroke = float(x.max() - x.min())
    if not stroke > 0:
        raise ConfigError(field, source, "a polished_rod_position_m that moves (the card has zero stroke)")
    # periodic spline: close the stroke with the first sample one period later
    s = CubicSpline(np.r_[t, t[0] + period_s], np.r_[x, x[0]], bc_type="periodic")
    # the bottom: the lowest stationary point of the spline (exact), or the lowest sample
    roots = s.derivative().roots(extrapolate=False)
    cand = np.r_[roots, t] if len(roots) else t
    vals = s(cand)
    t_bottom = float(cand[int(np.argmin(vals))])
    bottom = float(vals.min())
    top = float(max(np.max(s(roots)) if len(roots) else -np.inf, x.max()))
    return MeasuredMotion(s, float(period_s), t_bottom, top - bottom, bottom)


@lru_cache(maxsize=8)
def _load_cached(path: str, mtime_ns: int, size: int, spm: float) -> MeasuredMotion:
    field = "surface.measured_card_csv"
    cols = read_card_csv(path, field, ("polished_rod_position_m",), ("t_s",))
    x = cols["polished_rod_position_m"]
    if "t_s" not in cols:
        if not spm > 0:
            raise ConfigError("surface.measured_spm", spm, "a positive stroke rate in strokes/min when the card "
                              "has no t_s column (its samples are then equally spaced over one stroke)")
        period = 60.0 / spm
        t = np.arange(len(x)) * (period / len(x))
    else:
        t = cols["t_s"]
        period = 60.0 / spm if spm > 0 else stroke_period_s(t, x)
    return motion_from_samples(t, x, period, field, path)


def load_measured_motion(path: str | Path, measured_spm: float = 0.0) -> MeasuredMotion:
    """The measured motion of a card file (cached while the file is unchanged: the env rebuilds its
    simulator on every reset)."""
    p = Path(path)
    if not str(path) or not p.is_file():
        raise ConfigError("surface.measured_card_csv", str(path), "an existing CSV file with columns "
                          "t_s, polished_rod_position_m (surface.motion is 'measured')")
    st = p.stat()
    spm = float(measured_spm)
    if not (math.isfinite(spm) and spm >= 0):
        raise ConfigError("surface.measured_spm", measured_spm, "a non-negative stroke rate in strokes/min")
    return _load_cached(str(p.resolve()), st.st_mtime_ns, st.st_size, spm)
