"""A fixed summary of the operator's well file as student inputs (issue 24, helper d42).

The DAgger students see the field observation only; the causal oracle they imitate plans with the well's full
description. A field operator does know the well's equipment (:mod:`srenv.task.well_file`: :data:`WHITELIST`,
``well_file(env)``). :func:`features` turns one well file into 13 scalars chosen by rod-pumping physics (the
loads the string and the unit carry, what the pump can lift, how close the unit runs to its ratings), each in SI and
scaled by a range declared once in :data:`FEATURES` to ``(v - lo) / (hi - lo)``, clipped to [0, 1]. The ranges hold
every training and validation well of the v2 family (``tests/agents/policies/test_described_features.py``); a well
outside them reads as the nearest bound. Pre-registered in configs/benchmark/v2_oracle_distilled_described.yaml.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import numpy as np

from srenv.physics.rod import GRAVITY_M_S2
from srenv.task import well_family as wf
from srenv.task.well_file import pump_depth_m, read_well_file, well_file

# name (unit in the name), lo, hi of its scaling, what it is: declared once, read by features() and the tests
_TABLE = """
pump_depth_m               500      2500    the rod string's length
plunger_diameter_m         0.03175  0.0635  the pump's bore
fluid_density_kg_m3        850      1030    the produced fluid's
rod_weight_buoyant_n       0        80000   the tapers' steel weight, buoyed by the fluid
fluid_load_n               0        40000   (fluid head at the pump's TVD + wellhead pressure) x plunger area
fluid_to_rod_weight_ratio  0        2       fluid load / buoyant rod weight
stroke_max_m               1.5      3       the unit's longest stroke (control range)
gearbox_torque_rating_nm   0        50000   the beam unit's gearbox rating (no beam unit: 0)
spm_max_per_min            2        12      the top of the VSD's control range
pump_capacity_m3_s         0        0.002   plunger area x longest stroke x top SPM / 60
pprl_rating_n              0        150000  the structure's polished-rod load rating
pprl_headroom_ratio        1        1.5     PPRL rating / (rod weight in air + fluid load)
unit_geometry_code         0        1       conventional 0, Mark II 0.5, air-balanced 1 (no beam unit: 0)
"""
FEATURES: dict[str, tuple[float, float, str]] = {
    row[0]: (float(row[1]), float(row[2]), row[3]) for row in (line.split(maxsplit=3) for line in _TABLE.strip().splitlines())}
GEOMETRY_CODE = {"conventional": 0.0, "mark_ii": 0.5, "air_balanced": 1.0}  # no beam unit (harmonic drive): 0


def raw_features(file: Mapping[str, Any]) -> dict[str, float]:
    """The :data:`FEATURES` of a well file in SI, unscaled. ``file``: ``well_file(...)``'s mapping, checked by
    :func:`srenv.task.well_file.read_well_file` (an unknown, missing or out-of-bounds field is refused in one line)."""
    f = read_well_file(file)
    depth = pump_depth_m(f)
    rho = float(f["fluid"]["density_kg_m3"])
    area = math.pi / 4 * (float(f["pump"]["plunger_diameter_mm"]) * 1e-3) ** 2
    # each taper's weight in air, with its own density (steel or fiberglass), then buoyed by the fluid
    tapers = [(float(t["density_kg_m3"]), float(t["density_kg_m3"]) * GRAVITY_M_S2 * math.pi / 4
               * (float(t["diameter_mm"]) * 1e-3) ** 2 * float(t["length_m"])) for t in f["rod"]["tapers"]]
    rod_air = sum(w for _, w in tapers)
    rod_buoyant = sum(w * (1.0 - rho / dens) for dens, w in tapers)
    tvd = wf.tvd_m(f["survey"]["stations"], depth)
    fluid = (rho * GRAVITY_M_S2 * tvd + float(f["fluid"]["wellhead_pressure_pa"])) * area
    c = f["control"]
    unit = f["surface"].get("beam_unit") or {}
    rating = float(f["economics"]["pprl_rating_n"])
    return {
        "pump_depth_m": depth,
        "plunger_diameter_m": float(f["pump"]["plunger_diameter_mm"]) * 1e-3,
        "fluid_density_kg_m3": rho,
        "rod_weight_buoyant_n": rod_buoyant,
        "fluid_load_n": fluid,
        "fluid_to_rod_weight_ratio": fluid / max(rod_buoyant, 1.0),
        "stroke_max_m": float(c["stroke_max_m"]),
        "gearbox_torque_rating_nm": float(unit.get("torque_rating_nm", 0.0)),
        "spm_max_per_min": float(c["spm_max"]),
        "pump_capacity_m3_s": area * float(c["stroke_max_m"]) * float(c["spm_max"]) / 60.0,
        "pprl_rating_n": rating,
        "pprl_headroom_ratio": rating / max(rod_air + fluid, 1.0),
        "unit_geometry_code": GEOMETRY_CODE.get(str(unit.get("geometry", "")), 0.0),
    }


def features(file: Mapping[str, Any]) -> np.ndarray:
    """The well file's :data:`FEATURES`, each scaled by its declared range to [0, 1] (float32, in their order)."""
    raw = raw_features(file)
    out = np.empty(len(FEATURES), np.float32)
    for i, (name, (lo, hi, _)) in enumerate(FEATURES.items()):
        v = raw[name]
        if not np.isfinite(v):
            raise ValueError(f"well file feature {name} = {v!r}: expected a finite number (from the well file)")
        out[i] = min(max((v - lo) / (hi - lo), 0.0), 1.0)
    return out


def append_features(x: Any, extra: np.ndarray) -> np.ndarray:
    """The described student's input: ``x`` (float32) with ``extra`` appended on the last axis - one well's features
    broadcast over every row, or a row's own (the training pool's, ``table[well]``). The one place both the pool and
    the acting student build it, so the two cannot drift apart."""
    x = np.asarray(x, np.float32)
    extra = np.asarray(extra, np.float32)
    return np.concatenate([x, np.broadcast_to(extra, (*x.shape[:-1], extra.shape[-1]))], axis=-1)


class DescribedInputs:
    """A model policy whose every input gets the played well's :func:`features` appended: the operator's file is read
    once per episode, at ``reset``, from ``well_file(env)`` (the one hook by which the env hands anything of its
    well); the described student of configs/benchmark/v2_oracle_distilled_described.yaml."""

    def __init__(self, model: Any) -> None:
        self.model = model
        self.extra: np.ndarray | None = None

    def reset(self, env: Any, index: int | None = None) -> None:
        self.extra = features(well_file(env))

    def predict(self, observation: Any, state: Any = None, episode_start: Any = None,
                deterministic: bool = True) -> tuple[np.ndarray, Any]:
        if self.extra is None:
            raise RuntimeError("DescribedInputs: call reset(env) after env.reset (the well file is read there)")
        return self.model.predict(append_features(observation, self.extra), state=state, episode_start=episode_start,
                                  deterministic=deterministic)
