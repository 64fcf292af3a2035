"""The operator's well file (issue 24): what a field operator knows of their own v2 well, as DATA, and the twin
a model-based controller can build from it.

An operator knows the well's equipment: the rod string (tapers), the survey, the pump's bore and depth (the string's
length), the tubing and casing, the surface unit and motor with its gearbox and structure ratings, the VSD's control
range and the installed point, the wellhead and casing pressures and the produced fluid's density. They do not know
what srenv hides: the reservoir (its IPR, pressure, deliverability and decline), the rod-tubing friction and the
string's damping, the annulus level, the conditions and their schedule, the episode's events.

* :data:`WHITELIST` - the only config fields a well file may hold (``section -> fields``); everything else of the
  well's config is hidden truth or the model's numerics. :func:`well_file` writes a well's file from its config,
  :func:`read_well_file` reads one (a mapping, or a YAML/JSON file read as data by :mod:`srenv.safe_yaml`) and
  refuses an unknown or missing key, a value out of its declared bounds (the config's own declarations) or
  anything that is not a mapping, in one line naming the field, the value and what is expected.
* :func:`twin_config` - the well's twin: the file's equipment and, for what the file does not say, the family's
  nominal values (:data:`NOMINAL`: friction and Gibbs damping at mid-range, Kelvin-Voigt damping on the string's
  own fundamental, a Vogel IPR at the design rate - productivity 1 - and a static level at mid-range, no decline;
  the water cut of the economics from the density, as the family mixes oil and water). No condition: the twin is
  a well running normally.
"""

from __future__ import annotations

import copy
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from ..config import WellConfig, config_from_dict, to_dict
from ..errors import ConfigError
from . import v2_physics
from . import well_family as wf

WHITELIST: dict[str, tuple[str, ...]] = {
    "rod": ("tapers",),
    "survey": ("stations",),
    "fluid": ("density_kg_m3", "wellhead_pressure_pa"),
    "pump": ("load_source", "plunger_diameter_mm", "plunger_friction_n", "discharge_overpressure_pa"),
    "surface": ("motion", "spm", "stroke_length_m", "beam_unit", "motor"),
    "control": ("spm_min", "spm_max", "stroke_min_m", "stroke_max_m"),
    "tubing": ("anchored", "outer_diameter_mm", "inner_diameter_mm", "youngs_modulus_pa", "anchor_depth_m",
               "stiffness_n_m"),
    "inflow": ("casing_pressure_pa", "casing_inner_diameter_mm", "tubing_outer_diameter_mm"),
    "economics": ("pprl_rating_n",),
}
MID = {k: 0.5 * (lo + hi) for k, (lo, hi) in wf.PARAM_RANGES.items()}
NOMINAL = {"friction_coefficient": round(MID["friction_coefficient"], 3), "damping_factor": round(MID["damping_factor"], 3),
           "static_level_fraction": round(MID["static_level_fraction"], 3), "productivity": 1.0, "inflow_model": "vogel"}


def well_file(env_or_well: Any) -> dict[str, Any]:
    """The operator's file of a v2 well: the :data:`WHITELIST` fields of its config (SI, plain data). Takes an env
    after ``reset`` (its played well), a :class:`~srenv.task.well_family.WellSpec` or a :class:`WellConfig`."""
    cfg = env_or_well
    if hasattr(cfg, "unwrapped"):
        cfg = cfg.unwrapped.well
    if isinstance(cfg, wf.WellSpec):
        cfg = cfg.cfg
    if not isinstance(cfg, WellConfig):
        raise ConfigError("well_file", env_or_well, "a reset env, a WellSpec or a WellConfig")
    full = to_dict(cfg)
    return {sec: {k: copy.deepcopy(full[sec][k]) for k in keys} for sec, keys in WHITELIST.items()}


