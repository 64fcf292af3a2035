"""``srenv bench`` figures of the pump-condition tools: labelled cards per second (``srenv cards``'s
simulation on local worker processes) and the classifier's milliseconds per card."""

from __future__ import annotations

import time

import numpy as np


def cards_figures(n_cards: int = 200, workers: int = 2) -> dict:
    from ..analysis.card_classifier import DEFAULT_MODEL, CardClassifier
    from ..analysis.card_shape import features
    from ..physics.conditions import LABELS
    from .cards import simulate_set

    simulate_set(len(LABELS), 99, LABELS, 1, False)  # compile the kernel (cached for the workers)
    t0 = time.perf_counter()
    cards = simulate_set(n_cards, 98, LABELS, workers, False)
    dt = time.perf_counter() - t0
    out = {"cards_per_s": n_cards / dt, "n_cards": n_cards, "workers": workers}
    if DEFAULT_MODEL.exists():
        clf = CardClassifier.load()
        t0 = time.perf_counter()
        for c in cards:
            clf.proba_features(features(c["arrays"]["polished_rod_position_m"], c["arrays"]["polished_rod_load_n"]))
        out["classify_ms_per_card"] = 1e3 * (time.perf_counter() - t0) / max(len(cards), 1)
    out["mean_points"] = float(np.mean([len(c["arrays"]["polished_rod_load_n"]) for c in cards]))
    return out
