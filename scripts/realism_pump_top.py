"""docs/realism.md "The top of 11708328's upstroke and its ring": what-ifs of the pump's state read off each
record's own diagnosed pump card (never off the surface card), with the same four figures and the harmonics on
both field records, the ring's amplitude and timing, and the diagnosed vs predicted pump cards overlaid.

    python scripts/realism_pump_top.py [--out-dir docs/figures] > docs/realism_pump_top.json

The readings of a diagnosed pump card (plateaus, transfer travel, series stiffness, tagging up) are
srenv.analysis.transfer_reading's (each rule fixed before the figures it feeds were measured, applied to both
records alike). Here besides:
- **intake from the plateaus**: the chamber pressure under a rising plunger, p_d - (F_up - F_down - 2 P_f) /
  A_pl, from the two plateaus and validate's plunger drag P_f;
- **series compliance**: free tubing (``tubing.anchored: false``) of the stiffness the diagnosed upstroke
  transfer shows (``tubing.stiffness_n_m``);
- the ring: the predicted polished-rod load's harmonics 4-20 of the stroke, half their peak-to-peak (kN), and
  the time from the end of the predicted upstroke transfer (90 %) to their first peak.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import tempfile
from pathlib import Path

import numpy as np

from srenv.analysis.card_compare import resample_stroke
from srenv.analysis.field_model import (
    CLEARANCE_FRACTION,
    discharge_pressure_pa,
    liquid_compressibility_per_pa,
    well_config,
)
from srenv.analysis.field_record import read_dynacard_json
from srenv.analysis.pump_intake import intake_pressure_pa
from srenv.analysis.transfer_reading import (
    clearance_gas_fraction,
    plateaus,
    series_stiffness_n_m,
    tag_from_diagnosis,
    transfer_samples,
    transfer_travel_m,
)
from srenv.tools.validate import validate

DATA = Path(__file__).resolve().parent.parent / "tests" / "data" / "field"
WELLS = ("11708328", "7699227")
TUBING_AREA_M2 = math.pi / 4 * (0.073 ** 2 - 0.062 ** 2)  # srenv's default tubing, 2 7/8 in (config_sections)
FIGURES = ("pprl_error_pct", "mprl_error_pct", "card_rms_pct_of_pprl", "pump_card_rms_pct_of_range")


def intake_from_plateaus(rec, x: np.ndarray, f: np.ndarray, drag_n: float) -> float:
    """The what-if of the plateaus (25-75 % of each branch): the load lines' formula on another reading."""
    f_up, f_down = plateaus(x, f)
    a_pl = math.pi / 4 * rec.plunger_diameter_m ** 2
    return intake_pressure_pa(f_up - f_down, discharge_pressure_pa(rec), a_pl, drag_n)


def ring(load: np.ndarray) -> np.ndarray:
    """The load's harmonics 4-20 of the stroke (one stroke at equal times)."""
    c = np.fft.rfft(load)
    keep = np.zeros_like(c)
    keep[4:21] = c[4:21]
    return np.fft.irfft(keep, len(load))


def ring_figures(out: dict, rec, result, pa_n: float) -> dict:
    tr = result.trace
    n = len(rec.load_n)
    t = np.arange(n) * (result.duration_s / n)
    pred = resample_stroke(tr["t_s"], tr["polished_rod_load_n"], result.duration_s, n)
    pump = resample_stroke(tr["t_s"], tr["pump_load_n"] + pa_n, result.duration_s, n)
    xp = resample_stroke(tr["t_s"], tr["pump_position_m"], result.duration_s, n)
    top, (_, _, _, done) = transfer_samples(xp, pump)  # done: the upstroke's transfer reaches 90 %
    r = np.roll(ring(pred), -top)
    peaks = [k for k in range(done + 1, n - 1) if r[k] >= r[k - 1] and r[k] >= r[k + 1]]
    return {**{k: out[k] for k in (*FIGURES, "card_offset_n", "card_shape_rms_pct_of_pprl")},
            "h4_20_x_measured": out["spectrum"]["ratio_h4_20"],
            "above_h20_x_measured": out["spectrum"]["ratio_above_h20"],
            "ring_half_p2p_kn": 0.5 * float(np.ptp(ring(pred))) / 1e3,
            "measured_ring_half_p2p_kn": 0.5 * float(np.ptp(ring(rec.load_n))) / 1e3,
            "transfer_end_s": float(t[(done + top) % n]), "first_ring_peak_after_transfer_s":
                float(t[peaks[0]] - t[done]) if peaks else None,
            "predicted_transfer_travel_m": transfer_travel_m(xp, pump),
            "predicted_plunger_travel_m": float(np.ptp(xp))}


