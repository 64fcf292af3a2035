"""Why full and flowing overlap (issue 23): on held-out simulated cards, what a model calls the full-pump cards,
binned by the well's numbers and the card's, and the fluid load over the buoyant rod weight of each card's well.

    python scripts/full_flowing_overlap.py --model M.npz --out REPORT.json [--set DIR:SEED:SURFACE:EQUIPMENT:SPLITS ...]

A set is given as ``DIR:SEED:SURFACE:EQUIPMENT:SPLITS[:PLUNGERS]`` (splits joined by ``+``); each card's config is
rebuilt from its draw (``card_set.rebuilt_draw``: the attempt read off its well seed), so the well's numbers are the card's
own (its equipment included). F_o is the full pump's fluid load P- - P+ of the card's config (the valve law at the
simulator's start state, ``simulation.described``; a flowing card's divided by 1 - f back to the full pump's); W_rf
is the string's buoyant weight, sum of (rho_rod - rho_fluid) g A L over the tapers, along measured depth. Parted
rods are left out (no pump). The cards are read clean (no augmentation).
"""

from __future__ import annotations

import argparse
import json
import math

import numpy as np

from srenv.analysis.card_classifier import CardClassifier
from srenv.analysis.card_shape import features
from srenv.physics.conditions import GRAVITY_M_S2, LABELS
from srenv.simulation.described import described_pump
from srenv.task.card_set import card_config, load_cards, rebuilt_draw

DEFAULT_SETS = ("/tmp/f23/CARDS2:2:family:none:validation", "/tmp/f23/CARDS4:4:v2:none:validation",
                "/tmp/f23/CARDS7:7:v2:field:validation", "/tmp/f23/CARDS8:8:v2:none:train+validation")
KINDS = ("full", "flowing")
# bins over the ranges the family spans (the lowest F_o / W_rf bin split at 0.25 after the first table was read)
BINS = {"fo_over_wrf": [0, 0.25, 0.3, 0.4, 0.5, 0.6, 0.8, 1.0, 3.0],
        "card_min_over_max": [-1, 0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 1.0],
        "depth_m": [0, 900, 1300, 1700, 2100, 2600], "plunger_diameter_mm": [0, 30, 35, 40, 46, 52, 70],
        "plunger_friction_n": [0, 600, 1000, 2000, 5000], "damping_factor": [0, 0.05, 0.1, 0.2, 0.4, 2.0],
        "spm_over_n0": [0, 0.1, 0.15, 0.2, 0.25, 1.0], "sinker_bar_length_m": [0, 0.5, 1e9],
        "fiberglass_length_m": [0, 0.5, 1e9], "compressible": [0, 0.5, 2]}
WAVE_SPEED_M_S = 5047.5  # steel, sqrt(E / rho): N0 = 60 a / (4 L) strokes/min


def buoyant_weight_n(cfg) -> float:
    rho_f = cfg.fluid.density_kg_m3
    return sum((t.density_kg_m3 - rho_f) * GRAVITY_M_S2 * math.pi / 4 * (t.diameter_mm * 1e-3) ** 2 * t.length_m
               for t in cfg.rod.tapers)


