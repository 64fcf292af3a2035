"""Field equipment for card wells (run 7, docs/conditions.md; ``srenv cards --equipment field``).

The well family designs API steel strings with a fixed 500 N plunger drag and deviations up to 35 deg. Real
wells often carry a plunger drag of 0.5-3 kN, sinker bars at the bottom of the string (to keep the rods above in
tension), a fiberglass top section (a lighter, stretchier string) and deviations beyond 35 deg. One draw per card,
one function to put it on a config: the card set and the robustness check (e) both call these, so the check
meets exactly the equipment the set draws.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

EQUIPMENT = ("none", "field")  # --equipment: none = sets 1-6's generator, byte for byte
DRAG_RANGE_N = (200.0, 4000.0)  # plunger drag, log-uniform (pump fit and size: a few hundred N to a few kN)
SINKER_SHARE = 0.5
SINKER_DIAMETERS_MM = (31.75, 38.1, 44.45)  # API sinker bars 1.25 / 1.5 / 1.75 in
SINKER_FRACTION = (0.05, 0.20)  # of the string, from its bottom
# the config wants the bottom rod thinner than the plunger (the pressure loads act on the difference): a drawn
# size that is not is capped at the largest of these below the plunger (1.125 in for a 1.25-in plunger)
SINKER_CAP_SIZES_MM = (25.4, 28.575, 31.75, 38.1, 44.45)  # 25.4: under a 1.06-in plunger (--plungers api)
FIBERGLASS_SHARE = 0.3
FIBERGLASS_DIAMETERS_MM = (25.4, 31.75)  # API 11C fiberglass rods 1 / 1.25 in
FIBERGLASS_FRACTION = (0.40, 0.70)  # of the string, from its top
INCLINATION_RANGE_DEG = (8.0, 60.0)  # deviated wells' maximum inclination (the family's: 8-35 deg)
MIN_TAPER_M = 1.0  # the config's shortest taper: a steel taper cut shorter is dropped
# --plungers api (run 8): the API pump bores the family lacks at its small end. A full pump's card is a flowing
# card's when the fluid load over the buoyant rod weight is low (docs/conditions.md, "Full against flowing"):
# 1.06-in pumps on deep strings reach 0.12-0.2, below every full card of the family (0.22 at its 1st percentile)
PLUNGER_SETS = ("family", "api")
API_SMALL_BORE_MM = 26.9875  # 1.06 in (1 1/16 in)
# the columns an equipment set adds (docs/cards_dataset.md); 0 = none
COLUMNS = ("plunger_friction_n", "sinker_bar_diameter_mm", "sinker_bar_length_m", "fiberglass_diameter_mm",
           "fiberglass_length_m")


@dataclass(frozen=True)
class Equipment:
    plunger_friction_n: float
    sinker_bar_diameter_mm: float = 0.0  # 0: no sinker bars
    sinker_fraction: float = 0.0
    fiberglass_diameter_mm: float = 0.0  # 0: an all-steel string
    fiberglass_fraction: float = 0.0
    max_inclination_deg: float | None = None  # None: the family's own


def draw_equipment(rng) -> Equipment:
    """Every draw made whatever comes out, in a fixed order: a card's later draws do not depend on the earlier."""
    lo, hi = DRAG_RANGE_N
    drag = float(math.exp(rng.uniform(math.log(lo), math.log(hi))))
    sinker = bool(rng.uniform() < SINKER_SHARE)
    d_sb = SINKER_DIAMETERS_MM[int(rng.integers(len(SINKER_DIAMETERS_MM)))]
    f_sb = float(rng.uniform(*SINKER_FRACTION))
    glass = bool(rng.uniform() < FIBERGLASS_SHARE)
    d_fg = FIBERGLASS_DIAMETERS_MM[int(rng.integers(len(FIBERGLASS_DIAMETERS_MM)))]
    f_fg = float(rng.uniform(*FIBERGLASS_FRACTION))
    incl = float(rng.uniform(*INCLINATION_RANGE_DEG))
    return Equipment(round(drag, 1), d_sb if sinker else 0.0, round(f_sb, 4) if sinker else 0.0,
                     d_fg if glass else 0.0, round(f_fg, 4) if glass else 0.0, round(incl, 1))


