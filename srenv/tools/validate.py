"""``srenv validate RECORD [--fit PARAM ...] [--plot P.png] [--reverse] [--load-convention true|effective]``:
predict a field record's surface card from its description (no fitting unless asked), diagnose its measured
card, and compare both with what the record holds. One JSON line (docs/realism.md):

- ``pprl_error_pct``, ``mprl_error_pct``: predicted peak / minimum polished-rod load against the measured,
  in % of the measured;
- ``card_rms_pct_of_pprl``: RMS load difference of the predicted and measured surface cards on common
  positions, upstroke and downstroke apart (``analysis.card_compare``), in % of the measured PPRL;
- ``pump_card_rms_pct_of_range``: srenv's diagnosed pump card against the record's reference (vendor) pump
  card, in the reference's load convention (effective for the vendor layout), positions from each card's
  bottom, in % of the reference's load range (null without a reference);
- ``spectrum``: the share of each card's load-fluctuation energy in harmonics 4-20 and above 20 of the
  stroke, measured and predicted, and their ratios.

RECORD is the vendor dynacard JSON layout (field units; a card stored in reverse time is oriented forward and
reported as ``card_time_reversed``), or srenv's card CSV (``t_s, polished_rod_position_m,
polished_rod_load_n``, or a unit row) with ``--config WELL``. The pump's state (intake pressure, fillage)
comes from the record's own analysis where it has one, else from srenv's diagnosis of the measured card read
by its load lines (``analysis.pump_intake``: the field's p_in = p_d - F_o / A_pl).
"""

from __future__ import annotations

import json
import os
import tempfile

import numpy as np
import yaml

from ..analysis.damping_balance import RULES
from ..analysis.diagnose import LOAD_CONVENTIONS, load_in_convention
from ..errors import ConfigError, NumericFailure
from ..outputs import atomic_write, check_output_path

DEFAULT_STROKES = 4
DEFAULT_DAMPING = "energy-balance"  # the pre-registered decision of docs/realism.md, "The damping a diagnosis should use"


def write_motion_csv(rec, path: str) -> None:
    np.savetxt(path, np.c_[rec.t_s, rec.position_m], delimiter=",", header="t_s,polished_rod_position_m",
               comments="", fmt="%.12g")


def card_motion(rec):
    """The record as the prediction sees it. A vendor record whose position channel is a pure harmonic of time
    was not measured (a load-only controller writes a cosine): the polished rod then moves as the record's own
    unit at constant crank speed, scaled to its stroke, and the measured loads are placed on that motion by
    time (docs/realism.md). Any other record is itself."""
    from dataclasses import replace

    from ..analysis.field_model import position_is_synthesised, unit_position_for_card

    if rec.config is not None or not position_is_synthesised(rec.position_m):
        return rec
    x = unit_position_for_card(rec)
    if x is None:
        return replace(rec, notes=[*rec.notes, ("cardData.Position is a pure harmonic of time (synthesised, not "
                                   "measured) and the record has no unit to take the motion from: used as given")])
    return replace(rec, position_m=x, motion_from_unit=True, notes=[*rec.notes, (
        "cardData.Position is a pure harmonic of time (a synthesised position channel, not a measurement): the "
        "polished rod moves as the record's unit (API dimensions, rotation) at constant crank speed, scaled to "
        "the card's stroke, with the measured loads placed on it by time; the diagnosis reads the stored card")])


def _diagnose(cfg_dict: dict, rec, damping: str = "fixed") -> tuple[object, dict]:
    """The stored card diagnosed with the config's damping or the energy balance's (``summary`` + ``damping``)."""
    from ..analysis.damping_balance import diagnose_with_rule
    from ..analysis.diagnose import diagnose_card, summary
    from ..config import config_from_dict

    cfg, card, entry = diagnose_with_rule(config_from_dict(cfg_dict), damping, lambda c: diagnose_card(
        c, rec.t_s, rec.position_m, rec.load_n, period_s=rec.period_s))
    return card, {**summary(cfg, card), "damping": entry}