def rows_of(path: str, seed: int, surface: str, equipment: str, splits: tuple, clf, plungers: str = "family"):
    c = load_cards(f"{path}/cards.npz")
    for i in range(len(c["label"])):
        label = LABELS[int(c["label"][i])]
        if label not in KINDS or str(c["split"][i]) not in splits:
            continue
        try:
            d = rebuilt_draw(seed, i, int(c["well_seed"][i]), label, surface, equipment, plungers)
        except ValueError as exc:
            raise SystemExit(f"{path}: {exc}") from None
        cfg = card_config(d)
        f = cfg.pump.flow_through_fraction
        fo = described_pump(cfg).fluid_load_n / (1.0 - f)
        feat = features(c["polished_rod_position_m"][i], c["polished_rod_load_n"][i])
        p = clf.proba_features(feat)[0]
        yield {"set": seed, "index": i, "label": label, "severity": float(c["severity"][i]), "flow_fraction": f,
               "fo_n": fo, "wrf_n": buoyant_weight_n(cfg), "card_min_over_max": float(feat[-1]),
               "depth_m": cfg.rod_length_m, "plunger_diameter_mm": cfg.pump.plunger_diameter_mm,
               "plunger_friction_n": cfg.pump.plunger_friction_n, "damping_factor": cfg.damping.damping_factor,
               "spm_over_n0": cfg.surface.spm / (60 * WAVE_SPEED_M_S / (4 * cfg.rod_length_m)),
               "sinker_bar_length_m": sum(t.length_m for t in cfg.rod.tapers if t.material == "sinker_bar"),
               "fiberglass_length_m": sum(t.length_m for t in cfg.rod.tapers if t.material == "fiberglass"),
               "compressible": float(cfg.pump.liquid_compressibility_per_pa > 0),
               "called": LABELS[int(np.argmax(p))]}


def table(rows: list[dict], key: str, value=lambda r, k: r[k]) -> list[dict]:
    """Per bin of ``key``: cards, P(called flowing), P(called full)."""
    out = []
    v = np.array([value(r, key) for r in rows])
    called = np.array([r["called"] for r in rows])
    for lo, hi in zip(BINS[key][:-1], BINS[key][1:]):
        m = (v >= lo) & (v < hi)
        if m.any():
            out.append({"bin": [lo, hi], "cards": int(m.sum()), "p_flowing": round(float(np.mean(called[m] == "flowing")), 3),
                        "p_full": round(float(np.mean(called[m] == "full")), 3)})
    return out


def percentiles(v) -> dict:
    return {str(q): round(float(np.percentile(v, q)), 3) for q in (1, 5, 25, 50, 75, 95, 99)}


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--model", default="srenv/models/classifier.npz")
    ap.add_argument("--set", nargs="+", default=list(DEFAULT_SETS), dest="sets")
    ap.add_argument("--out", required=True)
    a = ap.parse_args()
    clf = CardClassifier.load(a.model)
    rows = []
    for spec in a.sets:
        path, seed, surface, equipment, splits, *rest = spec.split(":")
        rows += list(rows_of(path, int(seed), surface, equipment, tuple(splits.split("+")), clf, *rest))
    for r in rows:
        r["fo_over_wrf"] = r["fo_n"] / r["wrf_n"]
    full = [r for r in rows if r["label"] == "full"]
    flowing = [r for r in rows if r["label"] == "flowing"]
    # a flowing card's valve law is a full pump's with the fluid load (1 - f) F_o: its effective ratio
    eff = [(1 - r["flow_fraction"]) * r["fo_over_wrf"] for r in flowing]
    report = {"model": a.model, "sets": a.sets, "cards": {"full": len(full), "flowing": len(flowing)},
              "full_called": {k: sum(r["called"] == k for r in full) for k in LABELS},
              "flowing_called": {k: sum(r["called"] == k for r in flowing) for k in LABELS},
              "p_flowing_given_full": {k: table(full, k) for k in BINS},
              "p_full_given_flowing_by_effective_ratio": table(
                  [{**r, "fo_over_wrf": e} for r, e in zip(flowing, eff)], "fo_over_wrf"),
              "fo_over_wrf_percentiles": {"full": percentiles([r["fo_over_wrf"] for r in full]),
                                          "flowing_effective": percentiles(eff)},
              "card_min_over_max_percentiles": {"full": percentiles([r["card_min_over_max"] for r in full]),
                                                "flowing": percentiles([r["card_min_over_max"] for r in flowing])}}
    with open(a.out, "w") as f:
        json.dump(report, f, indent=1)
        f.write("\n")
    for k in ("fo_over_wrf", "plunger_diameter_mm", "card_min_over_max"):
        print(k, json.dumps(report["p_flowing_given_full"][k]))
    print("full called", report["full_called"])


if __name__ == "__main__":
    main()