def api_plunger(params, u: float | None):
    """The family's well parameters with the plunger drawn (``u`` uniform in [0, 1)) from the family's sizes at
    the well's depth and the 1.06-in bore (--plungers api); ``None``: the family's own plunger."""
    if u is None:
        return params
    from .well_family import plunger_sizes_mm

    sizes = [API_SMALL_BORE_MM, *plunger_sizes_mm(params.depth_m)]
    return dataclasses.replace(params, plunger_diameter_mm=sizes[min(int(u * len(sizes)), len(sizes) - 1)])


def deviated(params, eq: Equipment | None):
    """The family's well parameters with the equipment's inclination (a vertical well stays vertical)."""
    if eq is None or eq.max_inclination_deg is None or params.survey_shape == "vertical":
        return params
    return dataclasses.replace(params, max_inclination_deg=eq.max_inclination_deg)


def _cut(tapers: list[dict], length_m: float, from_top: bool) -> list[dict]:
    """The string (top-down taper dicts) with ``length_m`` taken off its top or bottom."""
    order = tapers if from_top else tapers[::-1]
    out, left = [], length_m
    for t in order:
        keep = t["length_m"] - left
        left = max(left - t["length_m"], 0.0)
        if keep >= MIN_TAPER_M:
            out.append({**t, "length_m": round(keep, 3)})
    return out if from_top else out[::-1]


def sinker_diameter_mm(drawn_mm: float, plunger_mm: float) -> float:
    """The drawn sinker-bar size, capped below the plunger (SINKER_CAP_SIZES_MM)."""
    return drawn_mm if drawn_mm < plunger_mm else max(d for d in SINKER_CAP_SIZES_MM if d < plunger_mm)


def string_with(tapers: list[dict], eq: Equipment, plunger_mm: float = math.inf) -> list[dict]:
    """Top-down tapers with the sinker bars at the bottom and the fiberglass at the top, the total length kept
    (the round-off goes to the longest steel taper)."""
    total = sum(t["length_m"] for t in tapers)
    sb = round(eq.sinker_fraction * total, 3) if eq.sinker_bar_diameter_mm > 0 else 0.0
    fg = round(eq.fiberglass_fraction * total, 3) if eq.fiberglass_diameter_mm > 0 else 0.0
    steel = _cut(_cut(tapers, sb, from_top=False), fg, from_top=True)
    if not steel:
        raise ValueError(f"equipment {eq}: no steel left in a {total:.1f} m string")
    i = max(range(len(steel)), key=lambda k: steel[k]["length_m"])
    steel[i]["length_m"] = round(steel[i]["length_m"] + total - sb - fg - sum(t["length_m"] for t in steel), 3)
    grade = tapers[-1].get("grade", "D")
    top = [{"diameter_mm": eq.fiberglass_diameter_mm, "length_m": fg, "material": "fiberglass"}] if fg else []
    bottom = ([{"diameter_mm": sinker_diameter_mm(eq.sinker_bar_diameter_mm, plunger_mm), "length_m": sb, "material": "sinker_bar", "grade": grade}]
              if sb else [])
    return top + steel + bottom


def with_equipment(cfg, eq: Equipment | None):
    """``cfg`` with the equipment's plunger drag and string (the inclination is the well's design: deviated)."""
    if eq is None:
        return cfg
    from ..config import apply_overrides, config_from_dict, to_dict

    data = to_dict(cfg)
    over = {"pump.plunger_friction_n": eq.plunger_friction_n, "rod.tapers": string_with(data["rod"]["tapers"], eq,
                                                                                  cfg.pump.plunger_diameter_mm)}
    return config_from_dict(apply_overrides(data, over))


def columns(cfg) -> dict[str, float]:
    """What a card's config carries of the equipment (parted rods: what is left of the string)."""
    sinker = [t for t in cfg.rod.tapers if t.material == "sinker_bar"]
    glass = [t for t in cfg.rod.tapers if t.material == "fiberglass"]
    return {"plunger_friction_n": cfg.pump.plunger_friction_n,
            "sinker_bar_diameter_mm": sinker[0].diameter_mm if sinker else 0.0,
            "sinker_bar_length_m": sum(t.length_m for t in sinker),
            "fiberglass_diameter_mm": glass[0].diameter_mm if glass else 0.0,
            "fiberglass_length_m": sum(t.length_m for t in glass)}
