"""A seeded family of realistic beam-pumped wells, with fixed train and test splits.

Each well is drawn from a well seed by :func:`draw_params` (the *randomised* parameters, ranges in
:data:`PARAM_RANGES`) and turned into a :class:`~srenv.config.WellConfig` by :func:`build_config`, which
designs the rest as an engineer would for that depth and pump:

* **rod string**: API steel rods 1", 7/8", 3/4" (25.4 / 22.2 / 19.05 mm); one taper above 900 m, two to
  1700 m, three below; lengths by the *equal top-stress* rule (West): the stress at the top of every taper
  under the buoyed rod weight below it plus the fluid load is the same. The grade (C, K, D) is the cheapest
  whose Goodman loading, estimated with Mills' impulse factor at the top of the control range, stays below
  90 %; if even grade D does not, the control range is cut until it does.
* **pump**: plunger 31.75 ... 63.5 mm, the largest sizes only in shallow wells (deeper pumps lift a heavier
  fluid column per unit area).
* **surface unit and VSD**: harmonic drive, maximum stroke ``unit_stroke_m``, control range stroke
  [0.5, 1] x that, SPM [2, min(12, 0.3 N0)] with N0 = 60 a / (4 L) the string's fundamental in strokes/min
  (the usual limit on N/N0 that keeps the rod dynamics tame). The *installed* operating point is what the
  designer set for the nominal inflow (productivity factor 1): 0.8 of the unit stroke at the SPM that
  displaces 1.2 x the nominal rate. The structure rating is 1.25 x Mills' PPRL estimate at that point.
* **survey**: vertical, build-and-hold or S-shape, kick-off and maximum inclination drawn, with dogleg
  noise (± 0.5 deg per 100 m station).
* **inflow**: Vogel or linear IPR whose full-drawdown rate is ``productivity`` x the nominal rate (0.7 x
  the pump's capacity at mid-range), reservoir pressure from a static fluid level (fraction of the TVD).

Splits: the train split is well seeds ``TRAIN_SEED0 + k`` (k < ``N_TRAIN``), the test split
``TEST_SEED0 + k`` (k < ``N_TEST``); the two seed ranges are disjoint and :func:`check_split` refuses the
test split to every tuning or training caller. For v2 (:data:`V2_SPLITS`) a fixed ``validation`` split
(``VALIDATION_SEED0 + k``, k < ``N_VALIDATION``) is for model selection only, and :func:`family_spec` draws well
SEED of the family from a separate random stream (``family:SEED``, id ``family-SEED``): outside every split
whatever SEED is, so a user can draw any number of wells nobody has seen. Both are refused to tuning and
training (:func:`check_split`; ``family`` also to selection).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..config import WellConfig, config_from_dict
from ..physics.rod import GRAVITY_M_S2

N_TRAIN, N_TEST = 200, 50
TRAIN_SEED0, TEST_SEED0 = 0, 1_000_000
SPLITS = ("train", "test")  # v1's scenarios
N_VALIDATION, VALIDATION_SEED0 = 50, 2_000_000
V2_SPLITS = ("train", "validation", "test")
FAMILY_STREAM = 0xFA  # family wells: a third entropy word, so no family seed reproduces a split's well

STEEL_E_PA, STEEL_RHO = 2.0e11, 7850.0
OIL_RHO, WATER_RHO = 850.0, 1030.0
ROD_SIZES_MM = (25.4, 22.225, 19.05)
PLUNGERS_MM = (31.75, 38.1, 44.45, 50.8, 57.15, 63.5)
GRADE_TENSILE_PA = {"C": 90e3 * 6894.757, "K": 85e3 * 6894.757, "D": 115e3 * 6894.757}
GRADE_ORDER = ("K", "C", "D")  # cheapest first
CASING_PRESSURE_PA = 2.0e5
SPM_MIN = 2.0

# every randomised parameter of a well: (low, high); each moves the rate or the loads by > 1 % across it
PARAM_RANGES: dict[str, tuple[float, float]] = {
    "depth_m": (500.0, 2500.0),
    "plunger_diameter_mm": (31.75, 63.5),
    "unit_stroke_m": (1.5, 3.0),
    "max_inclination_deg": (0.0, 35.0),
    "kickoff_fraction": (0.1, 0.4),
    "friction_coefficient": (0.05, 0.3),
    "water_cut": (0.2, 0.95),
    "productivity": (0.3, 3.0),
    "static_level_fraction": (0.15, 0.7),
    "damping_factor": (0.03, 0.12),
    "decline_per_day": (0.0, 0.3),
}
SURVEY_SHAPES = ("vertical", "build_hold", "s_shape")
INFLOW_MODELS = ("vogel", "linear")


@dataclass(frozen=True)
class WellParams:
    depth_m: float
    plunger_diameter_mm: float
    unit_stroke_m: float
    survey_shape: str
    max_inclination_deg: float
    kickoff_fraction: float
    friction_coefficient: float
    water_cut: float
    inflow_model: str
    productivity: float
    static_level_fraction: float
    damping_factor: float
    decline_per_day: float
    dogleg_seed: int = 0

    def hidden(self) -> dict[str, float]:
        """The numbers a field controller does not know (for the privileged observation and the oracle)."""
        return {k: float(getattr(self, k)) for k in PARAM_RANGES}


@dataclass(frozen=True)
class WellSpec:
    """A drawn well: its id, the hidden truth and the engineered config."""

    well_id: str
    params: WellParams
    cfg: WellConfig
    nominal_rate_m3_day: float
    design: dict = field(default_factory=dict)
    # the mapping ``cfg`` is parsed from; with ``cfg`` None a well not parsed yet (``spec_from_params(parse=False)``:
    # v2 parses it once, with its per-well physics applied, srenv/envs/sucker_rod_v2.py)
    raw: dict | None = field(default=None, compare=False, repr=False)


def check_split(split: str, purpose: str) -> None:
    """Refuse the test split (and v2's validation and family wells) to tuning and training: the test and
    family wells are for the final evaluation only, the validation wells for model selection."""
    if split not in V2_SPLITS + ("family",):
        raise ValueError(f"split = {split!r}: expected one of {V2_SPLITS + ('family',)}")
    if split in ("test", "family") and purpose in ("tune", "train", "select"):
        raise ValueError(f"split = {split!r} refused for {purpose}: {split} wells are only for the final "
                         "evaluation; tune and train on split 'train'")
    if split == "validation" and purpose in ("tune", "train"):
        raise ValueError(f"split = 'validation' refused for {purpose}: validation wells are for model selection "
                         "only; tune and train on split 'train'")


_SPLIT_SEEDS = {"train": (N_TRAIN, TRAIN_SEED0), "test": (N_TEST, TEST_SEED0),
                "validation": (N_VALIDATION, VALIDATION_SEED0)}


def well_seed(split: str, index: int) -> int:
    n, seed0 = _SPLIT_SEEDS[split]
    if not 0 <= index < n:
        raise ValueError(f"well index = {index}: expected 0 <= index < {n} for split {split!r}")
    return seed0 + index


def split_size(split: str) -> int:
    check_split(split, "evaluate")
    return _SPLIT_SEEDS[split][0]


def family_spec(seed: int) -> WellSpec:
    """Well SEED of the family outside every split (``scenario="family:SEED"``), deterministic per seed."""
    if not (isinstance(seed, (int, np.integer)) and 0 <= int(seed) < 2**63):
        raise ValueError(f"family seed = {seed!r}: expected an integer 0 <= seed < 2**63")
    return spec_from_params(draw_params(int(seed), stream=FAMILY_STREAM), f"family-{int(seed)}")


def draw_params(seed: int, stream: int | None = None) -> WellParams:
    rng = np.random.default_rng([seed, 0x5e11] if stream is None else [seed, 0x5e11, stream])
    lo_hi = PARAM_RANGES

    def u(name: str) -> float:
        lo, hi = lo_hi[name]
        return float(rng.uniform(lo, hi))

    depth = u("depth_m")
    sizes = plunger_sizes_mm(depth)
    shape = SURVEY_SHAPES[int(rng.choice(3, p=[0.3, 0.4, 0.3]))]
    return WellParams(
        depth_m=round(depth, 1),
        plunger_diameter_mm=float(sizes[int(rng.integers(len(sizes)))]),
        unit_stroke_m=round(u("unit_stroke_m"), 2),
        survey_shape=shape,
        max_inclination_deg=0.0 if shape == "vertical" else round(float(rng.uniform(8.0, 35.0)), 1),
        kickoff_fraction=round(u("kickoff_fraction"), 3),
        friction_coefficient=round(u("friction_coefficient"), 3),
        water_cut=round(u("water_cut"), 3),
        inflow_model=INFLOW_MODELS[int(rng.integers(2))],
        productivity=round(float(math.exp(rng.uniform(math.log(0.3), math.log(3.0)))), 3),
        static_level_fraction=round(u("static_level_fraction"), 3),
        damping_factor=round(u("damping_factor"), 3),
        decline_per_day=round(u("decline_per_day"), 3),
        dogleg_seed=int(rng.integers(2**31)),
    )


def plunger_sizes_mm(depth_m: float) -> list[float]:
    """The family's plunger sizes at a depth: larger plungers only in shallower wells (the fluid load grows with
    depth x plunger area)."""
    d_max = 63.5 - (63.5 - 38.1) * (depth_m - 500.0) / 2000.0
    return [d for d in PLUNGERS_MM if d <= d_max + 1e-9]


# ------------------------------------------------------------------------------------------- design
def fluid_density(water_cut: float) -> float:
    return OIL_RHO * (1.0 - water_cut) + WATER_RHO * water_cut


def survey_stations(p: WellParams) -> list[dict]:
    """(MD, inclination) stations every ~100 m of the chosen shape, with seeded dogleg noise."""
    if p.survey_shape == "vertical" or p.max_inclination_deg <= 0:
        return []
    d = p.depth_m
    kop = p.kickoff_fraction * d
    build = 2.5 / 30.0  # deg per m, a common build rate
    end_build = min(kop + p.max_inclination_deg / build, 0.9 * d)
    start_drop = max(end_build, 0.6 * d)
    end_drop = max(start_drop + 1.0, 0.85 * d)

    def incl(s: float) -> float:
        if s <= kop:
            return 0.0
        if s <= end_build:
            return p.max_inclination_deg * (s - kop) / (end_build - kop)
        if p.survey_shape == "build_hold" or s <= start_drop:
            return p.max_inclination_deg
        if s <= end_drop:
            return p.max_inclination_deg * (end_drop - s) / (end_drop - start_drop)
        return 0.0

    md = np.unique(np.r_[np.arange(0.0, d, 100.0), kop, end_build, d])
    rng = np.random.default_rng([p.dogleg_seed, 0xd06])
    noise = rng.uniform(-0.5, 0.5, len(md))
    noise[0] = 0.0
    inc = [max(0.0, incl(float(s)) + (n if incl(float(s)) > 0 else 0.0)) for s, n in zip(md, noise)]
    st = [{"md_m": round(float(s), 3), "inclination_deg": round(float(a), 3), "azimuth_deg": 0.0}
          for s, a in zip(md, inc)]
    st[-1]["md_m"] = d + 1.0  # past the pump: the survey must reach the string's end whatever the round-off
    return st


def taper_design(depth_m: float, fluid_load_n: float, rho_f: float) -> list[tuple[float, float]]:
    """Equal top-stress taper lengths, bottom-up [(diameter_mm, length_m)], solved as a linear system."""
    n_tapers = 1 if depth_m < 900 else (2 if depth_m < 1700 else 3)
    sizes = list(ROD_SIZES_MM[::-1][:n_tapers])  # bottom (smallest) first
    while True:
        areas = [math.pi / 4 * (d * 1e-3) ** 2 for d in sizes]
        w = [(STEEL_RHO - rho_f) * GRAVITY_M_S2 * a for a in areas]
        n = len(sizes)
        # unknowns L_1..L_n, sigma: F + sum_{j<=i} w_j L_j - sigma A_i = 0 (i = 1..n), sum L = depth
        a_mat = np.zeros((n + 1, n + 1))
        rhs = np.zeros(n + 1)
        for i in range(n):
            a_mat[i, : i + 1] = w[: i + 1]
            a_mat[i, n] = -areas[i]
            rhs[i] = -fluid_load_n
        a_mat[n, :n] = 1.0
        rhs[n] = depth_m
        sol = np.linalg.solve(a_mat, rhs)
        lengths = sol[:n]
        if n == 1 or np.all(lengths >= 0.1 * depth_m):
            return list(zip(sizes, [float(x) for x in lengths]))
        sizes = sizes[:-1]  # a taper too short to be worth running: drop the largest


def mills_loads_n(rod_weight_n: float, buoyed_weight_n: float, fluid_load_n: float, stroke_m: float,
                  spm: float) -> tuple[float, float]:
    """Mills' impulse-factor estimate of (PPRL, MPRL): W_rf + F_o + W_r a, W_rf - W_r a, a = S N^2 / 70471
    with S in inches (the classical pre-RP 11L hand method; used only for design, never for the reward)."""
    alpha = stroke_m / 0.0254 * spm * spm / 70471.0
    return buoyed_weight_n + fluid_load_n + rod_weight_n * alpha, buoyed_weight_n - rod_weight_n * alpha


def goodman_pct(smax: float, smin: float, tensile: float) -> float:
    allow = tensile / 4 + 0.5625 * smin
    return 100.0 * (smax - smin) / max(allow - smin, 1.0)


def build_spec(split: str, index: int, parse: bool = True) -> WellSpec:
    return spec_from_params(draw_params(well_seed(split, index)), well_name(split, index), parse)


def well_name(split: str, index: int) -> str:
    return f"{split}-{index:03d}"


def spec_from_params(p: WellParams, well_id: str, parse: bool = True) -> WellSpec:
    """The well of parameters ``p``; ``parse=False``: its config mapping in ``raw`` and ``cfg`` None (not parsed)."""
    rho_f = fluid_density(p.water_cut)
    a_pl = math.pi / 4 * (p.plunger_diameter_mm * 1e-3) ** 2
    stations = survey_stations(p)
    tvd = tvd_m(stations, p.depth_m)
    fluid_load = rho_f * GRAVITY_M_S2 * tvd * a_pl  # on the gross plunger area (tubing empty above nothing)
    tapers_bu = taper_design(p.depth_m, fluid_load, rho_f)
    # lengths to the millimetre, the top taper taking the round-off, so that the string ends at the pump
    lengths = [round(length, 3) for _, length in tapers_bu[:-1]]
    lengths.append(round(p.depth_m - sum(lengths), 3))
    tapers_bu = [(d, length) for (d, _), length in zip(tapers_bu, lengths)]
    tapers_td = tapers_bu[::-1]
    n0_spm = fundamental_spm(p.depth_m)
    spm_max = round(min(12.0, 0.3 * n0_spm), 2)
    stroke_max = p.unit_stroke_m
    stroke_min = round(0.5 * stroke_max, 3)
    rod_w = sum(STEEL_RHO * GRAVITY_M_S2 * math.pi / 4 * (d * 1e-3) ** 2 * length for d, length in tapers_bu)
    rod_wb = rod_w * (1.0 - rho_f / STEEL_RHO)
    top_area = math.pi / 4 * (tapers_td[0][0] * 1e-3) ** 2
    # grade: the cheapest whose estimated Goodman loading at the top of the range stays below 90 %
    grade = None
    for _ in range(40):
        pp, mp = mills_loads_n(rod_w, rod_wb, fluid_load, stroke_max, spm_max)
        for g in GRADE_ORDER:
            if goodman_pct(pp / top_area, mp / top_area, GRADE_TENSILE_PA[g]) < 90.0:
                grade = g
                break
        if grade is not None:
            break
        spm_max = round(0.95 * spm_max, 2)  # even grade D is overloaded: narrow the control range
    grade = grade or "D"
    spm_max = max(spm_max, SPM_MIN + 2.0)
    nominal = nominal_rate_m3_day(p.plunger_diameter_mm, spm_max, stroke_max)
    installed_stroke = round(0.8 * stroke_max, 3)
    installed_spm = float(np.clip(1.2 * nominal / (1440.0 * a_pl * installed_stroke * 0.85), SPM_MIN, spm_max))
    installed_spm = round(installed_spm, 2)
    pprl_inst, _ = mills_loads_n(rod_w, rod_wb, fluid_load, installed_stroke, installed_spm)
    rating = 5000.0 * math.ceil(1.25 * pprl_inst / 5000.0)
    q_max = p.productivity * nominal
    p_r = CASING_PRESSURE_PA + rho_f * GRAVITY_M_S2 * p.static_level_fraction * tvd
    pi = q_max / max(p_r - CASING_PRESSURE_PA, 1.0)
    raw = {
        "name": well_id,
        "description": f"srenv well family {well_id}: {p.survey_shape}, {p.depth_m:.0f} m, "
                       f"{p.plunger_diameter_mm} mm pump",
        "rod": {"tapers": [{"diameter_mm": d, "length_m": length, "grade": grade,
                            "youngs_modulus_pa": STEEL_E_PA, "density_kg_m3": STEEL_RHO}
                           for d, length in tapers_td]},
        "damping": {"model": "dimensionless", "damping_factor": p.damping_factor},
        "survey": {"stations": stations},
        "friction": {"law": "coulomb", "coefficient": p.friction_coefficient},
        "fluid": {"density_kg_m3": round(rho_f, 3), "wellhead_pressure_pa": 5.0e5},
        "pump": {"load_source": "pressures", "plunger_diameter_mm": p.plunger_diameter_mm,
                 "plunger_friction_n": 500.0, "discharge_overpressure_pa": 2.0e5},
        "surface": {"motion": "harmonic", "spm": installed_spm, "stroke_length_m": installed_stroke},
        "simulation": {"element_length_m": element_length_m(p.depth_m), "time_step_s": 0.005},
        "inflow": {"model": p.inflow_model, "reservoir_pressure_pa": round(p_r, 1),
                   "max_rate_m3_day": round(q_max, 4), "productivity_index_m3_day_pa": pi,
                   "casing_pressure_pa": CASING_PRESSURE_PA,
                   "initial_fluid_level_m": round(p.static_level_fraction * p.depth_m * 0.5, 2),
                   "casing_inner_diameter_mm": 124.0, "tubing_outer_diameter_mm": 73.0},
        "control": {"spm_min": SPM_MIN, "spm_max": spm_max, "stroke_min_m": stroke_min,
                    "stroke_max_m": stroke_max},
        "economics": {"water_cut": p.water_cut, "pprl_rating_n": rating},
        "task": {"inflow_decline_per_day": p.decline_per_day},
    }
    design = {"grade": grade, "tapers_bottom_up": tapers_bu, "n0_spm": n0_spm, "fluid_load_n": fluid_load,
              "mills_pprl_installed_n": pprl_inst, "static_level_m": p.static_level_fraction * tvd}
    return WellSpec(well_id, p, config_from_dict(raw) if parse else None, nominal, design, raw)


def fundamental_spm(depth_m: float) -> float:
    """N0 = 60 a / (4 L): the rod string's quarter-wave fundamental in strokes/min (steel, pump at depth L)."""
    wave = math.sqrt(STEEL_E_PA / STEEL_RHO)
    return 60.0 * wave / (4.0 * depth_m)


