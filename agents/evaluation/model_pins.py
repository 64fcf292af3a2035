"""A benchmark report names the model files it played by content, not only by file name.

An agent's record in a report (``policies.NAME``) lists its member models as ``models: [models/<file>.zip, ...]``;
a record written since issue 24's pinning also has ``sha256: {REF: DIGEST | null}``: for every member its zip and
its observation statistics (``models/<file>_obs_norm.npz``, null when the member played without them), each keyed
as the report names it. Whatever reads a report back to rebuild its policies (``python -m agents replay``,
``benchmark --evaluate-only --report``, the quick start) checks every member file it found against that record
(:func:`check_pins`) before any episode, so two fits that share a file name (a design's students and the shipped
ones in ``models/``) can never stand in for each other. A record without ``sha256`` (every report written before)
is trusted by name, as before.
"""

from __future__ import annotations

import re
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from .manifest import sha256
from .normalizer import obs_norm_path

PINS = "sha256"  # the record's field
_DIGEST = re.compile(r"[0-9a-f]{64}")


def member_pins(refs: Sequence[str], members: Sequence[dict[str, Any]]) -> dict[str, str | None]:
    """The ``sha256`` record of the members ``{"path", "obs_norm"}`` a report names ``refs`` (in order)."""
    if len(refs) != len(members):
        raise ValueError(f"{len(refs)} model names for {len(members)} members")
    out: dict[str, str | None] = {}
    for ref, m in zip(refs, members):
        out[ref] = sha256(Path(m["path"]))
        out[obs_norm_path(ref).as_posix()] = sha256(Path(m["obs_norm"])) if m.get("obs_norm") else None
    return out


def spec_members(spec: dict[str, Any]) -> list[dict[str, Any]]:
    """The member models ``{"path", "obs_norm", ...}`` a policy spec plays (an agent, an ensemble, a guarded one)."""
    if spec.get("kind") == "guarded":
        return spec_members(spec["inner"])
    if "members" in spec:
        return list(spec["members"])
    return [spec] if spec.get("path") else []


def check_record(pins: Any, field: str) -> dict[str, str | None] | None:
    """A record's ``sha256`` field, checked: None (an older report, trusted by name) or a mapping of file to digest."""
    if pins is None:
        return None
    if not (isinstance(pins, dict) and all(isinstance(k, str) and (v is None or (isinstance(v, str)
                                           and _DIGEST.fullmatch(v))) for k, v in pins.items())):
        raise ValueError(f"{field} = {str(pins)[:80]}: expected a mapping of each member file to its sha256 "
                         "(64 lowercase hex digits) or null")
    return pins


def check_pins(pins: dict[str, str | None] | None, ref: str, found: Path, field: str, root: Path) -> None:
    """Refuse in one line a member whose zip ``found`` (or the statistics beside it) is not the file the report
    played: the field (the member file), the recorded and the found digest, and what is expected."""
    if pins is None:
        return
    norm = obs_norm_path(found)
    for key, path in ((ref, found), (obs_norm_path(ref).as_posix(), norm if norm.is_file() else None)):
        if key not in pins:
            raise ValueError(f"{field}: no entry for {key}, expected one for each member's zip and its obs_norm "
                             "(null: played without one)")
        got = sha256(path) if path is not None else None
        if got != pins[key]:
            raise ValueError(f'{field}["{key}"]: the report recorded {pins[key] or "none (played without it)"}, '
                             f"found {f'{path} with sha256 {got}' if path else 'no such file'}; expected the "
                             f"file the report played (put it at {root / key}, looked in before models/)")
