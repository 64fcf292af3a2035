"""Stroke-to-stroke variability of each reward term's per-stroke figure inside an interval, every stroke simulated
(docs/speed.md §2g): per term the CV over an interval's strokes and the exact strokes K its mean needs to be within
the bound (by the standard error and by the first K strokes of the every-stroke run).

    python scripts/stroke_variability.py --wells 0 1 2 3 4 5 6 7 --hours 2 [--bound 0.005] [--json out.json]
"""
import argparse
import json

from srenv.tools.stepping_error import POLICIES
from srenv.tools.stroke_variability import FIGURES, every_stroke_intervals, variability

ap = argparse.ArgumentParser()
ap.add_argument("--wells", type=int, nargs="+", default=[0, 1, 2, 3, 4, 5, 6, 7])
ap.add_argument("--hours", type=float, default=2.0)
ap.add_argument("--policies", nargs="+", default=["full_speed", "vsd_minimum"], choices=POLICIES)
ap.add_argument("--bound", type=float, default=0.005)
ap.add_argument("--json")
args = ap.parse_args()
if not 0 < args.bound < 1:
    ap.error(f"--bound = {args.bound}: expected a fraction in (0, 1), e.g. 0.005")
rows = []
for policy in args.policies:
    for seed in args.wells:
        intervals, terms = every_stroke_intervals(policy, seed, args.hours)
        v = variability(intervals, terms, args.bound)
        rows.append({"policy": policy, "seed": seed, "terms": terms, **v})
        cells = [f"{n} cv {100 * v[n]['cv_median']:.2f}/{100 * v[n]['cv_max']:.2f} % (detrended "
                 f"{100 * v[n]['cv_detrended_median']:.2f}/{100 * v[n]['cv_detrended_max']:.2f}) K_se "
                 f"{v[n]['k_se_median']:.0f}/{v[n]['k_se_max']:.0f} K_dir {v[n]['k_direct_median']:.0f}/"
                 f"{v[n]['k_direct_max']:.0f} ep(K=1,4,16) "
                 + "/".join(f"{100 * v[n]['episode_error_first_k'][k]:.2f}" for k in (1, 4, 16)) + " %" for n in FIGURES if v[n] is not None]
        print(f"{policy:12s} well {seed} ({v['strokes']:.0f} strokes/interval): " + "; ".join(cells), flush=True)
if args.json:
    with open(args.json, "w") as fh:
        json.dump(rows, fh, indent=1)
