"""Run 9's representation study (issue 23; docs/cards_dataset.md "Run 9"): which entry describing the well a
surface model for ``srenv classify --config`` should read, on the validation wells of sets 2 + 4 + 7 only.

    python scripts/run9_representation_study.py --cards CARDS2 CARDS4 CARDS7 --out docs/run9_representation_study.json

Each card's description is its own well in the full condition (card_set.described_surfaces). The cards are
featurised once as run 7's trainer does (instrument effects 0.3 / 0.3; training 6 augmented copies, rng 0;
validation 3, rng 1), the description errors drawn after each card's augmentation (F_desc x U[0.85, 1.15], then
D_desc + F_desc x U[-0.15, 0.15]: train_classifier's order), and one MLP 256-256 (30 epochs, seed 0) is fitted per
entry: R1 spread (P90 - P10) / F, R2 midline ((P10 + P90) / 2 - D) / F, R3 up (P90 - D) / F and down (P10 - D) / F,
R4 spread and midline; R0 is the shipped run 7 model. Besides the validation confusion, a stress set: every
heavy-oil validation card re-simulated without heavy oil's added plunger friction (the well's own kept), read
clean and augmented x 3 (rng 1): how many each model still calls heavy_oil. Simulated cards only; minutes of CPU.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
from pathlib import Path

import numpy as np

from srenv.analysis.card_augment import InstrumentAugment, augment
from srenv.analysis.card_classifier import DEFAULT_MODEL, CardClassifier
from srenv.analysis.card_shape import features
from srenv.analysis.condition_card import simulate_card
from srenv.analysis.pump_level import DESCRIPTION_ERROR, LEVEL_QUANTILES, OFFSET_ERROR
from srenv.physics.conditions import LABELS
from srenv.task.card_set import card_config, load_cards, rebuilt_draw, resample
from srenv.tools.train_classifier import AUG_COPIES, VALIDATION_DRAWS, fit, load_sets

ENTRIES = {"R1": ("spread",), "R2": ("mid",), "R3": ("up", "down"), "R4": ("spread", "mid")}
HEAVY = LABELS.index("heavy_oil")


def featurise(pos, load, idx, rng, draws: int) -> dict:
    """Augmented shape features, load percentiles and description-error draws of cards idx (train_classifier's
    draw order)."""
    inst = InstrumentAugment(0.3, 0.3)
    x, q, e, card = [], [], [], []
    for _ in range(draws):
        for i in idx:
            p, y = augment(pos[i], load[i], rng, inst, None)
            x.append(features(p, y))
            q.append(np.quantile(y, LEVEL_QUANTILES))
            e.append((rng.uniform(1 - DESCRIPTION_ERROR, 1 + DESCRIPTION_ERROR), rng.uniform(-OFFSET_ERROR, OFFSET_ERROR)))
            card.append(i)
    return {"x": np.array(x), "q": np.array(q), "e": np.array(e), "i": np.array(card)}


def rows(z: dict, fluid, down, entry: str | None) -> np.ndarray:
    if entry is None:
        return z["x"]
    f = fluid[z["i"]] * z["e"][:, 0]
    d = down[z["i"]] + z["e"][:, 1] * fluid[z["i"]]
    lo, hi = z["q"][:, 0], z["q"][:, 1]
    cols = {"spread": (hi - lo) / f, "mid": (0.5 * (lo + hi) - d) / f, "up": (hi - d) / f, "down": (lo - d) / f}
    return np.c_[z["x"], np.clip(np.stack([cols[c] for c in ENTRIES[entry]], 1), -4.0, 4.0)]


def heavy_without_friction(dirs: list[str]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(global card index, position, load) of every heavy-oil validation card re-simulated with the plunger
    friction of its full-condition well (the viscous rods kept)."""
    out, offset = [], 0
    for path in dirs:
        meta = json.loads(Path(path, "dataset_card.json").read_text())
        c = load_cards(f"{path}/cards.npz")
        for i in np.flatnonzero((c["split"] == "validation") & (c["label"] == HEAVY)):
            d = rebuilt_draw(meta["seed"], int(i), int(c["well_seed"][i]), "heavy_oil", meta.get("surface", "family"),
                             meta.get("equipment", "none"), meta.get("plungers", "family"))
            base = card_config(dataclasses.replace(d, label="full", severity=0.0)).pump.plunger_friction_n
            cfg = card_config(d)
            card = simulate_card(dataclasses.replace(cfg, pump=dataclasses.replace(cfg.pump, plunger_friction_n=base)))
            out.append((offset + int(i), resample(card.t_s, card.polished_rod_position_m),
                        resample(card.t_s, card.polished_rod_load_n)))
        offset += len(c["label"])
    return tuple(np.array(v) for v in zip(*out))


def confusion(clf, x, t) -> np.ndarray:
    cm = np.zeros((12, 12), dtype=np.int64)
    np.add.at(cm, (t, np.argmax(clf.proba_features(x), axis=1)), 1)
    return cm


def summary(cm: np.ndarray) -> dict:
    fu, fl = LABELS.index("full"), LABELS.index("flowing")
    return {"accuracy": round(float(np.trace(cm) / cm.sum()), 4), "full_called_flowing": int(cm[fu, fl]),
            "flowing_called_full": int(cm[fl, fu]),
            "recall": {LABELS[k]: round(float(cm[k, k] / cm[k].sum()), 3) for k in range(12) if cm[k].sum()},
            "heavy_called": {LABELS[k]: int(cm[HEAVY, k]) for k in range(12) if cm[HEAVY, k]}}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cards", nargs=3, required=True)
    ap.add_argument("--out", required=True)
    a = ap.parse_args()
    data = load_sets(a.cards, "surface", described=True)
    fluid, down = data["fluid_load"], data["down_load"]
    split = {s: np.flatnonzero(data["split"] == s) for s in ("train", "validation")}
    tr = featurise(data["position"], data["load"], split["train"], np.random.default_rng(0), AUG_COPIES)
    va = featurise(data["position"], data["load"], split["validation"], np.random.default_rng(1), VALIDATION_DRAWS)
    t_tr, t_va = data["label"][tr["i"]], data["label"][va["i"]]
    idx, pos, load = heavy_without_friction(a.cards)
    stress = {"clean": {"x": np.array([features(p, y) for p, y in zip(pos, load)]),
                        "q": np.quantile(load, LEVEL_QUANTILES, axis=1).T, "e": np.tile([1.0, 0.0], (len(idx), 1)),
                        "i": idx}}
    stress["augmented"] = featurise(dict(zip(idx, pos)), dict(zip(idx, load)), idx, np.random.default_rng(1), 3)
    report = {}
    for name in ("R0", *ENTRIES):
        entry = None if name == "R0" else name
        if entry is None:
            clf = CardClassifier.load(DEFAULT_MODEL)
        else:
            w = fit(rows(tr, fluid, down, entry), t_tr, (256, 256), 30, 0)
            clf = CardClassifier(LABELS, w["mean"], w["std"], [(w[f"w{i}"], w[f"b{i}"]) for i in range(3)])
        r = {"validation": summary(confusion(clf, rows(va, fluid, down, entry), t_va))}
        for kind, z in stress.items():
            cm = confusion(clf, rows(z, fluid, down, entry), np.full(len(z["i"]), HEAVY))
            r[f"stress_heavy_{kind}"] = {**summary(cm)["heavy_called"], "of": int(cm.sum())}
        report[name] = r
        print(name, json.dumps(r), flush=True)
    with open(a.out, "w") as fh:
        json.dump({"what": " ".join(__doc__.split()), "models": report}, fh, indent=1)


if __name__ == "__main__":
    main()
