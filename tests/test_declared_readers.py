"""Hardening, third round (z26's black-box audit): the classes the generated cases of test_declared_inputs.py /
test_declared_files.py did not reach - a FIFO or a directory where a file is read (every reader, from one
table: a reader added to READERS is covered by construction), a CSV cell over csv's field limit, card values
whose arithmetic overflows, JSON nested a million deep, gymnasium.make's own keywords, outputs that cannot be
made (checked before any work), and flags whose items repeat or fit nothing.

Every refusal: exit 2, one stderr line naming the field or flag and the value, no traceback, nothing left.
"""

from __future__ import annotations

import os
import threading
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from declared_helpers import CARD_HEADER, FIG3, nothing_left, one_line, run_agents, run_srenv, write_card

from srenv.errors import ConfigError

RECORD = Path(__file__).resolve().parent / "data" / "field"


def _readers() -> dict[str, Callable[[Path], Any]]:
    """Every function that opens a file a command names, by the kind of file (each takes the path)."""
    from agents.evaluation.model_io import read_stats
    from agents.evaluation.replay import load_report
    from agents.inputs import obs_norm_npz
    from agents.training.config import read_train_yaml
    from srenv.analysis.card_classifier import CardClassifier
    from srenv.analysis.field_record import load_record_json
    from srenv.config import read_raw
    from srenv.safe_yaml import load_yaml_file
    from srenv.surface_unit.measured_motion import read_card_csv
    from srenv.tools.classify import read_card

    return {"well-yaml": lambda p: read_raw(p), "yaml": lambda p: load_yaml_file(p, "config"),
            "train-yaml": read_train_yaml, "record-json": load_record_json, "report-json": load_report,
            "stats-json": lambda p: read_stats(p, (4,)), "obs-norm-npz": obs_norm_npz,
            "classifier-npz": CardClassifier.load, "card-csv": lambda p: read_card_csv(p, "CARD.csv", ("t_s",)),
            "classify-csv": read_card}


READER_NAMES = ["well-yaml", "yaml", "train-yaml", "record-json", "report-json", "stats-json", "obs-norm-npz",
                "classifier-npz", "card-csv", "classify-csv"]
SUFFIX = {"json": ".json", "npz": ".npz", "csv": ".csv"}


def test_the_reader_table_is_complete() -> None:
    assert sorted(_readers()) == sorted(READER_NAMES)


def _suffix(name: str) -> str:
    return next((s for k, s in SUFFIX.items() if name.endswith(k)), ".yaml")


def _refused(call: Callable[[], Any]) -> str:
    """The one-line refusal of ``call`` (ConfigError, or the ValueError a model reader wraps it in)."""
    with pytest.raises(ValueError) as ex:
        call()
    msg = str(ex.value)
    assert "\n" not in msg and len(msg) < 600, msg
    return msg


@pytest.mark.parametrize("name", READER_NAMES)
def test_a_fifo_is_refused_by_every_reader_without_blocking(name: str, tmp_path: Path) -> None:
    """open() of a FIFO waits for a writer (a command that never ends): the readers open without blocking and
    refuse what is not a regular file. A watchdog plays the writer if a reader blocks, so a regression fails
    here instead of hanging the suite."""
    fifo = tmp_path / f"f{_suffix(name)}"
    os.mkfifo(fifo)
    blocked, done = [], threading.Event()

    def watchdog() -> None:
        deadline = time.time() + 10
        while not done.is_set() and time.time() < deadline:
            try:  # succeeds only while a reader holds the FIFO open
                fd = os.open(fifo, os.O_WRONLY | os.O_NONBLOCK)
            except OSError:
                time.sleep(0.05)
                continue
            time.sleep(0.5)
            if not done.is_set():
                blocked.append(True)
            os.close(fd)
            return
    t = threading.Thread(target=watchdog, daemon=True)
    t.start()
    try:
        msg = _refused(lambda: _readers()[name](fifo))
    finally:
        done.set()
        t.join(15)
    assert not blocked, f"{name} blocked on a FIFO"
    assert str(fifo) in msg


@pytest.mark.parametrize("name", READER_NAMES)
def test_a_directory_is_refused_by_every_reader(name: str, tmp_path: Path) -> None:
    d = tmp_path / f"d{_suffix(name)}"
    d.mkdir()
    assert str(d) in _refused(lambda: _readers()[name](d))


