"""What a vendor dynacard record holds beside the well it describes: the vendor's pump card, its predicted
full-pump surface card's extremes, its damping coefficients and the card's type (``field_record`` reads them;
none is needed to run a record, and one that cannot be read is left out and said)."""

from __future__ import annotations

import math

import numpy as np

from .. import field_units as fu
from ..errors import ConfigError
from ..surface_unit.card_checks import loop_work
from .record_fields import series


def card_type(details) -> str | None:
    """The vendor's card type (a short word: Startup, Shutdown, ...), or None."""
    v = details.get("CardType") if isinstance(details, dict) else None
    return v.strip() if isinstance(v, str) and 0 < len(v.strip()) <= 40 and v.strip().isprintable() else None


IDEAL = "Performance.IdealCardSimulation_SurfaceCard_"


def ideal_card(perf, stroke_m: float, notes: list[str]) -> dict | None:
    """The vendor's predicted full-pump surface card's extremes, where the record carries them. They are in SI
    (N, m) unlike the record's cards; the unit is checked on the record itself: the ideal card's position
    range must be the measured stroke (within 10 %), else the figures are left out and a note says why."""
    if not isinstance(perf, dict):
        return None
    keys = ("Load_max", "Load_min", "Position_max", "Position_min")
    vals = [perf.get("IdealCardSimulation_SurfaceCard_" + k) for k in keys]
    if all(v is None for v in vals):
        return None
    try:
        f_max, f_min, x_max, x_min = (float(v) for v in vals)
    except (TypeError, ValueError):
        notes.append(f"{IDEAL}*: not four numbers; the vendor's predicted card is left out")
        return None
    ok = all(math.isfinite(v) for v in (f_max, f_min, x_max, x_min)) and -1e7 < f_min < f_max < 1e7
    if not ok or abs((x_max - x_min) - stroke_m) > 0.1 * stroke_m:
        notes.append(f"{IDEAL}*: stroke {x_max - x_min:g} against the measured {stroke_m:.3f} m, or loads out of "
                     "order; not read as SI, the vendor's predicted card is left out")
        return None
    return {"pprl_n": f_max, "mprl_n": f_min, "stroke_m": x_max - x_min}


def coefficients(v) -> list[float]:
    """The vendor's damping coefficients as given (reported, not used by the model)."""
    if not isinstance(v, list):
        return []
    return [float(c) for c in v if isinstance(c, (int, float)) and not isinstance(c, bool) and math.isfinite(c)]


def pump_card(dh, notes: list[str]) -> tuple[np.ndarray | None, np.ndarray | None]:
    """The vendor's pump card (m, N), forward by its own loop (it keeps its own time order, not always the
    surface card's); (None, None) without one, and one that cannot be read is said."""
    if dh is not None and not isinstance(dh, dict):
        notes.append("downholeCard: not a JSON object: the vendor's pump card is not compared")
    if not isinstance(dh, dict) or not dh.get("Position") or not dh.get("Load"):
        return None, None
    try:
        xp, fp = series(dh, "Position", "downholeCard"), series(dh, "Load", "downholeCard")
    except ConfigError:
        xp = fp = np.zeros(0)
    if not (len(xp) == len(fp) and len(xp) >= 16 and np.all(np.isfinite(xp)) and np.all(np.isfinite(fp))
            and np.all(np.abs(xp) < 1e4) and np.all(np.abs(fp) < 1e7)):
        notes.append("downholeCard: not two finite lists of the same length (16 samples at least): the vendor's pump "
                     "card is not compared")
        return None, None
    back = loop_work(xp, fp) < 0
    return fu.to_si(xp[::-1] if back else xp, "in"), fu.to_si(fp[::-1] if back else fp, "lbf")
