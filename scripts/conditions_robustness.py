"""Classifiers on simulated wells the card sets did not draw: a check of how a model holds under a shift of the
wells, used to choose between models (docs/conditions.md, runs 3 and 4). Two checks:

* ``out_of_family``: the shipped well configs, every condition at a few severities, with realism's Kelvin-Voigt
  damping (damping.stiffness_proportional_s) off and on (226 cards with the defaults);
* ``v2_family``: wells of the family drawn from a stream of their own (``draw_params(k, stream=CHECK_STREAM)``,
  outside v2's train / validation / test / family wells and every card set), each with v2's per-well physics as
  v2 applies it (``v2_physics.overrides``: its beam unit and Kelvin-Voigt damping), at the four corners of its
  operating range, the full pump and every other condition at one severity (run 4's pre-registered check);
* ``v2_family_synth``: the v2-family check's cards, every one with its position channel replaced by what a
  load-only controller writes (``card_augment.synthesised_position``: a cosine of time at the card's stroke and
  period, phased on its bottom; the loads kept by time; run 5's pre-registered check);
* ``v2_family_smooth``: the v2-family check's cards, every one (position and load alike) low-passed by
  ``card_augment.spectral_lowpass`` at a fixed corner harmonic K = 10 (a real string and load cell smooth the card;
  run 6's pre-registered check);
* ``field_equipment``: the full pump and every other condition at one severity on wells with field equipment (run 7's
  pre-registered check): (e1) the shipped configs, each with a 1.5-in sinker-bar bottom over 10 % of the string and
  a 2 kN plunger drag, and with a 1-in fiberglass top over 50 % and a 1 kN drag; (e2) the v2-family check wells at
  their installed point, each with equipment drawn by the card set's own function (``card_equipment``) from a
  stream of its own, deviation to 60 deg included;
* ``field_record_well`` (reported only, never deciding): the described field well ``--field-record`` (7699227) as
  ``srenv validate`` builds it from the record's description and recorded surface motion, the pump full
  (``pump.fillage`` 1), in every condition at one severity; the record's load card and the vendor's verdict are
  not read for it beyond what ``validate.pump_state`` reads (the record's own intake pressure where it has one).

    python scripts/conditions_robustness.py [--models M.npz ...]
        [--checks out_of_family v2_family v2_family_synth v2_family_smooth field_equipment]
        [--wells NAME ...] [--severities 0.4 0.8] [--taus 0 0.02] [--v2-wells 12] [--v2-severity 0.6]
        [--out REPORT.json]

A model that reads the card against a described well (run 9's ``shape+midline``, ``srenv classify --config``)
is given each card's description: its well in the full condition (the same well, equipment, unit, operating point
and damping; not its condition), as a user's config describes the well; the other models read the card alone.

Prints one JSON line per model: per check the cards right, of how many, what each full card was called; the
score (the mean of the checks' accuracies, runs 4-6's rules). A combination a well's config refuses (e.g. free gas
on a well with the nonmonotone plunger law) is skipped, for every model alike.
"""

from __future__ import annotations

import argparse
import dataclasses
import json

from srenv.analysis.card_augment import spectral_lowpass, synthesised_position
from srenv.analysis.card_classifier import DEFAULT_MODEL, CardClassifier
from srenv.analysis.condition_card import condition_config, simulate_card
from srenv.config import load_config
from srenv.errors import ConfigError, NumericFailure, SolverFailure
from srenv.physics.conditions import LABELS
from srenv.task import card_equipment as ce

WELLS = ("conventional_fig4", "default", "paper_fig3_vertical", "paper_fig4_deviated", "paper_fig6_nonmonotone",
         "paper_fig7_pullout")
CHECK_STREAM = 0xC1A5  # the v2-family check's wells: a stream no split, family well or card set draws from
CORNERS = (("spm_min", "stroke_min"), ("spm_min", "stroke_max"), ("spm_max", "stroke_min"),
           ("spm_max", "stroke_max"))
FAILED = (ConfigError, NumericFailure, SolverFailure, ValueError)
SMOOTH_K = 10.0  # the v2_family_smooth check's corner harmonic (run 6, fixed before any measurement)
V2_CHECKS = ("v2_family", "v2_family_synth", "v2_family_smooth")
EQUIPMENT_STREAM = 0xE0E7  # check (e2)'s equipment draws: a stream no card set draws from
# check (e1)'s two fixed variants (run 7's pre-registration)
FIXED_EQUIPMENT = {"sinker": ce.Equipment(2000.0, 38.1, 0.10), "fiberglass": ce.Equipment(1000.0, 0.0, 0.0, 25.4, 0.5)}
E1_TAU_S = 0.02
FIELD_RECORD = "/work/shared/field/7699227.json"
# where -> (F_desc, D_desc) of the well the cards at ``where`` come from (its full condition), for models that need a
# config (run 9); filled by the card generators, read by score
DESCRIBED: dict[str, tuple[float, float]] = {}


