"""The shipped classifier on a well outside the family (paper_fig3_vertical), every condition at one
severity, with realism's Kelvin-Voigt damping (damping.stiffness_proportional_s) off and on.

    python scripts/conditions_robustness.py [--severity 0.6] [--taus 0 0.01 0.03]
"""

from __future__ import annotations

import argparse
import json

from srenv.analysis.card_classifier import CardClassifier
from srenv.analysis.condition_card import condition_config, simulate_card
from srenv.config import load_config
from srenv.physics.conditions import LABELS


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--well", default="paper_fig3_vertical")
    ap.add_argument("--severity", type=float, default=0.6)
    ap.add_argument("--taus", type=float, nargs="+", default=[0.0, 0.01, 0.03])
    a = ap.parse_args()
    clf, well = CardClassifier.load(), load_config(a.well)
    for tau in a.taus:
        got = {}
        for label in LABELS:
            cfg = condition_config(well, label, 0.0 if label == "full" else a.severity,
                                   {"damping.stiffness_proportional_s": tau})
            card = simulate_card(cfg)
            got[label] = clf.classify(card.polished_rod_position_m, card.polished_rod_load_n)[0]
        right = sum(got[k] == k for k in LABELS)
        print(json.dumps({"tau_s": tau, "right": right, "of": len(LABELS),
                          "wrong": {k: v for k, v in got.items() if v != k}}))


if __name__ == "__main__":
    main()