def _damping_rule(cfg: dict, rec, state: dict, damping: str | None) -> tuple[dict, dict | None]:
    """The config with the damping the energy balance reads off the record's card (the prediction then uses
    the string the diagnosis found, as it uses the pump state read off the record), and why not when it does
    not apply: a pump state read off the same card makes the balance degenerate (analysis/damping_balance);
    the default (None) also falls back where the model cannot take the rule, a rule asked for is refused."""
    from ..analysis.damping_balance import check_rule
    from ..config import apply_overrides, config_from_dict

    if damping == "fixed":
        return cfg, None
    if damping is None:
        damping = DEFAULT_DAMPING
        try:
            check_rule(damping, config_from_dict(cfg))
        except ConfigError as e:
            return cfg, {"rule": damping, "applied": False, "damping_factor": cfg["damping"]["damping_factor"],
                         "reason": f"the model cannot take it: {e}"}
    if state["source"] == "srenv diagnose":
        return cfg, {"rule": damping, "applied": False, "damping_factor": cfg["damping"]["damping_factor"],
                     "reason": "the pump's state is read off the same card (load lines): the balance is degenerate"}
    _, diag = _diagnose(cfg, rec, damping)
    entry = {**diag["damping"], "applied": diag["damping"]["bracketed"]}
    if not entry["applied"]:
        entry["reason"] = "no root of the balance in the searched range of the Gibbs factor"
        return cfg, entry
    return apply_overrides(cfg, {"damping.damping_factor": entry["damping_factor"]}), entry


def pump_state(rec, work_dir: str, survey_weight: str = "inclination") -> dict:
    """Intake pressure (Pa), fillage and plunger friction (N): the record's own analysis where it has one,
    else srenv's diagnosis of the measured card (never a fit to the surface card)."""
    from ..analysis.field_model import MIN_INTAKE_PA, pump_drag_n, well_config

    if rec.intake_pressure_pa is not None:
        p_in, fluid, source = rec.intake_pressure_pa, rec.fluid_load_n, "record"
        fill = 1.0 if rec.fillage is None else rec.fillage  # a fillage of 0 is a pump that did not fill
        lines = None
    else:
        # srenv's diagnosis of the measured card read as the field reads it: the load lines' fluid load at the
        # pump's own depth, p_in = p_d - F_o / A_pl (no plunger friction: the whole fluid load is pressure),
        # held at one atmosphere at least, and the fillage where the transfer ends (analysis/pump_intake.py)
        _, s = _diagnose(well_config(rec, os.path.join(work_dir, "motion.csv"), MIN_INTAKE_PA,
                                     survey_weight=survey_weight), rec)
        lines = s["load_lines"]
        p_in = max(float(s["intake_pressure_pa"]), MIN_INTAKE_PA)
        fill, fluid, source = float(lines["fillage"]), float(lines["fluid_load_n"]), "srenv diagnose"
    return {"intake_pressure_pa": p_in, "fillage": fill,
            "plunger_friction_n": pump_drag_n(rec, fluid, p_in, survey_weight),
            "source": source, "load_lines": lines}


def _simulate(cfg_dict: dict, strokes: int):
    from ..config import config_from_dict
    from ..simulation.simulator import Simulator

    sim = Simulator(config_from_dict(cfg_dict))
    return sim, sim.run_strokes(strokes)[-1]


MOTOR_TOLERANCE_PCT = 0.1  # two iterates of the motor's motion agree within this share of the stroke (%)
MOTOR_ITERATIONS = 6


