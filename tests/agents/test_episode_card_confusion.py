"""scripts/episode_card_confusion.py (issues 23/24, measurement only): bad flags are one line and exit 2, before any
work; a tiny run writes the documented JSON, whose run-2 probabilities are the observation's own; the confusion and
tagging-alarm arithmetic on fixed numbers."""

from __future__ import annotations

import importlib
import json
import sys
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]
SCRIPT = REPO / "scripts" / "episode_card_confusion.py"


@pytest.fixture(scope="module")
def mod():
    sys.path.insert(0, str(SCRIPT.parent))  # as when it runs
    return importlib.import_module(SCRIPT.stem)


def test_every_declared_flag_refuses_bad_values_in_one_line(mod, capsys, tmp_path):
    for flag, decl in mod.FLAGS.items():
        for text in decl.bad_texts():
            with pytest.raises(SystemExit) as ex:
                mod.main([flag, text, "--out", str(tmp_path / "c.json")])
            err = capsys.readouterr().err.strip().splitlines()
            assert ex.value.code == 2 and len(err) == 1 and flag in err[0] and "expected" in err[0], (flag, text, err)
    link = tmp_path / "link.json"
    link.symlink_to(tmp_path / "target.json")
    for flag in ("--out", "--rows"):
        for bad, needle in ((str(link), "symbolic link"), (str(tmp_path / "c.txt"), ".json")):
            with pytest.raises(SystemExit) as ex:
                mod.main(["--out", str(tmp_path / "c.json"), flag, bad])
            err = capsys.readouterr().err.strip().splitlines()
            assert ex.value.code == 2 and len(err) == 1 and flag in err[0] and needle in err[0], err
    assert not (tmp_path / "target.json").exists() and not (tmp_path / "c.json").exists()


def test_a_tiny_run_writes_the_documented_json(mod, tmp_path):
    out, rows = tmp_path / "c.json", tmp_path / "rows.json"
    assert mod.main(["--episodes", "1", "--workers", "1", "--max-intervals", "4", "--out", str(out),
                     "--rows", str(rows)]) == 0
    rep = json.loads(out.read_text())
    table = json.loads(rows.read_text())
    assert table["rows_columns"] == list(mod.ROW) and len(table["rows"]) == 4
    assert all(r[0] == 68000 and r[2] in rep["labels"] for r in table["rows"])
    assert tuple(rep) == mod.KEYS["top"] and rep["scenario"] == "train" and rep["policy"]["name"] == "alarm_pump_off"
    assert rep["rows_columns"] == list(mod.ROW) and rep["intervals"] == 4
    for m in mod.MODELS:
        assert tuple(rep["models"][m]) == mod.KEYS["model"]
        for a in rep["models"][m]["tagging_alarm"].values():
            assert tuple(a) == mod.KEYS["alarm"] and tuple(a["by_split"]) == mod.SPLITS
        assert sum(sum(r.values()) for r in rep["models"][m]["confusion"].values()) == 4
    docs = (REPO / "docs" / "conditions.md").read_text()
    section = docs[docs.index("## The classifiers on v2's own episode cards"):]
    assert all(f"`{k}`" in section for keys in mod.KEYS.values() for k in keys)


def test_the_recorded_run2_probabilities_are_the_observations(mod):
    from agents.envs import make_env
    from srenv.envs.sucker_rod_v2 import FIELD_OBS_NAMES, LABELS

    rec = mod.Recorder()
    env = make_env("srenv/SuckerRod-v2", scenario="train", classifier=rec)
    obs, _ = env.reset(seed=68000)
    for _ in range(3):
        obs, *_ = env.step(env.action_space.sample() * 0)
        shown = [obs[FIELD_OBS_NAMES.index(f"prob_{k}")] for k in LABELS]
        assert shown == pytest.approx(rec.last[0], abs=1e-6)
        assert rec.last[1].shape == (12,) and abs(rec.last[1].sum() - 1) < 1e-6
    env.close()


def test_the_arithmetic_on_fixed_numbers(mod):
    labels = ("full", "fluid_pound", "tagging_up", "tagging_down")
    c = mod.confusion(["full", "full", "tagging_down", "fluid_pound"], ["full", "tagging_down", "tagging_down", "full"],
                      labels)
    assert c == {"full": {"full": 1, "fluid_pound": 0, "tagging_up": 0, "tagging_down": 1},
                 "tagging_down": {"full": 0, "fluid_pound": 0, "tagging_up": 0, "tagging_down": 1},
                 "fluid_pound": {"full": 1, "fluid_pound": 0, "tagging_up": 0, "tagging_down": 0}}

    def row(seed, card, true, up, down, first=False, idle=False):
        return {"seed": seed, "card_index": card, "true": true, "first_card": first, "after_idle": idle,
                "m_tagging_up": up, "m_tagging_down": down}

    rows = [row(1, 1, "full", 0.0, 0.9, first=True), row(1, 2, "full", 0.6, 0.1),
            row(1, 3, "fluid_pound", 0.1, 0.2, idle=True), row(2, 2, "tagging_down", 0.0, 0.7),
            row(2, 2, "tagging_down", 0.0, 0.3), row(3, 1, "full", 0.0, 0.0)]
    a5, a8 = mod.tagging_alarm(rows, "m", 0.5), mod.tagging_alarm(rows, "m", 0.8)
    assert a5["false_alarm_rate"] == {"n": 4, "fired": 2, "rate": 0.5}
    assert a5["hit_rate"] == {"n": 2, "fired": 1, "rate": 0.5} and a8["hit_rate"]["fired"] == 0
    assert a8["false_alarm_rate"]["fired"] == 1 and a8["by_split"]["first_card"]["false_alarm_rate"]["rate"] == 1.0
    assert a8["by_split"]["other"]["false_alarm_rate"] == {"n": 2, "fired": 0, "rate": 0.0}
    assert a5["by_split"]["after_idle"]["false_alarm_rate"] == {"n": 1, "fired": 0, "rate": 0.0}
    assert a5["by_label"]["full"] == {"n": 3, "fired": 2, "rate": 2 / 3}
    assert a5["distinct_cards"] == {"false_alarm_rate": {"n": 4, "fired": 2, "rate": 0.5},
                                    "hit_rate": {"n": 1, "fired": 1, "rate": 1.0}}
    assert a5["episodes_fired"] == {"never_tagged": {"n": 2, "fired": 1, "rate": 0.5},
                                    "tagged": {"n": 1, "fired": 1, "rate": 1.0}}
