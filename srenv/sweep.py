"""``srenv sweep``: a parameter study (e.g. slip amplitude vs pulling velocity, paper Fig. 9) run on Ray.

::

    srenv sweep CONFIG --param surface.pull_velocity_m_s --values 0.05,0.5,1,2,3,5 --duration-s 60 \\
        [--set key=value ...] [--grid pump.reference_velocity_m_s=0.5,1,2 ...] \\
        [--case pump.upstroke_load_n=12090,pump.dynamic_load_n=8090 ...] \\
        [--workers N | --address HOST:PORT | --serial] --out results.csv [--plot fig9.png]

Parameter sets: the Cartesian product of the ``--grid`` lists, times the ``--case`` sets (each one fixed
combination), or the config alone. Each set is run at every ``--values`` entry of ``--param``, one
simulation per (set, value), every one from the same static start. ``--set`` overrides apply to all.

Metrics (CSV columns, unit in every name) are taken over the samples after ``--settle-fraction`` of the run
(default 0.3, the start transient excluded as in the pull-out acceptance check):
``plunger_stick_episodes`` (rests of >= 2 steps with the plunger velocity exactly 0), ``plunger_extra_
stick_episodes`` (beyond the two valve reversals per stroke; equal to the former in a pull-out),
``slip_amplitude_m`` (half peak-to-peak of du = u_B - u_A about its moving average over one natural period,
:func:`srenv.metrics.slip_amplitude_m`), polished-rod load peak, minimum and oscillation, and the DC/QP
effort. The critical value of each set (stdout JSON) is the lowest swept value from which on every case
has no extra plunger stick episode; it lies in (``last_sticking_...``, ``critical_...``]. The amplitude is
not used for it: a decaying transient leaves a small nonzero amplitude in any finite run.

Parallel runs: locally, each case runs in a pool of ``--workers`` processes (default: all cores) that
talk to this one through pipes only - no network listener, and the pool is terminated on any exit. A
local Ray is *not* started: Ray 2.x's gcs_server, raylet, workers and dashboard agent bind their gRPC
ports on all interfaces whatever ``_node_ip_address`` says (checked with ``ss -ltnp``), i.e. an
unauthenticated cluster reachable from the network. Ray is used only when ``--address`` names a running
cluster (one that its operator secures), whose nodes must have ``srenv`` installed; each case is then a
Ray task (1 CPU). Each case is a deterministic function of its config, so the CSV is identical whichever
backend ran it (tested); ``--serial`` runs in this process.
"""

from __future__ import annotations

import argparse
import csv
import itertools
import json
import math
import os
import sys
import time
import warnings
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from .errors import ConfigError

METRIC_COLUMNS = ("duration_s", "plunger_stick_episodes", "plunger_extra_stick_episodes", "slip_amplitude_m",
                  "peak_polished_rod_load_n", "min_polished_rod_load_n", "polished_rod_load_oscillation_pp_n",
                  "dc_iterations_per_step", "qp_steps")
SET_COLUMN = "parameter_set"
MAX_CASES = 10_000  # simulations of one study (rows of its CSV)
MAX_WORKERS = 256


@dataclass(frozen=True)
class Case:
    """One simulation of the study: parameter set ``set_index`` at swept value ``value``."""

    index: int
    set_index: int
    set_params: dict[str, Any]
    value: float
    raw: dict  # the full config mapping (overrides applied), shipped to the worker


# ----------------------------------------------------------------------------------------------- parsing
def parse_values(text: str, flag: str = "--values") -> list[float]:
    """'0.05,0.5,1' -> [0.05, 0.5, 1.0]; distinct finite numbers, at least one."""
    out: list[float] = []
    for item in text.split(","):
        try:
            x = float(item)
        except ValueError:
            raise ConfigError(flag, text, "comma-separated numbers, e.g. 0.05,0.5,1") from None
        if not math.isfinite(x):
            raise ConfigError(flag, text, "finite numbers")
        out.append(x)
    if len(set(out)) != len(out):
        raise ConfigError(flag, text, "distinct values")
    return out


