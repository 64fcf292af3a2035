"""The card set's field variation (srenv.task.card_set.field_overrides, docs/cards_dataset.md): what real wells
vary per card is drawn within its declared ranges, the liquid spring only where the kernel combines it with
the condition's law, and each variation moves the card the way its physics says."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from srenv.analysis.condition_card import simulate_card
from srenv.physics.conditions import LABELS
from srenv.task import card_set as cs


def _draws(n: int = 400) -> list[cs.Draw]:
    return [cs.draw(4, i, 0, LABELS) for i in range(n)]


def test_draws_stay_in_their_ranges_and_the_spring_only_on_labels_that_combine_it() -> None:
    d = _draws()
    tau = np.array([x.kv_tau_s for x in d])
    assert tau.min() >= cs.KV_TAU_RANGE_S[0] and tau.max() <= cs.KV_TAU_RANGE_S[1] and tau.std() > 0.01
    spring = [x for x in d if x.oil_compressibility_per_pa > 0 or x.unanchored]
    assert spring and {x.label for x in spring} <= set(cs.SPRING_LABELS)
    assert all(x.oil_compressibility_per_pa > 0 for x in d if x.unanchored)  # unanchored only when compressible
    eligible = [x for x in d if x.label in cs.SPRING_LABELS]
    share = len(spring) / len(eligible)
    assert abs(share - cs.COMPRESSIBLE_SHARE) < 0.12
    assert abs(np.mean([x.column_mass for x in d]) - cs.COLUMN_MASS_SHARE) < 0.1
    lo, hi = cs.OIL_COMPRESSIBILITY_PER_PA
    assert all(lo <= x.oil_compressibility_per_pa <= hi for x in spring)


def test_the_set_records_what_was_drawn() -> None:
    card = cs.make_card(4, 0, ("full",))
    d = cs.draw(4, 0, 0, ("full",))
    w = card["well"]
    assert w["kv_tau_s"] == round(d.kv_tau_s, 6)
    assert (w["fluid_column_mass_kg"] > 0) == d.column_mass
    assert (w["liquid_compressibility_per_pa"] > 0) == (d.oil_compressibility_per_pa > 0)
    assert w["tubing_anchored"] == float(not d.unanchored)
    assert set(cs.WELL_COLUMNS) == set(w)


def test_compressible_cards_keep_the_chamber_law_their_sets_were_drawn_with():
    """The sets of runs 3-6 drew their compressible no-gas cards with both transfers over the top's chamber
    volume; srenv's default now gives the upstroke's the clearance alone (docs/realism.md), so the set pins the
    earlier law and a seed draws the same card as before."""
    d = next(x for x in _draws() if x.oil_compressibility_per_pa > 0)
    cfg = cs.card_config(d)
    assert cfg.pump.liquid_chamber_volume == "top_of_stroke" and cfg.pump.liquid_compressibility_per_pa > 0
    assert "pump.liquid_chamber_volume" not in cs.field_overrides(_plain(d), cfg)


def _plain(d: cs.Draw) -> cs.Draw:
    return dataclasses.replace(d, kv_tau_s=0.0, column_mass=False, oil_compressibility_per_pa=0.0, unanchored=False)


def _transfer_travel(card) -> float:
    """Plunger travel (share of its stroke) from the bottom until the pump load reaches 90 % of its range:
    the load transfer at the start of the upstroke."""
    x, y = card.pump_position_m, card.pump_load_n
    b = int(np.argmin(x))
    x, y = np.roll(x, -b), np.roll(y, -b)
    top = int(np.argmax(x))
    lo, hi = float(y.min()), float(y.max())
    reached = np.flatnonzero(y[: top + 1] >= lo + 0.9 * (hi - lo))
    return float((x[reached[0]] - x[0]) / (x[top] - x[0]))


def test_compressible_liquid_and_unanchored_tubing_stretch_the_load_transfer() -> None:
    base = _plain(dataclasses.replace(cs.draw(4, 0, 0, ("full",)), conventional=False))
    travel = [_transfer_travel(simulate_card(cs.card_config(d))) for d in (
        base, dataclasses.replace(base, oil_compressibility_per_pa=3e-9),
        dataclasses.replace(base, oil_compressibility_per_pa=3e-9, unanchored=True))]
    assert travel[0] < travel[1] < travel[2], travel


def test_kelvin_voigt_damping_calms_the_ringing() -> None:
    base = _plain(dataclasses.replace(cs.draw(4, 0, 0, ("full",)), conventional=False, damping_factor=0.02))

    def wiggle(card) -> float:  # total variation of the load beyond what a smooth card of its range has
        y = card.polished_rod_load_n
        return float(np.abs(np.diff(y)).sum() / np.ptp(y))

    w = [wiggle(simulate_card(cs.card_config(dataclasses.replace(base, kv_tau_s=t)))) for t in (0.0, 0.02, 0.05)]
    assert w[0] > w[1] > w[2], w


_SPRINGS = [{"pump.intake_gas_fraction": 0.3}, {"pump.liquid_compressibility_per_pa": 5e-10}, {"tubing.anchored": False}]
_TAGS = [{"pump.tag_bottom_overtravel_m": 0.1}, {"pump.tag_top_overtravel_m": 0.1}]
_REFUSED = [(s, c) for s in _SPRINGS for c in ({"pump.travelling_valve_leak_fraction": 1.0},
                                               {"pump.standing_valve_leak_fraction": 1.0})] + [
    (_SPRINGS[2], t) for t in _TAGS]
_COMPOSED = [(s, t) for s in _SPRINGS[:2] for t in _TAGS] + [(s, {"pump.tubing_leak_fraction": 0.5}) for s in _SPRINGS]


@pytest.mark.parametrize(("spring", "condition"), _REFUSED)
def test_a_condition_the_chamber_spring_would_drop_is_refused(spring, condition):
    """With free gas, a compressible chamber liquid or unanchored tubing the plunger meets the chamber's spring law,
    which does not carry the valve leaks: the card came out identical to the well without them. Tagging adds its
    contact to the spring, but not with unanchored tubing (the barrel's ends move with it). The
    config refuses the pair in one line naming the condition's field instead of dropping it."""
    from srenv.config import load_config
    from srenv.errors import ConfigError

    base = load_config("default")
    load_config(base, spring)  # each alone is a valid well
    load_config(base, condition)
    with pytest.raises(ConfigError) as ex:
        load_config(base, {**spring, **condition})
    assert ex.value.field == "pump." + next(iter(condition)).split(".")[1] and "spring" in str(ex.value)


@pytest.mark.parametrize(("spring", "condition"), _COMPOSED)
def test_a_condition_the_chamber_spring_carries_is_accepted(spring, condition):
    """Tagging composes with free gas and a compressible liquid, a tubing leak with every chamber spring
    (their mechanisms: tests/srenv/physics/test_load_transfer.py)."""
    from srenv.config import load_config

    cfg = load_config(load_config("default"), {**spring, **condition})
    name = next(iter(condition)).split(".")[1]
    assert getattr(cfg.pump, name) == condition["pump." + name]