def read_well_file(source: Mapping[str, Any] | str | Path) -> dict[str, Any]:
    """A well file checked: exactly the :data:`WHITELIST` sections and fields (none unknown, none missing), values in
    the config's declared bounds. ``source``: a mapping, or the path of a YAML/JSON file (data, never code).
    Raises :class:`ValueError` (a :class:`~srenv.errors.ConfigError`) naming the field, the value and what is
    expected."""
    if isinstance(source, (str, Path)):
        from ..safe_yaml import load_yaml_file

        source = load_yaml_file(source, "well file")
    if not isinstance(source, Mapping):
        raise ConfigError("well file", source, "a mapping of the sections " + ", ".join(WHITELIST))
    for sec in source:
        if sec not in WHITELIST:
            raise ConfigError(f"well file: {sec}", source[sec], "only the operator's sections "
                              + ", ".join(WHITELIST) + " (the reservoir, conditions and state are not known)")
    out: dict[str, Any] = {}
    for sec, keys in WHITELIST.items():
        block = source.get(sec)
        if not isinstance(block, Mapping):
            raise ConfigError(f"well file: {sec}", block, "a mapping of " + ", ".join(keys))
        unknown = [k for k in block if k not in keys]
        if unknown:
            raise ConfigError(f"well file: {sec}.{unknown[0]}", block[unknown[0]],
                              f"only the fields {', '.join(keys)} (not hidden truth)")
        missing = [k for k in keys if k not in block]
        if missing:
            raise ConfigError(f"well file: {sec}.{missing[0]}", None, "a value (every whitelisted field is given)")
        out[sec] = {k: copy.deepcopy(block[k]) for k in keys}
    twin_config(out, checked=True)  # the values through the config's declared bounds
    return out


def pump_depth_m(file: Mapping[str, Any]) -> float:
    """The pump's measured depth: the rod string's length."""
    return float(sum(float(t["length_m"]) for t in file["rod"]["tapers"]))


def twin_config(file: Mapping[str, Any], checked: bool = False) -> WellConfig:
    """The twin of the described well: the file's equipment, the family's nominal values for what it does not say
    (module doc). ``checked``: the file already passed :func:`read_well_file`'s key checks."""
    f = dict(file) if checked else read_well_file(file)
    raw = copy.deepcopy({sec: dict(v) for sec, v in f.items()})
    given = config_from_dict(copy.deepcopy(raw))  # the file's values through the config's declared bounds
    depth = float(sum(t.length_m for t in given.rod.tapers))
    rho = given.fluid.density_kg_m3
    tvd = wf.tvd_m(to_dict(given.survey)["stations"], depth)
    nominal = wf.nominal_rate_m3_day(given.pump.plunger_diameter_mm, given.control.spm_max, given.control.stroke_max_m)
    casing = given.inflow.casing_pressure_pa
    p_r = casing + rho * wf.GRAVITY_M_S2 * NOMINAL["static_level_fraction"] * tvd
    q_max = NOMINAL["productivity"] * nominal
    water_cut = min(max((rho - wf.OIL_RHO) / (wf.WATER_RHO - wf.OIL_RHO), 0.0), 1.0)
    raw["name"] = "described_twin"
    raw["description"] = "the twin of a well built from its operator's file (srenv.task.well_file)"
    raw["damping"] = {"model": "dimensionless", "damping_factor": NOMINAL["damping_factor"],
                      "stiffness_proportional_s": v2_physics.kv_tau_of(wf.fundamental_spm(depth))}
    raw["friction"] = {"law": "coulomb", "coefficient": NOMINAL["friction_coefficient"]}
    raw["inflow"].update({"model": NOMINAL["inflow_model"], "reservoir_pressure_pa": round(p_r, 1),
                          "max_rate_m3_day": round(q_max, 4),
                          "productivity_index_m3_day_pa": q_max / max(p_r - casing, 1.0),
                          "initial_fluid_level_m": round(NOMINAL["static_level_fraction"] * depth * 0.5, 2)})
    raw["simulation"] = {"element_length_m": wf.element_length_m(depth), "time_step_s": 0.005}
    raw["economics"] = {"water_cut": round(water_cut, 6), **raw["economics"]}
    raw["task"] = {"inflow_decline_per_day": 0.0}
    return config_from_dict(raw)
