"""The cases of a sweep: parameter sets from ``--grid`` / ``--case``, each run at every ``--values`` entry; the
metric columns every backend reports (see :mod:`srenv.tools.sweep`)."""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass
from typing import Any

from ..declarations import MAX_SWEEP_WORKERS as MAX_WORKERS  # noqa: F401  (declared with the flag)
from ..errors import ConfigError

METRIC_COLUMNS = ("duration_s", "plunger_stick_episodes", "plunger_extra_stick_episodes", "slip_amplitude_m",
                  "peak_polished_rod_load_n", "min_polished_rod_load_n", "polished_rod_load_oscillation_pp_n",
                  "dc_iterations_per_step", "qp_steps")
SET_COLUMN = "parameter_set"
MAX_CASES = 10_000  # simulations of one study (rows of its CSV)


@dataclass(frozen=True)
class Case:
    """One simulation of the study: parameter set ``set_index`` at swept value ``value``."""

    index: int
    set_index: int
    set_params: dict[str, Any]
    value: float
    raw: dict  # the full config mapping (overrides applied), shipped to the worker


# ----------------------------------------------------------------------------------------------- parsing
def parse_values(text: str, flag: str = "--values") -> list[float]:
    """'0.05,0.5,1' -> [0.05, 0.5, 1.0]; distinct finite numbers, at least one."""
    out: list[float] = []
    for item in text.split(","):
        try:
            x = float(item)
        except ValueError:
            raise ConfigError(flag, text, "comma-separated numbers, e.g. 0.05,0.5,1") from None
        if not math.isfinite(x):
            raise ConfigError(flag, text, "finite numbers")
        out.append(x)
    if len(set(out)) != len(out):
        raise ConfigError(flag, text, "distinct values")
    return out


def _split_key(item: str, flag: str) -> tuple[str, str]:
    if "=" not in item or not item.split("=", 1)[0].strip():
        raise ConfigError(flag, item, "KEY.PATH=VALUE")
    key, value = item.split("=", 1)
    return key.strip(), value.strip()


def parse_grid(items: list[str] | None) -> list[tuple[str, list[float]]]:
    """['pump.reference_velocity_m_s=0.5,1,2'] -> [('pump.reference_velocity_m_s', [0.5, 1.0, 2.0])]"""
    grid = []
    for item in items or []:
        key, values = _split_key(item, "--grid")
        grid.append((key, parse_values(values, f"--grid {key}")))
    return grid


def parse_case(items: list[str] | None) -> list[dict[str, float]]:
    """['a.b_m=1,c.d_n=2'] -> [{'a.b_m': 1.0, 'c.d_n': 2.0}]: one fixed parameter set per item."""
    cases = []
    for item in items or []:
        case = {}
        for pair in item.split(","):
            key, value = _split_key(pair, "--case")
            case[key] = parse_values(value, f"--case {key}")[0]
        cases.append(case)
    return cases


def parameter_sets(grid: list[tuple[str, list[float]]],
                   cases: list[dict[str, float]]) -> list[dict[str, float]]:
    """Cartesian product of the grid lists, times the explicit cases (a set of no parameters if neither)."""
    product = [dict(zip([k for k, _ in grid], combo, strict=True))
               for combo in itertools.product(*[v for _, v in grid])]
    return [{**g, **c} for g in product for c in (cases or [{}])]


def column_names(keys: list[str]) -> dict[str, str]:
    """CSV column of each config key: its last segment (which carries the unit), the full path if two
    keys share it."""
    last = [k.rsplit(".", 1)[-1] for k in keys]
    return {k: (s if last.count(s) == 1 else k) for k, s in zip(keys, last, strict=True)}


def build_cases(config: str, param: str, values: list[float], overrides: list[str] | None,
                sets: list[dict[str, float]]) -> list[Case]:
    """Every (set, value) case with its config mapping, each validated here: one clear error before any
    simulation runs."""
    from ..config import apply_overrides, config_from_dict, read_raw

    if param in {k for s in sets for k in s}:
        raise ConfigError("--param", param, "a key not also given by --grid or --case")
    base = apply_overrides(read_raw(config), overrides)
    cases = []
    for si, params in enumerate(sets):
        for value in values:
            raw = apply_overrides(base, {**params, param: value})
            cfg = config_from_dict(raw)
            if param == "surface.pull_velocity_m_s" and cfg.surface.motion != "pullout":
                raise ConfigError("surface.motion", cfg.surface.motion,
                                  "'pullout' when sweeping surface.pull_velocity_m_s")
            cases.append(Case(len(cases), si, params, value, raw))
    return cases


# ----------------------------------------------------------------------------------------------- one case
