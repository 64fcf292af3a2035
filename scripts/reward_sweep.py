"""Figure for docs/task.md: the v1 reward of one control step along SPM (step 0.05) and stroke (step 0.05 m) on
three training wells, with the reward terms. Run: python scripts/reward_sweep.py docs/figures/v1_reward_sweep.png"""

from __future__ import annotations

import argparse

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt

from srenv.tools.action_sweep import sweep

SEEDS = (4, 11, 30)


def main(path: str) -> None:
    fig, axes = plt.subplots(2, len(SEEDS), figsize=(13, 7))
    for j, seed in enumerate(SEEDS):
        for i, (axis, step, label) in enumerate((("spm", 0.05, "average SPM"), ("stroke", 0.05, "stroke (m)"))):
            r = sweep("train", seed, axis, step)
            ax = axes[i, j]
            ax.plot(r["value"], r["reward"], "k.-", lw=1.2, ms=2, label="reward")
            for k in ("reward_energy", "reward_fatigue", "reward_stick_slip", "reward_peak_load", "reward_pound",
                      "reward_ramp"):
                if abs(r[k]).max() > 0.05:
                    ax.plot(r["value"], r[k], lw=0.8, label=k[7:])
            ax.set(xlabel=label, ylabel="USD/h", title=f"{r['well_id']} ({axis})")
            ax.grid(alpha=0.3)
            if j == 0:
                ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=90)


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("out", nargs="?", default="docs/figures/v1_reward_sweep.png", help="PNG to write")
    main(ap.parse_args().out)
