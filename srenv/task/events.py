"""Field conditions as events within a ``srenv/SuckerRod-v2`` episode: when they start, how severe, what they do.

An episode's schedule is drawn at reset (:func:`draw_schedule`) from the episode's ``np_random``: the well
runs *normally* until a condition starts; the hazard of each condition while the well runs normally is its
rate in :data:`EVENTS` (per hour of well time, competing exponential clocks). A *transient* condition (gas
slug, heavy-oil period, flowing) lasts a drawn time and the well returns to normal; a *persistent* one (valve
leaks, tubing leak, tagging) lasts to the end of the episode, a *developing* one (valve leaks) growing
linearly from 0 to its drawn severity over ``ramp_h``. Rods part by fatigue, not by a clock of their own
(:class:`PartingClock`): their hazard is ``PARTING_RATE_PER_H`` x ``(G / 60 %)^4`` x the fraction of the hour
pumped, with G the interval's peak Goodman loading, so how hard a controller runs the rods moves it; they end
the episode (a workover). Severities
are drawn per episode, uniform in ``severity``, in [0, 1] (what 1 means is each condition's, in
:func:`condition_overrides`). One condition at a time: the privileged observation shows it one-hot.

Conditions change the physics at interval boundaries only (:func:`apply_condition`): the config overrides of
``srenv.physics.conditions.condition_overrides`` (the field-true card of each of the 12 labels; a local fallback
for gas and heavy oil when that module is absent) are applied to the running simulator, its state (rod,
annulus) kept. That physics changes the loads - the card the classifier reads - but not the simulator's volume
accounting, so the env books what the volumes and the damage do (:func:`bookkeeping`): the liquid a leak loses
falls back to the annulus (lost production, priced), tagging costs a share of a workover per stroke, parted rods
lift nothing in the interval they part in and end the episode. When the simulator accounts a label's lost
liquid itself, that label must leave :data:`BOOKED`, or the loss would count twice.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

LABELS = ("full", "fluid_pound", "gas_interference", "travelling_valve_leak", "standing_valve_leak",
          "both_valves_leak", "parted_rods", "tagging_up", "tagging_down", "tubing_leak", "heavy_oil", "flowing")
NORMAL = ("full", "fluid_pound")  # no event: the label the operation itself gives (fillage below POUND_FILLAGE)
POUND_FILLAGE = 0.85


@dataclass(frozen=True)
class EventSpec:
    rate_per_h: float                      # hazard while the well runs normally (1/h of well time)
    severity: tuple[float, float]          # drawn per episode, uniform
    duration_h: tuple[float, float] | None = None  # transient: drawn length; None: to the episode's end
    ramp_h: float = 0.0                    # developing: hours from 0 to the drawn severity


# Rates: a 12-h episode sees about one condition in two episodes (sum of rates 0.058/h -> 1 - exp(-0.70) = 50 %).
EVENTS: dict[str, EventSpec] = {
    "gas_interference": EventSpec(0.020, (0.2, 1.0), duration_h=(0.5, 3.0)),        # gas slug
    "heavy_oil": EventSpec(0.008, (0.3, 1.0), duration_h=(1.0, 4.0)),               # cold / emulsion period
    "flowing": EventSpec(0.004, (0.3, 1.0), duration_h=(0.5, 2.0)),                 # the well flows through the pump
    "travelling_valve_leak": EventSpec(0.008, (0.1, 0.6), ramp_h=4.0),              # develops
    "standing_valve_leak": EventSpec(0.006, (0.1, 0.6), ramp_h=4.0),                # develops
    "tubing_leak": EventSpec(0.004, (0.05, 0.4)),
    "tagging_down": EventSpec(0.008, (0.2, 1.0)),                                   # after a spacing drift
}
# Rods part at this hazard when pumping at the reference Goodman loading: about once in 10^4 h (a year and a
# bit), the field's order; expected workover cost 3 USD/h at 60 % (30 000 USD), 15 USD/h at 90 % loading.
# Rare in a 12-h episode on purpose: a visible rate would make the workover dominate every return.
PARTING_RATE_PER_H = 1.0e-4
PARTING_REFERENCE_GOODMAN_PCT = 60.0
PARTING_EXPONENT = 4.0


@dataclass
class PartingClock:
    """Rods part when the accumulated hazard crosses a unit-exponential budget drawn per episode."""

    budget: float
    used: float = 0.0

    @classmethod
    def draw(cls, rng: np.random.Generator) -> PartingClock:
        return cls(float(rng.exponential(1.0)))

    def advance(self, hours: float, pumping_fraction: float, goodman_pct: float, rate_scale: float = 1.0) -> bool:
        """Add one interval's hazard; True when the rods part in it."""
        load = max(goodman_pct, 0.0) / PARTING_REFERENCE_GOODMAN_PCT
        self.used += rate_scale * PARTING_RATE_PER_H * hours * pumping_fraction * load ** PARTING_EXPONENT
        return self.used >= self.budget

# Bookkeeping until the physics lands: fraction of the lifted liquid lost at severity 1 (falls back to the
# annulus), and the tagging damage. BOOKED lists the labels the env books itself (remove one when
# condition_overrides gives it physics).
LOST_FRACTION_AT_1 = {"travelling_valve_leak": 0.5, "standing_valve_leak": 0.5, "both_valves_leak": 0.7,
                      "tubing_leak": 1.0, "parted_rods": 1.0}
