"""A labelled synthetic card set: wells of the family, a pump condition and a severity each (docs/cards_dataset.md).

Card ``i`` of a set with seed ``S`` is drawn from ``numpy.random.SeedSequence([S, i, attempt])`` only, so a
set is the same whatever the number of worker processes. Cards come in groups of ``CARDS_PER_WELL`` on one
well (one well seed each; the split follows the well seed, so no well is in two splits). A draw whose
simulation fails (an implausible combination the config loader refuses) is drawn again with the next
attempt number.
"""

from __future__ import annotations

import dataclasses
import functools
import io
import math
import zipfile
from dataclasses import dataclass

import numpy as np

from ..physics.conditions import LABELS
from . import card_equipment

N_POINTS = 256          # samples per card, equally spaced in time over the last stroke
CARDS_PER_WELL = 4
WELL_SEED0 = 10_000_000  # card wells: disjoint from the family's train (0...) and test (1 000 000...) seeds
SPLITS = ("train", "validation", "test")
MAX_ATTEMPTS = 8
DAMPING_RANGE = (0.02, 0.8)   # Gibbs factor, log-uniform: from ringing strings to strongly damped ones
CONVENTIONAL_SHARE = 0.5      # cards driven by a catalogue beam unit (four-bar linkage), the rest harmonic
MIN_SEVERITY = 0.25           # below it a condition's card is hard to tell from a full pump's
# What real wells vary per card and the family holds fixed (docs/cards_dataset.md "Field variation"):
KV_TAU_RANGE_S = (0.0, 0.05)  # Kelvin-Voigt retardation time: couplings, guides, fluid damp the high modes
COLUMN_MASS_SHARE = 0.5       # cards whose lifted liquid column's inertia loads the rising plunger
COMPRESSIBLE_SHARE = 0.5      # cards whose chamber liquid is compressible (gradual load transfer)
OIL_COMPRESSIBILITY_PER_PA = (1.0e-9, 3.0e-9)  # live oil, log-uniform; water 4.5e-10
WATER_COMPRESSIBILITY_PER_PA = 4.5e-10
UNANCHORED_SHARE = 0.5        # of the compressible cards: tubing free to stretch under the fluid load
# the labels the liquid spring (compressibility, unanchored tubing) is drawn with: when this set was drawn the
# kernel dropped the leak, tagging and tubing-leak laws under a spring (their cards became the full card); the
# config now refuses the valve leaks with a spring and tagging with free tubing, and tagging and the tubing leak
# compose with it (config_checks._check_chamber_conditions) - not drawn here yet, so run 3's set stays the same
SPRING_LABELS = ("full", "fluid_pound", "gas_interference", "parted_rods", "heavy_oil", "flowing")
WELL_COLUMNS = ("depth_m", "plunger_diameter_mm", "spm", "stroke_length_m", "damping_factor",
                "max_inclination_deg", "friction_coefficient", "fluid_density_kg_m3", "conventional_unit",
                "kv_tau_s", "fluid_column_mass_kg", "liquid_compressibility_per_pa", "tubing_anchored")
# --surface: "family" (sets 1-3: harmonic or the nearest catalogue unit, the operating point uniform) or "v2"
# (run 4's set: the well's own v2 unit, srenv.task.v2_physics, and the operating corners populated)
SURFACES = ("family", "v2")
CORNER_SHARE = 0.25  # v2 surface: each of SPM and stroke at its minimum, and at its maximum, with this share
ARRAYS = ("polished_rod_position_m", "polished_rod_load_n", "pump_position_m", "pump_load_n")


def split_of(well_seed: int) -> str:
    """80 / 10 / 10 by well seed."""
    r = int(np.random.SeedSequence(well_seed).generate_state(1)[0]) % 10  # consecutive seeds scrambled
    return "train" if r < 8 else ("validation" if r == 8 else "test")


