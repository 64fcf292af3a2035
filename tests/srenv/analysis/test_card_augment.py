"""The opt-in instrument effects of the card augmentation (run 5, docs/conditions.md): the position a load-only
controller writes is a pure cosine of time with the loads kept by time, a lagging transducer moves the position
only, and without the option every array is what runs 1-4 drew, bit for bit. The opt-in spectral low-pass (run 6):
harmonic k's gain exp(-(k/K)^2), no phase shift, the card's mean and stroke kept; without it runs 1-5's arrays."""

from __future__ import annotations

import functools
import hashlib
import importlib.util
import json
from pathlib import Path

import numpy as np
import pytest
from conftest import run_on_avx2_numpy

from srenv.analysis.card_augment import (
    InstrumentAugment,
    SpectralAugment,
    augment,
    spectral_lowpass,
    synthesised_position,
)
from srenv.analysis.condition_card import Card
from srenv.analysis.field_model import position_is_synthesised
from srenv.surface_unit.beam_unit import ConventionalUnit
from srenv.surface_unit.unit_catalogue import get_unit

# sha256 of three augmented versions (seeds 0, 1, 2) of _card() by card_augment.augment as it was for runs 1-4
# (commit 6487e7b, before the instrument option existed)
RUNS_1_TO_4_SHA256 = "47d4e355e315e1a7a18bdaca1ac54d7f3ee353c150bb58a98402aba48d75bb3a"
# sha256 of six versions (seeds 0-5) with run 5's instrument effects (0.3 / 0.3), as card_augment.augment drew them
# for run 5 (commit a876802, before the spectral option existed)
RUN_5_SHA256 = "8b740d4b132494826251f1586313c4a393561995416043a328961bb334ba6283"


def _robustness():
    """scripts/conditions_robustness.py as a module."""
    path = Path(__file__).parents[3] / "scripts" / "conditions_robustness.py"
    spec = importlib.util.spec_from_file_location("conditions_robustness", path)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def _card(n: int = 256) -> tuple[np.ndarray, np.ndarray]:
    """A four-bar's polished-rod position at constant crank speed from the bottom, and a card-like load."""
    unit = ConventionalUnit(get_unit("C-114D-143-64"))
    phase = 2 * np.pi * np.arange(n) / n
    x = np.asarray(unit.position_m(unit.theta_bottom + phase), dtype=float)
    return x, 1e4 + 4e3 * np.tanh(8 * np.sin(phase)) + 300 * np.sin(3 * phase)


def pinned_digests() -> dict:
    """The digests the two tests below pin, computed in this interpreter (they run it on numpy's AVX2 kernels,
    as the digests were made: conftest.run_on_avx2_numpy)."""
    x, y = _card()
    inst = InstrumentAugment(0.3, 0.3)
    return {
        "runs_1_to_4": _digest([augment(x, y, np.random.default_rng(s)) for s in range(3)]),
        "runs_1_to_4_none": _digest([augment(x, y, np.random.default_rng(s), None, None) for s in range(3)]),
        "run_5": _digest([augment(x, y, np.random.default_rng(s), inst) for s in range(6)]),
        "run_5_none": _digest([augment(x, y, np.random.default_rng(s), inst, None) for s in range(6)]),
        # p = 0: the option draws (after runs 1-5's draws) but never filters
        "run_5_zero": _digest([augment(x, y, np.random.default_rng(s), inst, SpectralAugment(0.0)) for s in range(6)]),
    }


@functools.cache
def _pinned() -> dict:
    code = ("import importlib.util, json; spec = importlib.util.spec_from_file_location('t', "
            f"{str(Path(__file__).resolve())!r}); m = importlib.util.module_from_spec(spec); "
            "spec.loader.exec_module(m); print(json.dumps(m.pinned_digests()))")
    return json.loads(run_on_avx2_numpy(code))


