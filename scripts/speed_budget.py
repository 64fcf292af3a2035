"""Issue 25's measured budget: why 10x v1@91adcce's env steps per core cannot hold together with the 0.5 % bound.

    git archive 91adcce | (mkdir -p /tmp/b42-old && tar -x -C /tmp/b42-old)
    PYTHONPATH=. python scripts/speed_budget.py --old /tmp/b42-old --repeats 3 --out /tmp/speed_budget.json

One run, for each of the acceptance's two actions ([1, 1] full speed, [-0.6, 1] the VSD minimum):
- v1@91adcce's, the newest env's and this tree's v1 env steps per CPU second on the acceptance's own protocol (its
  loop, below: v1@91adcce in the ``--old`` tree; each rate its own process, the trees alternating ``--repeats``
  rounds, the order reversed every other round; the acceptance reads the best of each side);
- the newest env's CPU split on that protocol (scripts/step_profile.py: the two resets, the steps' compiled kernel
  and their Python, the exact strokes a step);
- the floor program's cost of those exact strokes (srenv/numerics/floor.py on each protocol well's own mesh and
  time step, times the time steps of every exact stroke the protocol simulated);
then the budget (``budget``): a 10x step may cost 1 / (10 x v1's rate), less the resets' share of the protocol
(2 resets / 24 steps); what is left, over the floor's cost of one exact stroke, is the most exact strokes a step a
10x env could simulate with its kernel AT the floor and no Python. Beside it, the newest env's measured strokes a
step and the errors docs/speed.md §2g measured for such stepping (``CITED``: not re-measured here). Last, v1's
benchmark (``benchmark_env_steps``): the env steps configs/benchmark/v1.yaml plays, over v1's rate on 2 cores
(v1@91adcce's, and this tree's, which the benchmark runs), against the 20-min goal.
The JSON (``--out``, checked before the work, written atomically) holds every figure; docs/speed.md explains it.
"""

from __future__ import annotations

import json
import math
import os
import statistics
import subprocess
import sys
import time
from pathlib import Path

from srenv.cli_types import OneLineParser
from srenv.declarations import Number
from srenv.errors import ConfigError

TOOL = "speed_budget.py"
REPO = Path(__file__).resolve().parents[1]
N_TIMESTEPS = Number("n_timesteps", int, hi=10**9)  # a training config's, read as data
FLAGS = {"--repeats": Number("--repeats", int, hi=20, why="wall time: ~10-20 s of processes a round")}
ACTIONS = {"full_speed": 1.0, "vsd_minimum": -0.6}  # the acceptance's a0 of [a0, 1]
SPEEDUP = 10.0  # the goal over v1@91adcce
PROTOCOL_STEPS, PROTOCOL_RESETS = 24, 2  # seeds 11 and 12, 12 steps each, in the acceptance's timed loop
V1_ID = "srenv/SuckerRod-v1"
V1_HERE = f"{V1_ID} (this tree)"  # what `python -m agents benchmark configs/benchmark/v1.yaml` runs
CORES = 2  # the benchmark's machine (configs/benchmark/v1.yaml: workers 2)
# docs/speed.md §2g (helper a25): worst of production, PPRL and every reward term against every stroke exact, test
# wells 0-7, 2-h episodes; median / largest over the 8 wells, %; and the exact strokes it took a step (all policies).
CITED = {
    "source": "docs/speed.md §2g, `python scripts/stepping_error.py --version v2 --wells 0 1 2 3 4 5 6 7 --hours 2 "
              "--follow-drift --exact-min 4`",
    "stepping": {
        "v2 default": {"exact_strokes_per_step": 0.62, "full_speed_pct": [5.59, 25.5], "vsd_minimum_pct": [0.51, 15.4],
                       "episodes_within_0.5_pct_of_24": 4},
        "v1's stepping": {"exact_strokes_per_step": 2.35, "full_speed_pct": [4.46, 123.0],
                          "vsd_minimum_pct": [0.10, 1.31], "episodes_within_0.5_pct_of_24": 6},
        "v2 + exact_min=4 + follow_drift": {"exact_strokes_per_step": 4.00, "full_speed_pct": [2.87, 69.9],
                                            "vsd_minimum_pct": [0.08, 1.01], "episodes_within_0.5_pct_of_24": 8},
        "every stroke exact (the reference)": {"exact_strokes_per_step": 34.1, "full_speed_pct": [0.0, 0.0],
                                               "vsd_minimum_pct": [0.0, 0.0], "episodes_within_0.5_pct_of_24": 24}},
    # §2g's stroke-variability table: the exact strokes an interval needs for 0.5 % (K direct)
    "strokes_needed_per_step": {"full_speed": "56-60 of an interval's 60 on six of eight wells (drift, regime changes, "
                                              "the peak load's maximum over strokes): every stroke",
                                "vsd_minimum": "1 on scatter alone; the best measured scheme (4 a step) within "
                                               "0.5 % on 7 of 8 wells"},
}
# the acceptance's timed loop (acceptance/speed), verbatim but for the action and a JSON line
RATE_CODE = r'''
import json, sys, time, warnings
warnings.filterwarnings("ignore")
import numpy as np, gymnasium as gym, srenv  # noqa
ids = sorted(i for i in gym.registry if i.startswith("srenv/SuckerRod-v"))
env_id = ids[-1] if sys.argv[1] == "newest" else "srenv/SuckerRod-v1"
a = np.array([float(sys.argv[2]), 1.0], np.float32)
env = gym.make(env_id, scenario="train"); env.reset(seed=3); env.step(a)   # compile and warm up
n, t0 = 0, time.process_time()
for seed in (11, 12):
    env.reset(seed=seed)
    for _ in range(12):
        env.step(a); n += 1
print(json.dumps({"env_id": env_id, "rate": n / (time.process_time() - t0)}))
'''


