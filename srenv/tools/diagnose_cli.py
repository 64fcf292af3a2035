"""``srenv diagnose CARD.csv --config WELL --out PUMP.csv [--plot P.png]`` or ``srenv diagnose RECORD.json --out
PUMP.csv``: the command line of the downhole-card diagnosis (the analysis itself is :mod:`srenv.analysis.diagnose`;
a vendor dynacard record is diagnosed on the well it describes, :mod:`srenv.tools.record_well`).

Every flag is declared in :mod:`srenv.declarations`; the outputs are checked before any work and written
together (both or neither); the JSON summary is strict (a non-finite number is a failure, not a result).
"""

from __future__ import annotations

import argparse

import numpy as np

from ..analysis.damping_balance import RULES
from ..analysis.diagnose import DEFAULT_HARMONICS, LOAD_CONVENTIONS, PUMP_COLUMNS, load_in_convention
from ..cli_types import card_command, check_card_config
from ..declarations import OUTPUTS, add_number
from ..errors import ConfigError, NumericFailure
from ..outputs import atomic_write_all, check_outputs, json_line


def _pump_csv_writer(card, convention: str):
    """The pump card CSV; effective loads go under their own column name (pump_effective_load_n)."""
    load = load_in_convention(card.pump_load_n, convention, card.rod_end_pressure_pa, card.rod_end_area_m2)
    data = np.column_stack([card.t_s, card.pump_position_m, load])
    columns = PUMP_COLUMNS if convention == "true" else (*PUMP_COLUMNS[:2], "pump_effective_load_n")

    def write(tmp: str) -> None:
        np.savetxt(tmp, data, delimiter=",", header=",".join(columns), comments="", fmt="%.12g")
    return write


def cmd_diagnose(args: argparse.Namespace) -> int:
    from ..config import load_config

    check_outputs({flag: (getattr(args, flag[2:]), sfx) for flag, sfx in OUTPUTS["diagnose"].items()})
    if check_card_config(args.card, args.config):
        return _diagnose_record(args)
    from ..analysis.diagnose import read_surface_card

    cfg = load_config(args.config, list(args.set or []))
    cols = read_surface_card(args.card, args.reverse)
    t, x, f = cols["t_s"], cols["polished_rod_position_m"], cols["polished_rod_load_n"]
    return _diagnose_and_write(args, cfg, t, x, f, 60.0 / args.spm if args.spm else None)


def _diagnose_record(args: argparse.Namespace) -> int:
    """A dynacard record's stored card (forward in time, as ``srenv validate`` reads it) diagnosed on the well it
    describes (``record_well``: pump full, the intake pressure from the record's analysis or its load lines), at the
    record's stroke rate unless ``--spm``; the JSON line adds ``well`` (what came from the record)."""
    from ..config import apply_overrides, config_from_dict
    from .record_well import described_well, read_record_file

    rec = read_record_file(args.card, args.reverse)
    with described_well(rec) as well:
        if args.damping != "fixed" and well.pump_state["source"] != "record":
            raise ConfigError("--damping", args.damping, f"fixed for {args.card}: the record has no analysis of "
                              "its own, so the described well's intake pressure is read off this same card's load "
                              "lines and the energy balance is degenerate (docs/realism.md)")
        cfg = config_from_dict(apply_overrides(well.config, list(args.set or [])))
        period = 60.0 / args.spm if args.spm else rec.period_s
        return _diagnose_and_write(args, cfg, rec.t_s, rec.position_m, rec.load_n, period, {"well": well.entry()})


def _diagnose_and_write(args: argparse.Namespace, cfg, t, x, f, period: float | None, extra: dict | None = None):
    """Diagnose (t, x, f) on ``cfg`` with the damping rule asked for, print the JSON line and write the outputs."""
    from ..analysis.damping_balance import diagnose_with_rule
    from ..analysis.diagnose import diagnose_card, save_plot, summary

    if period is not None and t[-1] - t[0] < period * (1 - 1e-6) - 2 * float(np.median(np.diff(t))):
        raise ConfigError("--spm", args.spm, f"a stroke rate whose period fits in the card ({t[-1] - t[0]:.4g} s)")
    cfg, card, damping = diagnose_with_rule(cfg, args.damping, lambda c: diagnose_card(
        c, t, x, f, harmonics=args.harmonics, period_s=period, friction=not args.no_friction))
    for name in ("pump_position_m", "pump_load_n"):
        if not np.all(np.isfinite(getattr(card, name))):
            raise NumericFailure(name, "the diagnosed pump card is not finite; check the card's magnitudes")
    # before any file: a failed summary leaves no output
    line = json_line({**summary(cfg, card, args.load_convention), "damping": damping, **(extra or {})})
    writers = [(args.out, _pump_csv_writer(card, args.load_convention))]
    if args.plot:
        writers.append((args.plot, lambda tmp: save_plot(card, tmp, cfg.name)))
    atomic_write_all(writers)
    print(line)
    return 0


def add_parser(sub) -> None:
    d = card_command(sub, "diagnose", "downhole (pump) card from a measured surface card or a dynacard record",
                     "well YAML path or shipped name (rod string, fluid, survey)", record=True)
    d.add_argument("--set", action="append", metavar="KEY.PATH=VALUE", help="override a config field")
    d.add_argument("--out", required=True, help="pump card CSV: t_s, pump_position_m, pump_load_n")
    d.add_argument("--plot", help="PNG with the surface and the pump card")
    add_number(d, "diagnose", "--spm", help="stroke rate of the card (default: found from the position record)")
    add_number(d, "diagnose", "--harmonics", default=DEFAULT_HARMONICS,
               help=f"Fourier harmonics kept (default {DEFAULT_HARMONICS})")
    d.add_argument("--no-friction", action="store_true", help="skip the deviated-well friction correction")
    d.add_argument("--reverse", action="store_true", help="the card is stored in reverse time: reverse it")
    d.add_argument("--load-convention", choices=LOAD_CONVENTIONS, default="true",
                   help="pump loads written as true loads (default) or effective (buoyant) loads: true + p A at "
                        "the rod end (the JSON carries rod_end_pressure_pa and rod_end_area_m2)")
    d.add_argument("--damping", choices=RULES, default="fixed",
                   help="the string's Gibbs factor: as configured (default) or energy-balance, the one whose "
                        "pump card does the pump's work (valve interval x displaced liquid + gas compression; "
                        "Gibbs 1963, Everitt & Jennings 1992; docs/realism.md)")
    d.set_defaults(func=cmd_diagnose)
