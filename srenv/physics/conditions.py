"""The twelve pump conditions a production engineer diagnoses from a card, as config overrides.

:func:`condition_overrides` puts a well into a condition at a severity in [0, 1]: dotted config keys (the
keys ``srenv simulate --set key.path=value`` takes) -> values. Severity 0 gives the full-pump card for
every label; every label first applies the *full* base (a liquid column over the pump, so the well does
not pound unless asked to). The mechanisms (docs/conditions.md):

=====================  ===========================================================================
full                   the well's own pump, liquid over it
fluid_pound            inflow per stroke ``1 - 0.8 s`` of the pump's displacement (pump-off, annulus empty)
gas_interference       free gas in the intake mixture, volume fraction ``0.1 + 0.6 s`` (polytropic chamber)
travelling_valve_leak  ``pump.travelling_valve_leak_fraction = 2.5 s`` (laws.pump_conditions)
standing_valve_leak    ``pump.standing_valve_leak_fraction = 2.5 s``
both_valves_leak       both, ``1.5 s`` each
parted_rods            the string parted at ``1 - 0.9 s`` of its length (s > 0): only the rods above
tagging_up             the pump's top ``0.02 + 0.08 s`` x stroke inside the plunger's free upstroke
tagging_down           the pump's bottom the same inside its free downstroke
tubing_leak            ``pump.tubing_leak_fraction = 0.8 s`` of the fluid load lost over the upstroke
heavy_oil              viscous rods (Gibbs factor + ``0.3 + 0.7 s``) and plunger friction + ``0.3 s`` x fluid load
flowing                ``pump.flow_through_fraction = 0.9 s`` of the fluid load lifted by the well's flow
=====================  ===========================================================================
"""

from __future__ import annotations

import dataclasses
import math

LABELS = ("full", "fluid_pound", "gas_interference", "travelling_valve_leak", "standing_valve_leak",
          "both_valves_leak", "parted_rods", "tagging_up", "tagging_down", "tubing_leak", "heavy_oil", "flowing")

GRAVITY_M_S2 = 9.80665
FULL_LEVEL_M = 150.0           # liquid column over the pump of a full well (it cannot pump off in a few strokes)
POUND_HEAD_PA = 2.0e6          # reservoir pressure above the casing's of a pounding well's linear inflow
PLUNGER_STROKE_SHARE = 0.85    # plunger stroke / surface stroke used to size the pounding inflow
PARTED_DRAG_N = 200.0          # fluid drag on the parted string's free end (a valve-less "pump")
MIN_REMAINING_M = 50.0         # the parted string keeps at least this length


def _well(well):
    from ..config import WellConfig, load_config

    if well is None:
        return load_config("default")
    if isinstance(well, WellConfig):
        return well
    return load_config(well)


def check_label(label: str) -> str:
    if label not in LABELS:
        raise ValueError(f"condition = {label!r}: expected one of {', '.join(LABELS)}")
    return label


def check_severity(severity: float) -> float:
    s = float(severity)
    if not 0.0 <= s <= 1.0:
        raise ValueError(f"severity = {severity!r}: expected a number in [0, 1]")
    return s


def fluid_load_n(cfg) -> float:
    """The fluid load P- - P+ (N), from the loads or from the column over the gross plunger area."""
    if cfg.pump.load_source == "loads":
        return cfg.pump.upstroke_load_n - cfg.pump.downstroke_load_n
    a_pl = math.pi / 4 * (cfg.pump.plunger_diameter_mm * 1e-3) ** 2
    return cfg.fluid.density_kg_m3 * GRAVITY_M_S2 * cfg.rod_length_m * a_pl


def full_base(cfg) -> dict[str, object]:
    """A liquid column over the pump: no pump-off within the strokes of a card."""
    if cfg.inflow.model == "none":
        return {}
    return {"inflow.initial_fluid_level_m": max(cfg.inflow.initial_fluid_level_m, FULL_LEVEL_M)}


def as_pressures(cfg) -> dict[str, object]:
    """A well given by its two loads, restated by pressures (same P- and P+ in a vertical well) so that an
    intake pressure can set the load (inflow, free gas); {} for a well already given by pressures."""
    p = cfg.pump
    if p.load_source == "pressures":
        return {}
    a_pl = math.pi / 4 * (p.plunger_diameter_mm * 1e-3) ** 2
    a_rod = math.pi / 4 * (cfg.rod.tapers[-1].diameter_mm * 1e-3) ** 2
    p_out = cfg.fluid.wellhead_pressure_pa + cfg.fluid.density_kg_m3 * GRAVITY_M_S2 * cfg.rod_length_m
    p_in = p_out - (p.upstroke_load_n + p_out * a_rod - p.plunger_friction_n) / a_pl
    over = max(-(p.downstroke_load_n + p_out * a_rod + p.plunger_friction_n) / a_pl, 0.0)
    return {"pump.load_source": "pressures", "pump.intake_pressure_pa": round(max(p_in, 1.0e5), 1),
            "pump.discharge_overpressure_pa": round(over, 1), "pump.law": "constant"}