def _record_motor_block(rec, card, motor: dict | None) -> tuple[dict | None, dict]:
    """The motor that drives a record's unit (``field_model.record_motor``, fields of ``motor`` set over it;
    ``{"enabled": False}`` = none) and the JSON entry saying what was used and why."""
    from ..analysis.field_model import record_motor

    found = record_motor(rec) if rec.config is None else None
    if not getattr(card, "motion_from_unit", False):
        why = "the card's position is measured: the motor's slip is already in it" if found else "no motor"
        return None, {"used": False, "reason": why}
    over = dict(motor or {})
    if found is None or not over.pop("enabled", True):
        return None, {"used": False, "reason": "the record names no usable motor" if found is None else "disabled"}
    block = {**found["block"], **over}
    source = {**found["source"], **{k: "set by the caller (what-if)" for k in over}}
    return block, {"used": True, **block, "source": source}


def _simulate_motor(cfg: dict, card, rec, strokes: int, work_dir: str, block: dict, entry: dict):
    """The record's unit driven by its motor: simulate at the crank profile, take the last stroke's net torque
    (counterbalance: the record's, or the stroke's optimum when not given), the motor's crank speed from it,
    the unit's motion on that crank profile, simulate again; until two motions agree (MOTOR_TOLERANCE_PCT)."""
    from dataclasses import replace

    from ..analysis.field_model import unit_from_record, unit_position_for_card
    from ..config import _parse, apply_overrides
    from ..config_unit import MotorConfig
    from ..surface_unit.inline_unit import record_unit_config
    from ..surface_unit.motor import (
        CrankProfile,
        MotorLaw,
        crank_speed_rad_s,
        net_torque_nm,
        position_change_pct,
        torque_on_grid,
    )

    law = MotorLaw.from_config(_parse(MotorConfig, block, "equipmentData.RodPumpMotor"))  # declared ranges
    unit, ub = unit_from_record(rec), record_unit_config(rec.unit)
    moment = ub["counterbalance_moment_nm"] or None
    offset = np.radians(ub["crank_offset_deg"]) * (-1.0 if ub["geometry"] == "mark_ii" else 1.0)
    scale = float(np.ptp(rec.position_m)) / unit.stroke_m
    profile, changes = None, []
    for it in range(MOTOR_ITERATIONS):
        sim, result = _simulate(cfg, strokes)
        n = result.n_steps
        t = np.arange(1, n + 1) * (result.duration_s / n)
        past = 2 * np.pi * t / result.duration_s if profile is None else profile.angle_and_speed(t)[0]
        torque, cb = net_torque_nm(unit, unit.theta_bottom + past, result.trace["polished_rod_load_n"], moment,
                                   offset, tf_scale=scale)
        new = CrankProfile(crank_speed_rad_s(law, torque_on_grid(past, torque), rec.spm), rec.period_s)
        changes.append(position_change_pct(profile, new, unit))
        if changes[-1] < MOTOR_TOLERANCE_PCT or it == MOTOR_ITERATIONS - 1:
            break
        profile = new
        card = replace(card, position_m=unit_position_for_card(rec, profile))
        csv = os.path.join(work_dir, f"motion_motor{it + 1}.csv")  # a new file: the motion cache keys on it
        write_motion_csv(card, csv)
        cfg = apply_overrides(cfg, {"surface.measured_card_csv": csv})
    shown = profile if profile is not None else CrankProfile(np.full(8, 2 * np.pi / rec.period_s), rec.period_s)
    entry.update({"rated_slip_used": law.rated_slip, "counterbalance_nm": float(cb),
                  "counterbalance_source": "record" if moment else "srenv optimal (not in the record)",
                  "crank_speed_pct_of_mean": shown.speed_range_pct(), "simulations": len(changes),
                  "motion_change_pct_of_stroke": changes, "converged": changes[-1] < MOTOR_TOLERANCE_PCT})
    return sim, result, card


def _fit(cfg_dict: dict, rec, params: list[str], strokes: int, work_dir: str) -> dict:
    from ..analysis.fit import CardFit, fit_card, refuse_inert

    cfg_path = os.path.join(work_dir, "well.yaml")
    card_path = os.path.join(work_dir, "card.csv")
    with open(cfg_path, "w") as fh:
        yaml.safe_dump(cfg_dict, fh, sort_keys=False)
    np.savetxt(card_path, np.c_[rec.t_s, rec.position_m, rec.load_n], delimiter=",", comments="", fmt="%.12g",
               header="t_s,polished_rod_position_m,polished_rod_load_n")
    fit = CardFit(card_path, cfg_path, params, strokes=strokes, flag="--fit")
    refuse_inert(fit)
    return fit_card(fit)


