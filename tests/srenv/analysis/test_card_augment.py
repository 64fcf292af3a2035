"""The opt-in instrument effects of the card augmentation (run 5, docs/conditions.md): the position a load-only
controller writes is a pure cosine of time with the loads kept by time, a lagging transducer moves the position
only, and without the option every array is what runs 1-4 drew, bit for bit."""

from __future__ import annotations

import hashlib
import importlib.util
from pathlib import Path

import numpy as np
import pytest

from srenv.analysis.card_augment import InstrumentAugment, augment, synthesised_position
from srenv.analysis.condition_card import Card
from srenv.analysis.field_model import position_is_synthesised
from srenv.surface_unit.beam_unit import ConventionalUnit
from srenv.surface_unit.unit_catalogue import get_unit

# sha256 of three augmented versions (seeds 0, 1, 2) of _card() by card_augment.augment as it was for runs 1-4
# (commit 6487e7b, before the instrument option existed)
RUNS_1_TO_4_SHA256 = "47d4e355e315e1a7a18bdaca1ac54d7f3ee353c150bb58a98402aba48d75bb3a"


def _card(n: int = 256) -> tuple[np.ndarray, np.ndarray]:
    """A four-bar's polished-rod position at constant crank speed from the bottom, and a card-like load."""
    unit = ConventionalUnit(get_unit("C-114D-143-64"))
    phase = 2 * np.pi * np.arange(n) / n
    x = np.asarray(unit.position_m(unit.theta_bottom + phase), dtype=float)
    return x, 1e4 + 4e3 * np.tanh(8 * np.sin(phase)) + 300 * np.sin(3 * phase)


def test_without_the_option_the_arrays_are_those_of_runs_1_to_4():
    x, y = _card()
    outs = [augment(x, y, np.random.default_rng(s)) for s in range(3)]
    assert hashlib.sha256(b"".join(a.tobytes() + b.tobytes() for a, b in outs)).hexdigest() == RUNS_1_TO_4_SHA256
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
    path = Path(__file__).parents[3] / "scripts" / "conditions_robustness.py"
    spec = importlib.util.spec_from_file_location("conditions_robustness", path)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    x, y = _card()
    card = Card(np.arange(len(x)) * 0.01, x, y, x, y, 1.0)
    [(where, label, out)] = list(mod.synthesised([("w", "full", card)]))
    assert (where, label) == ("w", "full") and np.array_equal(out.polished_rod_load_n, y)
    assert position_is_synthesised(out.polished_rod_position_m)
    assert np.array_equal(out.polished_rod_position_m, synthesised_position(x))
