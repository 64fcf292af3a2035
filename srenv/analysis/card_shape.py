"""A scale-free representation of one surface card, for the condition classifier (docs/conditions.md).

A card is one stroke of (position, load) samples in time order, starting anywhere in the stroke, in any
units. Positions and loads are normalised to [0, 1] over the card; the stroke is cut at its lowest and
highest positions into the up branch (bottom -> top) and the down branch (top -> bottom); each branch's
load is read at ``N_GRID`` fixed positions. One more number survives any change of units: the load ratio
min / max (field loads are tension from the load cell's zero, so a unit change multiplies both): thin
cards high above zero (parted rods, a flowing well) keep it near 1.

Time order: the polished rod does positive work over a stroke (the loop integral of load d(position) is
positive: the up branch carries the higher load), so a card whose loop integral is negative was stored
with its time reversed (some field exports are) and is read backwards. Every simulated card has positive
work, so this changes no training card.

Pump (downhole) cards (``card="pump"``, run P1): the same numbers, except the load ratio, set to 0: pump cards come
in true or effective loads (the buoyancy convention moves the zero) and digitised ones on any axis, so the ratio
would carry the convention, not the condition.
"""

from __future__ import annotations

import numpy as np

N_GRID = 32
GRID = np.linspace(0.02, 0.98, N_GRID)
N_FEATURES = 2 * N_GRID + 1
MIN_POINTS = 8
CARD_TYPES = ("surface", "pump")  # which card a model reads: the polished rod's or the pump's (downhole)


class BadCard(ValueError):
    """A card the representation cannot read (too few points, no stroke, no load variation, not finite)."""


class FlatLoad(BadCard):
    """A card with a stroke but no load variation (a pump card of a string that carries nothing: parted rods)."""


def _branch(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Loads at GRID along a branch whose positions run from 0 to 1 (made monotone: a sample that steps
    back within the branch, noise at a reversal, is held at the running maximum)."""
    xm = np.maximum.accumulate(x)
    keep = np.concatenate(([True], np.diff(xm) > 0))  # np.r_'s values without its Python (every env step)
    if keep.sum() < 2:
        return np.interp(GRID, [0.0, 1.0], [y[0], y[-1]])
    return np.interp(GRID, xm[keep], y[keep])


def features(position, load, card: str = "surface") -> np.ndarray:
    """The representation of one card (N_FEATURES numbers; ``card`` one of CARD_TYPES); raises BadCard."""
    x = np.asarray(position, dtype=np.float64)
    y = np.asarray(load, dtype=np.float64)
    if x.ndim != 1 or x.shape != y.shape or len(x) < MIN_POINTS:
        raise BadCard(f"a card needs at least {MIN_POINTS} (position, load) pairs, got {x.size}")
    if not (np.all(np.isfinite(x)) and np.all(np.isfinite(y))):
        raise BadCard("the card holds values that are not finite")
    xr, yr = float(x.max() - x.min()), float(y.max() - y.min())
    if xr <= 1e-12 * max(1.0, abs(float(x.max()))):
        raise BadCard("the card's position does not vary (no stroke)")
    if yr <= 1e-12 * max(1.0, abs(float(y.max()))):
        raise FlatLoad("the card's load does not vary")
    xc, yc = np.concatenate((x, x[:1])), np.concatenate((y, y[:1]))
    if float(np.sum(0.5 * (yc[1:] + yc[:-1]) * np.diff(xc))) < 0.0:  # stored with time reversed
        x, y = x[::-1], y[::-1]
    ymax, ymin = float(y.max()), float(y.min())
    ratio = float(np.clip(ymin / ymax, -1.0, 1.0)) if ymax > 0 else 0.0
    xn = (x - x.min()) / xr
    yn = (y - ymin) / yr
    b = int(np.argmin(xn))
    xn, yn = np.concatenate((xn[b:], xn[:b])), np.concatenate((yn[b:], yn[:b]))  # np.roll(-b)
    t = int(np.argmax(xn))
    up_x, up_y = xn[: t + 1], yn[: t + 1]
    dn_x = np.concatenate((xn[t:], xn[:1]))
    dn_y = np.concatenate((yn[t:], yn[:1]))
    if len(up_x) < 2 or len(dn_x) < 2:
        raise BadCard("the card has no up or no down branch")
    up = _branch(up_x, up_y)
    down = _branch(1.0 - dn_x, dn_y)[::-1]  # read at the same GRID positions, bottom to top
    return np.concatenate((up, down, [ratio if card == "surface" else 0.0]))


def features_batch(positions: np.ndarray, loads: np.ndarray) -> np.ndarray:
    """features() of each row."""
    return np.stack([features(p, y) for p, y in zip(positions, loads)])
