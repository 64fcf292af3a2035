"""Interleaved CPU-time bench of two checkouts: strokes/s of `srenv bench`'s cases (unrecorded, after a warm-up
stroke), each side in its own process, sides alternating, process CPU time (a shared machine's load hits both).

    git worktree add /tmp/before <commit>
    python scripts/bench_interleaved.py /tmp/before . --repeats 9 --strokes 30
"""
import argparse
import json
import statistics
import subprocess
import sys

ap = argparse.ArgumentParser()
ap.add_argument("before")
ap.add_argument("after")
ap.add_argument("--repeats", type=int, default=9)
ap.add_argument("--strokes", type=int, default=30)
args = ap.parse_args()
reps, strokes = args.repeats, args.strokes
code = r'''
import sys, time, json
# the flat module names: the only ones a checkout from before the packages has (and aliases since, srenv/_compat.py)
from srenv.config import load_config
from srenv.simulation.simulator import Simulator
from srenv.tools.bench import CASES
strokes = int(sys.argv[1])
sims = {n: Simulator(load_config(n)) for n in CASES}
for s in sims.values(): s.run_stroke(record=False)
out = {}
for n, s in sims.items():
    t = time.process_time()
    for _ in range(strokes): s.run_stroke(record=False)
    out[n] = strokes / (time.process_time() - t)
print(json.dumps(out))
'''
trees = {"before": args.before, "after": args.after}
res = {k: [] for k in trees}
for r in range(reps):
    for side in (("before", "after") if r % 2 == 0 else ("after", "before")):
        p = subprocess.run([sys.executable, "-c", code, str(strokes)], env={"PYTHONPATH": trees[side], "PATH": "/usr/bin"},
                           capture_output=True, text=True, check=True)
        res[side].append(json.loads(p.stdout))
for case in res["before"][0]:
    ratios = [a[case] / b[case] for a, b in zip(res["after"], res["before"])]
    print(f"{case}: before {statistics.median(x[case] for x in res['before']):.1f} strokes/s, after "
          f"{statistics.median(x[case] for x in res['after']):.1f}; after/before min {min(ratios):.3f} "
          f"median {statistics.median(ratios):.3f} max {max(ratios):.3f} (n={len(ratios)})")
