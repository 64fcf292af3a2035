"""``srenv/SuckerRod-v3``'s leaks: the liquid a leaking valve or a hole in the tubing loses, from the leak's
own model instead of v2's fixed shares (:data:`srenv.task.events.LOST_FRACTION_AT_1`).

**Valves.** A closed valve passes q = C dp (srenv.physics.laws.pump_conditions): with dp the fluid load's
pressure, constant while the valve is closed, the leak is a plunger speed ``v_leak = C dp / A_pl`` (m/s)
set by the valve's wear. The condition's card (``srenv.physics.conditions.condition_overrides``) gives it as
the fraction ``f0 = v_leak / v_peak`` at the drawn severity; v3 fixes ``v_leak`` in m/s at the condition's
*onset* (``f0`` at the onset interval's stroke rate and length: the severity means what it means today) and
sets the config's fraction at every interval boundary from the interval's own setpoints,
``f = f0 (S0 N0) / (S N)`` (the nominal peak speed ``v_peak = pi S N / 60`` of the surface stroke S at N SPM;
a developing leak's ``f0`` grows with its severity). The liquid lost is the share of the plunger's
displacement the leak passes while the valve is closed, over the law's nominal speed profile
``v = v_peak sin(theta)`` (the law's ``v_peak sqrt(4 xi (1 - xi))`` in time):
``share(r) = int min(v, v_leak) dt / int v dt = 1 - sqrt(1 - r^2) + r (pi / 2 - asin r)`` for
``r = v_leak / v_peak < 1``, 1 from ``r = 1`` on (the plunger lifts nothing; the card carries no fluid load
then either). It rises with r: pumping faster (or longer strokes) loses a smaller share. Both valves leaking:
``1 - (1 - share_tv) (1 - share_sv)``.

**Tubing.** A hole drains the column at a rate per hour whatever the pump does: ``Q_hole`` (m3/h) is fixed at
the onset as the card's ``pump.tubing_leak_fraction`` (0.8 x severity) of the pump's displacement rate at the
onset's setpoints, ``A_pl S0 N0 60``; an interval loses ``min(lifted, Q_hole x hours)``. The card keeps v2's
law (the share of the fluid load lost over the upstroke).
"""

from __future__ import annotations

import math
from typing import Any

from ..physics.pump import plunger_area_m2

VALVE_KEYS = {"travelling_valve_leak": ("pump.travelling_valve_leak_fraction",),
              "standing_valve_leak": ("pump.standing_valve_leak_fraction",),
              "both_valves_leak": ("pump.travelling_valve_leak_fraction", "pump.standing_valve_leak_fraction")}
TUBING_KEY = "pump.tubing_leak_fraction"
# the labels whose lost liquid v3 takes from these models (never also from v2's fixed shares)
ACCOUNTED = frozenset(VALVE_KEYS) | {"tubing_leak"}
FRACTION_DIGITS = 6  # the fraction is rounded: the same setpoints give the same config (the env reuses strokes)


def peak_speed_m_s(spm: float, stroke_m: float) -> float:
    """The nominal (harmonic) peak speed of a stroke of ``stroke_m`` at ``spm`` strokes/min, m/s."""
    return math.pi * stroke_m * spm / 60.0


def valve_overrides(label: str | None, over: dict[str, Any], onset: tuple[float, float],
                    now: tuple[float, float]) -> dict[str, float]:
    """The valve-leak fractions of the condition's overrides ``over`` (its card at the severity) moved from the
    onset's setpoints ``onset`` (SPM, stroke m) to the interval's ``now``: v_leak in m/s kept (module docstring)."""
    ratio = peak_speed_m_s(*onset) / peak_speed_m_s(*now)
    return {k: round(float(over[k]) * ratio, FRACTION_DIGITS) for k in VALVE_KEYS.get(label, ()) if k in over}


def passed_share(r: float) -> float:
    """Share of the plunger's displacement a leak of speed ``r`` x the peak speed passes over a half stroke
    of the nominal profile (module docstring); 0 without a leak, 1 from r = 1 on."""
    if r <= 0.0:
        return 0.0
    if r >= 1.0:
        return 1.0
    return 1.0 - math.sqrt(1.0 - r * r) + r * (math.pi / 2.0 - math.asin(r))


def valve_lost_m3(pump: Any, lifted_m3: float) -> float:
    """The lifted liquid a leaking travelling and / or standing valve loses, from the fractions of the config
    the interval ran (``pump``: its pump section)."""
    kept = (1.0 - passed_share(pump.travelling_valve_leak_fraction)) * (
        1.0 - passed_share(pump.standing_valve_leak_fraction))
    return lifted_m3 * (1.0 - kept)


def hole_rate_m3_h(over: dict[str, Any], pump: Any, onset: tuple[float, float]) -> float:
    """The hole's drain rate (m3/h), fixed at the onset: the card's tubing-leak fraction of the pump's
    displacement rate at the onset's setpoints (SPM, stroke m)."""
    spm, stroke_m = onset
    return float(over.get(TUBING_KEY, 0.0)) * plunger_area_m2(pump) * stroke_m * spm * 60.0


def hole_lost_m3(rate_m3_h: float, hours: float, lifted_m3: float) -> float:
    """What the hole drains in an interval: its rate over the interval's hours, at most what was lifted."""
    return min(lifted_m3, max(rate_m3_h, 0.0) * hours)
