"""Mesh and time-step convergence study behind the default `element_length_m` and `time_step_s`.

For each paper well: PPRL and MPRL of the 3rd stroke for element lengths h and time steps dt, compared with
a run refined 4x in both space and time from the candidate default. Prints a Markdown table.
Usage: python scripts/convergence.py [--cases paper_fig3_vertical paper_fig4_deviated]
"""

from __future__ import annotations

import argparse

from srenv.config import load_config
from srenv.simulation.simulator import Simulator


def peak_loads(name: str, h: float, dt: float) -> tuple[float, float]:
    cfg = load_config(name, {"simulation.element_length_m": h, "simulation.time_step_s": dt})
    tr = Simulator(cfg).run_strokes(3)[-1].trace
    return float(tr["polished_rod_load_n"].max()), float(tr["polished_rod_load_n"].min())


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--cases", nargs="+", default=["paper_fig3_vertical", "paper_fig4_deviated"])
    args = ap.parse_args()
    print("| case | element_length_m | time_step_s | PPRL (kN) | PPRL error vs 4x refined | MPRL error |")
    print("|---|---|---|---|---|---|")
    for name in args.cases:
        for h, dt in [(100.0, 0.02), (50.0, 0.01), (25.0, 0.005), (12.5, 0.0025)]:
            ref_p, ref_m = peak_loads(name, h / 4, dt / 4)
            p, m = peak_loads(name, h, dt)
            print(f"| {name} | {h} | {dt} | {p / 1e3:.2f} | {100 * (p - ref_p) / ref_p:+.2f} % "
                  f"| {100 * (m - ref_m) / ref_m:+.2f} % |")


if __name__ == "__main__":
    main()
