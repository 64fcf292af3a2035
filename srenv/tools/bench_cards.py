"""``srenv bench`` figures of the pump-condition tools: labelled cards per second (``srenv cards``'s
simulation on local worker processes; wall clock and per CPU-second of the workers) and the classifier's
milliseconds per card."""

from __future__ import annotations

import resource
import time

import numpy as np


def cards_figures(n_cards: int = 200, workers: int = 2) -> dict:
    from ..analysis.card_classifier import DEFAULT_MODEL, CardClassifier
    from ..analysis.card_shape import features
    from ..physics.conditions import LABELS
    from .cards import simulate_set

    simulate_set(len(LABELS), 99, LABELS, 1, False)  # compile the kernel (cached for the workers)
    ru0 = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    cards = simulate_set(n_cards, 98, LABELS, workers, False)
    dt = time.perf_counter() - t0
    ru1 = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (ru1.ru_utime - ru0.ru_utime) + (ru1.ru_stime - ru0.ru_stime)  # the workers' CPU time
    # wall-clock rate on this machine as it is loaded, and the CPU cost: cards per CPU-second is what
    # one idle core gives (2 idle cores: twice that, less the parent's share)
    out = {"cards_per_s": n_cards / dt, "n_cards": n_cards, "workers": workers,
           "cards_per_cpu_s": n_cards / cpu if cpu > 0 else None}
    if DEFAULT_MODEL.exists():
        clf = CardClassifier.load()
        t0 = time.perf_counter()
        for c in cards:
            clf.proba_features(features(c["arrays"]["polished_rod_position_m"], c["arrays"]["polished_rod_load_n"]))
        out["classify_ms_per_card"] = 1e3 * (time.perf_counter() - t0) / max(len(cards), 1)
    out["mean_points"] = float(np.mean([len(c["arrays"]["polished_rod_load_n"]) for c in cards]))
    return out