def _describe(where: str, well, extra: dict | None = None) -> None:
    """Register the description of ``where``'s well: the same config in the full condition."""
    from srenv.analysis.surface_level import described_surface

    if where not in DESCRIBED:
        d = described_surface(condition_config(well, "full", 0.0, extra))
        DESCRIBED[where] = (d.fluid_load_n, d.downstroke_n)


def cards(wells, severities, taus):
    """(well@tau, label, card) of every combination the configs accept (full once per well and tau)."""
    for name in wells:
        well = load_config(name)
        for tau in taus:
            _describe(f"{name}@{tau}", well, {"damping.stiffness_proportional_s": tau})
            for label in LABELS:
                for sev in ([0.0] if label == "full" else severities):
                    try:
                        cfg = condition_config(well, label, sev, {"damping.stiffness_proportional_s": tau})
                        yield f"{name}@{tau}", label, simulate_card(cfg)
                    except FAILED:
                        continue


def v2_check_well(k: int):
    """Check well ``k`` with v2's per-well physics (its unit's geometry is in the config)."""
    from srenv.task import v2_physics
    from srenv.task import well_family as wf

    spec = wf.spec_from_params(wf.draw_params(k, stream=CHECK_STREAM), f"clscheck-{k}")
    return load_config(spec.cfg, v2_physics.overrides(spec))


def v2_cards(n_wells: int, severity: float):
    """(well/corner, label, card) of the v2-family check: every corner of every well, every condition."""
    for k in range(n_wells):
        cfg = v2_check_well(k)
        c = cfg.control
        for spm_end, stroke_end in CORNERS:
            spm = c.spm_min if spm_end == "spm_min" else c.spm_max
            stroke = c.stroke_min_m if stroke_end == "stroke_min" else c.stroke_max_m
            well = dataclasses.replace(cfg, surface=dataclasses.replace(cfg.surface, spm=spm, stroke_length_m=stroke))
            _describe(f"clscheck-{k}/{spm_end}/{stroke_end}", well)
            for label in LABELS:
                try:
                    card = simulate_card(condition_config(well, label, 0.0 if label == "full" else severity))
                except FAILED:
                    continue
                yield f"clscheck-{k}/{spm_end}/{stroke_end}", label, card


def _conditions(where: str, well, severity: float, extra: dict | None = None):
    """(where, label, card) of the full pump and every other condition at ``severity`` the config accepts."""
    _describe(where, well, extra)
    for label in LABELS:
        try:
            card = simulate_card(condition_config(well, label, 0.0 if label == "full" else severity, extra))
        except FAILED:
            continue
        yield where, label, card


def equipment_cards(wells, n_wells: int, severity: float):
    """Check (e): (e1) the shipped configs in FIXED_EQUIPMENT's variants, (e2) the v2-family check wells with drawn
    field equipment, at their installed operating point."""
    import numpy as np

    from srenv.task import v2_physics
    from srenv.task import well_family as wf

    for name in wells:
        for variant, eq in FIXED_EQUIPMENT.items():
            try:
                well = ce.with_equipment(load_config(name), eq)
            except FAILED:
                continue
            yield from _conditions(f"e1/{name}/{variant}", well, severity,
                                   {"damping.stiffness_proportional_s": E1_TAU_S})
    for k in range(n_wells):
        eq = ce.draw_equipment(np.random.default_rng([EQUIPMENT_STREAM, k]))
        spec = wf.spec_from_params(ce.deviated(wf.draw_params(k, stream=CHECK_STREAM), eq), f"clscheck-{k}")
        try:
            well = ce.with_equipment(load_config(spec.cfg, v2_physics.overrides(spec)), eq)
        except FAILED:
            continue
        yield from _conditions(f"e2/clscheck-{k}", well, severity)


def record_well_cards(path: str, severity: float):
    """Check (f): the described well of a field record (srenv.tools.record_well, the well ``srenv classify
    RECORD.json`` reads against), simulated in every condition (its motion file lives in a temporary directory for
    the simulations)."""
    import os

    from srenv.config import config_from_dict
    from srenv.tools.record_well import described_well
    from srenv.tools.validate import read_record

    rec = read_record(path, None, False)
    with described_well(rec) as well:
        yield from _conditions(f"f/{os.path.basename(path)}", config_from_dict(well.config), severity)


def synthesised(stream):
    """The same cards with the position a load-only controller writes (the last stroke's trace: one period,
    samples at equal times, the period's end not repeated)."""
    for where, label, card in stream:
        x = synthesised_position(card.polished_rod_position_m)
        yield where, label, dataclasses.replace(card, polished_rod_position_m=x)


