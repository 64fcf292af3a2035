"""Reading a pump (downhole) card: load levels, fillage, load-transfer interval and the card class.

Works on any one-stroke pump card (simulated or diagnosed), position upward and load tension positive:
- levels: the upstroke (fluid-load) plateau ``upstroke_load_n`` (85th percentile of the load) and the
  downstroke plateau ``downstroke_load_n`` (10th percentile); ``fluid_load_n`` their difference;
- fillage: on the downstroke, the plunger position where the load first falls through the middle of the two
  levels, as a fraction of the plunger stroke above the bottom (the travelling valve opens when the plunger
  meets liquid; a full pump transfers at the top: fillage 1);
- transfer interval: the plunger travel between 90 % and 10 % of the transfer on the downstroke: short for a
  full pump and for fluid pound (the plunger hits liquid), long for gas interference (the gas in the chamber
  is compressed to the discharge pressure before the valve opens);
- class: ``full`` (fillage >= FULL_FILLAGE), ``fluid_pound`` (sharp transfer), ``gas_interference``
  (transfer spread over more than GAS_TRANSFER_FRACTION of the stroke), ``no_fluid_load`` (the two levels
  within NO_LOAD_FRACTION of the upstroke level: leaking valves, pumped off, parted rods).
"""

from __future__ import annotations

import numpy as np

CARD_CLASSES = ("full", "fluid_pound", "gas_interference", "no_fluid_load")
FULL_FILLAGE = 0.9
GAS_TRANSFER_FRACTION = 0.12
NO_LOAD_FRACTION = 0.05


def _crossing(x: np.ndarray, f: np.ndarray, level: float) -> float:
    """Position where f first falls to `level` along the samples (linear between samples)."""
    below = f <= level
    i = int(np.argmax(below))
    if not below[i]:
        return float(x[-1])
    if i == 0:
        return float(x[0])
    a = (f[i - 1] - level) / (f[i - 1] - f[i])
    return float(x[i - 1] + a * (x[i] - x[i - 1]))


def analyse_pump_card(position_m: np.ndarray, load_n: np.ndarray) -> dict:
    x = np.asarray(position_m, dtype=float)
    f = np.asarray(load_n, dtype=float)
    # the two percentiles by one partial sort (np.percentile's 'linear' rule; this runs on every env step)
    m = len(f) - 1
    q = (0.10 * m, 0.85 * m)
    lo_i = [int(np.floor(v)) for v in q]
    part = np.partition(f, sorted({*lo_i, *(min(i + 1, m) for i in lo_i)}))
    down, up = (float(part[i] + (v - i) * (part[min(i + 1, m)] - part[i])) for i, v in zip(lo_i, q))
    fluid = up - down
    x_min, x_max = float(x.min()), float(x.max())
    stroke = x_max - x_min
    out = {"pump_stroke_m": stroke, "upstroke_load_n": up, "downstroke_load_n": down, "fluid_load_n": fluid}
    if not stroke > 0 or fluid <= NO_LOAD_FRACTION * max(abs(up), abs(down), 1.0):
        out.update(fillage=0.0, transfer_interval_m=0.0, card_class="no_fluid_load")
        return out
    # the downstroke: from the top of the plunger travel to the following bottom (the card is periodic)
    i_top = int(np.argmax(x))
    i_min = int(np.argmin(x))
    if i_min >= i_top:  # the downstroke lies inside the record
        xd, fd = x[i_top:i_min + 1], f[i_top:i_min + 1]
    else:  # it wraps round the end of the (periodic) record
        xd, fd = np.r_[x[i_top:], x[:i_min + 1]], np.r_[f[i_top:], f[:i_min + 1]]
    x_mid = _crossing(xd, fd, down + 0.5 * fluid)
    x90 = _crossing(xd, fd, down + 0.9 * fluid)
    x10 = _crossing(xd, fd, down + 0.1 * fluid)
    fillage = float(np.clip((x_mid - x_min) / stroke, 0.0, 1.0))
    width = max(0.0, x90 - x10)
    if fillage >= FULL_FILLAGE:
        cls = "full"
    elif width > GAS_TRANSFER_FRACTION * stroke:
        cls = "gas_interference"
    else:
        cls = "fluid_pound"
    out.update(fillage=fillage, transfer_interval_m=width, card_class=cls)
    return out
