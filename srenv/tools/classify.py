"""``srenv classify CARD.csv|DIR [--config WELL] [--json] [--model M.npz] [--card surface|pump]``: name the pump
condition of surface cards, or (``--card pump``, run P1) of pump (downhole) cards.

A card is a CSV with the columns ``polished_rod_position_m,polished_rod_load_n`` (one stroke, equally spaced
in time, any units: the classifier normalises both) or srenv's own simulate CSV (``t_s`` and those columns;
its last stroke is taken). A headerless two-column file is read as position, load. Given a directory,
every ``*.csv`` in it is classified (sorted by name). Output: one line per card (``--json``: a JSON object
with ``file``, ``label`` and ``probabilities`` of all twelve labels). Every card is read and checked before
any answer: an unreadable or degenerate card, or a model file that is not a classifier's data, prints
one line and exits 2.

``--card pump`` reads the same CSVs as pump cards (the plunger's position and the load at the rod string's bottom,
in any units and either load convention) with the pump model (``srenv/models/classifier_pump.npz``); a model
trained on the other card type is refused. A pump card with a stroke but no load variation is called
``parted_rods`` by rule (docs/conditions.md, run P1; ``"rule": true`` in its JSON line). With ``--config WELL`` the
CSVs are *surface* cards in SI units (one stroke at the well's stroke rate): each is diagnosed first (``srenv
diagnose``'s Gibbs method, true loads) and its pump card classified by run P3's model (``classifier_pump_p3.npz``;
else run P2's, else P1's): trained on pump cards *diagnosed* the same way, so train and use match. Its 65th feature is
the pump card's load level against the described well's fluid load (run P2, srenv.analysis.pump_level: on a pump card
only the level tells full, parted rods, flowing and heavy oil apart), its 66th the lower plateau against the described
plunger's downstroke load P+ as a true load (srenv.simulation.described): a parted string diagnosed through the
described intact string sits about the missing rods' weight below it. Without a config ``--card pump`` keeps run P1's
model; a level model is refused without a config. Surface cards with ``--config WELL`` (SI units) are read by run 9's
model (``classifier_config.npz``, if shipped; else the surface model alone): its 66th feature is the card's load
midline against the described well (srenv.analysis.surface_level: a flowing well's card is a full pump's with a
smaller fluid load, which only the description can tell). Without a config the surface model is run 7's.

A vendor dynacard record (``RECORD.json``, or ``*.json`` in a directory beside ``*.csv`` cards) is read as ``srenv
validate`` reads it (``--reverse``, or a reversed card turned forward and said so) and its stored card classified as
with ``--config``, the well the record describes (``record_well``) as the config; the line names the model and the
well's source. In a directory a JSON file without ``cardData`` is skipped (a note on stderr after the answers).
"""

from __future__ import annotations

import argparse
import csv
import io
import json
import sys
from pathlib import Path

import numpy as np

from ..analysis.card_shape import CARD_TYPES
from ..errors import ConfigError, short_repr
from ..input_files import read_regular
from ..surface_unit.card_checks import MAX_CARD_BYTES, check_magnitude

MAX_FILES = 100_000
POS, LOAD = "polished_rod_position_m", "polished_rod_load_n"
BOTTOM_BAND = 0.02  # share of the stroke: samples this close to the lowest position are at the bottom


def add_parser(sub) -> None:
    c = sub.add_parser("classify", help="name the pump condition of surface cards (CSV or a directory)")
    c.add_argument("path", help="a card CSV, a vendor dynacard record (.json: classified against the well it "
                   "describes) or a directory of *.csv cards and *.json records")
    c.add_argument("--config", help="the well's config (checked; with --card pump the cards are surface cards in SI "
                   "units, diagnosed to pump cards first and read with their load level against the well's fluid "
                   "load and P+ (run P3's model); surface cards in SI units are read with their load midline "
                   "against the described well (run 9's model, if shipped))")
    c.add_argument("--json", action="store_true", help="one JSON line per card")
    c.add_argument("--reverse", action="store_true", help="dynacard records only: the card is stored in reverse "
                   "time, reverse it (without it a reversed card is turned forward and said so, as srenv validate "
                   "reads it)")
    c.add_argument("--model", help="model file (default: the shipped srenv/models/classifier.npz, "
                   "with --config classifier_config.npz if shipped, with --card pump srenv/models/classifier_pump.npz, "
                   "with --config too classifier_pump_p3.npz)")
    c.add_argument("--card", choices=CARD_TYPES, default="surface",
                   help="the card type of the CSVs: the polished rod's (surface, default) or the pump's (downhole); "
                   "without --config full, parted rods, flowing and heavy oil share one normalised pump card shape "
                   "(run P1): give the well's config, or read those four on surface cards")
    c.set_defaults(func=main)


