"""The well a vendor dynacard record describes, for ``srenv classify RECORD.json`` and ``srenv diagnose
RECORD.json`` (docs/field.md, "A dynacard record describes its well").

The record is read as ``srenv validate`` reads it (``validate.read_record``: field units to SI, the card checked,
a card stored in reverse time turned forward and said so unless ``--reverse``). Its *described* well is
``field_model.well_config`` driven by the record's motion (``validate.card_motion``, written to a motion CSV), the
pump full (fillage 1: a diagnosis is not told the fillage it is asked for), the intake pressure and plunger
friction from ``validate.pump_state`` (the record's own analysis where it has one, else srenv's diagnosis of the
measured card by its load lines; never a fit to the surface card). The motion CSV lives in a temporary directory
that is removed when the work is done, also on error.
"""

from __future__ import annotations

import os
import tempfile
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path

from ..errors import ConfigError

FILLAGE = 1.0  # the described pump is full


@dataclass(frozen=True)
class DescribedWell:
    record: object        # the FieldRecord, its card forward in time
    config: dict          # the described well (a config mapping, field_model.well_config)
    pump_state: dict      # validate.pump_state: intake pressure, plunger friction and where they came from
    notes: tuple = ()     # the reader's notes and how the well's motion was taken (validate.card_motion)

    def entry(self) -> dict:
        """The JSON entry saying where the well came from (``well`` in classify's and diagnose's output)."""
        return {"source": "record", "record": self.record.source,
                "card_time_reversed": bool(self.record.time_reversed),
                "intake_pressure_pa": float(self.config["pump"]["intake_pressure_pa"]),
                "plunger_friction_n": float(self.pump_state["plunger_friction_n"]), "fillage": FILLAGE,
                "pump_state_source": self.pump_state["source"], "record_notes": list(self.notes)}


def _regular(path) -> Path:
    p = Path(path)
    if p.is_symlink():
        raise ConfigError("RECORD", str(path), "a regular file (a record is not read through a symbolic link)")
    return p


def read_record_file(path, reverse: bool = False):
    """The dynacard record at `path` (``validate.read_record``; a symbolic link is refused)."""
    from .validate import read_record

    return read_record(str(_regular(path)), None, reverse)


def is_dynacard(path) -> bool:
    """Whether a ``*.json`` file is a dynacard record: a JSON object with ``cardData``. One that parses and holds
    no card is not (``classify DIR`` skips it); one that does not parse is refused (a broken export, not a
    different file)."""
    from ..analysis.field_record import load_record_json

    data = load_record_json(_regular(path))
    return isinstance(data, dict) and "cardData" in data


@contextmanager
def described_well(rec, survey_weight: str = "inclination") -> Iterator[DescribedWell]:
    """The record's described well, valid inside the ``with`` block (its motion CSV is removed after it)."""
    from .validate import card_motion, described_config, write_motion_csv

    with tempfile.TemporaryDirectory(prefix="srenv-record-") as work:
        csv, motion = os.path.join(work, "motion.csv"), card_motion(rec)
        write_motion_csv(motion, csv)
        state, cfg = described_config(rec, csv, work, survey_weight, FILLAGE)
        yield DescribedWell(rec, cfg, state, tuple(motion.notes))