@dataclass(frozen=True)
class Draw:
    well_seed: int
    label: str
    severity: float
    spm: float
    stroke_length_m: float
    damping_factor: float
    conventional: bool = False
    kv_tau_s: float = 0.0
    column_mass: bool = False
    oil_compressibility_per_pa: float = 0.0  # 0: incompressible liquid
    unanchored: bool = False
    surface: str = "family"  # "v2": driven by the well's v2 unit (its geometry drawn from the well's seed)
    equipment: card_equipment.Equipment | None = None  # --equipment field (run 7): drag, sinker bars, fiberglass
    plunger_u: float | None = None  # --plungers api (run 8): the plunger's draw among the API bores; None: family's


def _corner_weighted(rng) -> float:
    """A fraction of the control range: 0 or 1 with CORNER_SHARE each, else uniform."""
    u, v = float(rng.uniform()), float(rng.uniform())
    return 0.0 if u < CORNER_SHARE else (1.0 if u < 2 * CORNER_SHARE else v)


def draw(seed: int, index: int, attempt: int, labels: tuple[str, ...], surface: str = "family",
         equipment: str = "none", plungers: str = "family") -> Draw:
    rng = np.random.default_rng(np.random.SeedSequence([seed, index, attempt]))
    well_seed = WELL_SEED0 + seed * 1_000_003 + index // CARDS_PER_WELL + attempt * 100_000_007
    label = labels[int(rng.integers(len(labels)))]
    severity = 0.0 if label == "full" else float(rng.uniform(MIN_SEVERITY, 1.0))
    lo, hi = DAMPING_RANGE
    base = (float(rng.uniform()), float(rng.uniform()), float(math.exp(rng.uniform(math.log(lo), math.log(hi)))),
            bool(rng.uniform() < CONVENTIONAL_SHARE))
    # drawn after the older fields, so those stay what they were for a seed
    tau = float(rng.uniform(*KV_TAU_RANGE_S))
    column_mass = bool(rng.uniform() < COLUMN_MASS_SHARE)
    c_lo, c_hi = OIL_COMPRESSIBILITY_PER_PA
    c_oil = float(math.exp(rng.uniform(math.log(c_lo), math.log(c_hi))))
    compressible = bool(rng.uniform() < COMPRESSIBLE_SHARE) and label in SPRING_LABELS
    unanchored = bool(rng.uniform() < UNANCHORED_SHARE) and compressible
    if surface == "v2":  # drawn after every older field: a "family" set's cards are what they were
        base = (_corner_weighted(rng), _corner_weighted(rng), base[2], False)
    elif surface != "family":
        raise ValueError(f"surface = {surface!r}: expected one of {', '.join(SURFACES)}")
    if equipment not in card_equipment.EQUIPMENT:
        raise ValueError(f"equipment = {equipment!r}: expected one of {', '.join(card_equipment.EQUIPMENT)}")
    # drawn after every older field (the v2 surface's too): a set without it is what it was
    eq = card_equipment.draw_equipment(rng) if equipment == "field" else None
    if plungers not in card_equipment.PLUNGER_SETS:
        raise ValueError(f"plungers = {plungers!r}: expected one of {', '.join(card_equipment.PLUNGER_SETS)}")
    u_plunger = float(rng.uniform()) if plungers == "api" else None  # after every older draw, as the equipment
    return Draw(well_seed, label, severity, *base, kv_tau_s=tau, column_mass=column_mass,
                oil_compressibility_per_pa=c_oil if compressible else 0.0, unanchored=unanchored, surface=surface,
                equipment=eq, plunger_u=u_plunger)