def compare(rec, sim, result, pump_card, convention: str) -> dict:
    """The JSON figures of one prediction and one diagnosis against the record."""
    from ..analysis.card_compare import card_difference, harmonic_shares, resample_stroke

    tr = result.trace
    x, f = tr["polished_rod_position_m"], tr["polished_rod_load_n"]
    pprl, mprl = float(rec.load_n.max()), float(rec.load_n.min())
    period = result.duration_s
    pred = resample_stroke(tr["t_s"], f, period, len(rec.load_n))
    meas_s, pred_s = harmonic_shares(rec.load_n), harmonic_shares(pred)
    diff = card_difference(rec.position_m, rec.load_n, x - x.min(), f)  # predicted - measured on common positions
    out = {
        "pprl_error_pct": 100.0 * (float(f.max()) / pprl - 1.0),
        "mprl_error_pct": 100.0 * (float(f.min()) / mprl - 1.0),
        "card_rms_pct_of_pprl": 100.0 * float(np.sqrt(np.mean(diff * diff))) / pprl,  # card_rms of this diff
        # the card difference split into a level (a constant: a load cell's zero or a string's weight moves the
        # whole card) and a shape (what is left about that level): docs/realism.md
        "card_offset_n": float(diff.mean()),
        "card_shape_rms_pct_of_pprl": 100.0 * float(diff.std()) / pprl,
        "pump_card_rms_pct_of_range": None,
        "measured_pprl_n": pprl, "measured_mprl_n": mprl,
        "predicted_pprl_n": float(f.max()), "predicted_mprl_n": float(f.min()),
        "spectrum": {"measured_share_h4_20": meas_s[0], "predicted_share_h4_20": pred_s[0],
                     "ratio_h4_20": pred_s[0] / meas_s[0] if meas_s[0] > 0 else None,
                     "measured_share_above_h20": meas_s[1], "predicted_share_above_h20": pred_s[1],
                     "ratio_above_h20": pred_s[1] / meas_s[1] if meas_s[1] > 0 else None},
    }
    ref = getattr(rec, "reference_prediction", None)
    # the vendor's own prediction from the same description, scored the same way: what a commercial
    # wave-equation tool reaches on this well (docs/realism.md)
    out["record_prediction"] = None if ref is None else {
        "pprl_error_pct": 100.0 * (ref["pprl_n"] / pprl - 1.0), "mprl_error_pct": 100.0 * (ref["mprl_n"] / mprl - 1.0),
        "pprl_n": ref["pprl_n"], "mprl_n": ref["mprl_n"],
        "source": "the record's Performance.IdealCardSimulation_SurfaceCard_Load_max/min (the vendor's full-pump "
                  "prediction)"}
    if rec.pump_load_n is not None:
        fp = load_in_convention(pump_card.pump_load_n, convention, sim.p_pump_pa, sim.area_bottom_m2)
        rng = float(np.ptp(rec.pump_load_n))
        d = card_difference(rec.pump_position_m, rec.pump_load_n, pump_card.pump_position_m, fp, align_bottom=True)
        out["pump_card_rms_pct_of_range"] = 100.0 * float(np.sqrt(np.mean(d * d))) / rng
        # where the difference sits: a constant (weight, load convention) moves both strokes alike, a card
        # height (damping, fluid load) moves them apart (docs/realism.md)
        half = d.size // 2
        out["pump_card_offset_n"] = {"upstroke": float(d[:half].mean()), "downstroke": float(d[half:].mean())}
        out["pump_card_convention"] = convention
    return out