def test_without_the_option_the_arrays_are_those_of_runs_1_to_4():
    assert _pinned()["runs_1_to_4"] == RUNS_1_TO_4_SHA256
    x, y = _card()
    outs = [augment(x, y, np.random.default_rng(s)) for s in range(3)]
    zero = [augment(x, y, np.random.default_rng(s), None) for s in range(3)]
    assert all(np.array_equal(a[0], b[0]) and np.array_equal(a[1], b[1]) for a, b in zip(outs, zero))


def test_synthesised_position_is_a_pure_cosine_on_the_cards_bottom_and_stroke():
    x, _ = _card()
    assert not position_is_synthesised(x)  # a real four-bar: 7-8 % of its first harmonic in the second
    s = synthesised_position(np.roll(x, 40))
    assert position_is_synthesised(s)
    assert int(np.argmin(s)) == 40 and s.min() == pytest.approx(x.min()) and np.ptp(s) == pytest.approx(np.ptp(x))
    assert np.max(np.abs(s - np.roll(x, 40))) > 0.03 * np.ptp(x)  # loads land at other positions


def test_augment_with_a_synthesised_position_keeps_the_loads_by_time():
    x, y = _card()
    inst = InstrumentAugment(synth_position_p=1.0)
    for seed in range(5):
        old_x, old_y = augment(x, y, np.random.default_rng(seed))
        new_x, new_y = augment(x, y, np.random.default_rng(seed), inst)
        assert np.array_equal(new_y, old_y)  # the same load at the same sample (time)
        assert position_is_synthesised(new_x) and not position_is_synthesised(old_x)
        assert len(new_x) == len(old_x)


def test_a_lagging_transducer_moves_the_position_not_the_loads():
    x, y = _card()
    old_x, old_y = augment(x, y, np.random.default_rng(3))
    lag_x, lag_y = augment(x, y, np.random.default_rng(3), InstrumentAugment(position_lag_p=1.0))
    assert np.array_equal(lag_y, old_y)
    assert not np.array_equal(lag_x, old_x) and not position_is_synthesised(lag_x)
    assert np.max(np.abs(lag_x - old_x)) < 0.1 * np.ptp(x)  # at most 3 % of the period late


def test_instrument_probabilities_outside_0_1_are_refused():
    with pytest.raises(ValueError, match="synth_position_p"):
        InstrumentAugment(synth_position_p=1.5)


def test_trainer_refuses_a_bad_probability_with_exit_2(capsys):
    from srenv.tools.train_classifier import main

    with pytest.raises(SystemExit) as exc:
        main(["--cards", "nowhere", "--out", "m.npz", "--synth-position-p", "1.5"])
    assert exc.value.code == 2 and "expected a probability in [0, 1]" in capsys.readouterr().err


def test_the_robustness_checks_synthesised_cards():
    mod = _robustness()
    x, y = _card()
    card = Card(np.arange(len(x)) * 0.01, x, y, x, y, 1.0)
    [(where, label, out)] = list(mod.synthesised([("w", "full", card)]))
    assert (where, label) == ("w", "full") and np.array_equal(out.polished_rod_load_n, y)
    assert position_is_synthesised(out.polished_rod_position_m)
    assert np.array_equal(out.polished_rod_position_m, synthesised_position(x))


def _digest(outs) -> str:
    return hashlib.sha256(b"".join(a.tobytes() + b.tobytes() for a, b in outs)).hexdigest()


def test_without_the_spectral_option_the_arrays_are_those_of_runs_1_to_5():
    d = _pinned()
    assert d["runs_1_to_4_none"] == RUNS_1_TO_4_SHA256
    assert d["run_5"] == d["run_5_none"] == d["run_5_zero"] == RUN_5_SHA256