def field_overrides(d: Draw, well) -> dict[str, object]:
    """Config keys for what real wells vary and the family holds fixed: Kelvin-Voigt damping of the string's
    high modes, the lifted column's inertia, the chamber liquid's compressibility (water and live oil mixed
    by the well's water cut) and unanchored tubing."""
    from ..physics.pump import fluid_column_mass_kg, plunger_area_m2
    from .well_family import OIL_RHO, WATER_RHO

    out: dict[str, object] = {"damping.stiffness_proportional_s": round(d.kv_tau_s, 6)}
    if d.column_mass and d.label != "parted_rods":  # a parted string lifts no column
        a_t = math.pi / 4 * (well.tubing.inner_diameter_mm * 1e-3) ** 2
        a_r = math.pi / 4 * (well.rod.tapers[-1].diameter_mm * 1e-3) ** 2
        m = fluid_column_mass_kg(well.fluid.density_kg_m3, well.rod_length_m, plunger_area_m2(well.pump), a_t, a_r)
        out["pump.fluid_column_mass_kg"] = round(m, 3)
    if d.oil_compressibility_per_pa > 0:
        wc = min(max((well.fluid.density_kg_m3 - OIL_RHO) / (WATER_RHO - OIL_RHO), 0.0), 1.0)
        c = wc * WATER_COMPRESSIBILITY_PER_PA + (1.0 - wc) * d.oil_compressibility_per_pa
        out["pump.liquid_compressibility_per_pa"] = float(f"{c:.4g}")
        out["pump.liquid_chamber_volume"] = "top_of_stroke"  # the law these sets were drawn with (runs 3-6)
    if d.unanchored:
        out["tubing.anchored"] = False
    return out


@functools.lru_cache(maxsize=1)
def _unit_strokes() -> tuple[tuple[float, str, int], ...]:
    """(stroke, designation, crank hole) of every catalogue unit and hole."""
    from ..surface_unit.unit_catalogue import conventional_unit, get_unit, list_units

    return tuple((conventional_unit(d, h).stroke_m, d, h) for d in list_units()
                 for h in range(len(get_unit(d).crank_radii_m)))


def _surface(surface, spm: float, stroke: float, conventional: bool):
    """Harmonic at the drawn stroke, or the catalogue unit and hole whose stroke is nearest."""
    if not conventional:
        return dataclasses.replace(surface, spm=spm, stroke_length_m=stroke)
    s, unit, hole = min(_unit_strokes(), key=lambda u: abs(u[0] - stroke))
    return dataclasses.replace(surface, motion="conventional", unit=unit, crank_hole=hole, spm=spm,
                               stroke_length_m=round(s, 4))


def card_config(d: Draw):
    """The family well of the draw at the drawn operating point and damping, in the drawn condition."""
    from ..analysis.condition_card import condition_config
    from .well_family import draw_params, spec_from_params

    params = card_equipment.api_plunger(card_equipment.deviated(draw_params(d.well_seed), d.equipment), d.plunger_u)
    spec = spec_from_params(params, f"card{d.well_seed}")
    well = card_equipment.with_equipment(spec.cfg, d.equipment)  # before the condition: heavy oil adds to the drag
    c = well.control
    spm = round(c.spm_min + d.spm * (c.spm_max - c.spm_min), 3)
    stroke = round(c.stroke_min_m + d.stroke_length_m * (c.stroke_max_m - c.stroke_min_m), 4)
    # the operating point and damping on the parsed config (checked again with the condition's overrides)
    well = dataclasses.replace(well, surface=_surface(well.surface, spm, stroke, d.conventional),
                               damping=dataclasses.replace(well.damping, model="dimensionless",
                                                           damping_factor=round(d.damping_factor, 6)))
    return condition_config(well, d.label, d.severity, {**field_overrides(d, well), **_unit_overrides(d, spec)})


def _unit_overrides(d: Draw, spec) -> dict[str, object]:
    """v2 surface: the well's own v2 unit (v2_physics' geometry draw and sizing; its crank follows the drawn
    stroke), run at the drawn SPM and stroke."""
    if d.surface != "v2":
        return {}
    from . import v2_physics

    return {"surface.motion": "beam_unit",
            "surface.beam_unit": v2_physics.unit_block(spec, v2_physics.draw_geometry(spec.params))}


def unit_geometry(cfg) -> str:
    """What drives a card: harmonic, catalogue (a catalogue conventional unit) or the v2 unit's geometry."""
    if cfg.surface.motion == "beam_unit" and cfg.surface.beam_unit is not None:
        return cfg.surface.beam_unit.geometry
    return "catalogue" if cfg.surface.motion == "conventional" else "harmonic"


