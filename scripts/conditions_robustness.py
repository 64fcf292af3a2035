"""Classifiers on wells outside the card set's family (the shipped well configs), every condition at a few
severities, with realism's Kelvin-Voigt damping (damping.stiffness_proportional_s) off and on: a simulated
check of how a model holds under a shift of the wells, used to choose between models (docs/conditions.md).

    python scripts/conditions_robustness.py [--models M.npz ...] [--wells NAME ...] [--severities 0.4 0.8]
        [--taus 0 0.02]

Prints one JSON line per model: cards right, of how many, and what each well's full card was called.
A combination a well's config refuses (e.g. free gas on a well with the nonmonotone plunger law) is skipped.
"""

from __future__ import annotations

import argparse
import json

from srenv.analysis.card_classifier import DEFAULT_MODEL, CardClassifier
from srenv.analysis.condition_card import condition_config, simulate_card
from srenv.config import load_config
from srenv.errors import ConfigError, NumericFailure, SolverFailure
from srenv.physics.conditions import LABELS

WELLS = ("conventional_fig4", "default", "paper_fig3_vertical", "paper_fig4_deviated", "paper_fig6_nonmonotone",
         "paper_fig7_pullout")


def cards(wells, severities, taus):
    """(well, tau, label, card) of every combination the configs accept (full once per well and tau)."""
    for name in wells:
        well = load_config(name)
        for tau in taus:
            for label in LABELS:
                for sev in ([0.0] if label == "full" else severities):
                    try:
                        cfg = condition_config(well, label, sev, {"damping.stiffness_proportional_s": tau})
                        yield name, tau, label, simulate_card(cfg)
                    except (ConfigError, NumericFailure, SolverFailure, ValueError):
                        continue


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--models", nargs="+", default=[str(DEFAULT_MODEL)])
    ap.add_argument("--wells", nargs="+", default=list(WELLS))
    ap.add_argument("--severities", type=float, nargs="+", default=[0.4, 0.8])
    ap.add_argument("--taus", type=float, nargs="+", default=[0.0, 0.02])
    a = ap.parse_args()
    clfs = {m: CardClassifier.load(m) for m in a.models}
    right = dict.fromkeys(clfs, 0)
    full = {m: {} for m in clfs}
    n = 0
    for name, tau, label, card in cards(a.wells, a.severities, a.taus):
        n += 1
        for m, clf in clfs.items():
            got = clf.classify(card.polished_rod_position_m, card.polished_rod_load_n)[0]
            right[m] += got == label
            if label == "full":
                full[m][f"{name}@{tau}"] = got
    for m in clfs:
        print(json.dumps({"model": m, "right": right[m], "of": n, "accuracy": round(right[m] / max(n, 1), 3),
                          "full_called": full[m]}))


if __name__ == "__main__":
    main()
