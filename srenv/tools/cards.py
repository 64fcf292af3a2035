"""``srenv cards --n N --out DIR [--conditions ...] [--seed S] [--workers W] [--surface family|v2]
[--equipment none|field] [--plungers family|api]``: a labelled synthetic card set.

Writes ``DIR/cards.npz`` (columns in docs/cards_dataset.md; the same seed gives the same bytes whatever
the number of workers) and ``DIR/dataset_card.json`` (the schema, the labels, the split counts). Cards are
simulated in local worker processes, a progress bar on stderr.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
from pathlib import Path

from ..declarations import MAX_CARDS  # noqa: F401  (re-exported: the set is held in memory, declared there)
from ..declarations import MAX_SWEEP_WORKERS as MAX_WORKERS  # noqa: F401


def _label_list(text: str) -> tuple[str, ...]:
    from ..physics.conditions import LABELS

    names = tuple(x.strip() for x in text.split(","))
    bad = [x for x in names if x not in LABELS]
    if bad or len(set(names)) != len(names):  # an empty item (a stray comma) or a label given twice too
        raise argparse.ArgumentTypeError(f"--conditions = {text[:200]!r}: expected a comma-separated list of "
                                         f"distinct labels among {', '.join(LABELS)}")
    return names


def add_parser(sub) -> None:
    from ..declarations import add_number

    c = sub.add_parser("cards", help="simulate a labelled card set (pump conditions) into DIR/cards.npz")
    add_number(c, "cards", "--n", required=True, help="number of cards")
    c.add_argument("--out", required=True, help="output directory (created; its cards.npz is replaced)")
    c.add_argument("--conditions", type=_label_list, help="comma-separated labels (default: all twelve)")
    add_number(c, "cards", "--seed", default=0, help="set seed (same seed, same files)")
    add_number(c, "cards", "--workers", default=None, help="worker processes (default: the CPUs available)")
    c.add_argument("--surface", choices=("family", "v2"), default="family",
                   help="family (default; sets 1-3): harmonic or the nearest catalogue unit, operating point "
                        "uniform; v2: each well's own v2 unit (conventional / Mark II / air-balanced), the "
                        "operating corners populated (docs/cards_dataset.md)")
    c.add_argument("--equipment", choices=("none", "field"), default="none",
                   help="none (default; sets 1-6): the family's API steel strings, 500 N plunger drag, deviation to "
                        "35 deg; field (run 7): per card a plunger drag of 0.2-4 kN, sinker bars, a fiberglass top, "
                        "deviation to 60 deg (docs/cards_dataset.md)")
    c.add_argument("--plungers", choices=("family", "api"), default="family",
                   help="family (default; sets 1-8): the family's plunger sizes; api (run 8): per card the plunger "
                        "drawn from those and the 1.06-in API bore (docs/cards_dataset.md)")
    c.add_argument("--no-progress", action="store_true", help="no progress bar")
    c.set_defaults(func=main)


OUT_FILES = ("cards.npz", "dataset_card.json")


def check_out_dir(path: str) -> Path:
    """``--out``, checked before the simulation (srenv.outputs.check_output_dir: the folder and its two files)."""
    from ..outputs import check_output_dir

    p = Path(path)
    check_output_dir(p, OUT_FILES, "--out", parents=False)
    return p


def _worker_init() -> None:
    # the command's SIGTERM handler (raise KeyboardInterrupt, for its own cleanup) is not the workers':
    # the pool ends them with SIGTERM after an interruption, and they should just stop
    import signal

    signal.signal(signal.SIGTERM, signal.SIG_DFL)


def _one(job: tuple) -> dict:
    from ..task.card_set import make_card

    return make_card(*job)


def simulate_set(n: int, seed: int, labels: tuple[str, ...], workers: int, progress: bool,
                 surface: str = "family", equipment: str = "none", plungers: str = "family") -> list[dict]:
    """Cards 0..n-1 of set ``seed``, in order (each card depends on (seed, index) only)."""
    from tqdm import tqdm

    jobs = [(seed, i, labels, surface, equipment, plungers) for i in range(n)]
    bar = tqdm(total=n, desc="cards", unit="card", file=sys.stderr, disable=not progress)
    try:
        if workers <= 1:
            out = []
            for j in jobs:
                out.append(_one(j))
                bar.update()
            return out
        import multiprocessing as mp

        ctx = mp.get_context("spawn" if sys.platform == "darwin" else "fork")
        with ctx.Pool(workers, initializer=_worker_init) as pool:
            out = []
            for card in pool.imap(_one, jobs, chunksize=max(1, min(16, n // (4 * workers) or 1))):
                out.append(card)
                bar.update()
            pool.close()  # let the workers finish on their own: no SIGTERM at the end of a good run
            pool.join()
            return out
    finally:
        bar.close()


def dataset_card(cols: dict, seed: int, labels: tuple[str, ...], surface: str = "family",
                 equipment: str = "none", plungers: str = "family") -> dict:
    import numpy as np

    from ..task.card_equipment import COLUMNS
    from ..task.card_set import ARRAYS, N_POINTS, SPLITS, WELL_COLUMNS

    names = list(cols["label_names"])
    return {"format": "srenv card set 1", "file": "cards.npz", "seed": seed, "n_cards": len(cols["label"]),
            "points_per_card": N_POINTS, "labels": names, "conditions_drawn": list(labels),
            "arrays": list(ARRAYS), "well_columns": list(WELL_COLUMNS) + (list(COLUMNS) if equipment != "none" else []),
            "splits": {s: int(np.sum(cols["split"] == s)) for s in SPLITS},
            "cards_per_label": {names[k]: int(np.sum(cols["label"] == k)) for k in range(len(names))},
            "doc": "docs/cards_dataset.md", **({"surface": surface} if surface != "family" else {}),
            **({"equipment": equipment} if equipment != "none" else {}),
            **({"plungers": plungers} if plungers != "family" else {})}


def main(args: argparse.Namespace) -> int:
    from ..outputs import atomic_write_all
    from ..physics.conditions import LABELS
    from ..task.card_set import columns, write_npz

    out = check_out_dir(args.out)
    labels = args.conditions or LABELS
    workers = args.workers or max(1, len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity")
                                  else (os.cpu_count() or 1))
    surface, equipment = getattr(args, "surface", "family"), getattr(args, "equipment", "none")
    plungers = getattr(args, "plungers", "family")
    cards = simulate_set(args.n, args.seed, labels, min(workers, args.n), not args.no_progress, surface, equipment,
                         plungers)
    cols = columns(cards)
    meta = dataset_card(cols, args.seed, labels, surface, equipment, plungers)
    created = not out.exists()
    out.mkdir(exist_ok=True)
    try:  # both files or neither (and no directory of ours left empty)
        atomic_write_all([(out / "cards.npz", lambda tmp: write_npz(tmp, cols)),
                          (out / "dataset_card.json",
                           lambda tmp: Path(tmp).write_text(json.dumps(meta, indent=1, sort_keys=True) + "\n"))])
    except BaseException:
        if created and not any(out.iterdir()):
            out.rmdir()
        raise
    print(json.dumps({"out": str(out), "n_cards": meta["n_cards"], "splits": meta["splits"]}))
    return 0