def resample(t: np.ndarray, y: np.ndarray, n: int = N_POINTS) -> np.ndarray:
    tt = np.linspace(t[0], t[-1], n)
    return np.interp(tt, t, y)


def make_card(seed: int, index: int, labels: tuple[str, ...], surface: str = "family",
              equipment: str = "none", plungers: str = "family") -> dict:
    """Card ``index`` of set ``seed``: arrays, label, severity, the well's numbers."""
    from ..analysis.condition_card import simulate_card
    from ..errors import ConfigError, NumericFailure, SolverFailure

    for attempt in range(MAX_ATTEMPTS):
        d = draw(seed, index, attempt, labels, surface, equipment, plungers)
        try:
            cfg = card_config(d)
            card = simulate_card(cfg)
        except (ConfigError, NumericFailure, SolverFailure, ValueError):
            continue
        arrays = {k: resample(card.t_s, getattr(card, k)) for k in ARRAYS}
        if not all(np.all(np.isfinite(a)) for a in arrays.values()):
            continue
        well = {"depth_m": cfg.rod_length_m, "plunger_diameter_mm": cfg.pump.plunger_diameter_mm,
                "spm": cfg.surface.spm, "stroke_length_m": cfg.surface.stroke_length_m,
                "damping_factor": cfg.damping.damping_factor,
                "max_inclination_deg": max([s.inclination_deg for s in cfg.survey.stations] or [0.0]),
                "friction_coefficient": cfg.friction.coefficient, "fluid_density_kg_m3": cfg.fluid.density_kg_m3,
                "conventional_unit": float(cfg.surface.motion == "conventional"),
                "kv_tau_s": cfg.damping.stiffness_proportional_s, "fluid_column_mass_kg": cfg.pump.fluid_column_mass_kg,
                "liquid_compressibility_per_pa": cfg.pump.liquid_compressibility_per_pa,
                "tubing_anchored": float(cfg.tubing.anchored)}
        if d.equipment is not None:
            well.update(card_equipment.columns(cfg))
        return {"arrays": arrays, "label": d.label, "severity": d.severity, "well_seed": d.well_seed,
                "fillage": card.fillage, "period_s": float(card.t_s[-1]), "well": well,
                "surface": surface, "unit_geometry": unit_geometry(cfg)}
    raise RuntimeError(f"card {index} of set {seed}: no simulation succeeded in {MAX_ATTEMPTS} draws")


def columns(cards: list[dict]) -> dict[str, np.ndarray]:
    """The set as columns (the NPZ's arrays, docs/cards_dataset.md)."""
    out = {k: np.stack([c["arrays"][k] for c in cards]).astype(np.float64) for k in ARRAYS}
    out["label"] = np.array([LABELS.index(c["label"]) for c in cards], dtype=np.int64)
    out["label_names"] = np.array(LABELS)
    out["severity"] = np.array([c["severity"] for c in cards], dtype=np.float64)
    out["well_seed"] = np.array([c["well_seed"] for c in cards], dtype=np.int64)
    out["split"] = np.array([split_of(c["well_seed"]) for c in cards])
    out["fillage"] = np.array([c["fillage"] for c in cards], dtype=np.float64)
    out["period_s"] = np.array([c["period_s"] for c in cards], dtype=np.float64)
    for k in WELL_COLUMNS:
        out[k] = np.array([c["well"][k] for c in cards], dtype=np.float64)
    if any(c.get("surface", "family") != "family" for c in cards):  # a column of --surface v2 sets only
        out["unit_geometry"] = np.array([c["unit_geometry"] for c in cards])
    if any(card_equipment.COLUMNS[0] in c["well"] for c in cards):  # columns of --equipment field sets only
        for k in card_equipment.COLUMNS:
            out[k] = np.array([c["well"][k] for c in cards], dtype=np.float64)
    return out


