"""How the surface classifier without a config reads cards a field instrument has changed (issue 23; reported only,
chooses nothing): simulated cards read clean, with the load cell's zero offset, resampled to fewer points, and
low-passed as smooth strings and load cells smooth them.

    srenv cards --n 1200 --seed 41 --surface v2 --out CARDS41 --workers 2
    python scripts/classifier_instrument_probe.py --cards CARDS41 [--model M.npz]

Prints one line per perturbation: the accuracy over every card of the set and the recall per label. No real card is
read.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from srenv.analysis.card_augment import spectral_lowpass
from srenv.analysis.card_classifier import BadModel, CardClassifier
from srenv.cli_types import OneLineParser
from srenv.task.card_set import ARRAYS, load_cards

TOOL = "classifier_instrument_probe.py"
NEEDED = ("label", "label_names", *ARRAYS[:2])  # the columns read: the label and the surface card


def _resampled(x: np.ndarray, y: np.ndarray, n: int = 200) -> tuple[np.ndarray, np.ndarray]:
    t = np.linspace(0.0, len(x) - 1.0, n)
    return np.interp(t, np.arange(len(x)), x), np.interp(t, np.arange(len(y)), y)


PERTURBATIONS = {
    "clean": lambda x, y: (x, y),
    **{f"zero offset {o:+.2f} of the peak": (lambda x, y, o=o: (x, y + o * np.abs(y).max()))
       for o in (-0.10, -0.05, 0.05, 0.10)},
    "resampled to 200 points": _resampled,
    **{f"low-pass K = {k}": (lambda x, y, k=k: (spectral_lowpass(x, k), spectral_lowpass(y, k))) for k in (15, 8)},
}


def main(argv: list[str] | None = None) -> int:
    p = OneLineParser(prog=TOOL, description=__doc__.split("\n\n")[0])
    p.tool = TOOL
    p.add_argument("--cards", required=True, type=Path, help="a directory written by `srenv cards`")
    p.add_argument("--model", default=None, help="a classifier file (default: the shipped surface model)")
    args = p.parse_args(argv)
    try:  # both inputs read, as data, before any card is classified
        c = load_cards(str(args.cards / "cards.npz"))
        missing = [k for k in NEEDED if k not in c]
        if missing:
            p.error(f"--cards {args.cards}: cards.npz lacks {', '.join(missing)} (expected a set `srenv cards` wrote)")
        clf = CardClassifier.load(args.model) if args.model else CardClassifier.load()
    except BadModel as exc:
        p.error(f"--model {args.model}: {exc}")
    except (OSError, ValueError) as exc:
        p.error(f"--cards {args.cards}: not a card set `srenv cards` wrote ({type(exc).__name__}: {exc})")
    names = [str(s) for s in c["label_names"]]
    truth = np.array([names[i] for i in c["label"]])
    for tag, perturb in PERTURBATIONS.items():
        pred = np.array([clf.classify(*perturb(x, y))[0]
                         for x, y in zip(c["polished_rod_position_m"], c["polished_rod_load_n"])])
        ok = pred == truth
        recall = ", ".join(f"{n} {ok[truth == n].mean():.2f}" for n in names if (truth == n).any())
        print(f"{tag:30s} accuracy {ok.mean():.3f} ({ok.sum()} / {ok.size}); recall: {recall}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
