"""Argument types of the command lines, kept for callers that build one without a declaration; every flag
of ``srenv`` itself is declared in :mod:`srenv.declarations` (type, unit, range) and parsed by it. A bad
value is one line naming the flag, the value and what is expected (argparse turns it into exit status 2)."""

from __future__ import annotations

import argparse
import sys
from collections.abc import Callable
from typing import Any

from .declarations import MAX_DURATION_S, Number  # noqa: F401  (MAX_DURATION_S: re-exported)
from .errors import ConfigError

EXIT_BAD_INPUT = 2  # the exit status of bad input, on every command line


class OneLineParser(argparse.ArgumentParser):
    """A parser whose error is one line ``<tool>: error: ...`` on stderr and exit status 2, no usage dump."""

    tool = "srenv"

    def error(self, message: str) -> None:
        print(f"{self.tool}: error: {message}", file=sys.stderr)
        sys.exit(EXIT_BAD_INPUT)


def command_parser(tool: str, prog: str, description: str) -> tuple[argparse.ArgumentParser, Any]:
    """The parser of a tool's command line and its required subcommands, both erring in one line as ``tool``."""
    parser_class = type(f"{tool.title()}Parser", (OneLineParser,), {"tool": tool})
    parser = parser_class(prog=prog, description=description)
    return parser, parser.add_subparsers(dest="command", required=True, parser_class=parser_class)


def positive(name: str, unit: str) -> Callable[[str], float]:
    return Number(name, float, unit).parse


def positive_int(name: str, hi: int | None = None) -> Callable[[str], int]:
    return Number(name, int, hi=hi).parse


def nonneg_int(name: str) -> Callable[[str], int]:
    return Number(name, int, lo=0, lo_open=False).parse


def bounded(parse: Callable[[str], float], name: str, unit: str, hi: float) -> Callable[[str], float]:
    def check(text: str) -> float:
        x = parse(text)
        if x > hi:
            raise argparse.ArgumentTypeError(f"{name} = {text[:40]!r}: expected a positive number in {unit} "
                                             f"at most {hi:g}")
        return x
    return check


CARD_HELP = "CSV with t_s, polished_rod_position_m, polished_rod_load_n"
RECORD_HELP = " or a vendor dynacard record (.json: its well is the one it describes, docs/field.md)"
RECORD_SUFFIX = ".json"


def is_record(path) -> bool:
    """A vendor dynacard record (by its name, as ``srenv validate`` reads it), not a card CSV."""
    return str(path).lower().endswith(RECORD_SUFFIX)


def check_card_config(card, config: str | None, required: bool = True) -> bool:
    """True for a dynacard record (it describes its well: ``--config`` beside it is refused), False for a card CSV
    (``--config`` required when `required`); one ConfigError line otherwise."""
    if is_record(card):
        if config is not None:
            raise ConfigError("--config", config, f"no --config with a dynacard record ({card} describes its well)")
        return True
    if required and config is None:
        raise ConfigError("--config", "missing", "a well YAML (path or shipped name) for a CSV card (only a dynacard "
                          "record, .json, describes its own well)")
    return False


def card_command(sub, name: str, help: str, config_help: str, record: bool = False):
    """A subcommand that reads one measured surface card against a well config (diagnose, fit). With `record` the
    card may be a dynacard record instead, which describes its well: ``--config`` is then checked by
    ``check_card_config`` (required for a CSV, refused with a record) rather than by argparse."""
    p = sub.add_parser(name, help=help)
    p.add_argument("card", help=CARD_HELP + (RECORD_HELP if record else ""))
    p.add_argument("--config", required=not record,
                   help=config_help + ("; required for a CSV card, refused with a record" if record else ""))
    return p