# of economics.workover_usd per stroke at severity 1: a workover every ~3 months of tagging at 8 SPM
TAG_WORKOVER_SHARE_PER_STROKE = 1e-6
BOOKED = frozenset(LOST_FRACTION_AT_1) | {"tagging_down", "tagging_up"}


@dataclass
class Event:
    label: str
    start_h: float
    end_h: float          # inf for persistent
    severity: float       # the drawn (final) severity
    ramp_h: float = 0.0

    def severity_at(self, t_h: float) -> float:
        if not self.start_h <= t_h < self.end_h:
            return 0.0
        if self.ramp_h > 0:
            return self.severity * min(1.0, (t_h - self.start_h) / self.ramp_h)
        return self.severity


@dataclass
class Schedule:
    events: list[Event] = field(default_factory=list)

    def active(self, t_h: float) -> tuple[str | None, float]:
        """The condition at well time t_h (h since the episode start) and its severity; (None, 0) if normal."""
        for ev in self.events:
            if ev.start_h <= t_h < ev.end_h:
                return ev.label, ev.severity_at(t_h)
        return None, 0.0


def draw_schedule(rng: np.random.Generator, horizon_h: float, rate_scale: float = 1.0) -> Schedule:
    """One episode's conditions: competing exponential clocks while normal (see the module docstring)."""
    names = list(EVENTS)
    rates = np.array([EVENTS[n].rate_per_h for n in names]) * rate_scale
    total = float(rates.sum())
    sched = Schedule()
    t = 0.0
    while total > 0:
        t += float(rng.exponential(1.0 / total))
        if t >= horizon_h:
            break
        name = names[int(rng.choice(len(names), p=rates / total))]
        spec = EVENTS[name]
        sev = float(rng.uniform(*spec.severity))
        if spec.duration_h is not None:
            end = t + float(rng.uniform(*spec.duration_h))
        else:
            end = math.inf
        sched.events.append(Event(name, t, end, sev, spec.ramp_h))
        if not math.isfinite(end):
            break  # persistent (or the end of the episode): nothing else starts
        t = end
    return sched


# ------------------------------------------------------------------------------------------- physics
def condition_overrides(label: str, severity: float, cfg: Any) -> dict[str, Any]:
    """Config overrides of a condition at a severity on the well ``cfg`` (its base, normal config).

    The conditions branch's ``srenv.physics.conditions.condition_overrides`` wins when it exists; the fallback
    covers what the physics has today."""
    try:
        from ..physics import conditions  # the conditions branch
    except ImportError:
        conditions = None
    if conditions is not None and hasattr(conditions, "condition_overrides"):
        return dict(conditions.condition_overrides(label, severity, cfg))
    if label == "gas_interference":
        return {"pump.intake_gas_fraction": round(0.2 + 0.7 * severity, 4)}
    if label == "heavy_oil":  # viscous drag on the rods and the plunger
        return {"damping.damping_factor": cfg.damping.damping_factor * (1.0 + 2.0 * severity),
                "pump.plunger_friction_n": cfg.pump.plunger_friction_n * (1.0 + 4.0 * severity)}
    return {}


def booked(label: str | None) -> bool:
    """Whether the env books this condition's volumes and damage itself: the conditions' physics changes the
    card (the loads: what the classifier sees), while the simulator's volume accounting does not see a leak's
    lost liquid, tagging damage or parted rods (:data:`BOOKED`)."""
    return label in BOOKED


def apply_condition(sim: Any, base_cfg: Any, label: str | None, severity: float,
                    extra: dict[str, Any] | None = None) -> None:
    """Put the simulator on the config of a condition (or back on ``base_cfg``), keeping its state.

    The condition's card-set settings for the reservoir (``inflow.*``: a full column so an isolated card cannot
    pump off) are left out: in an episode the well's own annulus and inflow carry on through a condition.
    ``extra``: overrides that win over the condition's (v3's leak fractions at the interval's setpoints)."""
    from ..config import load_config

    # parted rods end the episode in the interval they part in (the env books it): the base physics runs it
    over = condition_overrides(label, severity, base_cfg) if label not in (None, "parted_rods") else {}
    over.update(extra or {})
    over = {k: v for k, v in over.items() if not k.startswith("inflow.")}
    cfg = load_config(base_cfg, over) if over else base_cfg
    if cfg is sim.cfg or cfg == sim.cfg:
        return
    sim.switch_config(cfg, keep_annulus=True)


@dataclass
class Booking:
    lost_m3: float = 0.0       # liquid lifted but lost (falls back to the annulus)
    tag_damage: float = 0.0    # workovers' worth of tagging damage
    tag_strokes: float = 0.0


def bookkeeping(label: str | None, severity: float, lifted_m3: float, strokes: float) -> Booking:
    """What the env books for a condition without physics, over one interval (see :data:`BOOKED`)."""
    b = Booking()
    if not booked(label):
        return b
    if label in LOST_FRACTION_AT_1:
        b.lost_m3 = lifted_m3 * min(1.0, LOST_FRACTION_AT_1[label] * severity)
    if label in ("tagging_down", "tagging_up"):
        b.tag_strokes = strokes * severity
        b.tag_damage = TAG_WORKOVER_SHARE_PER_STROKE * b.tag_strokes
    return b


def true_label(label: str | None, fillage: float) -> str:
    """The condition label of an interval: the event's, else full or fluid pound by the true fillage."""
    if label is not None:
        return label
    return "fluid_pound" if np.isfinite(fillage) and fillage < POUND_FILLAGE else "full"
