"""The card set's ``--surface v2`` (run 4's set, docs/cards_dataset.md): every card driven by its well's own v2
unit (srenv.task.v2_physics' geometry draw and sizing), the operating corners populated; the default
``family`` sets keep their draws (sets 1-3 reproducible)."""

from __future__ import annotations

import dataclasses
import json

import numpy as np
import pytest

from srenv.physics.conditions import LABELS
from srenv.task import card_set as cs
from srenv.task import v2_physics
from srenv.task import well_family as wf


def test_family_draws_are_the_old_sets_draws() -> None:
    """Pinned from the generator before --surface existed (set 2 and set 3's cards: the same numbers)."""
    d = cs.draw(2, 5, 0, LABELS)
    assert (d.well_seed, d.label, d.conventional, d.surface) == (12000007, "tubing_leak", True, "family")
    assert (d.severity, d.spm, d.stroke_length_m, d.damping_factor, d.kv_tau_s) == pytest.approx(
        (0.7581475855586228, 0.5139709600702952, 0.8204508052070268, 0.7359221156313422, 0.04274478453244854),
        rel=1e-12)
    d = cs.draw(3, 1, 0, LABELS)
    assert (d.well_seed, d.label, d.spm, d.stroke_length_m) == (13000009, "flowing", pytest.approx(
        0.34136758203912354, rel=1e-12), pytest.approx(0.4274453739986771, rel=1e-12))


def test_v2_draws_keep_every_other_field_and_populate_the_corners() -> None:
    fam = [cs.draw(4, i, 0, LABELS) for i in range(800)]
    v2 = [cs.draw(4, i, 0, LABELS, "v2") for i in range(800)]
    for a, b in zip(fam, v2):
        assert dataclasses.replace(b, spm=a.spm, stroke_length_m=a.stroke_length_m, conventional=a.conventional,
                                   surface="family") == a
    for name in ("spm", "stroke_length_m"):
        x = np.array([getattr(b, name) for b in v2])
        assert abs(np.mean(x == 0.0) - cs.CORNER_SHARE) < 0.05 and abs(np.mean(x == 1.0) - cs.CORNER_SHARE) < 0.05
        inner = x[(x > 0) & (x < 1)]
        assert inner.size > 300 and 0.4 < inner.mean() < 0.6
    corner = np.mean([b.spm in (0.0, 1.0) and b.stroke_length_m in (0.0, 1.0) for b in v2])
    assert 0.18 < corner < 0.32  # a quarter of the cards exactly on a corner
    with pytest.raises(ValueError, match="surface"):
        cs.draw(4, 0, 0, LABELS, "catalogue")


def test_a_v2_card_runs_the_wells_own_v2_unit_at_the_drawn_corner() -> None:
    d = next(d for d in (cs.draw(4, i, 0, ("full",), "v2") for i in range(64))
             if d.spm == 1.0 and d.stroke_length_m == 0.0)
    cfg = cs.card_config(d)
    spec = wf.spec_from_params(wf.draw_params(d.well_seed), "w")
    assert cfg.surface.motion == "beam_unit" and cfg.surface.beam_unit.crank_follows_stroke
    assert cfg.surface.beam_unit.geometry == v2_physics.draw_geometry(spec.params)
    assert cfg.surface.beam_unit.a_m == v2_physics.unit_block(spec, cfg.surface.beam_unit.geometry)["a_m"]
    c = spec.cfg.control
    assert cfg.surface.spm == pytest.approx(c.spm_max) and cfg.surface.stroke_length_m == pytest.approx(c.stroke_min_m)
    geometries = {v2_physics.draw_geometry(wf.draw_params(cs.draw(4, 4 * k, 0, LABELS, "v2").well_seed))
                  for k in range(40)}
    assert geometries == {"conventional", "mark_ii", "air_balanced"}


def test_cards_cli_v2_surface_records_the_unit(tmp_path) -> None:
    from srenv.task.card_set import load_cards
    from srenv.tools.cli import main

    for surface in ("v2", "family"):
        out = tmp_path / surface
        assert main(["cards", "--n", "2", "--seed", "4", "--out", str(out), "--workers", "1", "--no-progress",
                     "--conditions", "full", "--surface", surface]) == 0
        cols = load_cards(str(out / "cards.npz"))
        meta = json.loads((out / "dataset_card.json").read_text())
        if surface == "v2":
            assert set(cols["unit_geometry"]) <= {"conventional", "mark_ii", "air_balanced"}
            assert meta["surface"] == "v2" and np.all(cols["conventional_unit"] == 0.0)
        else:  # the family set's files have no new column or key (the old sets' bytes)
            assert "unit_geometry" not in cols and "surface" not in meta
