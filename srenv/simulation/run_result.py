"""What a simulator run returns: counters, events and, if recorded, the per-step trace."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..numerics import kernel_layout as L

TRACE_COLUMNS = ("t_s", "polished_rod_position_m", "polished_rod_velocity_m_s", "polished_rod_load_n",
                 "pump_position_m", "pump_velocity_m_s", "pump_load_n", "step_path")


@dataclass
class RunResult:
    """One stroke (or a duration run): counters, events and, if recorded, the per-step trace."""

    n_steps: int
    duration_s: float
    spm: float
    stroke_length_m: float
    certified_steps: int
    corrected_steps: int
    qp_steps: int
    qp_calls: int
    dc_iterations: int
    fillage: float
    pumped_m3: float  # liquid lifted by the plunger in this run (fillage x upstroke x plunger area, summed)
    intake_pressure_pa: float
    rod_stick_episodes: np.ndarray
    element_force_max_eq_n: np.ndarray
    element_force_min_eq_n: np.ndarray
    energy_j: dict
    trace: dict | None = None
    events: list = field(default_factory=list)

    @property
    def solver_calls(self) -> int:
        return self.qp_calls


def trace_from_record(rec: np.ndarray, stuffing_box_friction_n: float) -> dict:
    """The trace columns from the kernel's record (views: no copies per stroke)."""
    prl = rec[L.R_PRL]
    if stuffing_box_friction_n > 0:  # the stuffing box resists the polished rod: the dynamometer reads it
        prl = prl + stuffing_box_friction_n * np.sign(rec[L.R_VA])
    return {
        "t_s": rec[L.R_T],
        "polished_rod_position_m": rec[L.R_UA],
        "polished_rod_velocity_m_s": rec[L.R_VA],
        "polished_rod_load_n": prl,
        "pump_position_m": rec[L.R_UB],
        "pump_velocity_m_s": rec[L.R_VB],
        "pump_load_n": rec[L.R_PUMP],
        "step_path": rec[L.R_PATH],
    }


def concat_traces(results: list[RunResult]) -> dict:
    traces = [r.trace for r in results if r.trace is not None]
    return {k: np.concatenate([t[k] for t in traces]) for k in TRACE_COLUMNS} if traces else {}