def write_npz(path: str, cols: dict[str, np.ndarray]) -> None:
    """An NPZ with fixed zip metadata (no time stamps): the same columns give the same bytes."""
    with zipfile.ZipFile(path, "w", compression=zipfile.ZIP_DEFLATED) as zf:
        for name in sorted(cols):
            buf = io.BytesIO()
            np.lib.format.write_array(buf, np.ascontiguousarray(cols[name]), allow_pickle=False)
            info = zipfile.ZipInfo(f"{name}.npy", date_time=(1980, 1, 1, 0, 0, 0))
            info.compress_type = zipfile.ZIP_DEFLATED
            info.external_attr = 0o644 << 16
            zf.writestr(info, buf.getvalue())


def load_cards(path: str) -> dict[str, np.ndarray]:
    """Read a card set (data only, no pickled objects)."""
    with np.load(path, allow_pickle=False) as z:
        return {k: z[k] for k in z.files}


def described_well(well_seed: int):
    """The description an engineer holds of a card's well: the family well of its seed in the *full* condition (the
    well and the liquid over its pump, not its condition, nor the card's drawn damping, operating point or unit; nor
    an equipment set's drag, string and deviation: runs P2 and P3 read sets 2 and 4 only)."""
    from ..analysis.condition_card import condition_config
    from .well_family import draw_params, spec_from_params

    return condition_config(spec_from_params(draw_params(well_seed), f"card{well_seed}").cfg, "full", 0.0)


def described_pumps(well_seeds: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(F_desc, P+_desc as a true load) in N of each card's described well (srenv.simulation.described): run P2's
    level (``train_classifier --card pump --level``) and run P3's offset (``--offset``)."""
    from ..simulation.described import described_pump

    cache: dict[int, tuple[float, float]] = {}
    out = np.empty((2, len(well_seeds)))
    for i, s in enumerate(int(v) for v in well_seeds):
        if s not in cache:
            d = described_pump(described_well(s))
            cache[s] = (d.fluid_load_n, d.downstroke_true_n)
        out[:, i] = cache[s]
    return out[0], out[1]


def described_fluid_loads_n(well_seeds: np.ndarray) -> np.ndarray:
    """F_desc (N) of each card's described well (described_pumps)."""
    return described_pumps(well_seeds)[0]


def rebuilt_draw(seed: int, index: int, well_seed: int, label: str, surface: str = "family", equipment: str = "none",
                 plungers: str = "family") -> Draw:
    """Card ``index``'s draw of a set (seed, surface, equipment, plungers as its dataset_card.json says), its attempt
    read off the stored well seed; raises ValueError if the draw does not give the stored well and label."""
    attempt = (int(well_seed) - WELL_SEED0 - seed * 1_000_003 - index // CARDS_PER_WELL) // 100_000_007
    d = draw(seed, index, attempt, LABELS, surface, equipment, plungers)
    if d.well_seed != int(well_seed) or d.label != label:
        raise ValueError(f"card {index} of set {seed} ({surface}, {equipment}, {plungers}): its draw does not rebuild")
    return d


def described_surfaces(cards_dir: str, cards: dict[str, np.ndarray] | None = None) -> tuple[np.ndarray, np.ndarray]:
    """(F_desc, D_desc) in N of each card of a set (analysis.surface_level, run 9): the card's *own* well (its
    equipment, survey, unit and operating point; not its condition) in the full condition - what the config a
    ``srenv classify --config`` user gives describes. The set's seed and recipe are read from its dataset_card.json."""
    import json
    from pathlib import Path

    from ..analysis.surface_level import described_surface

    meta = json.loads((Path(cards_dir) / "dataset_card.json").read_text())
    c = cards if cards is not None else load_cards(str(Path(cards_dir) / "cards.npz"))
    out = np.empty((2, len(c["label"])))
    for i, (ws, lab) in enumerate(zip(c["well_seed"], c["label"])):
        d = rebuilt_draw(int(meta["seed"]), i, int(ws), LABELS[int(lab)], meta.get("surface", "family"),
                         meta.get("equipment", "none"), meta.get("plungers", "family"))
        s = described_surface(card_config(dataclasses.replace(d, label="full", severity=0.0)))
        out[:, i] = s.fluid_load_n, s.downstroke_n
    return out[0], out[1]
