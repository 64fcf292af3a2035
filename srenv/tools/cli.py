"""Command line: ``srenv simulate | sweep | diagnose | fit | validate | cards | classify | bench | config-doc``.

Bad input (config or flags) prints one line naming the field, the value and the expected unit, exits with
status 2, and leaves no output file behind (outputs are written to a temporary file and renamed).
"""

from __future__ import annotations

import argparse
import math
import signal
import sys

import numpy as np

from ..cli_types import EXIT_BAD_INPUT, command_parser
from ..declarations import MAX_STROKES, OUTPUTS, add_number  # noqa: F401  (MAX_STROKES: re-exported)
from ..errors import ConfigError, NumericFailure, SolverFailure
from ..interrupts import EXIT_INTERRUPTED, raise_on_sigterm
from ..outputs import atomic_write_all, check_outputs, json_line
from .finite import check_finite

EXIT_SOLVER = 3
DEFAULT_STROKES = 3
# flags that only some surface motions use: with another motion they would be ignored without a word
MOTION_FLAGS = {
    "spm": ("harmonic", "conventional", "beam_unit"),         # a measured card runs at its own period
    "stroke_length_m": ("harmonic",),             # a conventional unit's crank hole / the card set the stroke
    "pull_velocity_m_s": ("pullout",),
    "strokes": ("harmonic", "conventional", "beam_unit", "measured"),  # a pull-out runs for --duration-s
}


# --out-units field: positions in in and loads in lbf, named in a unit row under the header that the card readers
# take (surface_unit.measured_motion.read_card_csv); the velocities stay m/s (no field unit: an empty cell)
FIELD_COLUMN_UNITS = {"t_s": "s", "polished_rod_position_m": "in", "polished_rod_load_n": "lbf",
                      "pump_position_m": "in", "pump_load_n": "lbf"}


def trace_csv_writer(trace: dict, units: str = "si"):
    from ..field_units import from_si
    from ..simulation.simulator import TRACE_COLUMNS

    cols = [c for c in TRACE_COLUMNS if c in trace]
    field = {c: FIELD_COLUMN_UNITS[c] for c in cols if c in FIELD_COLUMN_UNITS} if units == "field" else {}
    data = np.column_stack([from_si(trace[c], field[c]) if c in field else trace[c] for c in cols])
    header = ",".join(cols) + ("\n" + ",".join(field.get(c, "") for c in cols) if field else "")

    def write(tmp: str) -> None:
        np.savetxt(tmp, data, delimiter=",", header=header, comments="", fmt="%.12g")
    return write


def write_trace_csv(trace: dict, path: str) -> None:
    atomic_write_all([(path, trace_csv_writer(trace))])


def check_motion_flags(args: argparse.Namespace, motion: str) -> None:
    """Refuse a flag the chosen surface motion does not use (it would be silently ignored)."""
    for attr, motions in MOTION_FLAGS.items():
        value = getattr(args, attr, None)
        if value is not None and motion not in motions:
            raise ConfigError("--" + attr.replace("_", "-"), value,
                              f"no such flag with surface.motion = {motion} (it would be ignored; it applies to "
                              f"{' and '.join(motions)} motion)")


def cmd_simulate(args: argparse.Namespace) -> int:
    from ..analysis.stroke_summary import summarize
    from ..config import check_run_samples, load_config, steps_per_stroke
    from ..config_checks import run_spm
    from ..simulation.simulator import Simulator, concat_traces

    overrides = list(args.set or [])
    if args.spm is not None:
        overrides.append(f"surface.spm={args.spm}")
    if args.stroke_length_m is not None:
        overrides.append(f"surface.stroke_length_m={args.stroke_length_m}")
    if args.pull_velocity_m_s is not None:
        overrides.append(f"surface.pull_velocity_m_s={args.pull_velocity_m_s}")
    if args.qp_solver is not None:
        overrides.append(f"simulation.qp_solver={args.qp_solver}")
    check_outputs({flag: (getattr(args, flag[2:]), sfx) for flag, sfx in OUTPUTS["simulate"].items()})
    cfg = load_config(args.config, overrides)
    check_motion_flags(args, cfg.surface.motion)
    # the run's size, before any allocation: strokes x steps per stroke (at a measured card's own
    # period), or duration / time step
    if cfg.surface.motion == "pullout":
        duration = args.duration_s if args.duration_s is not None else 60.0
        check_run_samples(math.ceil(duration / cfg.simulation.time_step_s), "--duration-s", duration)
    else:
        spm = run_spm(cfg)
        n_strokes = args.strokes or DEFAULT_STROKES
        if args.duration_s is not None:
            n_strokes = max(1, round(args.duration_s * spm / 60.0))
        check_run_samples(n_strokes * steps_per_stroke(cfg, spm),
                          "--duration-s" if args.duration_s is not None else "--strokes",
                          args.duration_s if args.duration_s is not None else n_strokes)
    sim = Simulator(cfg, always_qp=True if args.always_qp else None)
    if cfg.surface.motion == "pullout":
        results = [sim.run_duration(duration)]
    else:
        results = sim.run_strokes(n_strokes)
    trace = concat_traces(results)
    if cfg.surface.motion == "pullout":
        summary = pullout_summary(sim, results[0])
    else:
        summary = summarize(sim, results)
    summary["natural_frequency_hz"] = sim.f1_hz
    summary["energy_residual_j"] = sim.energy_balance()["residual_j"]
    check_finite(trace, summary)
    line = json_line(summary)
    writers = [(args.out, trace_csv_writer(trace, args.out_units))]
    if args.plot:  # both files or neither: an interrupted plot leaves no CSV of a failed run
        from ..analysis.render import save_cards

        period = 60.0 / spm if cfg.surface.motion != "pullout" else None
        writers.append((args.plot, lambda tmp: save_cards(trace, tmp, cfg.name, period)))
    atomic_write_all(writers)
    print(line)
    return 0