@pytest.mark.parametrize("k_corner", [6.0, 10.0, 30.0])
def test_spectral_lowpass_gain_on_harmonic_k_is_as_declared_without_phase(k_corner):
    n = 240
    t = np.arange(n) / n
    harmonics = (1, 4, 10, 20, 45)
    y = 5.0 + sum(np.cos(2 * np.pi * k * t + 0.3 * k) for k in harmonics)
    c_in, c_out = np.fft.rfft(y), np.fft.rfft(spectral_lowpass(y, k_corner))
    for k in harmonics:
        assert abs(c_out[k]) / abs(c_in[k]) == pytest.approx(np.exp(-(k / k_corner) ** 2), rel=1e-9, abs=1e-12)
        if abs(c_out[k]) > 1e-6 * abs(c_in[k]):
            assert np.angle(c_out[k]) == pytest.approx(np.angle(c_in[k]), abs=1e-9)  # zero phase
    assert c_out[0] == pytest.approx(c_in[0])  # the mean kept
    assert spectral_lowpass(y, k_corner).shape == y.shape


def test_augment_with_the_low_pass_keeps_the_mean_and_stroke_and_smooths():
    x, y = _card()
    inst, smoothed = InstrumentAugment(0.3, 0.3), 0
    for seed in range(12):
        x0, y0 = augment(x, y, np.random.default_rng(seed), inst)
        x1, y1 = augment(x, y, np.random.default_rng(seed), inst, SpectralAugment(1.0))
        assert len(x1) == len(x0) and np.mean(y1) == pytest.approx(np.mean(y0), rel=1e-12)
        assert np.mean(x1) == pytest.approx(np.mean(x0), rel=1e-12)
        assert np.ptp(x1) == pytest.approx(np.ptp(x0), rel=0.05)  # K >= 6: the first harmonic keeps >= 97 %
        high0, high1 = (np.sum(np.abs(np.fft.rfft(v - v.mean())[20:]) ** 2) for v in (y0, y1))
        assert high1 < 0.7 * high0  # above the 20th harmonic, exp(-2 (20 / 30)^2) < 0.42 of the energy at most
        smoothed += 1
    assert smoothed == 12


def test_spectral_probabilities_outside_0_1_are_refused():
    with pytest.raises(ValueError, match="p="):
        SpectralAugment(p=-0.1)


@pytest.mark.parametrize("value", ["1.5", "-0.1", "nan", "half"])
def test_trainer_refuses_a_bad_spectral_probability_in_one_line(capsys, value):
    from srenv.tools.train_classifier import main

    with pytest.raises(SystemExit) as exc:
        main(["--cards", "nowhere", "--out", "m.npz", "--spectral-p", value])
    err = capsys.readouterr().err
    assert exc.value.code == 2 and err.count("\n") == 1
    assert "--spectral-p" in err and repr(value) in err and "expected a probability in [0, 1]" in err


def test_the_robustness_checks_smoothed_cards():
    mod = _robustness()
    x, y = _card()
    card = Card(np.arange(len(x)) * 0.01, x, y, x, y, 1.0)
    [(where, label, out)] = list(mod.smoothed([("w", "full", card)]))
    assert (where, label) == ("w", "full") and mod.SMOOTH_K == 10.0
    assert np.array_equal(out.polished_rod_load_n, spectral_lowpass(y, 10.0))
    assert np.array_equal(out.polished_rod_position_m, spectral_lowpass(x, 10.0))
    assert not np.array_equal(out.polished_rod_load_n, y)


def test_the_smoothed_check_runs_end_to_end(tmp_path, monkeypatch, capsys):
    mod = _robustness()
    out = tmp_path / "r.json"
    monkeypatch.setattr("sys.argv", ["x", "--checks", "v2_family", "v2_family_smooth", "--v2-wells", "1",
                                     "--out", str(out)])
    mod.main()
    report = json.loads(out.read_text())
    assert report["checks"] == ["v2_family", "v2_family_smooth"] and report["smooth_k"] == 10.0
    [row] = report["models"]
    assert row["v2_family_smooth"]["of"] == row["v2_family"]["of"] > 0  # the same cards, smoothed
    assert row["score"] == round((row["v2_family"]["right"] / row["v2_family"]["of"]
                                  + row["v2_family_smooth"]["right"] / row["v2_family_smooth"]["of"]) / 2, 4)
