"""Interleaved env overhead of two checkouts: ``srenv.envs.bench_env.env_overhead`` (the ``env`` figure of
``srenv bench``: v0 env.step vs the bare simulator on the same strokes, thread CPU time) run in its own process
per side, sides alternating, so a shared machine's load hits both alike.

    git worktree add /tmp/before <commit>      # or: mkdir /tmp/before && git archive <commit> | tar -x -C /tmp/before
    python scripts/bench_env_overhead.py /tmp/before . --repeats 5
"""
import argparse
import json
import statistics
import subprocess
import sys

ap = argparse.ArgumentParser()
ap.add_argument("before")
ap.add_argument("after")
ap.add_argument("--repeats", type=int, default=5)
args = ap.parse_args()
code = "import json; from srenv.envs.bench_env import env_overhead; print(json.dumps(env_overhead()))"
trees = {"before": args.before, "after": args.after}
res = {k: [] for k in trees}
for r in range(args.repeats):
    for side in (("before", "after") if r % 2 == 0 else ("after", "before")):
        p = subprocess.run([sys.executable, "-c", code], env={"PYTHONPATH": trees[side], "PATH": "/usr/bin"},
                           capture_output=True, text=True, check=True, cwd=trees[side])
        res[side].append(json.loads(p.stdout.strip().splitlines()[-1]))
out = {}
for side, runs in res.items():
    pct = [x["env_overhead_pct"] for x in runs]
    out[side] = {"env_overhead_pct": [round(v, 1) for v in pct], "median_pct": round(statistics.median(pct), 1),
                 "env_steps_per_s_median": round(statistics.median(x["env_steps_per_s"] for x in runs), 1),
                 "bare_strokes_per_s_median": round(statistics.median(x["bare_strokes_per_s"] for x in runs), 1)}
out["env_steps_per_s_after_over_before"] = round(out["after"]["env_steps_per_s_median"]
                                                 / out["before"]["env_steps_per_s_median"], 3)
print(json.dumps(out, indent=1))
