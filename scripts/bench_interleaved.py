"""Interleaved CPU-time bench of two checkouts, each side in its own process, sides alternating, process CPU time
(a shared machine's load hits both).

Strokes/s of `srenv bench`'s cases (unrecorded, after a warm-up stroke):

    git worktree add /tmp/before <commit>
    python scripts/bench_interleaved.py /tmp/before . --repeats 9 --strokes 30

The kernel against its floor (``--kernel``: ``srenv bench``'s kernel block, each side's own floor run in its
process; after/before of ``floor_ratio`` and ``us_per_step``):

    python scripts/bench_interleaved.py /tmp/before . --kernel --repeats 6

Env steps/s of srenv/SuckerRod-v1 with the acceptance's protocol (train scenario, a warm-up step on seed 3, then
12 steps on each of seeds 11 and 12 at full speed, action [1, 1], and at the VSD minimum, [-0.6, 1]);
``--fast-stepping`` makes the after side's env with ``fast_stepping=True`` (the before side cannot take it):

    python scripts/bench_interleaved.py /tmp/srenv-acceptance/old-91adcce . --env --fast-stepping --repeats 3

The same for v2 against a checkout that has it (``--env-id``, both sides):

    python scripts/bench_interleaved.py /tmp/main . --env --env-id srenv/SuckerRod-v2 --repeats 10

An opt-in stepping option of the interval runner against the default, one tree on both sides (``--after-runner``:
the after side's runner attributes set at every reset, srenv/task/stepping.py):

    python scripts/bench_interleaved.py . . --env --env-id srenv/SuckerRod-v2 --after-runner '{"follow_drift": true}'

CPU ms per reset of a well not seen before (v2 and v1, train wells 11-40 after a warm-up reset and step on seed 3):

    python scripts/bench_interleaved.py /tmp/main . --resets --repeats 6
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
ap.add_argument("--env", action="store_true", help="env steps/s of srenv/SuckerRod-v1 instead of strokes/s")
ap.add_argument("--kernel", action="store_true",
                help="srenv bench's kernel block (µs/step, the floor's, floor_ratio) instead of strokes/s")
ap.add_argument("--resets", action="store_true", help="CPU ms per reset of an unseen well (v2, v1)")
ap.add_argument("--fast-stepping", action="store_true", help="the after side's env with fast_stepping=True")
ap.add_argument("--env-id", default="srenv/SuckerRod-v1", help="the env of --env (both sides: e.g. srenv/SuckerRod-v2 "
                "against a checkout that has it)")
ap.add_argument("--after-runner", default="{}", help="JSON of interval-runner options for the after side's env")
args = ap.parse_args()
try:
    after_runner = json.loads(args.after_runner)
except ValueError:
    after_runner = None
if not isinstance(after_runner, dict):
    ap.error(f"--after-runner = {args.after_runner!r}: expected a JSON object, e.g. '{{\"follow_drift\": true}}'")
reps, strokes = args.repeats, args.strokes
code = r'''
import sys, time, json
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
env_code = r'''
import sys, time, json, warnings
warnings.filterwarnings("ignore")
import numpy as np, gymnasium as gym
import srenv  # noqa: F401  (registers the envs)
kw = {"fast_stepping": True} if sys.argv[2] == "fast" else {}
env_id = sys.argv[3]
runner_kw = json.loads(sys.argv[4])
out = {}
for label, a0 in (("full_speed", 1.0), ("vsd_minimum", -0.6)):
    a = np.array([a0, 1.0], np.float32)
    env = gym.make(env_id, scenario="train", **kw); env.reset(seed=3); env.step(a)
    n, t0 = 0, time.process_time()
    for seed in (11, 12):
        env.reset(seed=seed)
        for k, v in runner_kw.items():  # a fresh runner: setting its options is building it with them
            setattr(env.unwrapped.runner, k, v)
        for _ in range(12):
            env.step(a); n += 1
    out[label] = n / (time.process_time() - t0)
print(json.dumps(out))
'''
reset_code = r'''
import json, time, warnings
warnings.filterwarnings("ignore")
import numpy as np, gymnasium as gym
import srenv  # noqa: F401  (registers the envs)
from srenv.envs import sucker_rod_v1
out = {}
for env_id in ("srenv/SuckerRod-v2", "srenv/SuckerRod-v1"):
    sucker_rod_v1._spec.cache_clear()  # each env builds its own family wells (v2 no longer fills v1's cache)
    env = gym.make(env_id, scenario="train"); env.reset(seed=3); env.step(np.array([1.0, 1.0], np.float32))
    t0 = time.process_time()
    for seed in range(11, 41):
        env.reset(seed=seed)
    out[f"reset_ms {env_id}"] = 1e3 * (time.process_time() - t0) / 30
print(json.dumps(out))
'''
kernel_code = r'''
import json
from srenv.tools.bench_kernel import kernel_figures
k = kernel_figures(repeats=5, strokes=10)
print(json.dumps({key: k[key] for key in ("us_per_step", "floor_us_per_step", "floor_ratio")}))
'''
trees = {"before": args.before, "after": args.after}
res = {k: [] for k in trees}
for r in range(reps):
    for side in (("before", "after") if r % 2 == 0 else ("after", "before")):
        mode = "fast" if side == "after" and args.fast_stepping else "plain"
        argv = [sys.executable, "-c", env_code, "0", mode, args.env_id,
                args.after_runner if side == "after" else "{}"] if args.env else \
            [sys.executable, "-c", code, str(strokes)]
        if args.kernel:
            argv = [sys.executable, "-c", kernel_code]
        if args.resets:
            argv = [sys.executable, "-c", reset_code]
        p = subprocess.run(argv, env={"PYTHONPATH": trees[side], "PATH": "/usr/bin"}, capture_output=True, text=True,
                           check=True, cwd=trees[side])
        res[side].append(json.loads(p.stdout.strip().splitlines()[-1]))
unit = "env steps/s" if args.env else ("" if args.kernel or args.resets else "strokes/s")
for case in res["before"][0]:
    ratios = [a[case] / b[case] for a, b in zip(res["after"], res["before"])]
    print(f"{case}: before {statistics.median(x[case] for x in res['before']):.3g} {unit}, after "
          f"{statistics.median(x[case] for x in res['after']):.3g}; after/before min {min(ratios):.3f} "
          f"median {statistics.median(ratios):.3f} max {max(ratios):.3f} (n={len(ratios)})")
