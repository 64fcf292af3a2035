"""What a diagnosed pump card says about the pump's load transfers and the top of its upstroke
(docs/realism.md, "The top of 11708328's upstroke and its ring"). Read off the diagnosis, never the
surface card; each rule was fixed before the figures it feeds were measured.

- The plateaus: the upstroke's and the downstroke's median loads over 25-75 % of the plunger's travel.
- **Transfer travel**: the plunger's travel while the load moves 10 -> 90 % of the way between the plateaus:
  ``up`` (the bottom, the travelling valve closing) from the last sample near the downstroke's level to the
  first after it near the upstroke's; ``down`` (the top) from the first sample after the top below 90 % to the
  first after it below 10 %. A rigid valve law gives 0 (srenv's diagnosis of srenv's own card resolves it
  within 0.1 cm on both field records).
- **Series stiffness**: the spring in series with the pump the upstroke's transfer shows, 80 % of the step
  between the plateaus over its travel (the tubing's stretch when it is free; the chamber's contents).
- **Clearance gas**: the gas share psi of the clearance at p_d whose re-expansion to p_in takes the upstroke
  transfer's 10 -> 90 % travel (``pump.clearance_gas_fraction``): at the load's 10 % the chamber is at
  p_10 = p_d - 0.1 (p_d - p_in), at 90 % at p_90 = p_in + 0.1 (p_d - p_in), so the travel is
  psi V_d ((p_d / p_90)^(1/k) - (p_d / p_10)^(1/k)) / A_pl, the clearance's liquid neglected; at most 1.
- **Tagging up**: an upstroke whose top 15 % (median) climbs above its plateau by more than 10 % of the card's
  load range is read as a contact with the pump's top: from x_c, the highest position below that band whose
  load is still within 10 % of the climb of the plateau, to the top; the overtravel is the travel above x_c
  and the stiffness the climb over it (``pump.tag_top_overtravel_m``, ``pump.tag_stiffness_n_m``).
"""

from __future__ import annotations

import numpy as np

from .card_compare import stroke_branches

MIN_TRAVEL_M = 1e-3  # a transfer shorter than this is read as rigid (no series spring)


def upstroke(x: np.ndarray, f: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The card's rising part, from its lowest to its highest position (positions from the bottom)."""
    xu, fu = stroke_branches(x, f)[0]
    return xu - x.min(), fu


def downstroke(x: np.ndarray, f: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    xd, fd = stroke_branches(x, f)[1]
    return xd - x.min(), fd


def band_median(x: np.ndarray, f: np.ndarray, lo: float, hi: float) -> float:
    """Median load over the positions lo..hi (shares of the branch's travel)."""
    top = x.max()
    return float(np.median(f[(x >= lo * top) & (x <= hi * top)]))


def plateaus(x: np.ndarray, f: np.ndarray) -> tuple[float, float]:
    """(upstroke, downstroke) plateau loads."""
    return band_median(*upstroke(x, f), 0.25, 0.75), band_median(*downstroke(x, f), 0.25, 0.75)


def transfer_samples(x: np.ndarray, f: np.ndarray) -> tuple[int, tuple[int, int, int, int]]:
    """The card's top sample and, counted from it, the samples that bound the two transfers: downstroke
    start and end, upstroke start and end (module docstring)."""
    f_up, f_down = plateaus(x, f)
    lo, hi = f_down + 0.1 * (f_up - f_down), f_down + 0.9 * (f_up - f_down)
    top = int(np.argmax(x))
    fr = np.roll(f, -top)  # one cycle from the top: downstroke, then upstroke
    a = int(np.argmax(fr <= hi))
    b = a + int(np.argmax(fr[a:] <= lo))
    c = int(np.nonzero(fr <= lo)[0][-1])
    return top, (a, b, c, c + int(np.argmax(fr[c:] >= hi)))


def transfer_travel_m(x: np.ndarray, f: np.ndarray) -> dict:
    """Plunger travel of the upstroke's (``up``) and the downstroke's (``down``) load transfer."""
    top, (a, b, c, d) = transfer_samples(x, f)
    xr = np.roll(x, -top)
    return {"up": float(xr[d] - xr[c]), "down": float(xr[a] - xr[b])}


def series_stiffness_n_m(x: np.ndarray, f: np.ndarray) -> float | None:
    """The spring in series with the pump that the upstroke's transfer shows; None for a rigid transfer."""
    f_up, f_down = plateaus(x, f)
    travel = transfer_travel_m(x, f)["up"]
    return 0.8 * (f_up - f_down) / travel if travel >= MIN_TRAVEL_M and f_up > f_down else None


def tag_from_diagnosis(x: np.ndarray, f: np.ndarray) -> dict | None:
    """Tagging up read off a pump card (module docstring); None when its upstroke does not climb."""
    xu, fu = upstroke(x, f)
    top = float(xu.max())
    f_mid, f_top = band_median(xu, fu, 0.25, 0.75), band_median(xu, fu, 0.85, 1.0)
    climb = f_top - f_mid
    if climb <= 0.1 * float(np.ptp(f)):
        return None
    first_top = int(np.nonzero(xu >= 0.85 * top)[0][0])
    x_c = float(xu[np.nonzero(fu[:first_top + 1] <= f_mid + 0.1 * climb)[0][-1]])
    return {"climb_start_m": x_c, "travel_m": top, "plateau_n": f_mid, "climb_n": climb,
            "tag_top_overtravel_m": top - x_c, "tag_stiffness_n_m": climb / (top - x_c)}


def clearance_gas_fraction(travel_up_m: float, p_in_pa: float, p_d_pa: float, clearance_m: float,
                           exponent: float = 1.0) -> float:
    """The clearance's gas share at p_d that the upstroke's transfer travel shows (module docstring);
    ``clearance_m`` is the clearance volume over the plunger's area. 0 for a rigid transfer."""
    if not travel_up_m >= MIN_TRAVEL_M or not p_d_pa > p_in_pa > 0:
        return 0.0
    dp = p_d_pa - p_in_pa
    span = (p_d_pa / (p_in_pa + 0.1 * dp)) ** (1.0 / exponent) - (p_d_pa / (p_d_pa - 0.1 * dp)) ** (1.0 / exponent)
    return float(min(travel_up_m / (clearance_m * span), 1.0))
