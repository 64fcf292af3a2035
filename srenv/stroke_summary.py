"""Per-stroke summary: composes ``metrics`` (pure functions on traces) with a simulator run.

This is where a run's raw records become the numbers users read: PPRL/MPRL (``pprl_n``/``mprl_n`` over
every stroke of the run, start-up included; ``last_stroke_pprl_n``/``last_stroke_mprl_n`` of the last
stroke only, the periodic state a measured card is compared with), pump stroke, fillage,
production, the card class (``card_class``: full, fluid_pound, gas_interference, no_fluid_load),
Goodman loading per taper, card work, stick-slip index and the solver path counts; with a
conventional beam unit also the gearbox torque, its loading against the reducer rating and the
polished-rod and motor power (``gearbox.py``).
"""

from __future__ import annotations

import numpy as np

from . import metrics
from .fluid import tubing_pressure_pa
from .inflow import SECONDS_PER_DAY
from .pump_card import analyse_pump_card
from .simulator import RunResult, Simulator, concat_traces

# Smooth stroke-frequency curvature of du leaks through the moving average (metrics docstring);
# 5 mm keeps the index at 0 on smooth cards while a real slip cycle (cm-scale) still counts.
SLIP_FLOOR_M = 0.005


def taper_tops(sim: Simulator) -> list[int]:
    """Index of the first element of each taper."""
    taper = sim.mesh.taper
    return [int(np.argmax(taper == k)) for k in range(int(taper.max()) + 1)]


def _taper_top_data(sim: Simulator) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(element index, area, p*A shift to true load, tensile strength) at each taper top; cached per sim."""
    cached = getattr(sim, "_taper_top_data", None)
    if cached is None:
        mesh, cfg = sim.mesh, sim.cfg
        e = np.array(taper_tops(sim))
        p_top = tubing_pressure_pa(cfg.fluid, sim.survey.tvd(mesh.x_m[e]))
        tensile = np.array([metrics.ROD_GRADE_TENSILE_PA[t.grade] for t in cfg.rod.tapers])
        cached = (e, mesh.area_m2[e], p_top * mesh.area_m2[e], tensile)
        sim._taper_top_data = cached
    return cached


def goodman_per_taper(sim: Simulator, fmax_eq: np.ndarray, fmin_eq: np.ndarray) -> np.ndarray:
    """Goodman loading % (RP 11BR range form, SF = 1) at the top of each taper, from true loads
    (N = N_eq - p A)."""
    e, area, shift, tensile = _taper_top_data(sim)
    s = metrics.taper_stress_range(fmax_eq[e] - shift, fmin_eq[e] - shift, area)
    return np.atleast_1d(metrics.goodman_loading_pct(s["max_stress_pa"], s["min_stress_pa"], tensile))


def slip_window_s(t_s: np.ndarray, f1_hz: float) -> float:
    """Moving-average window of the slip amplitude: one natural period, clipped to what the trace can hold.

    A stroke shorter than a natural period (a fast SPM on a long string) or a natural period shorter than
    two time steps (a short, stiff string) would otherwise make the metric raise - inside ``env.step``,
    where any legal SPM must work. Clipped, the amplitude is taken about the average over the whole stroke
    (respectively about the samples themselves, i.e. 0)."""
    n = len(t_s)
    dt = float(t_s[-1] - t_s[0]) / (n - 1) if n > 1 else 1.0
    return min(max(1.0 / f1_hz, 2.0 * dt), max(n - 2, 2) * dt)


def summarize(sim: Simulator, results: list[RunResult]) -> dict:
    """Metrics of the strokes in `results` (recorded runs), as a flat JSON-ready dict."""
    tr = results[0].trace if len(results) == 1 else concat_traces(results)
    n_strokes = len(results)
    pos, load = tr["polished_rod_position_m"], tr["polished_rod_load_n"]
    card = metrics.card_metrics(pos, load)  # every stroke, start-up included
    last = card if n_strokes == 1 else metrics.card_metrics(results[-1].trace["polished_rod_position_m"],
                                                            results[-1].trace["polished_rod_load_n"])
    pump_stroke = metrics.pump_stroke_m(tr["pump_position_m"]) if n_strokes == 1 else float(np.mean(
        [metrics.pump_stroke_m(r.trace["pump_position_m"]) for r in results]))
    fill = float(np.mean([r.fillage for r in results]))
    # the card class of the last stroke's pump card (labelled cards for classifiers; pump_card.py)
    last_tr = results[-1].trace
    pump_card = analyse_pump_card(last_tr["pump_position_m"], last_tr["pump_load_n"])
    spm = results[-1].spm
    # production = liquid actually lifted over the time it took (a stroke whose barrel only partly filled
    # counts its liquid, not its swept volume; slow and fast strokes are weighed by their duration)
    duration_s = sum(r.duration_s for r in results)
    production = SECONDS_PER_DAY * sum(r.pumped_m3 for r in results) / duration_s
    du = tr["polished_rod_position_m"] - tr["pump_position_m"]  # u_B - u_A (both positive down)
    one = results[0] if n_strokes == 1 else None  # the env's case: skip the list reductions
    rod_eps = one.rod_stick_episodes if one else np.sum([r.rod_stick_episodes for r in results], axis=0)
    ss = metrics.stick_slip_index(tr["t_s"], tr["pump_velocity_m_s"], du, rod_eps, n_strokes,
                                  slip_window_s(tr["t_s"], sim.f1_hz), slip_floor_m=SLIP_FLOOR_M)
    fmax = one.element_force_max_eq_n if one else np.max([r.element_force_max_eq_n for r in results], axis=0)
    fmin = one.element_force_min_eq_n if one else np.min([r.element_force_min_eq_n for r in results], axis=0)
    goodman = goodman_per_taper(sim, fmax, fmin)
    n_steps = sum(r.n_steps for r in results)
    summary = {
        "strokes": n_strokes,
        "spm": spm,
        "pprl_n": card["pprl_n"],
        "mprl_n": card["mprl_n"],
        "last_stroke_pprl_n": last["pprl_n"],  # the periodic stroke a measured card compares with
        "last_stroke_mprl_n": last["mprl_n"],
        "polished_rod_stroke_m": card["stroke_m"],
        "pump_stroke_m": pump_stroke,
        "fillage": fill,
        "card_class": pump_card["card_class"],
        "card_fillage": pump_card["fillage"],  # read off the last pump card, as a diagnosis would
        "production_m3_day": production,
        "duration_s": duration_s,
        "card_work_j_per_stroke": card["card_area_j"] / n_strokes,
        "goodman_pct": goodman.tolist(),
        "goodman_max_pct": float(goodman.max()),
        **{k: (float(v) if isinstance(v, float) else int(v)) for k, v in ss.items()},
        "intake_pressure_pa": results[-1].intake_pressure_pa,
        "steps": n_steps,
        "certified_steps": sum(r.certified_steps for r in results),
        "corrected_steps": sum(r.corrected_steps for r in results),
        "qp_steps": sum(r.qp_steps for r in results),
        "solver_calls": sum(r.qp_calls for r in results),
        "solver_calls_per_stroke": sum(r.qp_calls for r in results) / n_strokes,
    }
    # a conventional unit has a gearbox: its torque loading is the env's peak-load signal at the surface
    gearbox = sim.surface.gearbox_report(results)
    if gearbox is not None:
        summary.update(gearbox.summary())
    return summary