def _bad(path: str | Path, what: str):
    from ..errors import ConfigError

    return ConfigError("card", str(path), what)


def last_stroke(t: np.ndarray, x: np.ndarray) -> slice:
    """The last full stroke of a multi-stroke record: between the last two visits to the bottom."""
    lo, rng = float(x.min()), float(x.max() - x.min())
    at_bottom = x <= lo + BOTTOM_BAND * rng
    starts = np.flatnonzero(at_bottom & ~np.r_[False, at_bottom[:-1]])
    if len(starts) < 2:
        return slice(0, len(x))
    return slice(int(starts[-2]), int(starts[-1]) + 1)


def _column(names: list[str], exact: str, stem: str) -> int | None:
    """The column named `exact`, else the only one whose name holds `stem` (case-insensitive): field exports name
    them "Position (in)", "Load, lbf"... and the classifier is scale-free, so the unit in the name does not matter."""
    if exact in names:
        return names.index(exact)
    hits = [i for i, n in enumerate(names) if stem in n.lower()]
    return hits[0] if len(hits) == 1 else None


def read_card(path: Path, si: bool = False) -> tuple[np.ndarray, np.ndarray]:
    """(position, load) of one card file (data only). `si`: the loads are read in newtons against a described well
    (``--config``), so the file must say so by its header; a header in other units or none is refused."""
    if path.is_symlink() or not path.is_file():
        raise _bad(path, "a regular CSV file")
    raw = read_regular(path, "card", "CSV file", MAX_CARD_BYTES)
    try:
        rows = [r for r in csv.reader(io.StringIO(raw.decode("utf-8"), newline="")) if r and any(c.strip() for c in r)]
    except (UnicodeDecodeError, csv.Error) as exc:
        raise _bad(path, f"a readable UTF-8 CSV ({exc.__class__.__name__}: {short_repr(str(exc), 80)})") from None
    if not rows:
        raise _bad(path, f"a CSV with columns {POS},{LOAD} (the file is empty)")
    head = [c.strip() for c in rows[0]]
    try:
        [float(c) for c in head]
        names, body = None, rows
    except ValueError:
        names, body = head, rows[1:]
    try:
        data = np.array([[float(c) for c in r] for r in body], dtype=np.float64)
    except ValueError:
        raise _bad(path, "numbers in every row below the header") from None
    if data.ndim != 2 or len(data) == 0:
        raise _bad(path, "rows of equal length with numbers")
    check_magnitude(data.ravel(), "card", str(path), "numbers", "value")  # before any arithmetic on the card
    if si and (names is None or POS not in names or LOAD not in names):
        got = ",".join(names) if names is not None else "no header"
        raise _bad(path, f"with --config a header naming {POS} and {LOAD} (SI: the loads are read in N against the "
                         f"described well; got {got[:80]!r}): convert the card to m and N, or classify without --config")
    if names is None:
        if data.shape[1] != 2:
            raise _bad(path, f"a header {POS},{LOAD} (or exactly two columns)")
        return data[:, 0], data[:, 1]
    pos, load = _column(names, POS, "pos"), _column(names, LOAD, "load")
    if pos is None or load is None or len(names) != data.shape[1]:
        raise _bad(path, f"a header with columns {POS} and {LOAD} (or one column named *position* and one *load*)")
    x, y = data[:, pos], data[:, load]
    if "t_s" in names and len(x) > 2:
        s = last_stroke(data[:, names.index("t_s")], x)
        x, y = x[s], y[s]
    return x, y


def card_files(path: str) -> list[Path]:
    """The card CSV or record named, or a directory's ``*.csv`` cards and ``*.json`` records (sorted by name)."""
    from ..cli_types import RECORD_SUFFIX

    p = Path(path)
    if p.is_dir():
        files = sorted([*p.glob("*.csv"), *p.glob("*" + RECORD_SUFFIX)])
        if not files:
            raise _bad(path, f"a directory with *.csv cards or *{RECORD_SUFFIX} dynacard records (none found)")
        if len(files) > MAX_FILES:
            raise _bad(path, f"at most {MAX_FILES} cards in a directory")
        return files
    if not p.exists():
        raise _bad(path, "an existing card CSV, dynacard record (.json) or directory")
    return [p]