def _split_key(item: str, flag: str) -> tuple[str, str]:
    if "=" not in item or not item.split("=", 1)[0].strip():
        raise ConfigError(flag, item, "KEY.PATH=VALUE")
    key, value = item.split("=", 1)
    return key.strip(), value.strip()


def parse_grid(items: list[str] | None) -> list[tuple[str, list[float]]]:
    """['pump.reference_velocity_m_s=0.5,1,2'] -> [('pump.reference_velocity_m_s', [0.5, 1.0, 2.0])]"""
    grid = []
    for item in items or []:
        key, values = _split_key(item, "--grid")
        grid.append((key, parse_values(values, f"--grid {key}")))
    return grid


def parse_case(items: list[str] | None) -> list[dict[str, float]]:
    """['a.b_m=1,c.d_n=2'] -> [{'a.b_m': 1.0, 'c.d_n': 2.0}]: one fixed parameter set per item."""
    cases = []
    for item in items or []:
        case = {}
        for pair in item.split(","):
            key, value = _split_key(pair, "--case")
            case[key] = parse_values(value, f"--case {key}")[0]
        cases.append(case)
    return cases


def parameter_sets(grid: list[tuple[str, list[float]]],
                   cases: list[dict[str, float]]) -> list[dict[str, float]]:
    """Cartesian product of the grid lists, times the explicit cases (a set of no parameters if neither)."""
    product = [dict(zip([k for k, _ in grid], combo, strict=True))
               for combo in itertools.product(*[v for _, v in grid])]
    return [{**g, **c} for g in product for c in (cases or [{}])]


def column_names(keys: list[str]) -> dict[str, str]:
    """CSV column of each config key: its last segment (which carries the unit), the full path if two
    keys share it."""
    last = [k.rsplit(".", 1)[-1] for k in keys]
    return {k: (s if last.count(s) == 1 else k) for k, s in zip(keys, last, strict=True)}


def build_cases(config: str, param: str, values: list[float], overrides: list[str] | None,
                sets: list[dict[str, float]]) -> list[Case]:
    """Every (set, value) case with its config mapping, each validated here: one clear error before any
    simulation runs."""
    from .config import apply_overrides, config_from_dict, read_raw

    if param in {k for s in sets for k in s}:
        raise ConfigError("--param", param, "a key not also given by --grid or --case")
    base = apply_overrides(read_raw(config), overrides)
    cases = []
    for si, params in enumerate(sets):
        for value in values:
            raw = apply_overrides(base, {**params, param: value})
            cfg = config_from_dict(raw)
            if param == "surface.pull_velocity_m_s" and cfg.surface.motion != "pullout":
                raise ConfigError("surface.motion", cfg.surface.motion,
                                  "'pullout' when sweeping surface.pull_velocity_m_s")
            cases.append(Case(len(cases), si, params, value, raw))
    return cases


