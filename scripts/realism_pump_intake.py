"""The pump's state read off a diagnosed card where the answer is known (docs/realism.md, "The pump's state from
the record's own diagnosis"): srenv's own cards simulated with a set intake pressure and fillage, their surface
cards diagnosed and read by the load lines (``analysis/pump_intake.py``) and by the card's percentiles (the
previous reading, ``pump_card.analyse_pump_card``); then both readings on the two records' cards against the
vendor's analysis. Prints one JSON document; a few seconds.

    python scripts/realism_pump_intake.py > /tmp/pump_intake.json
"""

from __future__ import annotations

import json
import os
import sys
import tempfile
from pathlib import Path

import numpy as np

from srenv.analysis.diagnose import diagnose_card, summary
from srenv.analysis.field_model import MIN_INTAKE_PA, discharge_pressure_pa, well_config
from srenv.analysis.field_record import read_dynacard_json
from srenv.analysis.pump_card import analyse_pump_card
from srenv.analysis.pump_intake import intake_pressure_pa, load_lines, read_pump_state
from srenv.config import apply_overrides, config_from_dict, load_config
from srenv.physics.pump import plunger_area_m2
from srenv.simulation.simulator import Simulator

DATA = Path(__file__).resolve().parent.parent / "tests" / "data" / "field"
PSI, LBF = 6894.757293168, 4.4482216152605
RINGING = {"damping.stiffness_proportional_s": 0.0, "damping.damping_factor": 0.05,
           "pump.liquid_compressibility_per_pa": 0.0}
TAG = {"pump.tag_top_overtravel_m": 0.36, "pump.tag_stiffness_n_m": 1.9e4}


def case(cfg, p_set: float, fill_set: float) -> dict:
    """One simulated card, diagnosed from its surface card and read both ways."""
    res = Simulator(cfg).run_strokes(3)[-1]
    tr = res.trace
    card = diagnose_card(cfg, tr["t_s"], tr["polished_rod_position_m"], tr["polished_rod_load_n"],
                         period_s=res.duration_s)
    s = summary(cfg, card)
    a, fr, dp = plunger_area_m2(cfg.pump), cfg.pump.plunger_friction_n, cfg.pump.discharge_overpressure_pa
    lines = read_pump_state(card.pump_position_m, card.pump_load_n, s["discharge_pressure_pa"], a, fr, dp)
    on_sim = read_pump_state(tr["pump_position_m"], tr["pump_load_n"], s["discharge_pressure_pa"], a, fr, dp)
    return {"p_set_pa": p_set, "fillage_set": fill_set,
            "lines_error_pa": lines["intake_pressure_pa"] - p_set,
            "percentiles_error_pa": intake_pressure_pa(s["fluid_load_n"], s["discharge_pressure_pa"], a, fr, dp) - p_set,
            "lines_on_simulated_pump_card_error_pa": on_sim["intake_pressure_pa"] - p_set,
            "lines_fillage_error": lines["fillage"] - fill_set, "percentiles_fillage_error": s["fillage"] - fill_set}


def simulated(work: str) -> dict:
    out: dict[str, list] = {"default": [], "records": [], "records_ringing": [], "11708328_tagging_up": []}
    for p in (0.5e6, 2e6, 4e6):
        for fill in (1.0, 0.75):
            cfg = load_config("default", ["inflow.model=none", f"pump.intake_pressure_pa={p}", f"pump.fillage={fill}"])
            out["default"].append(case(cfg, p, fill))
    for w in ("11708328", "7699227"):
        rec = read_dynacard_json(DATA / f"{w}.json", auto_orient=True)
        csv = os.path.join(work, f"{w}.csv")
        np.savetxt(csv, np.c_[rec.t_s, rec.position_m], delimiter=",", header="t_s,polished_rod_position_m",
                   comments="", fmt="%.12g")
        for key, over in (("records", {}), ("records_ringing", RINGING), ("11708328_tagging_up", TAG)):
            if key == "11708328_tagging_up" and w != "11708328":
                continue
            for p in (0.5e6, 2e6, 4.5e6):
                for fill in (1.0, 0.8):
                    cfg = config_from_dict(apply_overrides(well_config(rec, csv, p, fill), over))
                    out[key].append(case(cfg, p, fill))
    return out


def records(work: str) -> dict:
    """Both readings on each record's vendor pump card and on srenv's diagnosis of its measured card."""
    out = {}
    for w in ("11708328", "7699227"):
        rec = read_dynacard_json(DATA / f"{w}.json", auto_orient=True)
        csv = os.path.join(work, f"{w}.csv")
        cfg = config_from_dict(well_config(rec, csv, MIN_INTAKE_PA))
        card = diagnose_card(cfg, rec.t_s, rec.position_m, rec.load_n, period_s=rec.period_s)
        a = plunger_area_m2(cfg.pump)
        ours = read_pump_state(card.pump_position_m, card.pump_load_n, discharge_pressure_pa(rec), a)
        pct = analyse_pump_card(card.pump_position_m, card.pump_load_n)
        vendor = load_lines(rec.pump_position_m, rec.pump_load_n)
        vendor_pct = analyse_pump_card(rec.pump_position_m, rec.pump_load_n)
        row = {"discharge_pressure_psi": discharge_pressure_pa(rec) / PSI,
               "column_max_fluid_load_lbf": discharge_pressure_pa(rec) * a / LBF,
               "vendor_card": {"lines_fluid_load_lbf": vendor["fluid_load_n"] / LBF, "lines_fillage": vendor["fillage"],
                               "percentiles_fluid_load_lbf": vendor_pct["fluid_load_n"] / LBF,
                               "percentiles_fillage": vendor_pct["fillage"]},
               "srenv_diagnosis": {"lines_fluid_load_lbf": ours["fluid_load_n"] / LBF, "lines_fillage": ours["fillage"],
                                   "lines_intake_psi": ours["intake_pressure_pa"] / PSI,
                                   "percentiles_fluid_load_lbf": pct["fluid_load_n"] / LBF,
                                   "percentiles_fillage": pct["fillage"]}}
        if rec.fluid_load_n is not None:  # 7699227's analysis: its p_d is 1885 psi (downholeCardAnalysis)
            p_d = 1885 * PSI
            row["vendor_analysis"] = {"fluid_load_lbf": rec.fluid_load_n / LBF, "fillage": rec.fillage,
                                      "intake_psi": rec.intake_pressure_pa / PSI, "discharge_psi": 1885.0}
            row["srenv_diagnosis"]["lines_intake_with_vendor_pd_psi"] = intake_pressure_pa(ours["fluid_load_n"], p_d, a) / PSI
            row["srenv_diagnosis"]["percentiles_intake_with_vendor_pd_psi"] = intake_pressure_pa(pct["fluid_load_n"], p_d, a) / PSI
        out[w] = row
    return out


def main() -> int:
    with tempfile.TemporaryDirectory(prefix="srenv-pump-intake-") as work:
        sim = simulated(work)
        rec = records(work)
    summary_rows = {k: {"lines_max_abs_error_kpa": max(abs(r["lines_error_pa"]) for r in v) / 1e3,
                        "percentiles_max_abs_error_kpa": max(abs(r["percentiles_error_pa"]) for r in v) / 1e3,
                        "lines_max_abs_fillage_error": max(abs(r["lines_fillage_error"]) for r in v),
                        "percentiles_max_abs_fillage_error": max(abs(r["percentiles_fillage_error"]) for r in v)}
                    for k, v in sim.items()}
    json.dump({"simulated_summary": summary_rows, "simulated": sim, "records": rec}, sys.stdout, indent=1)
    print()
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
