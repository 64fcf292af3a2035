"""docs/realism.md's "The static load budget": the two field records' polished-rod loads term by term, with the
load plateaus (mean over 25-75 % of the travel, each stroke) of the measured surface card, srenv's prediction,
srenv's and the vendor's diagnosed pump cards, and the vendor's own full-pump prediction (7699227: only its PPRL
and MPRL are stored, so srenv simulates the same ideal pump card to compare like with like). Both survey
readings (`--survey-weight inclination|tvd`). Nothing is fitted.

    python scripts/realism_load_budget.py > docs/realism_load_budget.json
"""

from __future__ import annotations

import argparse
import json
import os
import tempfile
from pathlib import Path

import numpy as np

from srenv.analysis.field_model import discharge_pressure_pa, well_config
from srenv.analysis.field_record import read_dynacard_json
from srenv.analysis.load_budget import card_plateaus, static_budget
from srenv.config import apply_overrides, config_from_dict
from srenv.field_units import to_si
from srenv.simulation.simulator import Simulator
from srenv.tools.validate import pump_state, validate, write_motion_csv

DATA = Path(__file__).resolve().parent.parent / "tests" / "data" / "field"
WELLS = ("11708328", "7699227")
FRICTION_WHAT_IF = 0.1  # the records give no rod-tubing friction coefficient; validate runs 0


def _vendor(path: Path) -> dict:
    """The vendor's own analysis numbers the budget quotes (field units in the record, SI here)."""
    d = json.loads(path.read_text())
    a, perf = d.get("downholeCardAnalysis") or {}, d.get("Performance") or {}

    def num(v, unit):
        return None if v is None else to_si(float(str(v).rstrip("%")), unit, "record")

    return {"discharge_pressure_pa": num(a.get("Pump Discharge Pressure"), "psi"),
            "intake_pressure_pa": num(a.get("Pump Intake Pressure"), "psi"),
            "fluid_load_n": num(a.get("Fluid Load"), "lbf"),
            "upstroke_line_n": num(a.get("Fluid Load Upstroke"), "lbf"),
            "downstroke_line_n": num(a.get("Fluid Load Downstroke"), "lbf"),
            "ideal_pump_load_max_n": perf.get("IdealCardSimulation_DownholeCard_Load_max"),
            "ideal_pump_load_min_n": perf.get("IdealCardSimulation_DownholeCard_Load_min")}


def _model(rec, survey_weight: str, work: str, overrides: dict | None = None):
    csv = os.path.join(work, "motion.csv")
    write_motion_csv(rec, csv)
    st = pump_state(rec, work, survey_weight)
    cfg = well_config(rec, csv, st["intake_pressure_pa"], st["fillage"], st["plunger_friction_n"],
                      survey_weight=survey_weight)
    return Simulator(config_from_dict(apply_overrides(cfg, dict(overrides or {})))), st


def ideal_card(rec, survey_weight: str, vendor: dict) -> dict | None:
    """srenv driven by the measured motion with the vendor's ideal pump card (effective loads min..max, full,
    rigid transfer, no drag): its PPRL / MPRL against the vendor's prediction from the same pump card."""
    ref = rec.reference_prediction
    if ref is None or vendor["ideal_pump_load_max_n"] is None:
        return None
    with tempfile.TemporaryDirectory() as work:
        sim, _ = _model(rec, survey_weight, work)
        shift = sim.p_pump_pa * sim.area_bottom_m2  # effective -> true at the rod end
    over = {"pump.load_source": "loads", "pump.upstroke_load_n": float(vendor["ideal_pump_load_max_n"]) - shift,
            "pump.downstroke_load_n": float(vendor["ideal_pump_load_min_n"]) - shift, "pump.fillage": 1.0,
            "pump.liquid_compressibility_per_pa": 0.0, "pump.depth_m": None}
    out, _ = validate(rec, [], 4, "effective", over, survey_weight=survey_weight)
    return {"srenv_pprl_n": out["predicted_pprl_n"], "srenv_mprl_n": out["predicted_mprl_n"],
            "vendor_pprl_n": ref["pprl_n"], "vendor_mprl_n": ref["mprl_n"],
            "srenv_minus_vendor_pprl_n": out["predicted_pprl_n"] - ref["pprl_n"],
            "srenv_minus_vendor_mprl_n": out["predicted_mprl_n"] - ref["mprl_n"]}


def one(rec, survey_weight: str, vendor: dict) -> dict:
    with tempfile.TemporaryDirectory() as work:
        sim, st = _model(rec, survey_weight, work)
        budget = static_budget(sim)
        sim_mu, _ = _model(rec, survey_weight, work, {"friction.coefficient": FRICTION_WHAT_IF})
        fric = {k: static_budget(sim_mu)[k]["rod_tubing_friction_n"] for k in ("upstroke", "downstroke")}
        p_d = discharge_pressure_pa(rec, survey_weight)
    out, (card, result, pump_card) = validate(rec, [], 4, "effective", survey_weight=survey_weight)
    tr = result.trace
    a_pl = budget["pump"]["plunger_area_m2"]
    eff = pump_card.pump_load_n + pump_card.rod_end_pressure_pa * pump_card.rod_end_area_m2
    row = {
        "budget": budget,
        "rod_tubing_friction_at_mu_0.1_n": fric,
        "hydrostatic_discharge_pressure_pa": p_d,
        "hydrostatic_fluid_load_n": (p_d - st["intake_pressure_pa"]) * a_pl,
        "pump_state": st,
        "plateaus_n": {
            "measured_surface": card_plateaus(card.position_m, card.load_n),
            "predicted_surface": card_plateaus(tr["polished_rod_position_m"], tr["polished_rod_load_n"]),
            "static_budget": {k: budget[k]["effective_bookkeeping_n"] for k in ("upstroke", "downstroke")},
            "srenv_diagnosis_effective": card_plateaus(pump_card.pump_position_m, eff),
            "vendor_pump_card_effective": None if rec.pump_load_n is None else
            card_plateaus(rec.pump_position_m, rec.pump_load_n)},
        "validate": {k: out[k] for k in ("pprl_error_pct", "mprl_error_pct", "card_rms_pct_of_pprl", "card_offset_n",
                                         "card_shape_rms_pct_of_pprl", "pump_card_rms_pct_of_range")},
        "pump_card_offset_n": out.get("pump_card_offset_n"),
        "ideal_card": ideal_card(rec, survey_weight, vendor),
    }
    if vendor["discharge_pressure_pa"] is not None:  # what the vendor's p_d carries beyond the hydrostatic one
        row["vendor_pd_excess_force_n"] = (vendor["discharge_pressure_pa"] - p_d) * a_pl
    return row


def main() -> None:
    report = {"command": "python scripts/realism_load_budget.py > docs/realism_load_budget.json",
              "friction_what_if_coefficient": FRICTION_WHAT_IF}
    for well in WELLS:
        path = DATA / f"{well}.json"
        rec = read_dynacard_json(path, auto_orient=True)
        vendor = _vendor(path)
        entry = {"vendor": vendor, "inclination": one(rec, "inclination", vendor)}
        if rec.survey:  # a record without a survey is vertical under both readings
            entry["tvd"] = one(rec, "tvd", vendor)
        report[well] = entry
    print(json.dumps(report, indent=1, default=lambda o: float(o) if np.isscalar(o) else str(o)))


if __name__ == "__main__":
    argparse.ArgumentParser(description=__doc__.splitlines()[0]).parse_args()  # no options: --help only
    main()