def _pound(cfg, s: float) -> dict[str, object]:
    a_pl = math.pi / 4 * (cfg.pump.plunger_diameter_mm * 1e-3) ** 2
    rate = ((1.0 - 0.8 * s) * a_pl * PLUNGER_STROKE_SHARE * cfg.surface.stroke_length_m * cfg.surface.spm
            * 1440.0)
    return {**as_pressures(cfg), "inflow.model": "linear", "inflow.initial_fluid_level_m": 0.0,
            "inflow.reservoir_pressure_pa": cfg.inflow.casing_pressure_pa + POUND_HEAD_PA,
            "inflow.productivity_index_m3_day_pa": rate / POUND_HEAD_PA}


def _parted(cfg, s: float) -> dict[str, object]:
    keep = max((1.0 - 0.9 * s) * cfg.rod_length_m, MIN_REMAINING_M)
    tapers, left = [], keep
    for t in cfg.rod.tapers:  # top-down: keep what lies above the break
        if left <= 0:
            break
        d = dataclasses.asdict(t)
        d["length_m"] = round(min(t.length_m, left), 3)
        left -= t.length_m
        if d["length_m"] >= 1.0:
            tapers.append(d)
    return {"rod.tapers": tapers, "pump.load_source": "loads", "pump.upstroke_load_n": PARTED_DRAG_N,
            "pump.downstroke_load_n": -PARTED_DRAG_N, "pump.intake_gas_fraction": 0.0,
            "pump.intake_glr_m3_m3": 0.0, "inflow.model": "none"}


def condition_overrides(label: str, severity: float, well=None) -> dict[str, object]:
    """Dotted config keys -> values putting ``well`` (a WellConfig, a config name or path; None: the default
    well) into condition ``label`` at ``severity`` in [0, 1] (0: the full-pump card)."""
    check_label(label)
    s = check_severity(severity)
    cfg = _well(well)
    out = full_base(cfg)
    if s == 0.0 or label == "full":
        return out
    stroke = cfg.surface.stroke_length_m
    if label == "fluid_pound":
        out.update(_pound(cfg, s))
    elif label == "gas_interference":
        out.update({**as_pressures(cfg), "pump.intake_gas_fraction": round(0.1 + 0.6 * s, 6),
                    "pump.intake_glr_m3_m3": 0.0})
    elif label == "travelling_valve_leak":
        out["pump.travelling_valve_leak_fraction"] = 2.5 * s
    elif label == "standing_valve_leak":
        out["pump.standing_valve_leak_fraction"] = 2.5 * s
    elif label == "both_valves_leak":
        out.update({"pump.travelling_valve_leak_fraction": 1.5 * s, "pump.standing_valve_leak_fraction": 1.5 * s})
    elif label == "parted_rods":
        out.update(_parted(cfg, s))
    elif label == "tagging_up":
        out["pump.tag_top_overtravel_m"] = round((0.02 + 0.08 * s) * stroke, 6)
    elif label == "tagging_down":
        out["pump.tag_bottom_overtravel_m"] = round((0.02 + 0.08 * s) * stroke, 6)
    elif label == "tubing_leak":
        out["pump.tubing_leak_fraction"] = 0.8 * s
    elif label == "heavy_oil":
        out.update({"damping.model": "dimensionless",
                    "damping.damping_factor": round(cfg.damping.damping_factor + 0.3 + 0.7 * s, 6),
                    "pump.plunger_friction_n": round(cfg.pump.plunger_friction_n + 0.3 * s * fluid_load_n(cfg), 3)})
    elif label == "flowing":
        out["pump.flow_through_fraction"] = 0.9 * s
    return out


def condition_of(cfg) -> str:
    """The condition a config sets (the first that applies), for the stroke summary and the env's info;
    fluid pound follows the run (pump-off) and is named by the card class instead."""
    p = cfg.pump
    if p.load_source == "loads" and abs(p.upstroke_load_n - p.downstroke_load_n) <= 2 * PARTED_DRAG_N:
        return "parted_rods"
    if p.travelling_valve_leak_fraction > 0 and p.standing_valve_leak_fraction > 0:
        return "both_valves_leak"
    for field, label in (("travelling_valve_leak_fraction", "travelling_valve_leak"),
                         ("standing_valve_leak_fraction", "standing_valve_leak"),
                         ("tag_top_overtravel_m", "tagging_up"), ("tag_bottom_overtravel_m", "tagging_down"),
                         ("tubing_leak_fraction", "tubing_leak"), ("flow_through_fraction", "flowing"),
                         ("intake_gas_fraction", "gas_interference"), ("intake_glr_m3_m3", "gas_interference")):
        if getattr(p, field) > 0:
            return label
    return "full"


def condition_name(cfg, card_class: str = "full") -> str:
    """The stroke summary's ``condition``: the config's condition, or the card class (fluid pound, gas)
    that a well without a configured condition runs into."""
    label = condition_of(cfg)
    if label == "full" and card_class in ("fluid_pound", "gas_interference"):
        return card_class
    return label
