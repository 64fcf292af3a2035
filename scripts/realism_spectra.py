"""docs/realism.md's evidence: measured vs predicted surface cards and their load spectra by harmonic of the
stroke, for the previous model (viscous damping only, nu = 0.05) and the realistic model of `srenv validate`
(its damping read off the card by the energy balance where it applies, and the fixed factor beside it),
on the two public field records in tests/data/field/; and how much of the baseline's excess above the 20th
harmonic a load cell's sampling and low-pass filtering would hide.

    python scripts/realism_spectra.py [--out-dir docs/figures] > docs/realism_figures.json
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np

from srenv.analysis.card_compare import harmonic_shares, resample_stroke
from srenv.analysis.field_record import read_dynacard_json
from srenv.tools.validate import validate

DATA = Path(__file__).resolve().parent.parent / "tests" / "data" / "field"
WELLS = ("11708328", "7699227")
BASELINE = {"damping.damping_factor": 0.05, "damping.stiffness_proportional_s": 0.0,
            "pump.liquid_compressibility_per_pa": 0.0}
RIGID_TRANSFER = {"pump.liquid_compressibility_per_pa": 0.0}  # the realistic model with the instant transfer
UNANCHORED = {"tubing.anchored": False}  # what-if: the records do not say whether the tubing is anchored
MOTOR_WHAT_IFS = {"constant_crank_speed": {"enabled": False}, "motor_inertia_1e4": {"inertia_kg_m2": 1e4},
                  "motor_slip_0.13": {"rated_slip": 0.13}}
FRICTION_WHAT_IFS = (0.1, 0.2)  # rod-tubing friction coefficients, what-ifs (the records give none)
VERTICAL = {"survey.stations": []}  # the string's weight taken as if vertical (the vendor's diagnosis?)
FIGURES = ("pprl_error_pct", "mprl_error_pct", "card_rms_pct_of_pprl", "pump_card_rms_pct_of_range",
           "pump_card_offset_n", "spectrum")


def butter2_gain(f_hz: np.ndarray, fc_hz: float) -> np.ndarray:
    """|H| of a second-order Butterworth low-pass (a load-cell amplifier's anti-alias filter)."""
    return 1.0 / np.sqrt(1.0 + (f_hz / fc_hz) ** 4)


def filtered_share(load: np.ndarray, period_s: float, fc_hz: float) -> float:
    c = np.fft.rfft(load)
    f = np.arange(len(c)) / period_s
    e = np.abs(c * butter2_gain(f, fc_hz)) ** 2
    return float(e[21:].sum() / e[1:].sum())


def spectrum(load: np.ndarray) -> np.ndarray:
    e = np.abs(np.fft.rfft(load)) ** 2
    return e[1:] / e[1:].sum()


def fluid_inertia(report: dict):
    """Both records with the lifted liquid column's inertia (pump.fluid_column_mass_kg, opt-in): figures in
    the report, 7699227's surface card in a figure."""
    from matplotlib.figure import Figure

    from srenv.analysis.field_model import fluid_column_kg

    fig = Figure(figsize=(7, 4.2), dpi=100)
    ax = fig.subplots()
    for w in WELLS:
        rec = read_dynacard_json(DATA / f"{w}.json", auto_orient=True)
        m = fluid_column_kg(rec)
        out, (_, r, _) = validate(rec, [], 4, "effective", {"pump.fluid_column_mass_kg": m})
        report[w]["fluid_inertia"] = {"fluid_column_mass_kg": m, **{k: out[k] for k in FIGURES}}
        if w == "7699227":
            _, (_, r0, _) = validate(rec, [], 4, "effective")
            ax.plot(rec.position_m, rec.load_n / 1e3, "k", lw=1.3, label="measured")
            for res, lab in ((r0, "realistic"), (r, f"+ fluid inertia ({m:.0f} kg)")):
                x = res.trace["polished_rod_position_m"]
                ax.plot(x - x.min(), res.trace["polished_rod_load_n"] / 1e3, lw=1.0, label=lab)
            ax.set(xlabel="polished-rod position (m)", ylabel="load (kN)", title="7699227: the lifted column's inertia")
            ax.legend(fontsize=8)
    return fig


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--out-dir", default="docs/figures")
    args = ap.parse_args()
    import matplotlib

    matplotlib.use("Agg")
    from matplotlib.figure import Figure

    fig_s = Figure(figsize=(11, 4.2), dpi=100)
    fig_c = Figure(figsize=(11, 4.2), dpi=100)
    axs, axc = fig_s.subplots(1, 2), fig_c.subplots(1, 2)
    report = {}
    for k, w in enumerate(WELLS):
        rec = read_dynacard_json(DATA / f"{w}.json", auto_orient=True)
        base, (_, rb, _) = validate(rec, [], 4, "effective", BASELINE, damping="fixed")  # its own nu
        real, (_, rr, _) = validate(rec, [], 4, "effective")
        n = len(rec.load_n)
        pb = resample_stroke(rb.trace["t_s"], rb.trace["polished_rod_load_n"], rb.duration_s, n)
        pr = resample_stroke(rr.trace["t_s"], rr.trace["polished_rod_load_n"], rr.duration_s, n)
        h = np.arange(1, n // 2 + 1)
        for y, lab in ((rec.load_n, "measured"), (pb, "baseline (nu 0.05)"), (pr, "realistic (validate)")):
            axs[k].semilogy(h, spectrum(y), lw=1.0, label=lab)
        axs[k].axvspan(4, 20, color="0.9")
        axs[k].set(xlim=(1, 60), ylim=(1e-7, 1), xlabel="harmonic of the stroke", ylabel="share of energy",
                   title=f"{w}: load spectrum")
        axs[k].legend(fontsize=8)
        tr = rr.trace
        x = tr["polished_rod_position_m"]
        axc[k].plot(rec.position_m, rec.load_n / 1e3, lw=1.3, label="measured")
        xb = rb.trace["polished_rod_position_m"]
        axc[k].plot(xb - xb.min(), rb.trace["polished_rod_load_n"] / 1e3, lw=0.8, alpha=0.7, label="baseline")
        axc[k].plot(x - x.min(), tr["polished_rod_load_n"] / 1e3, lw=1.0, label="realistic")
        axc[k].set(xlabel="polished-rod position (m)", ylabel="load (kN)", title=f"{w}: surface card")
        axc[k].legend(fontsize=8)
        meas_above = harmonic_shares(rec.load_n)[1]
        report[w] = {
            "baseline": {key: base[key] for key in FIGURES},
            "realistic": {key: real[key] for key in (*FIGURES, "pump_state", "model", "damping_rule")},
            # the fixed Gibbs factor (0.02) in the diagnosis and the model, against the energy balance's
            # (validate's default since d27; docs/realism.md, "The damping a diagnosis should use")
            "damping_fixed": {key: validate(rec, [], 4, "effective", damping="fixed")[0][key]
                              for key in (*FIGURES, "card_offset_n", "model")},
            "rigid_transfer": {key: validate(rec, [], 4, "effective", RIGID_TRANSFER)[0][key] for key in FIGURES},
            "vertical_weight": {key: validate(rec, [], 4, "effective", VERTICAL)[0][key] for key in FIGURES},
            "unanchored_tubing": {key: validate(rec, [], 4, "effective", UNANCHORED)[0][key] for key in FIGURES},
            # the record's TVD column instead of its inclinations (validate --survey-weight tvd; docs/realism.md,
            # "The static load budget") and rod-tubing friction the records do not give (validate: 0)
            "survey_weight_tvd": {key: validate(rec, [], 4, "effective", survey_weight="tvd")[0][key]
                                  for key in FIGURES},
            **{f"rod_tubing_friction_{mu:g}": {key: validate(rec, [], 4, "effective", {"friction.coefficient": mu})[0][
                key] for key in (*FIGURES, "card_offset_n")} for mu in FRICTION_WHAT_IFS},
            # the record's motor (used where the motion is the record's unit's, 11708328): off (constant crank
            # speed, the previous model) and the what-ifs of its unknowns (docs/realism.md, "The record's motor")
            **{name: {key: got[key] for key in (*FIGURES, "motor")} for name, got in (
                (name, validate(rec, [], 4, "effective", motor=m)[0]) for name, m in MOTOR_WHAT_IFS.items())},
            # the baseline's share above h20 seen through a load cell's 2nd-order low-pass at fc, over the
            # measured share (the card's sampling, 187-200 per stroke, is above h90: it removes nothing below)
            "baseline_above_h20_ratio_through_lowpass": {
                f"{fc:g}_hz": filtered_share(pb, rec.period_s, fc) / meas_above for fc in (10.0, 5.0, 3.0, 2.0)},
            "stroke_frequency_hz": 1.0 / rec.period_s,
        }
    fig_f = fluid_inertia(report)
    for f, name in ((fig_s, "realism_spectra.png"), (fig_c, "realism_cards.png"),
                    (fig_f, "realism_fluid_inertia.png")):
        f.tight_layout()
        f.savefig(Path(args.out_dir) / name)
    print(json.dumps(report, indent=1, default=float))


if __name__ == "__main__":
    main()
