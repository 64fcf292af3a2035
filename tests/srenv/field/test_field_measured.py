"""Measured surface motion: a measured-motion run fed with a harmonic run's samples reproduces its card."""

from __future__ import annotations

import numpy as np
import pytest
from conftest import assert_cli_refuses

from srenv.config import load_config
from srenv.errors import ConfigError
from srenv.simulation.simulator import Simulator, concat_traces
from srenv.surface_unit.measured_motion import stroke_period_s

FIG3 = "paper_fig3_vertical"


def _write(path, cols: dict) -> str:
    np.savetxt(path, np.column_stack(list(cols.values())), delimiter=",", header=",".join(cols), comments="",
               fmt="%.12g")
    return str(path)


@pytest.fixture(scope="module")
def harmonic():
    sim = Simulator(load_config(FIG3))
    runs = sim.run_strokes(3)
    return runs, concat_traces(runs)


def _measured_sim(path, *extra):
    return Simulator(load_config(FIG3, ["surface.motion=measured", f"surface.measured_card_csv={path}", *extra]))


def test_last_stroke_samples_reproduce_the_harmonic_card(harmonic, tmp_path):
    runs, _ = harmonic
    last = runs[-1].trace
    t = last["t_s"] - last["t_s"][0]  # samples at dt, 2dt, ..., T: the file does not repeat its first row
    card = _write(tmp_path / "card.csv", {"t_s": t, "polished_rod_position_m": last["polished_rod_position_m"]})
    sim = _measured_sim(card)
    assert sim.surface.default_spm(1.0) == pytest.approx(6.0, rel=1e-9)
    assert sim.surface.stroke_length_m(0.5) == pytest.approx(2.4, rel=1e-5)
    m = sim.run_strokes(3)[-1].trace
    ref = last["polished_rod_load_n"]
    assert abs(m["polished_rod_load_n"].max() / ref.max() - 1) < 1e-4  # the floor is 0.5 %
    assert np.max(np.abs(m["polished_rod_load_n"] - ref)) < 0.01 * (ref.max() - ref.min())
    assert np.max(np.abs(m["polished_rod_position_m"] - last["polished_rod_position_m"])) < 1e-4


def test_multi_stroke_file_uses_its_last_stroke_and_rotates_to_the_bottom(harmonic, tmp_path):
    runs, tr = harmonic
    # start the file mid-stroke: the spline starts the stroke at the card's bottom anyway
    k = 700
    card = _write(tmp_path / "multi.csv", {"t_s": tr["t_s"][k:], "polished_rod_position_m":
                                           tr["polished_rod_position_m"][k:],
                                           "polished_rod_load_n": tr["polished_rod_load_n"][k:]})
    assert stroke_period_s(tr["t_s"][k:], tr["polished_rod_position_m"][k:]) == pytest.approx(10.0, rel=1e-3)
    sim = _measured_sim(card)
    mm = sim.surface.measured
    assert mm.period_s == pytest.approx(10.0, rel=1e-3)
    assert mm.position_m(np.array([0.0]))[0] == pytest.approx(0.0, abs=1e-9)
    m = sim.run_strokes(3)[-1].trace
    assert m["polished_rod_load_n"].max() == pytest.approx(runs[-1].trace["polished_rod_load_n"].max(), rel=2e-3)


def test_equally_spaced_samples_with_a_given_spm(harmonic, tmp_path):
    runs, _ = harmonic
    last = runs[-1].trace
    card = _write(tmp_path / "pos.csv", {"polished_rod_position_m": last["polished_rod_position_m"]})
    with pytest.raises(ConfigError, match="surface.measured_spm"):
        _measured_sim(card)
    sim = _measured_sim(card, "surface.measured_spm=6")
    m = sim.run_strokes(3)[-1].trace
    # samples taken as starting at t = 0 instead of dt: the same stroke, shifted by one sample
    assert m["polished_rod_load_n"].max() == pytest.approx(last["polished_rod_load_n"].max(), rel=1e-3)


def test_measured_card_retimed_to_another_spm_matches_the_harmonic_run(harmonic, tmp_path):
    runs, _ = harmonic
    last = runs[-1].trace
    card = _write(tmp_path / "card.csv", {"t_s": last["t_s"] - last["t_s"][0],
                                          "polished_rod_position_m": last["polished_rod_position_m"]})
    ref = Simulator(load_config(FIG3)).run_strokes(2, spm=8.0)[-1].trace["polished_rod_load_n"]
    got = _measured_sim(card).run_strokes(2, spm=8.0)[-1].trace["polished_rod_load_n"]
    assert got.max() == pytest.approx(ref.max(), rel=1e-3)


@pytest.mark.parametrize("content, expect", [
    ("t_s,x\n" + "".join(f"{i},{i}\n" for i in range(20)), "missing polished_rod_position_m"),
    ("t_s,polished_rod_position_m\n0,0\n1,1\n", "at least 16 data rows"),
    ("t_s,polished_rod_position_m\n" + "".join(f"{i},{i % 5}\n" for i in range(19)) + "3,abc\n", "a number in column"),
    ("t_s,polished_rod_position_m\n" + "".join(f"{i % 10},{i % 5}\n" for i in range(20)), "strictly increasing t_s"),
    ("t_s,polished_rod_position_m\n" + "".join(f"{i},1.0\n" for i in range(20)), "zero stroke"),
])
def test_bad_card_files_are_one_line_exit_2(tmp_path, content, expect):
    bad = tmp_path / "bad.csv"
    bad.write_text(content)
    out = tmp_path / "out.csv"
    assert_cli_refuses(["simulate", FIG3, "--set", "surface.motion=measured", "--set",
                        f"surface.measured_card_csv={bad}", "--out", str(out)], out, "surface.measured_card_csv", expect)


def test_missing_card_file_is_refused_at_load():
    with pytest.raises(ConfigError, match="surface.measured_card_csv"):
        load_config(FIG3, ["surface.motion=measured"])


def test_env_runs_on_measured_motion(harmonic, tmp_path):
    import gymnasium as gym

    import srenv  # noqa: F401  (registers the env)

    runs, _ = harmonic
    last = runs[-1].trace
    card = _write(tmp_path / "card.csv", {"t_s": last["t_s"] - last["t_s"][0],
                                          "polished_rod_position_m": last["polished_rod_position_m"]})
    env = gym.make("srenv/SuckerRod-v0", config=FIG3, surface__motion="measured",
                   surface__measured_card_csv=card, control__randomize=False)
    obs, info = env.reset(seed=0)
    obs, reward, _term, _trunc, info = env.step(np.zeros(2, dtype=np.float32))
    assert np.all(np.isfinite(obs)) and np.isfinite(reward)
    assert info["polished_rod_stroke_m"] == pytest.approx(2.4, rel=1e-3)  # the card's stroke, not the action's
