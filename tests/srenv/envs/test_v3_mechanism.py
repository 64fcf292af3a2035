"""scripts/v3_mechanism.py (docs/task.md, "v3"): its figures show v3's mechanisms against v2's; it takes no
arguments (one line, exit 2)."""

from __future__ import annotations

import importlib
import json
import sys
from pathlib import Path

import pytest

SCRIPT = Path(__file__).resolve().parents[3] / "scripts" / "v3_mechanism.py"


@pytest.fixture(scope="module")
def mod():
    sys.path.insert(0, str(SCRIPT.parent))  # as when it runs
    return importlib.import_module(SCRIPT.stem)


def test_an_argument_is_refused_in_one_line(mod, capsys) -> None:
    with pytest.raises(SystemExit) as ex:
        mod.main(["--out", "x"])
    err = capsys.readouterr().err.strip().splitlines()
    assert ex.value.code == 2 and len(err) == 1 and "--out" in err[0] and "expected" in err[0]


def test_the_figures_show_the_mechanisms(mod, capsys) -> None:
    mod.main([])
    d = json.loads(capsys.readouterr().out)
    v2, v3 = (d["tagging"][k] for k in mod.VERSIONS)
    by = {(r["spm"], r["stroke_m"], r["severity"]): r["reward_tagging_usd_h"] for r in v3}
    assert by[(3.0, "installed", 0.6)] > by[(8.0, "installed", 0.6)] and by[(8.0, "installed", 0.0)] == 0.0
    assert by[(6.0, 1.6, 0.6)] > by[(6.0, "installed", 0.6)]
    assert len({r["reward_tagging_usd_h"] for r in v2 if r["spm"] == 6.0}) == 1  # v2: the stroke moves nothing
    leak3 = d["leaks"][mod.VERSIONS[1]]
    assert all(s["3.0"] > s["5.0"] > s["8.0"] for s in leak3.values())
    ref = d["tag_reference"]
    assert ref["shipped_reference_m_s"] == pytest.approx(ref["reference_m_s"], rel=0.01)
