"""Opt-in: the fast-forward's annulus drained by the pump's own draw (docs/speed.md §2i).

``IntervalRunner(draw_follows_pump=True)`` (False, the default, is off: v1's and v2's results do not move). A
fast-forward repeats one stroke and, off, drains the annulus by that stroke's displacement at every stroke (the
pump draws ``min(displacement, liquid)``). The displacement is the plunger's stroke in the barrel, which the rod's
stretch under the plunger's fluid load shortens: as the annulus drains, the intake pressure falls, the load grows
and every exact stroke draws a little less, while the repeated stroke keeps the displacement of the pressure it
ran at. Over an interval at full speed that is ~0.1 L of extra drain (train well 77), a fifth of a stroke's liquid
by a pump-off onset, where the first partial stroke's fill, and its pound, is set by exactly that remainder
(§2h: fill 0.37 against every stroke's 0.54).

On, each fast-forwarded stroke's displacement is the repeated stroke's moved to the annulus' current intake
pressure by the string's static stretch: d(displacement)/d(p_intake) = A_plunger^2 / k_string (the fluid load
A (p_discharge - p_intake) over the string's stiffness; within 1 % of the exact strokes' on train wells 77 and
12, 15 % shallower on 40, 1.8x steeper on 11). The fill is then the exact stroke's rule: the pump takes what the annulus holds at the upstroke's end, up to
that displacement (times the free gas's share, as before). Designed on train wells 11, 12, 40, 77 (§2i): the
carry's measured slope of the displacement instead of the static one was worse there (two kept strokes far apart
carry their scatter), and re-planning the upstroke after a fast-forward changed nothing (not kept).
"""

from __future__ import annotations

from ..physics.pump import plunger_area_m2


def check(draw_follows_pump) -> bool:
    """The option, validated (runner_options.check_option: TypeError naming it, its value and what was expected)."""
    from .runner_options import check_option

    return check_option("draw_follows_pump", draw_follows_pump)


def displacement_rule(runner, displacement_m3: float):
    """The displacement a stroke repeating one of ``displacement_m3`` has at intake pressure p (a function of p),
    the repeated stroke taken at the annulus' pressure now (the fast-forward starts where it ran or was carried)."""
    area = plunger_area_m2(runner.sim.cfg.pump)
    slope, p_ref = area * area / runner.stiffness, runner._intake_pa()
    return lambda p: max(displacement_m3 + slope * (p - p_ref), 0.0)