def round_trip(rec, result, pa_n: float) -> dict:
    """Two checks of the diagnosis, with validate's model of the record: (1) its resolution of a transfer:
    srenv's own predicted surface card (a rigid transfer), sampled like the record and diagnosed like it; the
    transfer travels of the model's and of that diagnosis's pump cards; (2) a synthesised position channel
    (11708328) is not what makes the top climb: the measured loads diagnosed on the record's unit's motion."""
    from srenv.analysis.diagnose import diagnose_card
    from srenv.config import config_from_dict
    from srenv.tools.validate import card_motion, pump_state

    tr, n, period = result.trace, len(rec.load_n), result.duration_s
    x = resample_stroke(tr["t_s"], tr["polished_rod_position_m"], period, n)
    f = resample_stroke(tr["t_s"], tr["polished_rod_load_n"], period, n)
    with tempfile.TemporaryDirectory() as work:
        csv = os.path.join(work, "motion.csv")
        np.savetxt(csv, np.c_[rec.t_s, rec.position_m], delimiter=",", header="t_s,polished_rod_position_m",
                   comments="")
        st = pump_state(rec, work)
        cfg = config_from_dict(well_config(rec, csv, st["intake_pressure_pa"], st["fillage"],
                                           st["plunger_friction_n"]))
        card = diagnose_card(cfg, np.arange(n) * period / n, x - x.min(), f, period_s=period)
        moved = card_motion(rec)
        on_unit = None if moved is rec else diagnose_card(cfg, moved.t_s, moved.position_m, moved.load_n,
                                                          period_s=rec.period_s)
    out = {"model": transfer_travel_m(tr["pump_position_m"], tr["pump_load_n"] + pa_n),
           "diagnosed_from_the_model_card": transfer_travel_m(card.pump_position_m, card.pump_load_n + pa_n)}
    if on_unit is not None:
        xu, fu = on_unit.pump_position_m, on_unit.pump_load_n + pa_n
        out["measured_card_diagnosed_on_the_units_motion"] = {
            "max_effective_load_n": float(fu.max()), "tag": tag_from_diagnosis(xu, fu),
            "transfer_travel_m": transfer_travel_m(xu, fu), "plateaus_n": plateaus(xu, fu)}
    return out


def what_ifs(rec, base: dict, diag_x: np.ndarray, diag_f: np.ndarray) -> dict:
    """The same what-ifs for every record, each read off its diagnosis or set alike (module docstring)."""
    tag = tag_from_diagnosis(diag_x, diag_f)
    p_c = intake_from_plateaus(rec, diag_x, diag_f, base["pump_state"]["plunger_friction_n"])
    c = liquid_compressibility_per_pa(rec)
    k_read = series_stiffness_n_m(diag_x, diag_f)
    # the clearance's gas read off the diagnosed upstroke transfer, at the model's intake and at the plateaus'
    # (validate's clearance share of the surface stroke; isothermal gas, as validate's model)
    travel_up, p_d = transfer_travel_m(diag_x, diag_f)["up"], discharge_pressure_pa(rec)
    clear_m = CLEARANCE_FRACTION * float(np.ptp(rec.position_m))
    psi = clearance_gas_fraction(travel_up, base["pump_state"]["intake_pressure_pa"], p_d, clear_m)
    psi_pc = clearance_gas_fraction(travel_up, max(p_c, 101325.0), p_d, clear_m)
    return {
        "tagging_up (read off the diagnosis)": None if tag is None else {
            "pump.tag_top_overtravel_m": tag["tag_top_overtravel_m"],
            "pump.tag_stiffness_n_m": tag["tag_stiffness_n_m"]},
        "no free gas (fillage 1)": {"pump.fillage": 1.0},
        "gas at 2x the diagnosed share": {"pump.fillage": max(1.0 - 2.0 * (1.0 - base["model"]["fillage"]), 0.05)},
        "liquid 10x as compressible (slower transfer)": {"pump.liquid_compressibility_per_pa": 10.0 * c},
        "clearance 4x (0.2)": {"pump.clearance_volume_fraction": 0.2},
        "intake from the diagnosed plateaus": {"pump.intake_pressure_pa": max(p_c, 101325.0)},
        "unanchored tubing": {"tubing.anchored": False},
        # the compliance the diagnosed transfer shows, carried by free tubing of that stiffness
        "series compliance read off the diagnosed transfer": None if k_read is None else {
            "tubing.anchored": False, "tubing.stiffness_n_m": k_read},
        "clearance gas read off the diagnosed upstroke transfer": None if psi == 0 else {
            "pump.clearance_gas_fraction": psi},
        "clearance gas and intake read off the diagnosis (plateaus)": None if psi_pc == 0 else {
            "pump.clearance_gas_fraction": psi_pc, "pump.intake_pressure_pa": max(p_c, 101325.0)},
    }, tag, p_c


CLEARANCE_GAS_SHARES = (0.02, 0.05, 0.1, 0.15, 0.2, 0.3)  # the same shares on both records: the law's response