def default_model(card: str, with_config: bool) -> str:
    """The shipped model: surface (run 7), with a config run 9's if shipped; pump (P1) without a config; with one,
    P3's model if shipped, else P2's level model if shipped, else P1."""
    from ..analysis.card_classifier import (
        CONFIG_MODEL,
        DEFAULT_MODEL,
        PUMP_LEVEL_MODEL,
        PUMP_MODEL,
        PUMP_P3_MODEL,
    )

    if card != "pump":
        return str(CONFIG_MODEL if with_config and CONFIG_MODEL.is_file() else DEFAULT_MODEL)
    shipped = [m for m in (PUMP_P3_MODEL, PUMP_LEVEL_MODEL) if with_config and m.is_file()]
    return str(shipped[0] if shipped else PUMP_MODEL)


def load_model(model: str | None, card: str, with_config: bool = False):
    """The classifier for ``card`` (``model`` or the shipped one); a file of the other card type is refused, and a
    level model (run P2) without a config."""
    from ..analysis.card_classifier import BadModel, CardClassifier
    from ..errors import ConfigError

    path = model or default_model(card, with_config)
    try:
        clf = CardClassifier.load(path)
    except BadModel as exc:
        raise ConfigError("--model", path, f"a classifier's data ({exc})") from None
    if clf.card_type != card:
        raise ConfigError("--card", card, f"{clf.card_type}, the card type model {path} was trained on")
    if clf.needs_config and not with_config:
        what = "the pump card's load level against the described fluid load" if clf.needs_level else \
            "the surface card's load midline against the described well"
        raise ConfigError("--config", None, f"a well config: model {path} reads {what}")
    return clf


def described(cfg, card: str) -> tuple[float, float]:
    """(F_desc, the description's downstroke load) in N: for pump cards the described pump's P+ as a true load
    (srenv.simulation.described; the level and the offset), for surface cards the static polished-rod downstroke load
    (analysis.surface_level; the midline); a description that lifts no load (0, or not finite) in one line."""
    from ..analysis.pump_level import BadLevel, check_fluid_load
    from ..analysis.surface_level import described_surface
    from ..errors import ConfigError
    from ..simulation import described as desc

    # the config loader refuses P- <= P+ given as loads, the simulator an intake pressure at or above the discharge
    # pressure (one line each); what passes both and still lifts no finite load is refused here
    if card == "pump":
        pump = desc.described_pump(cfg)
        out = (pump.fluid_load_n, pump.downstroke_true_n)
    else:
        surf = described_surface(cfg)
        out = (surf.fluid_load_n, surf.downstroke_n)
    try:
        check_fluid_load(out[0], f"well {cfg.name}")
    except BadLevel as exc:
        raise ConfigError("--config", cfg.name, f"a well whose pump lifts a fluid load ({exc})") from None
    return out


def _features_or_rule(clf, x: np.ndarray, y: np.ndarray, f: Path, pump) -> np.ndarray | None:
    """The card's features (``pump``: the description's (F_desc, downstroke load), or None); None for a pump card
    with a stroke and no load (run P1's rule: parted rods)."""
    from ..analysis.card_shape import BadCard, FlatLoad
    from ..analysis.pump_level import BadLevel

    try:
        if pump is None:
            return clf.card_features(x, y)
        return clf.card_features(x, y, *pump)
    except FlatLoad as exc:
        if clf.card_type == "pump":
            return None
        raise _bad(f, f"a readable card ({exc})") from None
    except (BadCard, BadLevel) as exc:
        raise _bad(f, f"a readable card ({exc})") from None


def diagnosed(cfg, x: np.ndarray, y: np.ndarray, f: Path) -> tuple[np.ndarray, np.ndarray]:
    """The pump card of one surface card (SI, one stroke equally spaced in time at the well's stroke rate); a card
    the diagnosis cannot read (wrong units for this well, say) is refused in one line naming the file."""
    from ..analysis.diagnose import diagnose_card
    from ..config_checks import run_spm

    period = 60.0 / run_spm(cfg)
    try:
        card = diagnose_card(cfg, np.arange(len(x)) * (period / len(x)), x, y, period_s=period)
    except (ValueError, ArithmeticError, np.linalg.LinAlgError) as exc:
        raise _bad(f, f"a surface card in SI units of well {cfg.name} that srenv diagnose reads ({exc})") from None
    if not (np.all(np.isfinite(card.pump_position_m)) and np.all(np.isfinite(card.pump_load_n))):
        raise _bad(f, f"a surface card in SI units of well {cfg.name} (its diagnosed pump card is not finite)")
    return card.pump_position_m, card.pump_load_n