# ----------------------------------------------------------------------------------------------- one case
def run_case(raw: dict, duration_s: float, settle_fraction: float) -> dict[str, float]:
    """Simulate one case and measure it (module docstring); runs in a Ray worker or in this process."""
    from . import metrics
    from .config import config_from_dict
    from .simulator import Simulator, concat_traces

    cfg = config_from_dict(raw)
    with warnings.catch_warnings():
        # the driver already warned once per set when it validated the cases
        warnings.simplefilter("ignore", UserWarning)
        sim = Simulator(cfg)
    if cfg.surface.motion == "pullout":
        results = [sim.run_duration(duration_s)]
        strokes_late = 0.0
        trace = results[0].trace
        t = trace["t_s"]
        late = t >= t[0] + settle_fraction * (t[-1] - t[0])
    else:
        n_strokes = max(1, round(duration_s * cfg.surface.spm / 60.0))
        results = sim.run_strokes(n_strokes)
        trace = concat_traces(results)
        first = math.ceil(settle_fraction * n_strokes - 1e-9)  # a window starting at a stroke boundary
        strokes_late = float(n_strokes - first)
        late = np.zeros(len(trace["t_s"]), dtype=bool)
        late[sum(r.n_steps for r in results[:first]):] = True
    t, load, vb = trace["t_s"][late], trace["polished_rod_load_n"][late], trace["pump_velocity_m_s"][late]
    du = (trace["polished_rod_position_m"] - trace["pump_position_m"])[late]  # u_B - u_A, positive down
    window_s = 1.0 / sim.f1_hz
    n_steps = sum(r.n_steps for r in results)
    return {
        "duration_s": float(sum(r.duration_s for r in results)),
        "plunger_stick_episodes": len(metrics.rest_episodes(vb)),
        "plunger_extra_stick_episodes": metrics.plunger_extra_stick_episodes(vb, strokes_late),
        "slip_amplitude_m": metrics.slip_amplitude_m(t, du, window_s),
        "peak_polished_rod_load_n": float(load.max()),
        "min_polished_rod_load_n": float(load.min()),
        "polished_rod_load_oscillation_pp_n": metrics.load_oscillation_pp_n(t, load, window_s),
        "dc_iterations_per_step": sum(r.dc_iterations for r in results) / n_steps,
        "qp_steps": sum(r.qp_steps for r in results),
    }


def _run_case_portable(raw: dict, duration_s: float, settle_fraction: float) -> dict[str, Any]:
    """run_case for another process: srenv's own errors come back as data, because their constructors
    take several arguments and so do not survive Ray's exception pickling."""
    from .errors import SolverFailure

    try:
        return run_case(raw, duration_s, settle_fraction)
    except ConfigError as exc:
        return {"error": "ConfigError", "args": [exc.field, exc.value, exc.expected]}
    except SolverFailure as exc:
        return {"error": "SolverFailure", "args": [exc.step, exc.time_s, exc.detail]}


def _unwrap(result: dict[str, Any]) -> dict[str, Any]:
    """Re-raise an error returned by :func:`_run_case_portable` as itself (the CLI reports it as for a
    serial run); pass a metrics row through."""
    from .errors import SolverFailure

    if "error" in result:
        raise {"ConfigError": ConfigError, "SolverFailure": SolverFailure}[result["error"]](*result["args"])
    return result


# ----------------------------------------------------------------------------------------------- backends
def run_serial(cases: list[Case], duration_s: float, settle_fraction: float,
               progress: bool = True) -> list[dict[str, float]]:
    from tqdm import tqdm

    return [run_case(c.raw, duration_s, settle_fraction)
            for c in tqdm(cases, desc="sweep", unit="case", disable=not progress)]


def _run_indexed(job: tuple[int, dict, float, float]) -> tuple[int, dict[str, Any]]:
    index, raw, duration_s, settle_fraction = job
    return index, _run_case_portable(raw, duration_s, settle_fraction)


def run_local(cases: list[Case], duration_s: float, settle_fraction: float, workers: int | None = None,
              progress: bool = True) -> list[dict[str, float]]:
    """Cases in a local process pool (spawned, so no state of this process is shared); results come back
    in case order. The pool is terminated on any exit, an error, Ctrl-C or SIGTERM included."""
    import multiprocessing

    from tqdm import tqdm

    n = min(workers or os.cpu_count() or 1, len(cases))
    pool = multiprocessing.get_context("spawn").Pool(n)
    try:
        out: list[dict[str, float] | None] = [None] * len(cases)
        jobs = [(c.index, c.raw, duration_s, settle_fraction) for c in cases]
        with tqdm(total=len(cases), desc="sweep", unit="case", disable=not progress) as bar:
            for i, result in pool.imap_unordered(_run_indexed, jobs):
                out[i] = _unwrap(result)
                bar.update()
        pool.close()
        return [r for r in out if r is not None]
    finally:
        pool.terminate()
        pool.join()