def clearance_gas_scan(rec, pa_n: float) -> dict:
    """The four figures, the harmonics and the transfer travels with the clearance keeping each share as gas."""
    out = {}
    for psi in CLEARANCE_GAS_SHARES:
        o, (_, r, _) = validate(rec, [], 4, "effective", {"pump.clearance_gas_fraction": psi})
        out[str(psi)] = {**{k: o[k] for k in FIGURES}, "h4_20_x_measured": o["spectrum"]["ratio_h4_20"],
                         "predicted_transfer_travel_m": transfer_travel_m(r.trace["pump_position_m"],
                                                                          r.trace["pump_load_n"] + pa_n)}
    return out


def run_well(w: str, ax_cards, ax_ring) -> dict:
    rec = read_dynacard_json(DATA / f"{w}.json", auto_orient=True)
    base, (_, res, pc) = validate(rec, [], 4, "effective")
    pa = pc.rod_end_pressure_pa * pc.rod_end_area_m2
    dx, df = pc.pump_position_m, pc.pump_load_n + pa  # srenv's diagnosis, effective loads
    rows = {"now": ring_figures(base, rec, res, pa)}
    ifs, tag, p_c = what_ifs(rec, base, dx, df)
    ax_cards.plot(rec.pump_position_m - rec.pump_position_m.min(), rec.pump_load_n / 1e3, "k", lw=1.6,
                  label="vendor diagnosis")
    ax_cards.plot(dx - dx.min(), df / 1e3, "0.5", lw=1.2, label="srenv diagnosis")
    plotted = {"now": res, "series compliance read off the diagnosed transfer": None,
               "clearance gas read off the diagnosed upstroke transfer": None,
               "clearance gas and intake read off the diagnosis (plateaus)": None}
    for name, over in ifs.items():
        if over is None:
            rows[name] = {"applied": False, "why": "the diagnosis does not show it (transfer_reading rule)"}
            continue
        out, (_, r, _) = validate(rec, [], 4, "effective", over)
        rows[name] = {"overrides": over, **ring_figures(out, rec, r, pa)}
        if name in plotted:
            plotted[name] = r
    n = len(rec.load_n)
    for name, r in plotted.items():
        if r is None:
            continue
        x = r.trace["pump_position_m"]
        ax_cards.plot(x - x.min(), (r.trace["pump_load_n"] + pa) / 1e3, lw=1.0, label=f"predicted: {name}")
        pred = resample_stroke(r.trace["t_s"], r.trace["polished_rod_load_n"], r.duration_s, n)
        ax_ring.plot(np.arange(n) * r.duration_s / n, ring(pred) / 1e3, lw=1.0, label=f"predicted: {name}")
    ax_ring.plot(rec.t_s - rec.t_s[0], ring(rec.load_n) / 1e3, "k", lw=1.6, label="measured")
    ax_cards.set(xlabel="plunger position from its bottom (m)", ylabel="effective pump load (kN)",
                 title=f"{w}: pump cards")
    ax_ring.set(xlabel="time from the card's first sample (s)", ylabel="harmonics 4-20 of the PR load (kN)",
                title=f"{w}: the ring")
    for a in (ax_cards, ax_ring):
        a.legend(fontsize=7)
    return {"rows": rows, "tag_read_off_diagnosis": tag, "intake_from_plateaus_pa": p_c,
            "clearance_gas_scan": clearance_gas_scan(rec, pa),
            "diagnosed_transfer_travel_m": transfer_travel_m(dx, df),
            "series_stiffness_read_n_m": series_stiffness_n_m(dx, df),
            "free_tubing_stiffness_n_m": 2.07e11 * TUBING_AREA_M2 / rec.rod_length_m,
            "diagnosis_checks": round_trip(rec, res, pa),
            # the most a pump can carry hydraulically: the model's upstroke plateau with the chamber emptied to 0
            "hydraulic_ceiling_n": plateaus(res.trace["pump_position_m"], res.trace["pump_load_n"] + pa)[0]
            + base["pump_state"]["intake_pressure_pa"] * math.pi / 4 * rec.plunger_diameter_m ** 2,
            "diagnosed_top_n": None if tag is None else tag["plateau_n"] + tag["climb_n"],
            "vendor_transfer_travel_m": transfer_travel_m(rec.pump_position_m, rec.pump_load_n),
            "pump_state": base["pump_state"], "model_fillage": base["model"]["fillage"]}


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--out-dir", default="docs/figures")
    args = ap.parse_args()
    import matplotlib

    matplotlib.use("Agg")
    from matplotlib.figure import Figure

    fig = Figure(figsize=(12, 8.5), dpi=100)
    axs = fig.subplots(2, 2)
    report = {w: run_well(w, axs[0, k], axs[1, k]) for k, w in enumerate(WELLS)}
    fig.tight_layout()
    fig.savefig(Path(args.out_dir) / "realism_pump_top.png")
    print(json.dumps(report, indent=1, default=float))


if __name__ == "__main__":
    main()
