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

import weakref

import numpy as np

from ..physics.conditions import condition_name
from ..physics.fluid import tubing_pressure_pa
from ..physics.inflow import SECONDS_PER_DAY
from ..simulation.simulator import RunResult, Simulator, concat_traces
from . import metrics
from .pump_card import FULL_FILLAGE, GAS_TRANSFER_FRACTION, NO_LOAD_FRACTION
from .stick_metrics import _reversal_allowance
from .stroke_pass import goodman_pct, stroke_pass

# Smooth stroke-frequency curvature of du leaks through the moving average (metrics docstring);
# 5 mm keeps the index at 0 on smooth cards while a real slip cycle (cm-scale) still counts.
SLIP_FLOOR_M = 0.005
# the defaults of metrics.stick_slip_index (definitions in the metrics docstring)
SLIP_REFERENCE_M = 0.01
SLIP_TOL_M = 1e-9
REST_TOL_M_S = 1e-12
REST_MIN_STEPS = 2


def taper_tops(sim: Simulator) -> list[int]:
    """Index of the first element of each taper."""
    taper = sim.mesh.taper
    return [int(np.argmax(taper == k)) for k in range(int(taper.max()) + 1)]


# per simulator, kept here rather than written onto it (its state changes only through its own methods)
_TAPER_TOP_DATA: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def _taper_top_data(sim: Simulator) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(element index, area, p*A shift to true load, tensile strength) at each taper top; cached per sim."""
    cached = _TAPER_TOP_DATA.get(sim)
    if cached is None:
        mesh, cfg = sim.mesh, sim.cfg
        e = np.array(taper_tops(sim))
        p_top = tubing_pressure_pa(cfg.fluid, sim.survey.tvd(mesh.x_m[e]))
        tensile = np.array([t.tensile_strength_pa or metrics.ROD_GRADE_TENSILE_PA[t.grade] for t in cfg.rod.tapers])
        cached = (e, mesh.area_m2[e], p_top * mesh.area_m2[e], tensile)
        _TAPER_TOP_DATA[sim] = cached
    return cached


def goodman_per_taper(sim: Simulator, fmax_eq: np.ndarray, fmin_eq: np.ndarray) -> np.ndarray:
    """Goodman loading % (RP 11BR range form, SF = 1) at the top of each taper, from true loads
    (N = N_eq - p A): :func:`srenv.analysis.metrics.goodman_loading_pct` of :func:`srenv.analysis.metrics.taper_stress_range`,
    compiled on the few taper tops (the numpy calls cost more than their arithmetic here)."""
    e, area, shift, tensile = _taper_top_data(sim)
    return goodman_pct(fmax_eq, fmin_eq, e, shift, area, tensile / 4)


def slip_window_s(t_s: np.ndarray, f1_hz: float) -> float:
    """Moving-average window of the slip amplitude: one natural period, clipped to what the trace can hold.

    A stroke shorter than a natural period (a fast SPM on a long string) or a natural period shorter than
    two time steps (a short, stiff string) would otherwise make the metric raise - inside ``env.step``,
    where any legal SPM must work. Clipped, the amplitude is taken about the average over the whole stroke
    (respectively about the samples themselves, i.e. 0)."""
    n = len(t_s)
    dt = float(t_s[-1] - t_s[0]) / (n - 1) if n > 1 else 1.0
    return min(max(1.0 / f1_hz, 2.0 * dt), max(n - 2, 2) * dt)


def _card_class(stroke: float, down: float, up: float, x_min: float, x_mid: float, x90: float,
                x10: float) -> tuple[str, float]:
    """(card class, fillage) of :func:`srenv.analysis.pump_card.analyse_pump_card` from
    :func:`srenv.analysis.stroke_pass.pump_card_figures`."""
    fluid = up - down
    if not stroke > 0 or fluid <= NO_LOAD_FRACTION * max(abs(up), abs(down), 1.0):
        return "no_fluid_load", 0.0
    fillage = min(max((x_mid - x_min) / stroke, 0.0), 1.0)
    if fillage >= FULL_FILLAGE:
        return "full", fillage
    return ("gas_interference" if max(0.0, x90 - x10) > GAS_TRANSFER_FRACTION * stroke else "fluid_pound"), fillage


def _stroke_figures(sim: Simulator, tr: dict, last_tr: dict, n_strokes: int, rod_eps: np.ndarray) -> tuple:
    """(card metrics, stick-slip components, (card class, card fillage)) of a trace and of the last stroke's pump
    card by one compiled pass (:mod:`srenv.analysis.stroke_pass`), with the checks of
    :func:`srenv.analysis.stick_metrics.stick_slip_index`."""
    t = tr["t_s"]
    n = t.size
    if n < 2:
        raise ValueError("need at least two time samples")
    dt = float(t[-1] - t[0]) / (n - 1)
    half = round(0.5 * slip_window_s(t, sim.f1_hz) / dt)
    if half < 1 or n < 2 * half + 1:
        raise ValueError(f"trace of {n} samples cannot hold the slip window of {2 * half + 1} samples")
    allowance = _reversal_allowance(n_strokes)
    figures, rod_extra, pump_card = stroke_pass(
        t, tr["polished_rod_position_m"], tr["polished_rod_load_n"], tr["pump_position_m"], tr["pump_velocity_m_s"],
        last_tr["pump_position_m"], last_tr["pump_load_n"], half, REST_TOL_M_S, REST_MIN_STEPS, rod_eps, allowance)
    jitter, f_max, f_min, stroke, area, pump_stroke, episodes, slip_pp = figures
    if not dt > 0.0 or jitter > 1e-6 * dt:
        raise ValueError("t_s must be strictly increasing and uniformly sampled")
    card = {"pprl_n": f_max, "mprl_n": f_min, "stroke_m": stroke, "card_area_j": area, "pump_stroke_m": pump_stroke}
    amplitude = 0.5 * slip_pp if 0.5 * slip_pp > SLIP_TOL_M else 0.0
    plunger_extra = max(0, episodes - allowance)
    index = plunger_extra + (rod_extra / rod_eps.size if rod_eps.size else 0.0) \
        + max(0.0, amplitude - SLIP_FLOOR_M) / SLIP_REFERENCE_M
    ss = {"plunger_stick_episodes": episodes, "plunger_extra_stick_episodes": plunger_extra,
          "rod_extra_stick_episodes": rod_extra, "slip_amplitude_m": amplitude, "stick_slip_index": float(index)}
    return card, ss, _card_class(*pump_card)


def summarize(sim: Simulator, results: list[RunResult]) -> dict:
    """Metrics of the strokes in `results` (recorded runs), as a flat JSON-ready dict."""
    tr = results[0].trace if len(results) == 1 else concat_traces(results)
    n_strokes = len(results)
    one = results[0] if n_strokes == 1 else None  # the env's case: skip the list reductions
    rod_eps = np.asarray(one.rod_stick_episodes if one else np.sum([r.rod_stick_episodes for r in results], axis=0),
                         dtype=np.int64)
    # the card of every stroke, start-up included, and the card class of the last stroke's pump card (labelled
    # cards for classifiers; pump_card.py)
    card, ss, (card_class, card_fillage) = _stroke_figures(sim, tr, results[-1].trace, n_strokes, rod_eps)
    last = card if n_strokes == 1 else metrics.card_metrics(results[-1].trace["polished_rod_position_m"],
                                                            results[-1].trace["polished_rod_load_n"])
    pump_stroke = card["pump_stroke_m"] if n_strokes == 1 else float(np.mean(
        [metrics.pump_stroke_m(r.trace["pump_position_m"]) for r in results]))
    fill = float(results[0].fillage) if n_strokes == 1 else float(np.mean([r.fillage for r in results]))
    spm = results[-1].spm
    # production = liquid actually lifted over the time it took (a stroke whose barrel only partly filled
    # counts its liquid, not its swept volume; slow and fast strokes are weighed by their duration)
    duration_s = sum(r.duration_s for r in results)
    production = SECONDS_PER_DAY * sum(r.pumped_m3 for r in results) / duration_s
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
        "card_class": card_class,
        "condition": condition_name(sim.cfg, card_class),  # one of physics.conditions.LABELS
        "card_fillage": card_fillage,  # read off the last pump card, as a diagnosis would
        "production_m3_day": production,
        "duration_s": duration_s,
        "card_work_j_per_stroke": card["card_area_j"] / n_strokes,
        "goodman_pct": goodman.tolist(),
        "goodman_max_pct": float(goodman.max()),
        **ss,
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
    if getattr(sim.surface, "motor", None) is not None:  # surface.motor: the crank speed it gave (motor.py)
        summary["motor"] = sim.surface.motor.summary()
    return summary