def run_ray(cases: list[Case], duration_s: float, settle_fraction: float, workers: int | None = None,
            address: str | None = None, progress: bool = True,
            timings: dict[str, float] | None = None) -> list[dict[str, float]]:
    """One Ray task per case on the running cluster at ``address``; results are returned in case order
    whatever order they finish in. ``timings`` (if given) receives ``ray_init_s``, the time spent
    connecting. No local Ray is ever started here (module docstring: it would listen on every interface)."""
    import logging

    import ray
    from tqdm import tqdm

    if not address:
        raise ConfigError("--address", address, "the address of a running Ray cluster (local runs use "
                          "run_local, which opens no network port)")
    started = False
    t0 = time.perf_counter()
    _check_reachable(address)
    if not ray.is_initialized():
        quiet = {"include_dashboard": False, "log_to_driver": False, "logging_level": logging.ERROR}
        try:
            ray.init(address=address, **quiet)
        except ConnectionError as exc:
            raise ConfigError("--address", address, f"the address of a running Ray cluster ({exc})") from None
        started = True
    if timings is not None:
        timings["ray_init_s"] = round(time.perf_counter() - t0, 3)
    try:
        task = ray.remote(num_cpus=1)(_run_case_portable)
        refs = [task.remote(c.raw, duration_s, settle_fraction) for c in cases]
        order = {ref: i for i, ref in enumerate(refs)}
        out: list[dict[str, float] | None] = [None] * len(refs)
        pending = list(refs)
        with tqdm(total=len(refs), desc="sweep", unit="case", disable=not progress) as bar:
            while pending:
                done, pending = ray.wait(pending, num_returns=1)
                for ref in done:
                    out[order[ref]] = _unwrap(ray.get(ref))
                    bar.update()
        return [r for r in out if r is not None]
    finally:
        if started:
            ray.shutdown()


def _check_reachable(address: str, timeout_s: float = 5.0) -> None:
    """Fail fast on a HOST:PORT nobody listens on: ray.init would retry for minutes before giving up.
    'auto', 'local' and other forms without a port are left to Ray."""
    import socket

    hostport = address.split("://", 1)[-1]
    host, _, port = hostport.rpartition(":")
    if not host or not port.isdigit():
        return
    try:
        socket.create_connection((host, int(port)), timeout=timeout_s).close()
    except OSError as exc:
        raise ConfigError("--address", address, f"the HOST:PORT of a running Ray cluster ({exc})") from None


# ----------------------------------------------------------------------------------------------- results
def result_rows(cases: list[Case], metrics_rows: list[dict[str, float]], param: str) -> list[dict[str, Any]]:
    keys = list(dict.fromkeys(k for c in cases for k in c.set_params))
    names = column_names(keys + [param])
    rows = []
    for c, m in zip(cases, metrics_rows, strict=True):
        row: dict[str, Any] = {SET_COLUMN: c.set_index}
        row.update({names[k]: c.set_params.get(k, "") for k in keys})
        row[names[param]] = c.value
        row.update(m)
        rows.append(row)
    return rows


def critical_values(rows: list[dict[str, Any]], value_column: str) -> list[dict[str, Any]]:
    """Per parameter set: the lowest swept value from which on no case has an extra plunger stick episode
    (None if the highest value still sticks), and the highest value that sticks (None if none does)."""
    out = []
    for si in sorted({r[SET_COLUMN] for r in rows}):
        mine = sorted((r for r in rows if r[SET_COLUMN] == si), key=lambda r: r[value_column])
        sticking = [i for i, r in enumerate(mine) if r["plunger_extra_stick_episodes"] > 0]
        last = sticking[-1] if sticking else -1
        params = {k: v for k, v in mine[0].items() if k not in METRIC_COLUMNS and k != value_column}
        critical = mine[last + 1][value_column] if last + 1 < len(mine) else None
        out.append({**params, f"critical_{value_column}": critical,
                    f"last_sticking_{value_column}": mine[last][value_column] if last >= 0 else None})
    return out