def described_config(rec, motion_csv: str, work_dir: str, survey_weight: str = "inclination",
                     fillage: float | None = None) -> tuple[dict, dict]:
    """(the pump state read off the record, :func:`pump_state`; the well the record describes, driven by the
    motion in `motion_csv`, ``field_model.well_config``), with the state's fillage unless `fillage` is given:
    ``validate`` and the record commands (``record_well``) build it here alike."""
    from ..analysis.field_model import well_config

    state = pump_state(rec, work_dir, survey_weight)
    fill = state["fillage"] if fillage is None else fillage
    return state, well_config(rec, motion_csv, state["intake_pressure_pa"], fill, state["plunger_friction_n"],
                              survey_weight=survey_weight)


def validate(rec, params: list[str], strokes: int, convention: str, overrides: dict | None = None,
             motor: dict | None = None, survey_weight: str = "inclination",
             damping: str | None = None) -> tuple[dict, object]:
    """Predict, diagnose and compare one record (`overrides`: config fields set on the realistic model,
    e.g. for the baseline of docs/realism.md; `motor`: fields set over the record's motor, e.g.
    ``{"inertia_kg_m2": 1e4}``, or ``{"enabled": False}`` for constant crank speed; `survey_weight`: the
    survey column the string follows, ``field_model.survey_stations``; `damping`: ``fixed`` (the model's
    Gibbs factor) or ``energy-balance`` (read off the record's card, analysis/damping_balance); None = the
    default, DEFAULT_DAMPING where it applies)."""
    from dataclasses import replace

    from ..config import apply_overrides

    card = card_motion(rec)  # the record whose positions drive the model and place the measured loads
    with tempfile.TemporaryDirectory(prefix="srenv-validate-") as work:
        csv = os.path.join(work, "motion.csv")
        write_motion_csv(card, csv)
        if rec.config is not None:  # srenv's own record: its well YAML is the model, driven by the card
            if survey_weight != "inclination":  # its YAML's survey is the model; it has no TVD column
                raise ConfigError("--survey-weight", survey_weight, "inclination for a CSV record with --config")
            pump = rec.config.get("pump") or {}
            state = {"intake_pressure_pa": pump.get("intake_pressure_pa"), "fillage": pump.get("fillage"),
                     "plunger_friction_n": pump.get("plunger_friction_n"), "source": "config"}
            cfg = apply_overrides(rec.config, {"surface.motion": "measured", "surface.measured_card_csv": csv,
                                               "surface.measured_spm": rec.spm, **dict(overrides or {})})
        else:
            state, cfg = described_config(rec, csv, work, survey_weight)
            cfg = apply_overrides(cfg, dict(overrides or {}))
        cfg, rule_entry = _damping_rule(cfg, rec, state, damping)
        fitted = None
        if params:
            fitted = _fit(cfg, card, params, strokes, work)
            cfg = apply_overrides(cfg, fitted["params"])
        block, motor_entry = _record_motor_block(rec, card, motor)
        if block is None:
            sim, result = _simulate(cfg, strokes)
        else:  # the record's unit driven by its motor: the crank speed follows the torque (docs/realism.md)
            sim, result, card = _simulate_motor(cfg, card, rec, strokes, work, block, motor_entry)
            card = replace(card, notes=[*card.notes, (
                f"the unit is driven by the record's motor (NEMA {block['nema_design']}, "
                f"{block['rated_power_w']:.0f} W, rated slip {motor_entry['rated_slip_used']:g}, inertia "
                f"{block['inertia_kg_m2']:g} kg*m^2 at the crank; counterbalance "
                f"{motor_entry['counterbalance_source']}): the crank speed follows the net gearbox torque, "
                f"{motor_entry['crank_speed_pct_of_mean']['min_pct_of_mean']:.1f}-"
                f"{motor_entry['crank_speed_pct_of_mean']['max_pct_of_mean']:.1f} % of its mean")])
        # the stored card, as the vendor diagnosed it (with the rule, on the model's final state)
        pump_card, diag = _diagnose(cfg, rec, rule_entry["rule"] if rule_entry and rule_entry["applied"] else "fixed")
        out = compare(card, sim, result, pump_card, convention)
    from ..analysis.field_model import position_is_synthesised, unit_kinematics_check

    out["unit_kinematics"] = unit_kinematics_check(rec)
    out["motor"] = motor_entry
    out.update({"record": rec.source, "record_notes": list(getattr(card, "notes", [])),
                "position_synthesised": rec.config is None and position_is_synthesised(rec.position_m),
                "motion_source": "record unit" if getattr(card, "motion_from_unit", False) else "card",
                "card_time_reversed": bool(getattr(rec, "time_reversed", False)),
                "record_card_type": getattr(rec, "card_type", None),
                "pump_state": state, "survey_weight": survey_weight,
                "diagnosis": {k: diag[k] for k in ("fillage", "card_class", "fluid_load_n", "intake_pressure_pa")},
                "damping_rule": rule_entry or {"rule": "fixed", "applied": True},
                "fit": fitted, "model": {"damping_factor": cfg.get("damping", {}).get("damping_factor"),
                                         "fillage": cfg.get("pump", {}).get("fillage")}})
    return out, (card, result, pump_card)


