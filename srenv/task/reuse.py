"""A converged stroke carried to a nearby intake pressure (v2's fast stepping, docs/speed.md).

At one setpoint and one physics, a converged stroke's figures are smooth functions of the pump's intake
pressure (the plunger's fluid load and the liquid it finds) while the pump fills. Two strokes kept at intake
pressures p_a and p_b give each figure's slope; a stroke at a pressure p within the span of that pair beyond
its nearer end (``EXTRAPOLATE``) is the nearer stroke's figures moved along the slopes, its card unchanged.
The error of the scheme against simulating every stroke is measured by srenv.tools.stepping_error.
"""

from __future__ import annotations

import dataclasses

# how far past the kept pair a stroke is carried, as a fraction of the pair's pressure span; and the smallest
# span that gives a slope, as a fraction of the plunger's fluid load change over the stroke's PPRL (closer
# strokes differ by their stroke-to-stroke scatter more than by the pressure)
EXTRAPOLATE = 3.0
MIN_SPAN_LOAD_FRACTION = 0.001
SCALARS = ("lifted_m3", "displacement_m3", "fillage", "fillage_est", "work_j", "damage", "stick_slip_j",
           "impact_m_s", "power_mean_w", "power_peak_w")
SUMMARY = ("pprl_n", "mprl_n", "goodman_max_pct", "gearbox_loading_pct")
NONNEGATIVE = ("lifted_m3", "displacement_m3", "fillage", "fillage_est", "damage", "stick_slip_j", "impact_m_s")


@dataclasses.dataclass(frozen=True)
class Slopes:
    """d(figure)/d(intake pressure) between two converged strokes kept at p_a and p_b (p_b the later)."""

    p_a: float
    p_b: float
    of: dict

    def reaches(self, p: float) -> bool:
        span = abs(self.p_b - self.p_a)
        return min(abs(p - self.p_a), abs(p - self.p_b)) <= EXTRAPOLATE * span


def slopes(a, p_a: float, b, p_b: float) -> Slopes:
    """The slopes between stroke figures ``a`` at intake pressure p_a and ``b`` at p_b (p_a != p_b)."""
    dp = p_b - p_a
    of = {k: (getattr(b, k) - getattr(a, k)) / dp for k in SCALARS}
    of.update({k: (b.summary.get(k, 0.0) - a.summary.get(k, 0.0)) / dp for k in SUMMARY})
    return Slopes(p_a, p_b, of)


def carried(f, s: Slopes, dp: float):
    """Stroke figures ``f`` moved by ``dp`` Pa of intake pressure along the slopes ``s``; the card (trace) and the
    rest of the summary stay ``f``'s. Figures that cannot be negative are clipped at 0, the fillages at 1."""
    new = {k: getattr(f, k) + s.of[k] * dp for k in SCALARS}
    for k in NONNEGATIVE:
        new[k] = max(new[k], 0.0)
    new["fillage"], new["fillage_est"] = min(new["fillage"], 1.0), min(new["fillage_est"], 1.0)
    summary = dict(f.summary)
    summary.update({k: f.summary[k] + s.of[k] * dp for k in SUMMARY if k in f.summary})
    return dataclasses.replace(f, summary=summary, **new)