def smoothed(stream, k_corner: float = SMOOTH_K):
    """The same cards low-passed as a real string and load cell would (position and load alike; one period,
    samples at equal times): harmonic k of the stroke times exp(-(k / k_corner)^2)."""
    for where, label, card in stream:
        x, y = spectral_lowpass(card.polished_rod_position_m, k_corner), spectral_lowpass(card.polished_rod_load_n,
                                                                                          k_corner)
        yield where, label, dataclasses.replace(card, polished_rod_position_m=x, polished_rod_load_n=y)


def score(clfs: dict, stream) -> dict:
    """Per model: cards right, of how many, what each full card was called, right per label."""
    out = {m: {"right": 0, "of": 0, "full_called": {}, "right_by_label": dict.fromkeys(LABELS, 0),
               "of_by_label": dict.fromkeys(LABELS, 0)} for m in clfs}
    for where, label, card in stream:
        for m, clf in clfs.items():
            desc = DESCRIBED[where] if clf.needs_config else ()
            got = clf.classify(card.polished_rod_position_m, card.polished_rod_load_n, *desc)[0]
            r = out[m]
            r["of"] += 1
            r["right"] += got == label
            r["of_by_label"][label] += 1
            r["right_by_label"][label] += got == label
            if label == "full":
                r["full_called"][where] = got
            if where[:3] in ("e1/", "e2/"):  # check (e)'s two parts, reported apart
                part = r.setdefault("right_of_by_part", {}).setdefault(where[:2], [0, 0])
                part[0] += got == label
                part[1] += 1
    for r in out.values():
        r["accuracy"] = round(r["right"] / max(r["of"], 1), 3)
    return out


def healthy_by_corner(full_called: dict) -> dict:
    """v2-family check: the full cards called ``full``, per corner (right / of)."""
    out = {}
    for spm_end, stroke_end in CORNERS:
        got = [v for k, v in full_called.items() if k.endswith(f"/{spm_end}/{stroke_end}")]
        out[f"{spm_end}/{stroke_end}"] = f"{sum(v == 'full' for v in got)}/{len(got)}"
    return out


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--models", nargs="+", default=[str(DEFAULT_MODEL)])
    ap.add_argument("--checks", nargs="+", choices=("out_of_family", *V2_CHECKS, "field_equipment",
                                                        "field_record_well"),
                    default=["out_of_family", "v2_family"])
    ap.add_argument("--wells", nargs="+", default=list(WELLS))
    ap.add_argument("--severities", type=float, nargs="+", default=[0.4, 0.8])
    ap.add_argument("--taus", type=float, nargs="+", default=[0.0, 0.02])
    ap.add_argument("--v2-wells", type=int, default=12)
    ap.add_argument("--v2-severity", type=float, default=0.6)
    ap.add_argument("--field-record", default=FIELD_RECORD, help="check field_record_well's record (JSON)")
    ap.add_argument("--out", help="also write the lines as one JSON report")
    a = ap.parse_args()
    clfs = {m: CardClassifier.load(m) for m in a.models}
    checks = {}
    if "out_of_family" in a.checks:
        checks["out_of_family"] = score(clfs, cards(a.wells, a.severities, a.taus))
    v2 = list(v2_cards(a.v2_wells, a.v2_severity)) if set(V2_CHECKS) & set(a.checks) else []
    if "v2_family" in a.checks:
        checks["v2_family"] = score(clfs, v2)
    if "v2_family_synth" in a.checks:
        checks["v2_family_synth"] = score(clfs, synthesised(v2))
    if "v2_family_smooth" in a.checks:
        checks["v2_family_smooth"] = score(clfs, smoothed(v2))
    if "field_equipment" in a.checks:
        checks["field_equipment"] = score(clfs, equipment_cards(a.wells, a.v2_wells, a.v2_severity))
    reported = {}  # checks outside the score (run 7's check (f))
    if "field_record_well" in a.checks:
        reported["field_record_well"] = score(clfs, record_well_cards(a.field_record, a.v2_severity))
    for check in V2_CHECKS:
        for r in checks.get(check, {}).values():
            r["healthy_full_by_corner"] = healthy_by_corner(r["full_called"])
    rows = []
    for m in clfs:
        row = {"model": m, **{k: v[m] for k, v in checks.items()}, **{k: v[m] for k, v in reported.items()},
               "score": round(sum(v[m]["right"] / max(v[m]["of"], 1) for v in checks.values()) / max(len(checks), 1), 4)}
        rows.append(row)
        print(json.dumps(row))
    if a.out:
        with open(a.out, "w") as f:
            json.dump({"checks": list(checks), "reported_only": list(reported), "v2_wells": a.v2_wells, "v2_severity": a.v2_severity,
                       "severities": a.severities, "taus": a.taus,
                       **({"smooth_k": SMOOTH_K} if "v2_family_smooth" in checks else {}), "models": rows}, f, indent=1)
            f.write("\n")


if __name__ == "__main__":
    main()
