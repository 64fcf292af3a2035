"""Catalogue of API 11E pumping units, read with ``yaml.safe_load`` (nothing is evaluated). An entry is a
named nameplate: the same fields as an inline ``surface.beam_unit`` plus its crank holes, ``kind`` one of
conventional (the default: all shipped units), mark_ii, air_balanced.

The loader reads ``configs/units/catalogue.yaml``: in a checkout directly, from a wheel as the package
data it ships (:func:`srenv.shipped.shipped_dir`). Each entry gives either ``k_m`` or ``h_m`` (saddle bearing
height above the crank shaft), see :class:`~srenv.beam_unit.BeamUnitGeometry`.
"""

from __future__ import annotations

import functools
import math
import re
from pathlib import Path
from typing import Any

import yaml

from ..errors import ConfigError
from ..shipped import shipped_dir
from .beam_unit import BeamUnitGeometry, ConventionalUnit

PACKAGE_CATALOGUE_PATH = shipped_dir("units") / "catalogue.yaml"
REPO_CATALOGUE_PATH = Path(__file__).parents[2] / "configs" / "units" / "catalogue.yaml"  # srenv/surface_unit/ up two

IN_LB_TO_NM = 0.0254 * 4.4482216152605
LBF_TO_N = 4.4482216152605
INCH_TO_M = 0.0254

_DESIGNATION = re.compile(
    r"^(?P<kind>[A-Z]+)-(?P<torque>\d+(?:\.\d+)?)(?P<gear>[A-Z]?)-(?P<load>\d+)-(?P<stroke>\d+)$"
)
_GEOMETRY_FIELDS = {
    "designation", "a_m", "c_m", "i_m", "p_m", "crank_radii_m", "rotation", "torque_rating_nm",
    "structural_unbalance_n", "max_stroke_m", "max_load_n",
}


def parse_designation(designation: str) -> tuple[float, float, float]:
    """(torque rating N·m, polished-rod load rating N, max stroke m) from e.g. ``C-228D-213-86``."""
    match = _DESIGNATION.match(designation.strip())
    if match is None:
        raise ConfigError("designation", designation, "an API 11E designation like C-228D-213-86")
    return (float(match["torque"]) * 1000.0 * IN_LB_TO_NM, float(match["load"]) * 100.0 * LBF_TO_N,
            float(match["stroke"]) * INCH_TO_M)


def _geometry_from_entry(entry: Any, index: int) -> BeamUnitGeometry:
    where = f"units[{index}]"
    if not isinstance(entry, dict):
        raise ConfigError(where, entry, "a mapping of unit fields")
    keys = set(entry)
    allowed = _GEOMETRY_FIELDS | {"k_m", "h_m", "kind"}  # kind: conventional (default), mark_ii, air_balanced
    # a misspelt field would otherwise silently fall back to nothing and fail later with a vaguer message
    if unknown := sorted(keys - allowed):
        raise ConfigError(f"{where}.{unknown[0]}", entry[unknown[0]], f"one of the fields {sorted(allowed)}")
    if missing := sorted(_GEOMETRY_FIELDS - keys):
        raise ConfigError(f"{where}.{missing[0]}", None, "a value (field is required)")
    if ("k_m" in keys) == ("h_m" in keys):
        raise ConfigError(f"{where}.k_m", entry.get("k_m"), "exactly one of k_m or h_m, in m")
    # BeamUnitGeometry turns the YAML list of crank radii into its tuple
    if "h_m" in entry:
        return BeamUnitGeometry.from_height(**entry)
    return BeamUnitGeometry(**entry)


@functools.cache
def _load(path: Path) -> dict[str, BeamUnitGeometry]:
    with path.open("r", encoding="utf-8") as handle:
        document = yaml.safe_load(handle)
    if not isinstance(document, dict) or not isinstance(document.get("units"), list):
        raise ConfigError("units", None if not isinstance(document, dict) else document.get("units"),
                          f"a list of units in {path}")
    units: dict[str, BeamUnitGeometry] = {}
    for index, entry in enumerate(document["units"]):
        geometry = _geometry_from_entry(entry, index)
        if geometry.designation in units:
            raise ConfigError(f"units[{index}].designation", geometry.designation, "a new designation")
        _check_ratings_match_designation(geometry)
        units[geometry.designation] = geometry
    return units


def _check_ratings_match_designation(geometry: BeamUnitGeometry) -> None:
    """The SI ratings must be the designation's numbers converted: catches a unit mix-up in the YAML."""
    expected = parse_designation(geometry.designation)
    names = ("torque_rating_nm", "max_load_n", "max_stroke_m")
    for name, value in zip(names, expected, strict=True):
        actual = getattr(geometry, name)
        if not math.isclose(actual, value, rel_tol=1e-3):
            raise ConfigError(f"{geometry.designation}.{name}", actual,
                              f"{value:.6g} (from the designation {geometry.designation})")


def load_catalogue(path: Path | str | None = None) -> dict[str, BeamUnitGeometry]:
    """All units keyed by designation; ``path`` defaults to the copy shipped in the package."""
    return dict(_load(Path(path) if path is not None else PACKAGE_CATALOGUE_PATH))


def list_units() -> list[str]:
    """Known designations, in catalogue order."""
    return list(_load(PACKAGE_CATALOGUE_PATH))


def get_unit(designation: str) -> BeamUnitGeometry:
    """The catalogue unit with this API designation (exact match, surrounding blanks ignored)."""
    units = _load(PACKAGE_CATALOGUE_PATH)
    key = designation.strip() if isinstance(designation, str) else designation
    if key not in units:
        raise KeyError(f"unknown pumping unit {designation!r}; known units: {', '.join(units)}")
    return units[key]


@functools.lru_cache(maxsize=16)
def conventional_unit(designation: str, crank_hole: int) -> ConventionalUnit:
    """Catalogue unit with its crank hole, cached: the env rebuilds simulators on every reset. The one place
    that resolves a unit (config validation and the surface motion both call it)."""
    try:
        geometry = get_unit(designation)
    except KeyError:
        raise ConfigError("surface.unit", designation,
                          "an API designation from the unit catalogue: " + ", ".join(list_units())) from None
    holes = len(geometry.crank_radii_m)
    if not 0 <= crank_hole < holes:
        raise ConfigError("surface.crank_hole", crank_hole, f"an index in 0..{holes - 1} (0 = longest stroke)")
    return ConventionalUnit(geometry, crank_hole)
