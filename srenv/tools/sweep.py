"""``srenv sweep``: a parameter study (e.g. slip amplitude vs pulling velocity, paper Fig. 9) in parallel.

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
:func:`srenv.analysis.metrics.slip_amplitude_m`), polished-rod load peak, minimum and oscillation, and the DC/QP
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
import json
import math
import os
import sys
import time
from pathlib import Path
from typing import Any

from ..errors import ConfigError
from .sweep_cases import (
    MAX_CASES,
    METRIC_COLUMNS,
    SET_COLUMN,
    Case,
    build_cases,
    column_names,
    parameter_sets,
    parse_case,
    parse_grid,
    parse_values,
)
from .sweep_runners import (  # noqa: F401
    _check_reachable,
    _run_case_portable,
    _run_indexed,
    _unwrap,
    run_case,
    run_local,
    run_ray,
    run_serial,
)


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
    from ..outputs import atomic_write

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

    from ..outputs import atomic_write

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
    from ..config import MAX_RUN_SAMPLES, config_from_dict
    from ..outputs import check_outputs
    from ..simulation.simulator import Simulator

    check_outputs({"--out": (args.out, (".csv",)), "--plot": (args.plot, (".png",))})
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
                from ..errors import NumericFailure

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
    from ..declarations import add_number

    s = subparsers.add_parser("sweep", help="parameter study in parallel: local processes, or Ray with --address (e.g. "
                              "slip amplitude vs pulling velocity)", description=__doc__.splitlines()[0])
    s.add_argument("config", help="well YAML path or shipped name")
    s.add_argument("--param", required=True, metavar="KEY.PATH", help="swept config field, e.g. "
                   "surface.pull_velocity_m_s")
    s.add_argument("--values", required=True, help="comma-separated values of --param (its unit)")
    add_number(s, "sweep", "--duration-s", default=60.0,
               help="simulated time per case (s); harmonic runs take round(T*spm/60) strokes")
    add_number(s, "sweep", "--settle-fraction", default=0.3,
               help="fraction of each run excluded from the metrics as start transient (default 0.3)")
    s.add_argument("--set", action="append", metavar="KEY.PATH=VALUE", help="override for every case")
    s.add_argument("--grid", action="append", metavar="KEY.PATH=V1,V2,...",
                   help="parameter-set axis; several --grid form their Cartesian product")
    s.add_argument("--case", action="append", metavar="KEY.PATH=V[,KEY.PATH=V...]",
                   help="one explicit parameter set (repeatable)")
    add_number(s, "sweep", "--workers", help="local worker processes (default: all cores)")
    where = s.add_mutually_exclusive_group()
    where.add_argument("--address", help="address of a running Ray cluster (e.g. auto or HOST:PORT); "
                       "without it no Ray is started")
    where.add_argument("--serial", action="store_true", help="run in this process")
    s.add_argument("--out", required=True, help="CSV file, one row per case")
    s.add_argument("--plot", help="PNG: slip amplitude and stick episodes vs the swept value")
    s.set_defaults(func=cmd_sweep)

