"""``srenv fit CARD.csv --config WELL --param KEY ... --out FITTED.yaml``: the command line of the card fit
(the fit itself is :mod:`srenv.analysis.fit`).

Every flag is declared in :mod:`srenv.declarations`; the run's size (strokes per evaluation at the card's own
period) is bounded before any work; a ``--param`` that does not change the simulated card is refused (least
squares cannot fit it); the JSON summary is strict.
"""

from __future__ import annotations

import argparse
import os

import yaml

from ..analysis.fit import DEFAULT_STROKES, CardFit, fit_card, refuse_inert
from ..cli_types import card_command
from ..config import apply_overrides, check_run_samples, config_from_dict, steps_per_stroke
from ..declarations import OUTPUTS, add_number
from ..outputs import atomic_write, check_outputs, json_line


def write_fitted_yaml(fit: CardFit, values: dict, path: str) -> None:
    """The fitted config: the input config with the fitted values and the measured motion, validated
    before it is written atomically."""
    data = apply_overrides(fit.raw, values)
    config_from_dict(data)  # validated before the write

    def write(tmp: str) -> None:
        with open(tmp, "w") as fh:
            fh.write("# fitted by `srenv fit` to " + fit.card_path + "\n")
            yaml.safe_dump(data, fh, sort_keys=False)
    atomic_write(path, write)


def cmd_fit(args: argparse.Namespace) -> int:
    check_outputs({flag: (getattr(args, flag[2:]), sfx) for flag, sfx in OUTPUTS["fit"].items()})
    fit = CardFit(args.card, args.config, list(args.param), list(args.set or []), strokes=args.strokes)
    # each evaluation simulates --strokes strokes at the card's own period, not at surface.spm
    check_run_samples(fit.strokes * steps_per_stroke(fit.base, 60.0 / fit.period), "--strokes", args.strokes)
    refuse_inert(fit)
    result = fit_card(fit, max_evaluations=args.max_evaluations)
    result["out"] = os.fspath(args.out)
    line = json_line(result)
    write_fitted_yaml(fit, result["params"], args.out)
    print(line)
    return 0


def add_parser(sub) -> None:
    f = card_command(sub, "fit", "fit config fields to a measured surface card (least squares)",
                     "well YAML path or shipped name (the starting model)")
    f.add_argument("--param", action="extend", nargs="+", required=True, metavar="KEY.PATH",
                   help="config field(s) to fit: e.g. damping.damping_factor, friction.coefficient, "
                        "pump.intake_pressure_pa, fluid.wellhead_pressure_pa, pump.plunger_friction_n")
    f.add_argument("--set", action="append", metavar="KEY.PATH=VALUE", help="override a config field first")
    f.add_argument("--out", required=True, help="fitted well YAML")
    add_number(f, "fit", "--strokes", default=DEFAULT_STROKES,
               help=f"strokes simulated per evaluation; the last is compared (default {DEFAULT_STROKES})")
    add_number(f, "fit", "--max-evaluations", default=200)
    f.set_defaults(func=cmd_fit)