def test_a_json_nested_a_million_deep_is_one_line(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    (tmp_path / "r.json").write_text("[" * 1_000_000 + "]" * 1_000_000)
    rc, err = run_agents(["replay", str(tmp_path / "r.json")], capsys)
    one_line(rc, err, "report", "nested too deeply")
    from srenv.input_files import read_json

    with pytest.raises(ConfigError, match="not UTF-8"):
        (tmp_path / "b.json").write_bytes(b"\xff\xfe{}")
        read_json(tmp_path / "b.json", "x", "file", 100)
    with pytest.raises(ConfigError, match="at most 100 bytes"):
        (tmp_path / "big.json").write_text("[" + "1," * 100 + "1]")
        read_json(tmp_path / "big.json", "x", "file", 100)


# ----------------------------------------------------------------------------------- card contents
def _csv_cell_over_limit(p: Path) -> None:
    p.write_text(CARD_HEADER + "\n" + "1" * 200_000 + ",2,3\n")


def _csv_overflowing(p: Path) -> None:
    p.write_text(CARD_HEADER + "\n" + "".join(f"{i},1e308,1e308\n" for i in range(20)))


def _csv_times_overflowing(p: Path) -> None:
    t = (np.arange(200) - 100) * 9.5e305  # finite times whose span, 1.89e308 s, overflows
    x = 1.2 * (1 - np.cos(2 * np.pi * np.arange(200) / 200))
    np.savetxt(p, np.c_[t, x, 40e3 + 8e3 * np.sin(2 * np.pi * np.arange(200) / 200)], delimiter=",",
               header=CARD_HEADER, comments="")


CARD_CLASSES = [("cell-over-csv-limit", _csv_cell_over_limit, "field larger than field limit"),
                ("values-1e308", _csv_overflowing, "magnitude at most"),
                ("times-1e308", _csv_times_overflowing, "")]


@pytest.mark.parametrize(("make", "needle"), [pytest.param(m, n, id=i) for i, m, n in CARD_CLASSES])
@pytest.mark.parametrize("cmd", ["diagnose", "fit", "validate", "classify", "simulate"])
def test_card_csv_classes_are_one_line_in_every_command(cmd: str, make: Any, needle: str, tmp_path: Path,
                                                       capsys: pytest.CaptureFixture,
                                                       monkeypatch: pytest.MonkeyPatch) -> None:
    """Before: a traceback (csv.Error) or the overflow's RuntimeWarning lines above a misleading 'zero stroke'."""
    monkeypatch.chdir(tmp_path)
    make(tmp_path / "card.csv")
    argv = {"diagnose": ["diagnose", "card.csv", "--config", FIG3, "--out", "o.csv"],
            "fit": ["fit", "card.csv", "--config", FIG3, "--param", "damping.damping_factor", "--out", "f.yaml"],
            "validate": ["validate", "card.csv", "--config", FIG3], "classify": ["classify", "card.csv"],
            "simulate": ["simulate", FIG3, "--set", "surface.motion=measured", "--set",
                         "surface.measured_card_csv=card.csv", "--out", "o.csv"]}[cmd]
    with np.errstate(all="warn"):
        rc, err = run_srenv(argv, capsys)
    one_line(rc, err, "card.csv", needle or ("stroke period" if cmd != "classify" else "card.csv"))
    nothing_left(tmp_path, {"card.csv"})


def test_a_record_whose_loads_overflow_is_one_line(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    import json

    rec = json.loads(next(RECORD.glob("*.json")).read_text())
    rec["cardData"]["Load"] = [1e308] * len(rec["cardData"]["Load"])
    (tmp_path / "r.json").write_text(json.dumps(rec))
    for argv in (["validate", str(tmp_path / "r.json")], ["classify", str(tmp_path / "r.json")]):
        rc, err = run_srenv(argv, capsys)
        one_line(rc, err, "cardData", "loads of magnitude at most")


# ---------------------------------------------------------------------------- gymnasium.make's keywords
def _make_cases() -> list[Any]:
    from agents.inputs import MAKE_FLAGS, MAKE_NUMBERS

    cases = [pytest.param(k, v, id=f"{k}={v!r:.12}") for k, d in MAKE_NUMBERS.items() for v in d.bad_values()
             if v is not None]
    cases += [pytest.param(k, v, id=f"{k}={v!r}") for k in MAKE_FLAGS for v in ("x", 1, [1])]
    return cases + [pytest.param("render_mode", 1, id="render_mode=1")]


@pytest.mark.parametrize(("key", "value"), _make_cases())
def test_gymnasium_make_keywords_are_declared_and_checked(key: str, value: Any) -> None:
    """Before: max_episode_steps=0 or 1e308 an AssertionError, -1 accepted, render_mode=1 an AttributeError,
    disable_env_checker=[1] taken as true."""
    from agents.envs import make_env

    with pytest.raises(ConfigError) as ex:
        make_env("srenv/SuckerRod-v0", **{key: value})
    assert ex.value.field == key and "\n" not in str(ex.value)


def test_evaluate_env_kwargs_name_the_flag(capsys: pytest.CaptureFixture) -> None:
    rc, err = run_agents(["evaluate", "--policy", "rocking", "--episodes", "1", "--env-kwarg", "config=x"], capsys)
    one_line(rc, err, "--env-kwarg config", "--config")  # before: a TypeError traceback (config given twice)
    rc, err = run_agents(["evaluate", "--policy", "rocking", "--episodes", "1", "--env-kwarg",
                          "max_episode_steps=0"], capsys)
    one_line(rc, err, "max_episode_steps", "positive integer")


# ------------------------------------------------------------------------ outputs checked before any work
def _no_work(monkeypatch: pytest.MonkeyPatch) -> None:
    """Any work (a card simulated, a benchmark run, a training) or any reading for it (the benchmark config and
    its training YAMLs, a shipped report and its models) fails the test."""
    def work(*_a: Any, **_k: Any) -> None:
        raise AssertionError("work started before the outputs were checked")
    import agents.benchmark.config as bench_config
    import agents.training.sb3.train as sb3_train
    from agents.benchmark import fresh, run, shipped_quickstart
    from srenv.tools import cards

    monkeypatch.setattr(cards, "simulate_set", work)
    monkeypatch.setattr(run, "tune_baselines", work)
    monkeypatch.setattr(sb3_train, "train", work)
    for module in (bench_config, run):
        monkeypatch.setattr(module, "load_benchmark_config", work)
    for module in (fresh, shipped_quickstart):
        monkeypatch.setattr(module, "load_report", work)


OUT_CASES = [("train", ["train", "configs/train/ppo_quick.yaml", "--out"], "--out"),
             ("quickstart-train", ["quickstart", "--train", "--out"], "--out"),
             ("quickstart-shipped", ["quickstart", "--out"], "--out"),
             ("benchmark", ["benchmark", "configs/benchmark/v1_quick.yaml", "--out-dir"], "--out-dir"),
             ("benchmark-evaluate-only", ["benchmark", "configs/benchmark/v2.yaml", "--evaluate-only", "--fresh-seed",
                                          "1", "--episodes", "1", "--out-dir"], "--out-dir"),
             ("cards", ["cards", "--n", "1", "--out"], "--out")]


@pytest.mark.parametrize("where", ["file", "under-file", "unwritable", "link-to-file", "link-to-dir"])
@pytest.mark.parametrize(("argv", "flag"), [pytest.param(a, f, id=i) for i, a, f in OUT_CASES])
def test_an_output_directory_that_cannot_be_made_is_refused_before_any_work(
        argv: list[str], flag: str, where: str, tmp_path: Path, capsys: pytest.CaptureFixture,
        monkeypatch: pytest.MonkeyPatch) -> None:
    """Before: train --out FILE a FileExistsError traceback after building the envs; quickstart --train a notice
    line, minutes of tuning, then the error; cards --out /proc/x a traceback after the simulation; benchmark
    --evaluate-only --out-dir FILE refused only after the config, the report and its models were read (~7 s),
    quickstart --train and benchmark --out-dir after the config and its training YAMLs."""
    root = Path(__file__).resolve().parents[1]
    monkeypatch.chdir(root)
    _no_work(monkeypatch)
    (tmp_path / "f.txt").write_text("keep")
    (tmp_path / "d").mkdir()
    os.symlink(tmp_path / "f.txt", tmp_path / "link_f")
    os.symlink(tmp_path / "d", tmp_path / "link_d")
    before = set(os.listdir(tmp_path))
    out = {"file": tmp_path / "f.txt", "under-file": tmp_path / "f.txt" / "x", "unwritable": Path("/proc/srenv_x"),
           "link-to-file": tmp_path / "link_f", "link-to-dir": tmp_path / "link_d"}[where]
    run = run_srenv if argv[0] == "cards" else run_agents
    rc, err = run([*argv, str(out)], capsys)
    one_line(rc, err, flag, str(out))
    assert (tmp_path / "f.txt").read_text() == "keep" and os.listdir(tmp_path / "d") == []
    nothing_left(tmp_path, before)


def test_cards_refuses_a_special_file_among_its_outputs(tmp_path: Path, capsys: pytest.CaptureFixture,
                                                        monkeypatch: pytest.MonkeyPatch) -> None:
    """srenv cards checks its folder with the one check agents' commands use (srenv.outputs.check_output_dir):
    a FIFO where cards.npz will go is refused before any card is simulated (its own copy did not look)."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "o").mkdir()
    os.mkfifo(tmp_path / "o" / "cards.npz")
    before = set(os.listdir(tmp_path / "o"))
    rc, err = run_srenv(["cards", "--n", "1", "--out", "o"], capsys)
    one_line(rc, err, "--out", "special file")
    assert set(os.listdir(tmp_path / "o")) == before


# ------------------------------------------------------------------------------------------ flags
@pytest.mark.parametrize("text", ["full,full", "full,,", "full, ,fluid_pound"])
def test_cards_conditions_refuse_repeats_and_empty_items(text: str, tmp_path: Path,
                                                         capsys: pytest.CaptureFixture,
                                                         monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(tmp_path)
    rc, err = run_srenv(["cards", "--n", "1", "--conditions", text, "--out", "o"], capsys)
    one_line(rc, err, "--conditions", "distinct labels")
    nothing_left(tmp_path, set())


def test_sweep_address_that_is_no_address_is_one_line(tmp_path: Path, capsys: pytest.CaptureFixture,
                                                      monkeypatch: pytest.MonkeyPatch) -> None:
    pytest.importorskip("ray")
    monkeypatch.chdir(tmp_path)
    rc, err = run_srenv(["sweep", "paper_fig7_pullout", "--param", "surface.pull_velocity_m_s", "--values", "0.5",
                         "--address", "garbage", "--out", "o.csv"], capsys)
    one_line(rc, err, "--address", "garbage")  # before: a ValueError traceback from ray.init
    nothing_left(tmp_path, set())


def test_validate_fit_refuses_a_field_without_effect_as_fit_does(tmp_path: Path, capsys: pytest.CaptureFixture,
                                                                 monkeypatch: pytest.MonkeyPatch) -> None:
    """Before: validate --fit economics.oil_price_usd_m3 'fitted' a field that does not move the card, exit 0."""
    monkeypatch.chdir(tmp_path)
    write_card(tmp_path / "card.csv")
    rc, err = run_srenv(["validate", "card.csv", "--config", FIG3, "--fit", "economics.oil_price_usd_m3",
                         "--strokes", "1"], capsys)
    one_line(rc, err, "--fit", "economics.oil_price_usd_m3", "change the simulated card")
    rc, err = run_srenv(["validate", "card.csv", "--config", FIG3, "--fit", "nosuch.key"], capsys)
    one_line(rc, err, "--fit", "nosuch.key")  # the flag of the command, not fit's --param


@pytest.mark.parametrize("text", ["1_0", "0b110", "1_0.5", "6.0_0"])
def test_a_number_yaml_versions_read_differently_is_refused(text: str, tmp_path: Path) -> None:
    """Before: --set surface.spm=1_0 ran at 10 strokes/min (YAML 1.1 drops the underscore; YAML 1.2 and every
    other tool read a string) and 0b110 at 6; the leading-zero and colon forms were already refused."""
    import re

    from srenv.config import CONFIG_DIR, load_config

    with pytest.raises(ConfigError, match=rf"surface.spm.*'{re.escape(text)}'.*ambiguous"):
        load_config(FIG3, [f"surface.spm={text}"])
    yaml_text = (CONFIG_DIR / f"{FIG3}.yaml").read_text()
    (tmp_path / "w.yaml").write_text(re.sub(r"(?m)^(\s+)spm: .*$", rf"\g<1>spm: {text}", yaml_text, count=1))
    with pytest.raises(ConfigError, match=f"{re.escape(text)} is ambiguous"):
        load_config(tmp_path / "w.yaml")


def test_a_model_zip_whose_data_is_nested_a_million_deep_is_one_line(tmp_path: Path,
                                                                     capsys: pytest.CaptureFixture) -> None:
    import zipfile

    with zipfile.ZipFile(tmp_path / "m.zip", "w") as z:
        z.writestr("data", "[" * 1_000_000 + "]" * 1_000_000)
    rc, err = run_agents(["evaluate", "--policy", str(tmp_path / "m.zip"), "--episodes", "1"], capsys)
    one_line(rc, err, "m.zip", "nested too deeply")  # before: a RecursionError traceback