def pullout_summary(sim, result) -> dict:
    from ..analysis import metrics

    tr = result.trace
    t = tr["t_s"]
    late = t >= t[0] + 0.3 * (t[-1] - t[0])
    du = tr["polished_rod_position_m"] - tr["pump_position_m"]
    return {
        "duration_s": result.duration_s,
        "plunger_stick_episodes_after_start": len(metrics.rest_episodes(tr["pump_velocity_m_s"][late])),
        "slip_amplitude_m": metrics.slip_amplitude_m(t[late], du[late], 1.0 / sim.f1_hz),
        "pprl_n": float(tr["polished_rod_load_n"].max()),
        "certified_steps": result.certified_steps, "corrected_steps": result.corrected_steps,
        "qp_steps": result.qp_steps, "solver_calls": result.qp_calls,
    }


def build_parser() -> argparse.ArgumentParser:
    p, sub = command_parser("srenv", "srenv", __doc__.splitlines()[0])
    s = sub.add_parser("simulate", help="simulate a well and write a per-time-step CSV")
    s.add_argument("config", help="well YAML path or shipped name")
    g = s.add_mutually_exclusive_group()
    add_number(g, "simulate", "--strokes", help=f"strokes to simulate (default {DEFAULT_STROKES})")
    add_number(g, "simulate", "--duration-s", help="simulated time (s); harmonic runs take round(T*spm/60) strokes")
    add_number(s, "simulate", "--spm", help="stroke rate (harmonic and conventional motion)")
    add_number(s, "simulate", "--stroke-length-m", help="stroke length (harmonic motion)")
    add_number(s, "simulate", "--pull-velocity-m-s", help="pulling speed (pull-out)")
    s.add_argument("--set", action="append", metavar="KEY.PATH=VALUE", help="override a config field")
    s.add_argument("--qp-solver", help="qpsolvers backend for the step QP (default proxqp)")
    s.add_argument("--always-qp", action="store_true", help="solve every step's QP (reference mode)")
    s.add_argument("--out", required=True, help="CSV file, one row per time step")
    s.add_argument("--plot", help="PNG with the surface and pump cards")
    s.add_argument("--out-units", choices=("si", "field"), default="si", help="CSV units: si (the column names' "
                   "units) or field (positions in in, loads in lbf, named in a unit row under the header)")
    s.set_defaults(func=cmd_simulate)
    b = sub.add_parser("bench", help="performance figures as JSON")
    add_number(b, "bench", "--repeats", default=5)
    add_number(b, "bench", "--strokes", default=10)
    b.add_argument("--quick", action="store_true", help="fewer repeats and strokes (smoke run)")
    b.set_defaults(func=lambda a: __import__("srenv.tools.bench", fromlist=["main"]).main(a))
    d = sub.add_parser("config-doc", help="print the table of config fields")
    d.set_defaults(func=lambda a: print(__import__("srenv.config", fromlist=["x"]).config_doc()) or 0)
    try:
        from .sweep import add_parser as add_sweep
    except ImportError:
        add_sweep = None
    if add_sweep is not None:
        add_sweep(sub)
    from .diagnose_cli import add_parser as add_diagnose  # field engineering (docs/field.md)
    from .fit_cli import add_parser as add_fit

    add_diagnose(sub)
    add_fit(sub)
    from .validate import add_parser as add_validate  # field records (docs/realism.md)

    add_validate(sub)
    from .cards import add_parser as add_cards  # pump conditions (docs/conditions.md)

    add_cards(sub)
    from .classify import add_parser as add_classify

    add_classify(sub)
    return p


def main(argv: list[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    previous = None
    if argv is None:  # the command itself, not a test calling main() in-process
        previous = signal.signal(signal.SIGTERM, raise_on_sigterm)
    try:
        rc = args.func(args)
    except ConfigError as exc:
        print(f"srenv: error: {exc}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except NumericFailure as exc:
        print(f"srenv: error: {exc}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except SolverFailure as exc:
        print(f"srenv: solver failure: {exc}", file=sys.stderr)
        return EXIT_SOLVER
    except KeyboardInterrupt:
        print("srenv: interrupted", file=sys.stderr)
        return EXIT_INTERRUPTED
    finally:
        if previous is not None:
            signal.signal(signal.SIGTERM, previous)
    return int(rc or 0)


if __name__ == "__main__":
    sys.exit(main())
