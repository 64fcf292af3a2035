"""docs/realism.md "The top of 11708328's upstroke and its ring": what-ifs of the pump's state read off each
record's own diagnosed pump card (never off the surface card), with the same four figures and the harmonics on
both field records, the ring's amplitude and timing, and the diagnosed vs predicted pump cards overlaid.

    python scripts/realism_pump_top.py [--out-dir docs/figures] > docs/realism_pump_top.json

The rules (decided before any figure was measured, applied to both records alike; docs/realism.md):
- the diagnosed upstroke is the diagnosed pump card (effective loads, position from its bottom) from its
  lowest to its highest plunger position; its plateau F_mid is the median load over 25-75 % of the travel,
  its top F_top the median over the top 15 %;
- **tagging up**: a climb F_top - F_mid above 10 % of the card's load range is read as a contact with the
  pump's top: it starts at x_c, the highest position below the top band whose load is still within 10 % of
  the climb of F_mid; the overtravel is travel - x_c, the stiffness the climb over it. No climb: no tag;
- **transfer travel**: the plunger's travel while the upstroke's load rises from 10 % to 90 % of the way from
  its bottom load to F_mid (the diagnosed and the predicted cards alike);
- **intake from the plateaus**: the chamber pressure under a rising plunger, p_d - (F_mid - F_down - 2 P_f) /
  A_pl, F_down the downstroke's median over 25-75 % of the travel, P_f validate's plunger drag;
- the ring: the predicted polished-rod load's harmonics 4-20 of the stroke, half their peak-to-peak (kN), and
  the time from the end of the predicted load transfer (90 %) to their first peak.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import tempfile
from pathlib import Path

import numpy as np

from srenv.analysis.card_compare import _branches, resample_stroke
from srenv.analysis.field_model import discharge_pressure_pa, liquid_compressibility_per_pa, well_config
from srenv.analysis.field_record import read_dynacard_json
from srenv.tools.validate import validate

DATA = Path(__file__).resolve().parent.parent / "tests" / "data" / "field"
WELLS = ("11708328", "7699227")
TUBING_AREA_M2 = math.pi / 4 * (0.073 ** 2 - 0.062 ** 2)  # srenv's default tubing, 2 7/8 in (config_sections)
FIGURES = ("pprl_error_pct", "mprl_error_pct", "card_rms_pct_of_pprl", "pump_card_rms_pct_of_range")


def upstroke(x: np.ndarray, f: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The card's rising part, from its lowest to its highest position (positions from the bottom)."""
    xu, fu = _branches(x, f)[0]
    return xu - x.min(), fu