def nominal_rate_m3_day(plunger_diameter_mm: float, spm_max: float, stroke_max_m: float) -> float:
    """The design rate of the family's wells (productivity factor 1): 0.7 x the pump's capacity at mid-range (mid
    SPM of [SPM_MIN, spm_max], 0.75 x the longest stroke, 85 % volumetric efficiency) - equipment only."""
    a_pl = math.pi / 4 * (plunger_diameter_mm * 1e-3) ** 2
    capacity_mid = 1440.0 * 0.5 * (SPM_MIN + spm_max) * a_pl * 0.75 * stroke_max_m * 0.85
    return 0.7 * capacity_mid


def element_length_m(depth_m: float) -> float:
    """The family's FE element length for a string of that depth (~40 elements, within [12.5, 50] m)."""
    return float(np.clip(depth_m / 40.0, 12.5, 50.0))


def tvd_m(stations: list[dict], depth_m: float) -> float:
    """True vertical depth at MD ``depth_m`` of a survey's (MD, inclination) stations (vertical when none)."""
    if not stations:
        return depth_m
    md = np.array([s["md_m"] for s in stations])
    inc = np.radians([s["inclination_deg"] for s in stations])
    grid = np.linspace(0.0, depth_m, 2001)
    c = np.cos(np.interp(grid, md, inc))
    return float(np.sum(0.5 * (c[1:] + c[:-1]) * np.diff(grid)))