def classify_cards(clf, files: list[Path], cfg, card: str, read) -> list[tuple[np.ndarray, bool]]:
    """(probabilities, by rule) of each card: ``read(f)`` gives its (position, load); with ``cfg`` (a described
    well) the config-aware path of ``--config`` (pump cards diagnosed first, the description's loads as features)."""
    pump = described(cfg, card) if clf.needs_config else None
    cards = [read(f) for f in files]
    if cfg is not None and card == "pump":  # surface cards of a described well: diagnose them first
        cards = [diagnosed(cfg, x, y, f) for f, (x, y) in zip(files, cards)]
    rows = [_features_or_rule(clf, x, y, f, pump) for f, (x, y) in zip(files, cards)]
    readable = [r for r in rows if r is not None]
    proba = iter(clf.proba_features(np.array(readable)) if readable else [])
    rule = np.array([lab == "parted_rods" for lab in clf.labels], dtype=np.float64)
    return [(rule, True) if r is None else (next(proba), False) for r in rows]


def _line(f: Path, labels, p: np.ndarray, by_rule: bool, extra: dict | None, as_json: bool) -> str:
    """One card's output line (``extra``: what a record adds, the model and the well it was read against)."""
    label = labels[int(np.argmax(p))]
    if as_json:
        row = {"file": str(f), "label": label, "probabilities": {k: round(float(v), 6) for k, v in zip(labels, p)}}
        return json.dumps({**row, **({"rule": True} if by_rule else {}), **(extra or {})})
    text = f"{f}\t{label}\t{float(p.max()):.3f}" + ("\t(rule: no load variation)" if by_rule else "")
    if extra:
        turned = "; card stored in reverse time, read forward" if extra["well"]["card_time_reversed"] else ""
        text += f"\t(model {Path(extra['model']).name}; well described by the record{turned})"
    return text


def split_records(files: list[Path], path: str, config: str | None, reverse: bool):
    """(the dynacard records read, with their files; the card CSVs; notes of JSON files skipped). In a directory a
    ``*.json`` that parses and holds no ``cardData`` is not a card and is skipped (said on stderr after the
    answers); one that does not parse, or a record that does not read, is refused; so is ``--config`` beside a
    record (it describes its well) and ``--reverse`` beside a CSV card (its rows' order is taken as it is)."""
    from ..cli_types import check_card_config, is_record
    from .record_well import is_dynacard, read_record_file

    jsons, csvs = [f for f in files if is_record(f)], [f for f in files if not is_record(f)]
    skipped = [f for f in jsons if Path(path).is_dir() and not is_dynacard(f)]
    if skipped and len(skipped) == len(files):
        raise _bad(path, f"a directory with *.csv cards or dynacard records ({len(skipped)} JSON files without "
                   "cardData skipped, none left)")
    records = [f for f in jsons if f not in skipped]
    if records:
        check_card_config(records[0], config, required=False)
    if reverse and csvs:
        raise ConfigError("--reverse", str(csvs[0]), "dynacard records (.json) only: a CSV card is read in its "
                          "rows' order")
    notes = [f"srenv: note: skipped {f}: a JSON file that is not a dynacard record (no cardData)" for f in skipped]
    return [(f, read_record_file(f, reverse)) for f in records], csvs, notes


def classify_records(records: list, args: argparse.Namespace) -> dict:
    """Each record's card classified as ``classify CARD.csv --config WELL`` does, its described well as WELL
    (``record_well.described_well``); the line says which model answered and that the well is the record's."""
    from ..config import config_from_dict
    from .record_well import described_well

    if not records:
        return {}
    model, clf = args.model or default_model(args.card, True), load_model(args.model, args.card, True)
    out = {}
    for f, rec in records:
        with described_well(rec) as well:
            [(p, by_rule)] = classify_cards(clf, [f], config_from_dict(well.config), args.card,
                                            lambda _, r=rec: (r.position_m, r.load_n))
        out[f] = (clf.labels, p, by_rule, {"model": str(model), "well": well.entry()})
    return out


def main(args: argparse.Namespace) -> int:
    cfg = None
    if args.config:
        from ..config import load_config

        cfg = load_config(args.config)
    records, files, notes = split_records(card_files(args.path), args.path, args.config, args.reverse)
    out: dict[Path, tuple] = {}
    if files:
        clf = load_model(args.model, args.card, cfg is not None)
        for f, (p, by_rule) in zip(files, classify_cards(clf, files, cfg, args.card,
                                                         lambda f: read_card(f, si=clf.needs_config))):
            out[f] = (clf.labels, p, by_rule, None)
    out.update(classify_records(records, args))
    for f in sorted(out):
        print(_line(f, *out[f], args.json))
    for note in notes:
        print(note, file=sys.stderr)
    return 0
