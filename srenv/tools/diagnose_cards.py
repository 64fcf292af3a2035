"""Diagnosed pump cards of a card set, as a derived card set (run P3, docs/conditions.md).

    python -m srenv.tools.diagnose_cards --cards DIR --out DIR

With a well config ``srenv classify --card pump`` reads a surface card's pump card *diagnosed* through the
described well, not the string end's true card the card sets hold. This writes a card set with the same columns
whose ``pump_position_m``/``pump_load_n`` are each card's surface card diagnosed (``srenv diagnose``'s
``diagnose_card``, true loads) through its described well (card_set.described_well: the family well of its seed in
the full condition; not the card's drawn damping, Kelvin-Voigt time or unit) at the card's period, so a model
trained on it meets what it will read. A card whose diagnosis fails or is not finite gets NaN pump arrays (the
trainer counts it degenerate). The dataset card is copied with ``pump_source: diagnosed`` and the failure count.
No real card is read here.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np

from ..cli_types import OneLineParser
from ..errors import ConfigError
from ..outputs import atomic_write_all, check_output_path
from ..task.card_set import described_well, load_cards, write_npz


def diagnosed_card(cfg, x: np.ndarray, y: np.ndarray, period_s: float) -> tuple[np.ndarray, np.ndarray]:
    """The pump card (256 samples, periodic: the last repeats the first, as the set's) of one set card, whose
    last sample repeats its first; NaN where the diagnosis cannot read it."""
    from ..analysis.diagnose import diagnose_card

    m = len(x) - 1  # the set's cards run from t = 0 to t = period: the last sample is the first again
    try:
        c = diagnose_card(cfg, np.arange(m) * (period_s / m), x[:m], y[:m], period_s=period_s)
        p, q = np.r_[c.pump_position_m, c.pump_position_m[0]], np.r_[c.pump_load_n, c.pump_load_n[0]]
    except (ValueError, ArithmeticError, np.linalg.LinAlgError):
        return np.full(len(x), np.nan), np.full(len(x), np.nan)
    if not (np.all(np.isfinite(p)) and np.all(np.isfinite(q))):
        return np.full(len(x), np.nan), np.full(len(x), np.nan)
    return p, q


def diagnose_set(cols: dict[str, np.ndarray], progress: bool = True) -> tuple[dict[str, np.ndarray], int]:
    """The set's columns with its pump arrays diagnosed; the number of cards whose diagnosis failed."""
    out = dict(cols)
    pos, load = np.empty_like(cols["pump_position_m"]), np.empty_like(cols["pump_load_n"])
    wells: dict[int, object] = {}
    n = len(cols["label"])
    for i in range(n):
        s = int(cols["well_seed"][i])
        if s not in wells:
            wells[s] = described_well(s)
        pos[i], load[i] = diagnosed_card(wells[s], cols["polished_rod_position_m"][i],
                                         cols["polished_rod_load_n"][i], float(cols["period_s"][i]))
        if progress and (i + 1) % 1000 == 0:
            print(f"diagnose_cards: {i + 1}/{n}", file=sys.stderr)
    out["pump_position_m"], out["pump_load_n"] = pos, load
    return out, int(np.sum(~np.isfinite(load[:, 0])))


class _Parser(OneLineParser):
    tool = "diagnose_cards"


def main(argv: list[str] | None = None) -> int:
    ap = _Parser(prog="python -m srenv.tools.diagnose_cards", description=__doc__.splitlines()[0])
    ap.add_argument("--cards", required=True, help="a directory written by `srenv cards`")
    ap.add_argument("--out", required=True, help="the derived set's directory (created; must not hold a set)")
    a = ap.parse_args(argv)
    src, dst = Path(a.cards), Path(a.out)
    if not (src / "cards.npz").is_file():
        ap.error(f"--cards {a.cards}: expected a directory with cards.npz (written by `srenv cards`)")
    if (dst / "cards.npz").exists():
        ap.error(f"--out {a.out}: holds a card set already, expected a new directory")
    if dst.is_symlink() or (dst.exists() and not dst.is_dir()):
        ap.error(f"--out {a.out}: expected a directory that is not a symbolic link")
    try:  # both outputs checked before the work, written atomically (both or neither) as `srenv cards` does
        dst.mkdir(parents=True, exist_ok=True)
        for name in ("cards.npz", "dataset_card.json"):
            check_output_path("--out", str(dst / name), (Path(name).suffix,))
        cols, failed = diagnose_set(load_cards(str(src / "cards.npz")))
        meta_path = src / "dataset_card.json"
        meta = json.loads(meta_path.read_text()) if meta_path.is_file() else {}
        meta.update(pump_source="diagnosed", diagnosis_failed=failed, derived_from=str(src))
        atomic_write_all([(dst / "cards.npz", lambda tmp: write_npz(tmp, cols)),
                          (dst / "dataset_card.json",
                           lambda tmp: Path(tmp).write_text(json.dumps(meta, indent=1) + "\n"))])
    except (ConfigError, OSError) as exc:
        ap.error(str(exc))
    print(json.dumps({"cards": len(cols["label"]), "diagnosis_failed": failed}))
    return 0


if __name__ == "__main__":
    sys.exit(main())
