"""The pump's state read off a pump card the way the field reads it: the two **load lines**, the fluid load
between them and the pump intake pressure it implies (docs/realism.md, "The pump's state from the record's
own diagnosis").

The rule (API RP 11L's fluid load F_o = (p_d - p_in) A_pl, read backwards, as dynamometer analysis does it:
Rowlan, Podio & McCoy, "Pump Intake Pressure Determined from Fluid Levels, Dynamometers, and Valve Test
Measurements", CIPC 2009-170; the vendor's export shows the same rule, 7699227's "Fluid Load" 3965 lbf =
(1885 - 239 psi) x 2.405 in^2):

    p_in = p_d + dp_valve - (F_o - 2 P_f) / A_pl,    F_o = (upstroke load line) - (downstroke load line),

with P_f the plunger's friction and dp_valve the travelling valve's opening overpressure where they are known
(srenv's valve law: F_o = (p_d - p_in + dp_valve) A_pl + 2 P_f; 0 when not known: then the whole fluid load is
read as pressure, the vendor's reading). A load line is where the analyst
draws it: the load the plunger carries while a valve stands open, not the card's extremes (the paper above:
PIPs from the card's maximum and minimum loads come out too low, the peaks and the ringing are not pressure).
Here it is the **median load over the middle half of the plunger travel for which that valve is open**:
- the upstroke: from the pickup (the first position on the way up where the load reaches the middle between
  the lines) to the top;
- the downstroke: from the transfer (the first position on the way down where the load falls to the middle) to
  the bottom, so a pump that does not fill reads its line below its transfer, not across it.
The middle is found from the card's 85th/10th load percentiles (``pump_card``'s levels) and refined with the
lines until it stops moving. The fillage is the transfer's end: the downstroke position where the load first
comes within ``FILL_BAND`` of the fluid load above the downstroke line (the travelling valve open; with free
gas the compression ends there, srenv's ``pump.fillage``), as a share of the plunger stroke above its bottom.
"""

from __future__ import annotations

import numpy as np

from .card_compare import stroke_branches

LINE_BAND = (0.25, 0.75)   # the middle half of each valve's open travel
FILL_BAND = 0.10           # the transfer ends within 10 % of the fluid load above the downstroke line
MAX_PASSES = 6
LINE_TOLERANCE = 1e-4      # lines settled: the middle moves less than this share of the fluid load


def _open_median(x: np.ndarray, f: np.ndarray, x_from: float, x_to: float) -> float:
    """Median load over the middle half (LINE_BAND) of the travel x_from..x_to (either order)."""
    lo, hi = sorted((x_from, x_to))
    a, b = lo + LINE_BAND[0] * (hi - lo), lo + LINE_BAND[1] * (hi - lo)
    inside = (x >= a) & (x <= b)
    if not inside.any():  # a valve open over less than a sample or two: the whole open travel
        inside = (x >= lo) & (x <= hi)
    return float(np.median(f[inside])) if inside.any() else float(np.median(f))


def _first_crossing(x: np.ndarray, f: np.ndarray, level: float, rising: bool) -> float:
    """Position of the first sample along the branch whose load reaches `level` (from below when rising)."""
    hit = f >= level if rising else f <= level
    return float(x[int(np.argmax(hit))]) if hit.any() else float(x[-1])


def load_lines(position_m, load_n) -> dict:
    """The upstroke and downstroke load lines of one stroke's pump card (position upward, load tension
    positive, any convention: the lines move with it, their difference does not), the fluid load between
    them, the pickup and transfer positions and the fillage (module docstring)."""
    x = np.asarray(position_m, dtype=float)
    f = np.asarray(load_n, dtype=float)
    (xu, fu), (xd, fd) = stroke_branches(x, f)
    bottom, top = float(x.min()), float(x.max())
    hi, lo = (float(v) for v in np.percentile(f, (85.0, 10.0)))
    for _ in range(MAX_PASSES):
        mid = 0.5 * (hi + lo)
        pickup = _first_crossing(xu, fu, mid, rising=True)
        transfer = _first_crossing(xd, fd, mid, rising=False)
        new_hi, new_lo = _open_median(xu, fu, pickup, top), _open_median(xd, fd, transfer, bottom)
        settled = abs(0.5 * (new_hi + new_lo) - mid) <= LINE_TOLERANCE * max(abs(new_hi - new_lo), 1.0)
        hi, lo = new_hi, new_lo
        if settled:
            break
    fluid = hi - lo
    stroke = top - bottom
    end = _first_crossing(xd, fd, lo + FILL_BAND * fluid, rising=False) if fluid > 0 else bottom
    fillage = float(np.clip((end - bottom) / stroke, 0.0, 1.0)) if stroke > 0 else 0.0
    return {"upstroke_line_n": hi, "downstroke_line_n": lo, "fluid_load_n": fluid,
            "pickup_m": pickup - bottom, "transfer_m": transfer - bottom, "fillage": fillage}


def intake_pressure_pa(fluid_load_n: float, discharge_pressure_pa: float, plunger_area_m2: float,
                       plunger_friction_n: float = 0.0, overpressure_pa: float = 0.0) -> float:
    """p_in = p_d + dp_valve - (F_o - 2 P_f) / A_pl (module docstring); not clipped: below 0 says the
    diagnosed fluid load exceeds what the column above the pump can put on the plunger."""
    return float(discharge_pressure_pa + overpressure_pa - (fluid_load_n - 2.0 * plunger_friction_n) / plunger_area_m2)


def read_pump_state(position_m, load_n, discharge_pressure_pa: float, plunger_area_m2: float,
                    plunger_friction_n: float = 0.0, overpressure_pa: float = 0.0) -> dict:
    """The load lines and the intake pressure they imply (``intake_pressure_pa``, unclipped), in one dict."""
    lines = load_lines(position_m, load_n)
    p_in = intake_pressure_pa(lines["fluid_load_n"], discharge_pressure_pa, plunger_area_m2, plunger_friction_n,
                              overpressure_pa)
    return {**lines, "intake_pressure_pa": p_in, "discharge_pressure_pa": float(discharge_pressure_pa)}