def read_record(path: str, config: str | None, reverse: bool):
    from ..analysis.field_record import read_dynacard_json, read_record_csv
    from ..cli_types import is_record

    if is_record(path):
        return read_dynacard_json(path, reverse=reverse, auto_orient=not reverse)
    if config is None:
        raise ConfigError("--config", "missing", "a well YAML (path or shipped name) for a CSV record")
    return read_record_csv(path, config, reverse=reverse)


def cmd_validate(args) -> int:
    check_output_path("--plot", args.plot, (".png",))
    rec = read_record(args.record, args.config, args.reverse)
    out, parts = validate(rec, list(args.fit or []), args.strokes, args.load_convention,
                          survey_weight=args.survey_weight, damping=args.damping)
    try:  # a figure that is not finite is a failure, not a result (and NaN is not JSON)
        line = json.dumps(out, default=float, allow_nan=False)
    except ValueError:
        raise NumericFailure("validate", "a figure is not finite; check the record's magnitudes") from None
    if args.plot:
        from .validate_plot import save_validation_plot

        atomic_write(args.plot, lambda tmp: save_validation_plot(*parts, tmp, args.load_convention))
    print(line)
    return 0


def add_parser(sub) -> None:
    from ..analysis.field_model import SURVEY_WEIGHTS
    from ..declarations import add_number

    v = sub.add_parser("validate", help="predict and diagnose a field record, compared with its measured card")
    v.add_argument("record", help="vendor dynacard JSON, or a card CSV with --config")
    v.add_argument("--config", help="well YAML path or shipped name (CSV records)")
    v.add_argument("--fit", nargs="+", metavar="KEY.PATH", help="config fields to fit to the surface card first")
    v.add_argument("--plot", help="PNG with the measured and predicted surface cards and the pump cards")
    v.add_argument("--reverse", action="store_true", help="the card is stored in reverse time: reverse it")
    v.add_argument("--load-convention", choices=LOAD_CONVENTIONS, default="effective",
                   help="pump loads compared as true loads or effective (buoyant) loads (the vendor's)")
    v.add_argument("--survey-weight", choices=SURVEY_WEIGHTS, default="inclination",
                   help="the string follows the record's inclinations (the physics) or its TVD column (a vendor "
                        "JSON's convention: 7699227's TVD column is vertical; docs/realism.md)")
    v.add_argument("--damping", choices=RULES, default=None,
                   help=f"the diagnosis's and the model's Gibbs factor: fixed (the model's) or energy-balance "
                        f"(read off the card; default {DEFAULT_DAMPING} where it applies, else fixed; docs/realism.md)")
    add_number(v, "validate", "--strokes", default=DEFAULT_STROKES,
               help=f"strokes simulated from the static state; the last is compared (default {DEFAULT_STROKES})")
    v.set_defaults(func=cmd_validate)