def budget(v1_rate: float, reset_ms: float, floor_stroke_ms: float, speedup: float = SPEEDUP,
           steps: int = PROTOCOL_STEPS, resets: int = PROTOCOL_RESETS) -> dict:
    """The most exact strokes a step an env `speedup` x v1's protocol rate (env steps per CPU s, resets included)
    could simulate at `floor_stroke_ms` a stroke, once `resets` resets of `reset_ms` each are paid out of the
    protocol's `steps` steps: 0 when the resets alone take the budget."""
    step_ms = 1e3 / (speedup * v1_rate)
    resets_ms = resets * reset_ms / steps
    left_ms = step_ms - resets_ms
    return {"step_budget_ms": step_ms, "resets_ms_per_step": resets_ms, "left_ms_per_step": left_ms,
            "floor_ms_per_exact_stroke": floor_stroke_ms,
            "max_exact_strokes_per_step": max(left_ms, 0.0) / floor_stroke_ms}


def rate_multiple(v1_rate: float, reset_ms: float, stroke_ms: float, strokes_per_step: float,
                  steps: int = PROTOCOL_STEPS, resets: int = PROTOCOL_RESETS) -> float:
    """The protocol rate over v1's of an env whose step costs only `strokes_per_step` exact strokes of `stroke_ms`
    and whose reset costs `reset_ms`: the other side of ``budget`` (the frontier of strokes against speed)."""
    protocol_ms = steps * strokes_per_step * stroke_ms + resets * reset_ms
    return steps * 1e3 / protocol_ms / v1_rate


def benchmark_env_steps(cfg: dict, n_timesteps: dict[str, int], tuning_candidates: int,
                        steps_per_episode: int) -> dict[str, int]:
    """Env steps a benchmark config plays, by stage: tuning (`tuning_candidates` baseline settings, each on every
    tuning seed), training (n_timesteps of each run's config x its seeds; a teacher-student run's teachers are its
    seeds), distillation (DAgger: iterations x episodes a student seed), validation (every model on every validation
    seed), test (the installed and configured baselines, every model and every ensemble on every test seed). Not
    counted: what a baseline simulates to plan (the oracle) - a lower bound."""
    runs = cfg["agents"]["runs"]
    models = sum(len(r["seeds"]) for r in runs.values())
    ensembles = sum(bool(r.get("ensemble")) for r in runs.values())
    baselines = 1 + len(cfg["baselines"])  # "installed" is always played
    ep = steps_per_episode
    out = {"tuning": tuning_candidates * len(cfg["tuning"]["seeds"]) * ep,
           "training": sum(r.get("overrides", {}).get("n_timesteps", n_timesteps[r["config"]]) * len(r["seeds"])
                           for r in runs.values()),
           "distillation": sum(r["teacher"]["iterations"] * r["teacher"]["episodes"] * len(r["seeds"]) * ep
                               for r in runs.values() if "teacher" in r),
           "validation": models * len(cfg["validation"]["seeds"]) * ep,
           "test": (baselines + models + ensembles) * len(cfg["test"]["seeds"]) * ep}
    out["total"] = sum(out.values())
    return out


