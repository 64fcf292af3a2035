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


def fatigue_damage(goodman_pct: float, exponent: float, life_cycles: float) -> float:
    """A stroke's fatigue damage from its Goodman loading in %: (G/100)^m / life (economics.fatigue_*)."""
    return (max(goodman_pct, 0.0) / 100.0) ** exponent / life_cycles


# --- the opt-in stepping options (IntervalRunner(exact_min=K, follow_drift=True); docs/speed.md §2g) ---

def mean_stroke(strokes: list):
    """One stroke standing for ``strokes`` (figures of one setpoint): each per-stroke figure their mean, the
    impact speed their root mean square (the pound term sums its square), the card and summary the last's.
    A fast-forward repeating it books the strokes' mean where repeating the last books one stroke's scatter."""
    if len(strokes) == 1:
        return strokes[0]
    new = {k: sum(getattr(f, k) for f in strokes) / len(strokes) for k in SCALARS}
    new["impact_m_s"] = (sum(f.impact_m_s ** 2 for f in strokes) / len(strokes)) ** 0.5
    return dataclasses.replace(strokes[-1], **new)


def drift(f, s: Slopes, p_f: float, weight: float, p_start: float, p_end: float,
          damage_of=None) -> tuple[dict, list]:
    """What ``weight`` fast-forwarded strokes repeating ``f`` (figures at intake pressure ``p_f``) book too much
    or too little when the intake pressure moved from ``p_start`` to ``p_end`` over them: the figures at the run's
    mean pressure (the level moves near-linearly over a run) less ``f``'s, times ``weight``, per interval sum; and
    the summaries at the run's two ends for the peaks. ``damage_of(goodman_pct)``: the fatigue damage a stroke of
    that Goodman loading does (a power law: carried linearly it falls behind as the loading grows), averaged over
    the run by Simpson's rule."""
    ends = [carried(f, s, p - p_f) for p in (p_start, p_end)]
    g = carried(f, s, 0.5 * (p_start + p_end) - p_f)
    damage = g.damage
    if damage_of is not None:
        damage = sum(w * damage_of(h.summary["goodman_max_pct"]) for w, h in zip((1, 4, 1), (ends[0], g, ends[1])))
        damage /= 6.0
    sums = {"work_j": g.work_j - f.work_j, "damage": damage - f.damage, "stick_slip_j": g.stick_slip_j
            - f.stick_slip_j, "impact_sq_sum": g.impact_m_s ** 2 - f.impact_m_s ** 2,
            "impact_sum": g.impact_m_s - f.impact_m_s}
    return {k: weight * v for k, v in sums.items()}, [h.summary for h in ends]
