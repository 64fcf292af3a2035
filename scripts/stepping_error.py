"""The stepping's error against simulating every stroke (docs/speed.md's tables): v1 as it is and v1 with
``fast_stepping=True``; or, with ``--version v2``, v2 as it is (fast stepping on) and v2 with it off.

    python scripts/stepping_error.py --wells 0 1 2 3 --hours 1 [--version v2] [--json out.json]
    python scripts/stepping_error.py --version v2 --follow-drift --exact-min 2 4 [--skip-v2-off]   # the options
    python scripts/stepping_error.py --version v2 --follow-drift --boundary-strokes 4 --skip-v2-off
    python scripts/stepping_error.py --version v2 --follow-drift --boundary-strokes 4 --skip-v2-off --draw-follows-pump

Wells are seeds of the benchmark's test scenario; each policy of srenv.tools.stepping_error runs one episode
per well three ways (every stroke exact and the two options) and the relative errors are printed.
"""
import argparse
import json
from pathlib import Path

from srenv.outputs import atomic_write
from srenv.task.boundary import BOUNDARY_STROKES_MAX
from srenv.tools.stepping_error import POLICIES, compare, summary

ap = argparse.ArgumentParser()
ap.add_argument("--wells", type=int, nargs="+", default=[0, 1, 2, 3])
ap.add_argument("--hours", type=float, default=1.0)
ap.add_argument("--policies", nargs="+", default=list(POLICIES), choices=POLICIES)
ap.add_argument("--version", default="v1", choices=("v1", "v2"))
ap.add_argument("--scenario", default="test", help="the wells' scenario (train wells for designing an option)")
ap.add_argument("--exact-min", type=int, nargs="*", default=[],
                help="v2 with IntervalRunner(exact_min=K) for each K (srenv/task/stepping.py)")
ap.add_argument("--follow-drift", action="store_true", help="v2 with IntervalRunner(follow_drift=True)")
ap.add_argument("--boundary-strokes", type=int, nargs="*", default=[],
                help="v2 with IntervalRunner(boundary_strokes=N) for each N (srenv/task/boundary.py)")
ap.add_argument("--draw-follows-pump", action="store_true",
                help="each option above also with IntervalRunner(draw_follows_pump=True) (srenv/task/pump_draw.py)")
ap.add_argument("--skip-v2-off", action="store_true", help="leave out v2 with fast_stepping=False")
ap.add_argument("--json")
args = ap.parse_args()
if any(k < 0 for k in args.exact_min):
    ap.error(f"--exact-min = {args.exact_min}: expected integers >= 0")
if args.json and Path(args.json).is_symlink():  # checked before the run, not after it
    ap.error(f"--json = {args.json!r}: expected a path that is not a symbolic link")
if any(not 0 <= n <= BOUNDARY_STROKES_MAX for n in args.boundary_strokes):
    ap.error(f"--boundary-strokes = {args.boundary_strokes}: expected integers in 0..{BOUNDARY_STROKES_MAX}")
options = ({"v1": {}, "fast_stepping": {"fast_stepping": True}} if args.version == "v1" else
           {"v2_fast_off": {"fast_stepping": False}, "v2": {}})
if args.skip_v2_off:
    options.pop("v2_fast_off", None)
if args.follow_drift:
    options["v2_drift"] = {"runner": {"follow_drift": True}}
for k in args.exact_min:
    options[f"v2_exact{k}"] = {"runner": {"exact_min": k}}
    if args.follow_drift:
        options[f"v2_exact{k}_drift"] = {"runner": {"exact_min": k, "follow_drift": True}}
for n in args.boundary_strokes:
    options[f"v2_boundary{n}"] = {"runner": {"boundary_strokes": n}}
    if args.follow_drift:
        options[f"v2_boundary{n}_drift"] = {"runner": {"boundary_strokes": n, "follow_drift": True}}
if args.draw_follows_pump:  # every option above (v2's default too) also with the fast-forward drawing as the pump
    for label, kw in list(options.items()):
        if label != "v2_fast_off":
            options[f"{label}_pump"] = {**kw, "runner": {**kw.get("runner", {}), "draw_follows_pump": True}}
rows = []
for policy in args.policies:
    for seed in args.wells:
        r = compare(policy, seed, args.hours, scenario=args.scenario, options=options, version=args.version)
        rows.append(r)
        for label in options:
            e = r[label]["relative_error"]
            worst = max(e, key=e.get)
            print(f"{policy:16s} well {seed:3d} {label:16s}: production {100 * e['production_m3']:7.3f} %, PPRL "
                  f"{100 * e['pprl_max_n']:7.3f} %, return {100 * e['return']:7.3f} %, worst {worst} "
                  f"{100 * e[worst]:.3f} %; exact strokes {r[label]['figures']['exact_strokes']} of "
                  f"{r['reference']['exact_strokes']}", flush=True)
for label in options:
    for key in ("production_m3", "pprl_max_n", "return"):
        worst = max(r[label]["relative_error"][key] for r in rows)
        print(f"{label}: largest {key} error over {len(rows)} episodes {100 * worst:.3f} %")
for (policy, label), s in summary(rows, list(options)).items():
    vs = "; ".join(f"vs {k[3:]}: {v['smaller']} smaller / {v['larger']} larger, geomean {v['geomean']:.2f}"
                   for k, v in s.items() if k.startswith("vs_"))
    print(f"{policy:16s} {label:20s}: within 0.5 % {s['within']}/{s['episodes']}, worst term median "
          f"{100 * s['median']:.2f} % largest {100 * s['largest']:.2f} %, exact strokes/step {s['exact_per_step']:.2f}"
          f"; {vs}")
if args.json:  # atomically, never through a symlink (srenv.outputs)
    atomic_write(args.json, lambda tmp: Path(tmp).write_text(json.dumps(rows, indent=1)))