def _child(code: list[str], tree: Path) -> dict:
    env = dict(os.environ, PYTHONPATH=str(tree))
    p = subprocess.run([sys.executable, *code], capture_output=True, text=True, env=env, cwd=tree, timeout=1800,
                       check=False)
    if p.returncode:
        raise RuntimeError(f"{tree}: {' '.join(code)[:60]} failed: {p.stderr.strip()[-300:]}")
    return json.loads(p.stdout.strip().splitlines()[-1])


def floor_costs(env_id: str, a0: float) -> dict:
    """The protocol at action [a0, 1] replayed (deterministic: the timed runs' strokes), every exact stroke's time
    steps kept, and the floor program timed on each protocol well's own mesh and time step."""
    import warnings

    warnings.filterwarnings("ignore")
    import gymnasium as gym
    import numpy as np

    import srenv  # noqa: F401  (registers the envs)
    from srenv.simulation.simulator import Simulator
    from srenv.tools.bench_kernel import FloorRun

    kept: list[int] = []
    recording = [False]
    run_stroke = Simulator.run_stroke

    def counted(self, *a, **k):
        r = run_stroke(self, *a, **k)
        if recording[0]:
            kept.append(r.n_steps)
        return r

    Simulator.run_stroke = counted
    a = np.array([a0, 1.0], np.float32)
    env = gym.make(env_id, scenario="train")
    env.reset(seed=3)
    env.step(a)
    wells = []
    for seed in (11, 12):
        well_id = env.reset(seed=seed)[1]["well_id"]
        kept.clear()
        recording[0], exact, every = True, 0, 0.0
        for _ in range(PROTOCOL_STEPS // 2):
            info = env.step(a)[4]
            exact, every = exact + info["exact_strokes"], every + info["strokes"]
        recording[0] = False
        sim = env.unwrapped.sim
        us = floor_us_per_step(FloorRun(sim))
        wells.append({"seed": seed, "well_id": well_id, "nodes": sim.mesh.n_nodes,
                      "time_step_s": sim.cfg.simulation.time_step_s, "exact_strokes": exact, "strokes_run": len(kept),
                      "strokes": every,
                      "time_steps_per_exact_stroke": sum(kept) / max(len(kept), 1), "floor_us_per_time_step": us,
                      "floor_ms_of_its_exact_strokes": us * sum(kept) / 1e3})
    strokes = sum(w["strokes_run"] for w in wells)
    return {"wells": wells, "exact_strokes_per_step": sum(w["exact_strokes"] for w in wells) / PROTOCOL_STEPS,
            "strokes_per_step": sum(w["strokes"] for w in wells) / PROTOCOL_STEPS,
            "floor_ms_per_exact_stroke": sum(w["floor_ms_of_its_exact_strokes"] for w in wells) / max(strokes, 1)}


def floor_us_per_step(floor, repeats: int = 5) -> float:
    """CPU µs per time step of the floor program (median of `repeats` timings of >= 50,000 time steps)."""
    floor.stroke()  # compiled (numba's cache) and warm
    k = max(2, math.ceil(50_000 / floor.n_steps))
    out = []
    for _ in range(repeats):
        t0 = time.process_time()
        for _ in range(k):
            floor.stroke()
        out.append((time.process_time() - t0) / (k * floor.n_steps))
    return 1e6 * statistics.median(out)


def measure(old: Path, env_id: str, a0: float, repeats: int) -> dict:
    """Rates of the trees alternating (the order reversed every other round), the CPU split of the newest env and of
    this tree's v1 each round, then the floor's cost of each one's protocol strokes."""
    rates: dict[str, list[float]] = {"v1@91adcce": [], env_id: [], V1_HERE: []}
    splits: dict[str, list[dict]] = {env_id: [], V1_ID: []}
    for r in range(repeats):
        sides = [("v1@91adcce", old, "v1"), (env_id, REPO, "newest"), (V1_HERE, REPO, "v1")]
        for name, tree, which in sides[::(-1 if r % 2 else 1)]:
            rates[name].append(_child(["-c", RATE_CODE, which, str(a0)], tree)["rate"])
        for e, rounds in splits.items():
            rounds.append(_child(["scripts/step_profile.py", "--env", e, "--action", str(a0)], REPO))
    floor = "import sys, json; sys.path.insert(0, 'scripts'); import speed_budget as m; " \
            "print(json.dumps(m.floor_costs(sys.argv[1], float(sys.argv[2]))))"
    both = {e: {"split": _split(rounds), "floor": _child(["-c", floor, e, str(a0)], REPO)}
            for e, rounds in splits.items()}
    return {"rates": rates, **both[env_id], "v1_here": both[V1_ID]}


def _split(rounds: list[dict]) -> dict:
    """scripts/step_profile.py's rounds (medians): a reset's ms, a step's kernel and Python ms, its exact strokes."""
    med = {k: statistics.median(s[k] for s in rounds) for k in
           ("reset_ms", "reset_kernel_ms", "steps_ms", "steps_kernel_ms", "exact_strokes_per_step")}
    split = {"reset_ms_each": med["reset_ms"] / PROTOCOL_RESETS, "reset_kernel_ms_each": med["reset_kernel_ms"] / PROTOCOL_RESETS,
             "steps_kernel_ms_per_step": med["steps_kernel_ms"] / PROTOCOL_STEPS,
             "steps_python_ms_per_step": (med["steps_ms"] - med["steps_kernel_ms"]) / PROTOCOL_STEPS,
             "exact_strokes_per_step": med["exact_strokes_per_step"], "rounds": rounds}
    per = split["exact_strokes_per_step"]
    split["kernel_ms_per_exact_stroke"] = split["steps_kernel_ms_per_step"] / per if per else None
    return split


def summarise(label: str, m: dict, env_id: str) -> dict:
    """The per-action figures: the rates (best, as the acceptance reads them, and the range); the budget with the
    stroke at today's kernel, at the issue's kernel goal (1.5x the floor), at the floor (the headline), and the most
    generous reading (v1's slowest round, each reset only its warm-up stroke at the floor); the frontier: the rate a
    step of K exact strokes at the floor and nothing else could reach, over v1's."""
    v1, new = m["rates"]["v1@91adcce"], m["rates"][env_id]
    fs, reset = m["floor"]["floor_ms_per_exact_stroke"], m["split"]["reset_ms_each"]
    kernel = m["split"]["kernel_ms_per_exact_stroke"]
    out = {"v1_rate_best": max(v1), "v1_rate_min_median_max": [min(v1), statistics.median(v1), max(v1)],
           "new_rate_best": max(new), "new_rate_min_median_max": [min(new), statistics.median(new), max(new)],
           "new_over_v1_best": max(new) / max(v1), "v1_here_rate_best": max(m["rates"][V1_HERE]),
           "budget": budget(max(v1), reset, fs),
           "budget_kernel_today": budget(max(v1), reset, kernel) if kernel else None,
           "budget_kernel_goal": budget(max(v1), reset, 1.5 * fs),
           "budget_generous": budget(min(v1), fs, fs),
           "new_exact_strokes_per_step": m["split"]["exact_strokes_per_step"],
           "every_stroke_per_step": m["floor"]["strokes_per_step"]}
    ks = {"new env's": out["new_exact_strokes_per_step"], "1 a step": 1.0, "4 a step (exact_min=4)": 4.0,
          "every stroke": out["every_stroke_per_step"]}
    out["frontier_at_floor"] = {k: {"strokes_per_step": x, "over_v1_resets_today": rate_multiple(max(v1), reset, fs, x),
                                    "over_v1_resets_at_floor": rate_multiple(max(v1), fs, fs, x)}
                                for k, x in ks.items()}
    if "v1_here" in m:  # this tree's v1 with its exact strokes at the floor and no Python: env steps per CPU s
        sp, f1 = m["v1_here"]["split"], m["v1_here"]["floor"]["floor_ms_per_exact_stroke"]
        out["v1_here_at_floor_rate"] = {
            "resets_today": rate_multiple(1.0, sp["reset_ms_each"], f1, sp["exact_strokes_per_step"]),
            "resets_at_floor": rate_multiple(1.0, f1, f1, sp["exact_strokes_per_step"])}
    return {"action": [ACTIONS[label], 1.0], **out, **m}


def benchmark_bound(rates: dict[str, float]) -> dict:
    """v1's benchmark: its env steps (configs/benchmark/v1.yaml; the tuning candidates from the run's record,
    docs/benchmark.json) over each tree's best v1 protocol rate on `CORES` cores with a free learner; the rate per
    core the 20-min goal needs; the recorded run's env steps per second of its stages (learner included)."""
    import gymnasium as gym

    import srenv  # noqa: F401
    from agents.benchmark.config import load_benchmark_config
    from srenv.safe_yaml import load_yaml_file

    cfg = load_benchmark_config(REPO / "configs/benchmark/v1.yaml")
    n_timesteps = {}
    for r in cfg["agents"]["runs"].values():
        train = load_yaml_file(REPO / r["config"], "training config")
        n_timesteps[r["config"]] = N_TIMESTEPS.check(train.get("n_timesteps"), f"{r['config']}: n_timesteps")
    record = json.loads((REPO / "docs/benchmark.json").read_text())
    wall = record.get("wall_time_s")
    if record.get("env_id") != cfg["env_id"] or not isinstance(record.get("tuning_history"), dict) \
            or not isinstance(wall, dict):
        raise ConfigError("docs/benchmark.json", record.get("env_id"), f"the record of a {cfg['env_id']} run")
    candidates = sum(len(v) for v in record["tuning_history"].values() if isinstance(v, list))
    kw = gym.spec(cfg["env_id"]).kwargs
    per_episode = round(kw["episode_hours"] * 3600.0 / kw["interval_s"])
    steps = benchmark_env_steps(cfg, n_timesteps, candidates, per_episode)
    goal_s = 1200.0
    recorded = {"training": (steps["training"] + steps["distillation"]) / wall["training"],
                "test": steps["test"] / wall["test"], "total": steps["total"] / wall["total"]}
    return {"env_steps": steps, "tuning_candidates": candidates, "steps_per_episode": per_episode, "cores": CORES,
            "goal_s": goal_s, "needed_rate_per_core": steps["total"] / (goal_s * CORES),
            "lower_bound_s": {k: steps["total"] / (CORES * x) for k, x in rates.items()},
            "lower_bound_training_s": {k: steps["training"] / (CORES * x) for k, x in rates.items()},
            "v1_rates_per_core": rates, "recorded_wall_time_s": wall,
            "recorded_env_steps_per_s_a_stage_2_cores": recorded}


def report_lines(res: dict) -> list[str]:
    """The budget in plain lines (the JSON holds every figure)."""
    lines, e = [], res["env_id"]
    for label, r in res["actions"].items():
        b, g, sp, fl = r["budget"], r["budget_generous"], r["split"], r["floor"]
        wells = ", ".join(f"{w['well_id']} {w['nodes']} nodes {w['time_steps_per_exact_stroke']:.0f} steps"
                          for w in fl["wells"])
        lines.append(f"{label}: v1@91adcce {r['v1_rate_best']:.0f} env steps/CPU s, {e} {r['new_rate_best']:.0f} "
                     f"({r['new_over_v1_best']:.2f}x; best of {res['repeats']}, as the acceptance reads them)")
        lines.append(f"  {e} split: reset {sp['reset_ms_each']:.2f} ms each; a step: kernel "
                     f"{sp['steps_kernel_ms_per_step']:.3f} ms + Python {sp['steps_python_ms_per_step']:.3f} ms; "
                     f"{sp['exact_strokes_per_step']:.2f} exact strokes a step")
        lines.append(f"  floor: {fl['floor_ms_per_exact_stroke']:.3f} ms an exact stroke ({wells})")
        lines.append(f"  10x budget: {b['step_budget_ms']:.3f} ms a step - resets {b['resets_ms_per_step']:.3f} = "
                     f"{b['left_ms_per_step']:.3f} ms -> at most {b['max_exact_strokes_per_step']:.2f} exact strokes "
                     f"a step at the floor with no Python (most generous: {g['max_exact_strokes_per_step']:.2f}); "
                     f"{e} simulates {r['new_exact_strokes_per_step']:.2f}, every stroke {r['every_stroke_per_step']:.1f}")
        today = r["budget_kernel_today"] or {"max_exact_strokes_per_step": math.nan}  # None: no exact stroke ran
        lines.append(f"  strokes a 10x step admits with today's kernel {today['max_exact_strokes_per_step']:.2f}, "
                     f"at 1.5x the floor {r['budget_kernel_goal']['max_exact_strokes_per_step']:.2f}")
        lines.append("  frontier at the floor, no Python (x v1; resets today / at the floor): " + "; ".join(
            f"{k} {f['strokes_per_step']:.2f}: {f['over_v1_resets_today']:.1f}x / {f['over_v1_resets_at_floor']:.1f}x"
            for k, f in r["frontier_at_floor"].items()))
    bb = res["benchmark"]
    lines.append(f"v1 benchmark: {bb['env_steps']['total']:,} env steps ({bb['env_steps']['training']:,} training); "
                 f"the {bb['goal_s']:.0f} s goal needs {bb['needed_rate_per_core']:.0f} env steps/s a core on "
                 f"{bb['cores']} cores with a free learner")
    for k, x in bb["v1_rates_per_core"].items():
        lines.append(f"  at {k}: {x:.0f} env steps/CPU s a core -> at least {bb['lower_bound_s'][k]:.0f} s")
    return lines


def main(argv: list[str] | None = None) -> int:
    ap = OneLineParser(prog=TOOL, description=__doc__.splitlines()[0])
    ap.tool = TOOL
    ap.add_argument("--old", required=True, type=Path, help="a tree of commit 91adcce (git archive or worktree)")
    ap.add_argument("--repeats", type=FLAGS["--repeats"].parse, default=3, help="rounds of old/new rate processes")
    ap.add_argument("--out", default=None, help="the JSON of every figure (.json)")
    args = ap.parse_args(argv)
    if not (args.old / "srenv" / "__init__.py").is_file() or not (args.old / "srenv" / "envs").is_dir():
        ap.error(f"--old = {str(args.old)!r}: expected a tree of commit 91adcce (a directory holding srenv/)")
    from srenv.outputs import atomic_write, check_outputs

    try:
        check_outputs({"--out": (args.out, (".json",))})
    except ConfigError as exc:
        ap.error(f"{exc.field} = {exc.value!r}: expected {exc.expected}")
    from srenv.tools.bench_speed import task_env_ids

    env_id = task_env_ids()[-1]
    res: dict = {"started_utc": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()), "load_avg_start": os.getloadavg(),
                 "old": str(args.old), "env_id": env_id, "repeats": args.repeats, "speedup_goal": SPEEDUP,
                 "actions": {}}
    for label, a0 in ACTIONS.items():
        res["actions"][label] = summarise(label, measure(args.old, env_id, a0, args.repeats), env_id)
    rates = {k: max(r[key] for r in res["actions"].values())
             for k, key in (("v1@91adcce", "v1_rate_best"), (V1_HERE, "v1_here_rate_best"))}
    for label, r in res["actions"].items():  # the most v1's stepping could give: its strokes at the floor only
        rates[f"{V1_HERE} at the floor, no Python, {label}"] = r["v1_here_at_floor_rate"]["resets_today"]
    res["benchmark"] = benchmark_bound(rates)
    res["cited_errors"] = CITED
    res["load_avg_end"] = os.getloadavg()
    print("\n".join(report_lines(res)))
    if args.out:
        text = json.dumps(res, indent=1)
        atomic_write(args.out, lambda tmp: Path(tmp).write_text(text + "\n"))
    return 0


if __name__ == "__main__":
    sys.exit(main())