def write_csv(rows: list[dict[str, Any]], path: str) -> None:
    from .outputs import atomic_write

    columns = list(rows[0])

    def write(tmp: str) -> None:
        with open(tmp, "w", newline="") as fh:
            w = csv.DictWriter(fh, fieldnames=columns)
            w.writeheader()
            # repr keeps every float exactly (round-trips), so serial and Ray files compare byte for byte
            w.writerows({k: (repr(v) if isinstance(v, float) else v) for k, v in r.items()} for r in rows)
    atomic_write(path, write)


def plot(rows: list[dict[str, Any]], value_column: str, critical: list[dict[str, Any]], path: str,
         title: str) -> None:
    """Slip amplitude and extra stick episodes vs the swept value, one curve per parameter set."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from .outputs import atomic_write

    fig, (ax1, ax2) = plt.subplots(2, 1, figsize=(7.5, 7), sharex=True)
    for crit in critical:
        si = crit[SET_COLUMN]
        mine = sorted((r for r in rows if r[SET_COLUMN] == si), key=lambda r: r[value_column])
        x = [r[value_column] for r in mine]
        shown = {k: v for k, v in crit.items()
                 if k != SET_COLUMN and not k.startswith(("critical_", "last_sticking_"))}
        label = ", ".join(f"{k}={v:g}" for k, v in shown.items()) or "config"
        line, = ax1.plot(x, [1e3 * r["slip_amplitude_m"] for r in mine], "o-", ms=4, label=label)
        ax2.plot(x, [r["plunger_extra_stick_episodes"] for r in mine], "o-", ms=4, color=line.get_color())
        if crit[f"critical_{value_column}"] is not None:
            for ax in (ax1, ax2):
                ax.axvline(crit[f"critical_{value_column}"], color=line.get_color(), ls=":", lw=1)
    values = [r[value_column] for r in rows]
    if min(values) > 0 and max(values) / min(values) > 20:
        ax2.set_xscale("log")
    ax1.set_ylabel("slip amplitude of u_B - u_A (mm)")
    ax2.set_ylabel("extra plunger stick episodes")
    ax2.set_xlabel(value_column)
    ax1.set_title(title)
    ax1.legend(fontsize=7)
    for ax in (ax1, ax2):
        ax.grid(alpha=0.3)
    fig.tight_layout()
    atomic_write(path, lambda tmp: fig.savefig(tmp, dpi=110))
    plt.close(fig)


# ----------------------------------------------------------------------------------------------- CLI
def cmd_sweep(args: argparse.Namespace) -> int:
    from .config import MAX_RUN_SAMPLES, config_from_dict
    from .outputs import check_output_path
    from .simulator import Simulator

    check_output_path("--out", args.out, (".csv",))
    check_output_path("--plot", args.plot, (".png",))
    if not 0.0 <= args.settle_fraction < 1.0:
        raise ConfigError("--settle-fraction", args.settle_fraction, "a fraction of the run in [0, 1)")
    values = parse_values(args.values)
    sets = parameter_sets(parse_grid(args.grid), parse_case(args.case))
    if len(sets) * len(values) > MAX_CASES:
        raise ConfigError("--values", args.values, f"at most {MAX_CASES} cases in all (--values times the "
                          f"parameter sets; this study has {len(sets) * len(values)})")
    cases = build_cases(args.config, args.param, values, args.set, sets)
    dt = min(config_from_dict(c.raw).simulation.time_step_s for c in cases)
    if args.duration_s / dt > MAX_RUN_SAMPLES:
        raise ConfigError("--duration-s", args.duration_s, f"a duration in s of at most {MAX_RUN_SAMPLES} "
                          f"time steps per case (at most {MAX_RUN_SAMPLES * dt:g} s at {dt:g} s per step)")
    # one simulator per set, here in the driver: shows the convexity warning once and sizes the
    # moving-average window (one natural period) against the measured part of the run
    for si in range(len(sets)):
        sim = Simulator(config_from_dict(next(c for c in cases if c.set_index == si).raw))
        if (1.0 - args.settle_fraction) * args.duration_s < 2.0 / sim.f1_hz:
            raise ConfigError("--duration-s", args.duration_s,
                              f"a duration in s whose measured part spans two natural periods "
                              f"(2/f1 = {2.0 / sim.f1_hz:.3g} s) after --settle-fraction "
                              f"{args.settle_fraction}")
    progress = sys.stderr.isatty()
    t0 = time.perf_counter()
    timings: dict[str, float] = {}
    if args.serial:
        metric_rows = run_serial(cases, args.duration_s, args.settle_fraction, progress)
        backend = "serial"
    elif args.address:
        metric_rows = run_ray(cases, args.duration_s, args.settle_fraction, args.workers, args.address,
                              progress, timings)
        backend = "ray"
    else:
        metric_rows = run_local(cases, args.duration_s, args.settle_fraction, args.workers, progress)
        backend = "processes"
    wall = time.perf_counter() - t0
    value_column = column_names([args.param] + [k for s in sets for k in s])[args.param]
    rows = result_rows(cases, metric_rows, args.param)
    for row in rows:
        for key, v in row.items():
            if isinstance(v, float) and not math.isfinite(v):
                from .errors import NumericFailure

                raise NumericFailure(key, "a case's metric is not finite; check the config's magnitudes")
    crit = critical_values(rows, value_column)
    write_csv(rows, args.out)
    if args.plot:
        plot(rows, value_column, crit, args.plot, Path(args.config).stem)
    print(json.dumps({"cases": len(cases), "backend": backend,
                      "workers": 1 if args.serial else (args.workers or ("cluster" if args.address
                                                                          else os.cpu_count())),
                      "wall_time_s": round(wall, 3), **timings, "out": args.out, "plot": args.plot,
                      "sets": crit}, allow_nan=False))
    return 0


def add_parser(subparsers: argparse._SubParsersAction) -> None:
    from .cli_types import MAX_DURATION_S
    from .cli_types import bounded as _bounded
    from .cli_types import positive as _positive
    from .cli_types import positive_int as _positive_int

    s = subparsers.add_parser("sweep", help="parameter study in parallel on Ray (e.g. slip amplitude vs "
                              "pulling velocity)", description=__doc__.splitlines()[0])
    s.add_argument("config", help="well YAML path or shipped name")
    s.add_argument("--param", required=True, metavar="KEY.PATH", help="swept config field, e.g. "
                   "surface.pull_velocity_m_s")
    s.add_argument("--values", required=True, help="comma-separated values of --param (its unit)")
    s.add_argument("--duration-s", type=_bounded(_positive("--duration-s", "s"), "--duration-s", "s",
                                                 MAX_DURATION_S), default=60.0,
                   help="simulated time per case (s); harmonic runs take round(T*spm/60) strokes")
    s.add_argument("--settle-fraction", type=float, default=0.3,
                   help="fraction of each run excluded from the metrics as start transient (default 0.3)")
    s.add_argument("--set", action="append", metavar="KEY.PATH=VALUE", help="override for every case")
    s.add_argument("--grid", action="append", metavar="KEY.PATH=V1,V2,...",
                   help="parameter-set axis; several --grid form their Cartesian product")
    s.add_argument("--case", action="append", metavar="KEY.PATH=V[,KEY.PATH=V...]",
                   help="one explicit parameter set (repeatable)")
    s.add_argument("--workers", type=_positive_int("--workers", MAX_WORKERS),
                   help="local worker processes (default: all cores)")
    where = s.add_mutually_exclusive_group()
    where.add_argument("--address", help="address of a running Ray cluster (e.g. auto or HOST:PORT); "
                       "without it no Ray is started")
    where.add_argument("--serial", action="store_true", help="run in this process")
    s.add_argument("--out", required=True, help="CSV file, one row per case")
    s.add_argument("--plot", help="PNG: slip amplitude and stick episodes vs the swept value")
    s.set_defaults(func=cmd_sweep)
