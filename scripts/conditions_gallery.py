"""Gallery of the twelve pump conditions (docs/conditions.md): one PNG per condition under docs/figures/.

    python scripts/conditions_gallery.py [--well paper_fig3_vertical] [--severity 0.7] [--out docs/figures]

Each figure: the surface card and the pump card of the condition (last of srenv's card strokes), the
full-pump cards of the same well in grey.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt

from srenv.analysis.condition_card import condition_config, simulate_card
from srenv.config import load_config
from srenv.physics.conditions import LABELS


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--well", default="paper_fig3_vertical")
    ap.add_argument("--severity", type=float, default=0.7)
    ap.add_argument("--out", default="docs/figures")
    a = ap.parse_args()
    well = load_config(a.well)
    full = simulate_card(condition_config(well, "full", 0.0))
    for label in LABELS:
        card = simulate_card(condition_config(well, label, a.severity if label != "full" else 0.0))
        fig, (s, p) = plt.subplots(1, 2, figsize=(9, 3.4))
        for ax, key, title in ((s, "polished_rod", "surface card"), (p, "pump", "pump card")):
            ax.plot(getattr(full, f"{key}_position_m"), getattr(full, f"{key}_load_n") / 1e3, color="0.75",
                    lw=1, label="full pump")
            ax.plot(getattr(card, f"{key}_position_m"), getattr(card, f"{key}_load_n") / 1e3, lw=1.2, label=label)
            ax.set_xlabel("position (m)")
            ax.set_ylabel("load (kN)")
            ax.set_title(title)
        s.legend(fontsize=7, loc="best")
        fig.suptitle(f"{label} (severity {a.severity if label != 'full' else 0.0}), {a.well}", fontsize=10)
        fig.tight_layout()
        fig.savefig(Path(a.out) / f"condition_{label}.png", dpi=80)
        plt.close(fig)


if __name__ == "__main__":
    main()