def downstroke(x: np.ndarray, f: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    xd, fd = _branches(x, f)[1]
    return xd - x.min(), fd


def band_median(x: np.ndarray, f: np.ndarray, lo: float, hi: float) -> float:
    top = x.max()
    return float(np.median(f[(x >= lo * top) & (x <= hi * top)]))


def tag_from_diagnosis(x: np.ndarray, f: np.ndarray) -> dict | None:
    """Tagging up read off a diagnosed pump card (module docstring); None when its upstroke does not climb."""
    xu, fu = upstroke(x, f)
    top = float(xu.max())
    f_mid, f_top = band_median(xu, fu, 0.25, 0.75), band_median(xu, fu, 0.85, 1.0)
    climb = f_top - f_mid
    if climb <= 0.1 * float(np.ptp(f)):
        return None
    first_top = int(np.nonzero(xu >= 0.85 * top)[0][0])
    x_c = float(xu[np.nonzero(fu[:first_top + 1] <= f_mid + 0.1 * climb)[0][-1]])
    return {"climb_start_m": x_c, "travel_m": top, "plateau_n": f_mid, "climb_n": climb,
            "tag_top_overtravel_m": top - x_c, "tag_stiffness_n_m": climb / (top - x_c)}


def transfer_travel_m(x: np.ndarray, f: np.ndarray) -> dict:
    """Plunger travel of the two load transfers, between 10 and 90 % of the way from the downstroke's plateau
    to the upstroke's (medians over 25-75 % of the travel): ``up`` from the last sample of the stroke near
    the downstroke's level to the first after it near the upstroke's (the valve opening at the bottom),
    ``down`` from the first sample after the top below 90 % to the first after it below 10 %."""
    top, (a, b, c, d) = transfer_samples(x, f)
    xr = np.roll(x, -top)
    return {"up": float(xr[d] - xr[c]), "down": float(xr[a] - xr[b])}


def transfer_samples(x: np.ndarray, f: np.ndarray) -> tuple[int, tuple[int, int, int, int]]:
    """The card's top sample and, counted from it, the samples that bound the two transfers
    (transfer_travel_m): downstroke start and end, upstroke start and end."""
    f_up, f_down = band_median(*upstroke(x, f), 0.25, 0.75), band_median(*downstroke(x, f), 0.25, 0.75)
    lo, hi = f_down + 0.1 * (f_up - f_down), f_down + 0.9 * (f_up - f_down)
    top = int(np.argmax(x))
    fr = np.roll(f, -top)  # one cycle from the top: downstroke, then upstroke
    a = int(np.argmax(fr <= hi))
    b = a + int(np.argmax(fr[a:] <= lo))
    c = int(np.nonzero(fr <= lo)[0][-1])
    return top, (a, b, c, c + int(np.argmax(fr[c:] >= hi)))


def series_stiffness_read_n_m(x: np.ndarray, f: np.ndarray) -> float:
    """The spring in series with the pump that the diagnosed upstroke transfer shows: 80 % of the load step
    between the plateaus over the transfer's 10-90 % travel."""
    f_up, f_down = band_median(*upstroke(x, f), 0.25, 0.75), band_median(*downstroke(x, f), 0.25, 0.75)
    return 0.8 * (f_up - f_down) / max(transfer_travel_m(x, f)["up"], 1e-3)


def intake_from_plateaus(rec, x: np.ndarray, f: np.ndarray, drag_n: float) -> float:
    f_up = band_median(*upstroke(x, f), 0.25, 0.75)
    f_down = band_median(*downstroke(x, f), 0.25, 0.75)
    a_pl = math.pi / 4 * rec.plunger_diameter_m ** 2
    return discharge_pressure_pa(rec) - (f_up - f_down - 2.0 * drag_n) / a_pl


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
    return {**{k: out[k] for k in FIGURES}, "h4_20_x_measured": out["spectrum"]["ratio_h4_20"],
            "above_h20_x_measured": out["spectrum"]["ratio_above_h20"],
            "ring_half_p2p_kn": 0.5 * float(np.ptp(ring(pred))) / 1e3,
            "measured_ring_half_p2p_kn": 0.5 * float(np.ptp(ring(rec.load_n))) / 1e3,
            "transfer_end_s": float(t[(done + top) % n]), "first_ring_peak_after_transfer_s":
                float(t[peaks[0]] - t[done]) if peaks else None,
            "predicted_transfer_travel_m": transfer_travel_m(xp, pump),
            "predicted_plunger_travel_m": float(np.ptp(xp))}


def round_trip(rec, result, pa_n: float) -> dict:
    """The diagnosis's resolution of a transfer: srenv's own predicted surface card (a rigid transfer),
    sampled like the record and diagnosed like it; the transfer travels of the model's and that diagnosis's
    pump cards."""
    from srenv.analysis.diagnose import diagnose_card
    from srenv.config import config_from_dict
    from srenv.tools.validate import pump_state

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
    return {"model": transfer_travel_m(tr["pump_position_m"], tr["pump_load_n"] + pa_n),
            "diagnosed_from_the_model_card": transfer_travel_m(card.pump_position_m, card.pump_load_n + pa_n)}


def what_ifs(rec, base: dict, diag_x: np.ndarray, diag_f: np.ndarray) -> dict:
    """The same what-ifs for every record, each read off its diagnosis or set alike (module docstring)."""
    tag = tag_from_diagnosis(diag_x, diag_f)
    p_c = intake_from_plateaus(rec, diag_x, diag_f, base["pump_state"]["plunger_friction_n"])
    c = liquid_compressibility_per_pa(rec)
    k_read = series_stiffness_read_n_m(diag_x, diag_f)
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
        # the compliance the diagnosed transfer shows, carried by free tubing of that stiffness (E scaled)
        "series compliance read off the diagnosed transfer": {
            "tubing.anchored": False, "tubing.youngs_modulus_pa": k_read * rec.rod_length_m / TUBING_AREA_M2},
    }, tag, p_c


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
    plotted = {"now": res, "tagging_up (read off the diagnosis)": None,
               "series compliance read off the diagnosed transfer": None}
    for name, over in ifs.items():
        if over is None:
            rows[name] = {"applied": False, "why": "the diagnosed upstroke does not climb (rule)"}
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
            "diagnosed_transfer_travel_m": transfer_travel_m(dx, df),
            "series_stiffness_read_n_m": series_stiffness_read_n_m(dx, df),
            "free_tubing_stiffness_n_m": 2.07e11 * TUBING_AREA_M2 / rec.rod_length_m,
            "diagnosis_round_trip_transfer_travel_m": round_trip(rec, res, pa),
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
