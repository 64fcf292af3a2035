"""Train the condition classifier on simulated cards only (docs/conditions.md).

    python -m srenv.tools.train_classifier --cards DIR [DIR ...] --out srenv/models/classifier.npz \
        [--report docs/classifier_report.json] [--epochs 30] [--seed 0] [--candidates ...] [--compare M.npz ...] \
        [--card surface|pump]

Reads the card sets written by ``srenv cards`` (their ``train`` split to fit, ``validation`` to choose the
model; the ``test`` split is scored once at the end, for the docs), fits each candidate of CANDIDATES on
AUG_COPIES augmented versions of every training card (srenv.analysis.card_augment), picks the one with the best
accuracy on augmented validation cards, and writes its weights as data (NPZ, no pickle). No real card is
read here. Needs torch (a training-time dependency; inference is numpy only).

``--card pump`` (run P1) trains on the sets' pump (downhole) cards instead, with the load ratio set to 0
(card_shape), and records ``card_type`` in the model file; a clean pump card the representation cannot read is
*degenerate*: left out of the training pool and the validation scoring, counted, and on the test split called
``parted_rods`` by rule (docs/conditions.md, run P1). The default, ``surface``, is runs 1-6's path bit for bit.
``--card pump --level`` (run P2) puts the load level against each card's described fluid load (pump_level) in the
65th entry, with a description error on augmented cards, and records ``feature_set: shape+level``.
``--offset`` with it (run P3) adds the lower plateau against each card's described P+ (true load) as a 66th entry
(``feature_set: shape+level+offset``); run P3 trains it on diagnosed pump cards (srenv.tools.diagnose_cards).
``--described`` (run 9, surface cards) adds the surface card's load midline against each card's *own* well in the
full condition (surface_level; card_set.described_surfaces) as a 66th entry, the description's fluid load times
U[1 - e, 1 + e] and its downstroke load moved by the fluid load times U[-e, e] on augmented cards (P3's draws), and
records ``feature_set: shape+midline``: a model ``srenv classify`` reads only with ``--config``.
``--members K`` (run 10) trains each candidate K times, member k with seed ``--seed`` + k (its augmented pool and its
network), and writes the K members into one file (card_classifier.stack_members; the model's probabilities are the
mean of the members'); K = 1, the default, is every earlier run's path and file.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

from ..analysis.card_augment import InstrumentAugment, SpectralAugment, augment
from ..analysis.card_classifier import MAX_MEMBERS, CardClassifier, stack_members
from ..analysis.card_shape import CARD_TYPES, BadCard, features
from ..analysis.pump_level import DESCRIPTION_ERROR, FEATURE_SETS, OFFSET_ERROR, with_level, with_offset
from ..analysis.surface_level import FEATURE_SET as MIDLINE
from ..analysis.surface_level import with_midline
from ..cli_types import OneLineParser
from ..declarations import Number
from ..physics.conditions import LABELS
from ..task.card_set import described_pumps, described_surfaces, load_cards

# name -> (hidden widths, augmented training); chosen on augmented validation accuracy
CANDIDATES = {"mlp_aug": ((128, 128), True), "mlp_clean": ((128, 128), False), "linear_aug": ((), True),
              "mlp_wide_aug": ((256, 256), True)}
VALIDATION_DRAWS = 3  # augmented copies of each validation card
AUG_COPIES = 6  # augmented copies of each training card (the training pool)
BATCH = 512
# the card set's (position, load) arrays of each card type (docs/cards_dataset.md)
CARD_ARRAYS = {"surface": ("polished_rod_position_m", "polished_rod_load_n"), "pump": ("pump_position_m", "pump_load_n")}
FEATURE_SET_LEVEL = FEATURE_SETS[1]  # run P2's model file entry
DEGENERATE_RULE = "parted_rods"  # a degenerate pump card's label by rule (run P1, fixed a priori)
# --members: an ensemble's size (run 10); bounded by what one model file may hold
MEMBERS_FLAG = Number("--members", int, hi=MAX_MEMBERS, why="one model file's members")


def load_sets(dirs: list[str], card: str = "surface", level: bool = False, offset: bool = False,
              described: bool = False) -> dict[str, np.ndarray]:
    """The sets' columns; ``position`` and ``load`` are the card type's arrays; ``fluid_load``: with ``level`` each
    card's described fluid load from its well seed (run P2), else None; ``down_load``: with ``offset`` its described
    P+ as a true load (run P3), else None; with ``described`` (run 9, surface) the two are each card's own well's
    F_desc and D_desc (card_set.described_surfaces)."""
    sets = [load_cards(str(Path(d) / "cards.npz")) for d in dirs]
    keys = (*CARD_ARRAYS[card], "label", "split", "well_seed")
    data = {k: np.concatenate([s[k] for s in sets]) for k in keys}
    data["position"], data["load"] = (data[k] for k in CARD_ARRAYS[card])
    fluid, down = described_pumps(data["well_seed"]) if level else (None, None)
    data["fluid_load"], data["down_load"] = fluid, down if offset else None
    if described:
        pairs = [described_surfaces(d, s) for d, s in zip(dirs, sets)]
        data["fluid_load"], data["down_load"] = (np.concatenate([p[k] for p in pairs]) for k in (0, 1))
    return data


def _row(p: np.ndarray, q: np.ndarray, card: str, fluid_load: float | None, rng, aug: bool,
         down_load: float | None = None) -> np.ndarray:
    """One card's features; with a described fluid load the level in the 65th entry (augmented: times the
    description error, drawn after the card's augmentation so the runs without the level draw what they drew); with
    a described P+ the offset in a 66th (augmented: P+ moved by F_desc times U[-e, e], drawn after P2's draws)."""
    f = features(p, q, card)
    if fluid_load is None:
        return f
    err = rng.uniform(1.0 - DESCRIPTION_ERROR, 1.0 + DESCRIPTION_ERROR) if aug else 1.0
    shift = (rng.uniform(-OFFSET_ERROR, OFFSET_ERROR) * fluid_load if aug else 0.0) if down_load is not None else 0.0
    if card == "surface":  # run 9: the midline against the card's described well
        return with_midline(f, q, down_load + shift, fluid_load * err)
    f = with_level(f, q, fluid_load * err)
    return f if down_load is None else with_offset(f, q, down_load + shift, fluid_load * err)


def featurise(x: np.ndarray, y: np.ndarray, labels: np.ndarray, rng, aug: bool, draws: int = 1,
              instrument: InstrumentAugment | None = None, spectral: SpectralAugment | None = None,
              card: str = "surface", fluid_load: np.ndarray | None = None, down_load: np.ndarray | None = None):
    """Feature rows and labels (cards the representation cannot read are dropped and counted); ``fluid_load``:
    each card's described fluid load (run P2's level), None without the level; ``down_load``: each card's described
    P+ (run P3's offset), None without it."""
    rows, out = [], []
    loads = [None] * len(labels) if fluid_load is None else fluid_load
    downs = [None] * len(labels) if down_load is None else down_load
    for _ in range(draws):
        for p, q, lab, fl, dl in zip(x, y, labels, loads, downs):
            if aug:
                p, q = augment(p, q, rng, instrument, spectral)
            try:
                rows.append(_row(p, q, card, fl, rng, aug, dl))
            except BadCard:
                continue
            out.append(lab)
    return np.array(rows), np.array(out, dtype=np.int64)


def fit(f0: np.ndarray, t0: np.ndarray, widths: tuple, epochs: int, seed: int) -> dict:
    """An MLP (or linear model without hidden widths) on feature rows f0 with labels t0."""
    import torch

    torch.set_num_threads(1)  # a shared machine: one thread is faster than several contending
    torch.manual_seed(seed)
    mean, std = f0.mean(axis=0), f0.std(axis=0) + 1e-6
    dims = [f0.shape[1], *widths, len(LABELS)]
    mods = []
    for i in range(len(dims) - 1):
        mods.append(torch.nn.Linear(dims[i], dims[i + 1]))
        if i < len(dims) - 2:
            mods += [torch.nn.ReLU(), torch.nn.Dropout(0.1)]
    net = torch.nn.Sequential(*mods)
    opt = torch.optim.AdamW(net.parameters(), lr=3e-3, weight_decay=1e-4)
    sched = torch.optim.lr_scheduler.CosineAnnealingLR(opt, epochs)
    fx, ty = torch.from_numpy(((f0 - mean) / std).astype(np.float32)), torch.from_numpy(t0)
    for _ in range(epochs):
        net.train()
        perm = torch.randperm(len(ty))
        for i in range(0, len(ty), BATCH):
            b = perm[i:i + BATCH]
            opt.zero_grad()
            torch.nn.functional.cross_entropy(net(fx[b]), ty[b]).backward()
            opt.step()
        sched.step()
    net.eval()
    weights = {"mean": mean, "std": std, "labels": np.array(LABELS)}
    for i, m in enumerate(m for m in net if isinstance(m, torch.nn.Linear)):
        weights[f"w{i}"] = m.weight.detach().double().numpy().T.copy()
        weights[f"b{i}"] = m.bias.detach().double().numpy().copy()
    return weights


def degenerate(data: dict, card: str) -> np.ndarray:
    """Cards whose clean card the representation cannot read (run P1's rule; always none for surface cards, whose
    path stays runs 1-6's)."""
    bad = np.zeros(len(data["label"]), dtype=bool)
    if card == "surface":
        return bad
    for i, (p, q) in enumerate(zip(data["position"], data["load"])):
        try:
            features(p, q, card)
        except BadCard:
            bad[i] = True
    return bad


def evaluate(weights: dict, data: dict, idx: np.ndarray, aug: bool, seed: int,
             instrument: InstrumentAugment | None = None,
             spectral: SpectralAugment | None = None, card: str = "surface",
             ruled: np.ndarray | None = None) -> tuple[float, np.ndarray]:
    """Accuracy and confusion on cards idx (augmented: VALIDATION_DRAWS versions each); ``ruled``: labels of
    degenerate cards, called DEGENERATE_RULE by rule, counted once per draw."""
    clf = CardClassifier.from_weights(weights, n_features=np.shape(weights["mean"])[-1])
    rng = np.random.default_rng(seed)
    fl, dl = (None if data.get(k) is None else data[k][idx] for k in ("fluid_load", "down_load"))
    f, t = featurise(data["position"][idx], data["load"][idx], data["label"][idx],
                     rng, aug, VALIDATION_DRAWS if aug else 1, instrument, spectral, card, fl, dl)
    pred = np.argmax(clf.proba_features(f), axis=1)
    cm = np.zeros((len(LABELS), len(LABELS)), dtype=np.int64)
    np.add.at(cm, (t, pred), 1)
    if ruled is None or not len(ruled):
        return float(np.mean(pred == t)), cm
    np.add.at(cm, (ruled, LABELS.index(DEGENERATE_RULE)), VALIDATION_DRAWS if aug else 1)
    return float(np.trace(cm) / cm.sum()), cm


def _read_weights(path: str) -> dict:
    with np.load(path, allow_pickle=False) as z:
        return {k: z[k] for k in z.files}


def _card_type_of(path: str) -> tuple[str, str]:
    """(card type, feature set) of a model file; ("unreadable", "") if it is not one."""
    from ..analysis.card_classifier import card_type_of_file, feature_set_of_file

    try:
        w = _read_weights(path)
        return card_type_of_file(w), feature_set_of_file(w)
    except (OSError, ValueError, EOFError):
        return "unreadable", ""


def write_model(path: str, weights: dict) -> None:
    from ..task.card_set import write_npz

    write_npz(path, {k: np.asarray(v) for k, v in weights.items()})


def _probability(text: str) -> float:
    try:
        v = float(text)
    except ValueError:
        v = float("nan")
    if not 0.0 <= v <= 1.0:
        raise argparse.ArgumentTypeError(f"{text!r}: expected a probability in [0, 1]")
    return v


class _Parser(OneLineParser):
    tool = "train_classifier"  # a bad flag: one line, exit 2, no usage dump


def _check_args(ap, a) -> None:
    if a.card == "pump" and (a.synth_position_p > 0.0 or a.position_lag_p > 0.0):
        ap.error("--synth-position-p/--position-lag-p: the instrument effects belong to the surface unit's "
                 "position channel, expected 0 with --card pump")
    if a.level and a.card != "pump":
        ap.error(f"--level: the load level is a pump card's feature, expected --card pump (got --card {a.card})")
    if a.offset and not a.level:
        ap.error("--offset: the offset is read with the level, expected --level with it")
    if a.described and a.card != "surface":
        ap.error(f"--described: the midline is a surface card's feature, expected --card surface (got --card {a.card})")
    want = MIDLINE if a.described else FEATURE_SETS[2] if a.offset else FEATURE_SET_LEVEL if a.level else FEATURE_SETS[0]
    for path in a.compare:  # a model of the other card type (or features) would be scored on cards it cannot read
        kind, fset = _card_type_of(path)
        if kind != a.card:
            ap.error(f"--compare {path}: " + ("not a readable model file" if kind == "unreadable" else
                                              f"a {kind} card model") + f", expected a {a.card} card model")
        if fset != want:
            ap.error(f"--compare {path}: a model with features {fset}, expected features {want}")


def _pump_report(data: dict, bad: np.ndarray, split_idx: dict, level: bool, offset: bool = False) -> dict:
    """The pump run's report entries: degenerate counts per split and label, the rule; P2's feature set."""
    out = {"card": "pump", "degenerate": {s: {lab: int(np.sum(bad[i] & (data["label"][i] == k)))
                                              for k, lab in enumerate(LABELS)
                                              if np.any(bad[i] & (data["label"][i] == k))}
                                          for s, i in split_idx.items()},
           "degenerate_rule": DEGENERATE_RULE}
    if level:
        out.update({"feature_set": FEATURE_SET_LEVEL, "description_error": DESCRIPTION_ERROR})
    if offset:
        out.update({"feature_set": FEATURE_SETS[2], "offset_error": OFFSET_ERROR})
    return out


def _parser() -> _Parser:
    ap = _Parser(prog="python -m srenv.tools.train_classifier", description=__doc__.splitlines()[0])
    ap.add_argument("--cards", nargs="+", required=True, help="directories written by `srenv cards`")
    ap.add_argument("--out", required=True, help="model file (.npz)")
    ap.add_argument("--report", help="JSON report: every candidate's validation accuracy, the test confusion")
    ap.add_argument("--epochs", type=int, default=30)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--candidates", nargs="*", choices=sorted(CANDIDATES), default=list(CANDIDATES))
    ap.add_argument("--compare", nargs="*", default=[], help="existing model files to score on the same "
                    "validation cards as candidates (e.g. the shipped model)")
    ap.add_argument("--synth-position-p", type=_probability, default=0.0, help="augmentation: probability of a "
                    "position channel synthesised by a load-only controller (run 5; default 0: runs 1-4)")
    ap.add_argument("--position-lag-p", type=_probability, default=0.0, help="augmentation: probability of a "
                    "position transducer lagging the load by up to 3 %% of the period (run 5; default 0)")
    ap.add_argument("--spectral-p", type=_probability, default=0.0, help="augmentation: probability of the card's "
                    "zero-phase low-pass exp(-(k/K)^2), K log-uniform in [6, 30] (run 6; default 0: runs 1-5)")
    ap.add_argument("--card", choices=CARD_TYPES, default="surface", help="the card to train on: the polished "
                    "rod's (surface, default: runs 1-6) or the pump's (downhole; run P1, the load ratio set to 0)")
    ap.add_argument("--level", action="store_true", help="with --card pump: the load level against each card's "
                    "described fluid load in the 65th entry (run P2; the model then needs a well config)")
    ap.add_argument("--offset", action="store_true", help="with --level: the lower plateau against each card's "
                    "described P+ (true load) in a 66th entry (run P3)")
    ap.add_argument("--described", action="store_true", help="surface cards: the load midline against each card's "
                    "own described well in a 66th entry (run 9; the model then needs a well config)")
    ap.add_argument("--members", type=MEMBERS_FLAG.parse, default=1, help="run 10: train each candidate this many "
                    "times (member k with seed --seed + k) into one ensemble file, probabilities averaged "
                    f"(default 1: one network, every earlier run; at most {MEMBERS_FLAG.hi})")
    return ap


def _members(pool, name: str, a) -> list[dict]:
    """Candidate ``name``'s members: member k fitted with seed a.seed + k on the pool drawn with that seed."""
    widths, aug = CANDIDATES[name]
    return [fit(*pool(aug, a.seed + k), widths, a.epochs, a.seed + k) for k in range(a.members)]


def _members_report(members: list[dict], data: dict, idx: np.ndarray, a, inst, spec) -> list[dict]:
    """Each member's validation accuracies (augmented as the run's validation is, and clean), for the record; scored
    as the ensemble is (seed a.seed + 1)."""
    out = []
    for k, m in enumerate(members):
        aug_acc, _ = evaluate(m, data, idx, True, a.seed + 1, inst, spec, a.card)
        clean_acc, _ = evaluate(m, data, idx, False, a.seed + 1, card=a.card)
        out.append({"seed": a.seed + k, "validation_accuracy_augmented": aug_acc, "validation_accuracy_clean": clean_acc})
    return out


def main(argv: list[str] | None = None) -> int:
    ap = _parser()
    a = ap.parse_args(argv)
    _check_args(ap, a)
    inst = (InstrumentAugment(a.synth_position_p, a.position_lag_p)
            if a.synth_position_p > 0.0 or a.position_lag_p > 0.0 else None)
    spec = SpectralAugment(a.spectral_p) if a.spectral_p > 0.0 else None
    data = load_sets(a.cards, a.card, a.level, a.offset, a.described)
    bad = degenerate(data, a.card)
    split_idx = {s: np.flatnonzero(data["split"] == s) for s in ("train", "validation", "test")}
    report: dict = {"n_cards": {s: len(i) for s, i in split_idx.items()}, "candidates": {}}
    if a.card == "pump":
        report.update(_pump_report(data, bad, split_idx, a.level, a.offset))
    if a.described:
        report.update({"feature_set": MIDLINE, "description_error": DESCRIPTION_ERROR, "offset_error": OFFSET_ERROR})
    ruled = data["label"][split_idx["test"][bad[split_idx["test"]]]]
    split_idx = {s: i[~bad[i]] for s, i in split_idx.items()}  # the model reads only readable cards
    if inst is not None:
        report["instrument_augment"] = {"synth_position_p": inst.synth_position_p,
                                        "position_lag_p": inst.position_lag_p,
                                        "max_lag_of_period": inst.max_lag_of_period}
    if spec is not None:
        report["spectral_augment"] = {"p": spec.p, "k_range": list(spec.k_range)}
    best, best_acc = None, -1.0
    tr = split_idx["train"]
    pools: dict = {}  # AUG_COPIES augmented versions of every training card (or the clean cards), drawn once a seed

    def pool(aug: bool, seed: int):
        if (aug, seed) not in pools:
            pools[aug, seed] = featurise(
                data["position"][tr], data["load"][tr], data["label"][tr], np.random.default_rng(seed), aug,
                AUG_COPIES if aug else 1, inst, spec, a.card,
                *(None if data[k] is None else data[k][tr] for k in ("fluid_load", "down_load")))
        return pools[aug, seed]

    models = {name: (lambda name=name: _members(pool, name, a)) for name in CANDIDATES if name in a.candidates}
    models.update({path: (lambda path=path: [_read_weights(path)]) for path in a.compare})  # trained before
    if a.members > 1:
        report["members"] = {"count": a.members, "seeds": [a.seed + k for k in range(a.members)]}
    for name, make in models.items():
        members = make()
        if len(members) > 1:  # each member's validation, for the record
            report["candidates"][f"{name} members"] = _members_report(members, data, split_idx["validation"], a, inst,
                                                                         spec)
        w = stack_members(members)
        acc_aug, _ = evaluate(w, data, split_idx["validation"], True, a.seed + 1, inst, spec, a.card)
        acc_clean, _ = evaluate(w, data, split_idx["validation"], False, a.seed + 1, card=a.card)
        report["candidates"][name] = {"validation_accuracy_augmented": acc_aug,
                                      "validation_accuracy_clean": acc_clean}
        print(json.dumps({name: report["candidates"][name]}), file=sys.stderr)
        if acc_aug > best_acc:
            best, best_acc, report["chosen"] = w, acc_aug, name
    for aug in (True, False):
        acc, cm = evaluate(best, data, split_idx["test"], aug, a.seed + 2, inst, spec, a.card, ruled)
        key = "augmented" if aug else "clean"
        report[f"test_accuracy_{key}"], report[f"test_confusion_{key}"] = acc, cm.tolist()
    report["labels"] = list(LABELS)
    if a.card != "surface":  # a surface model's file stays runs 1-6's (no entry = surface)
        best = {**best, "card_type": np.array(a.card)}
    if a.level:  # P1's file has no entry (= shape)
        best = {**best, "feature_set": np.array(FEATURE_SETS[2] if a.offset else FEATURE_SET_LEVEL)}
    if a.described:  # a surface model that needs a config (run 9)
        best = {**best, "feature_set": np.array(MIDLINE)}
    write_model(a.out, best)
    if a.report:
        Path(a.report).write_text(json.dumps(report, indent=1) + "\n")
    print(json.dumps({k: report[k] for k in ("chosen", "test_accuracy_augmented", "test_accuracy_clean")}))
    return 0


if __name__ == "__main__":
    sys.exit(main())
