"""Reading a pump card's load transfers and the top of its upstroke (srenv.analysis.transfer_reading), and
the given stiffness of free tubing (tubing.stiffness_n_m) that carries a compliance read that way."""

from __future__ import annotations

import numpy as np
import pytest

from srenv.analysis.transfer_reading import series_stiffness_n_m, tag_from_diagnosis, transfer_travel_m
from srenv.config import load_config
from srenv.errors import ConfigError
from srenv.simulation.simulator import Simulator

N = 4000
FLUID_N = 10e3


def _card(spring_n_m: float | None = None, tag_from_m: float | None = None, tag_n_m: float = 2e4):
    """A 1-m pump card in time, plunger x = (1 - cos)/2 (upstroke first): upstroke FLUID_N, downstroke 0;
    with a series spring both transfers take FLUID_N / k of travel; with a tag the upstroke climbs above
    tag_from_m at tag_n_m (and falls back the same way on the downstroke)."""
    ph = 2 * np.pi * np.arange(N) / N
    x = 0.5 * (1 - np.cos(ph))
    rising = ph < np.pi
    if spring_n_m is None:
        f = np.where(rising, FLUID_N, 0.0)
        f[0] = 0.0  # the bottom sample still carries the downstroke's load
    else:
        f = np.where(rising, np.minimum(FLUID_N, spring_n_m * x), np.maximum(0.0, FLUID_N - spring_n_m * (1 - x)))
    if tag_from_m is not None:
        f = f + tag_n_m * np.maximum(x - tag_from_m, 0.0)
    return x, f


def test_a_series_spring_is_read_off_the_transfer_travel():
    x, f = _card(spring_n_m=1e5)  # the transfer takes 0.1 m; its 10-90 % part 0.08 m
    t = transfer_travel_m(x, f)
    assert t["up"] == pytest.approx(0.08, abs=1e-3) and t["down"] == pytest.approx(0.08, abs=1e-3)
    assert series_stiffness_n_m(x, f) == pytest.approx(1e5, rel=0.02)
    x2, f2 = _card(spring_n_m=5e4)  # half as stiff: twice the travel
    assert transfer_travel_m(x2, f2)["up"] == pytest.approx(2 * t["up"], rel=0.02)
    assert series_stiffness_n_m(x2, f2) == pytest.approx(5e4, rel=0.02)


def test_a_rigid_transfer_reads_no_spring_and_no_tag():
    x, f = _card()
    t = transfer_travel_m(x, f)
    assert abs(t["up"]) < 1e-3 and abs(t["down"]) < 1e-3
    assert series_stiffness_n_m(x, f) is None
    assert tag_from_diagnosis(x, f) is None


def test_a_climb_at_the_top_of_the_upstroke_is_read_as_tagging_up():
    x, f = _card(tag_from_m=0.7)  # climbs 6 kN over the top 0.3 m
    tag = tag_from_diagnosis(x, f)
    assert tag is not None
    assert tag["climb_start_m"] == pytest.approx(0.7, abs=0.04)
    assert tag["tag_top_overtravel_m"] == pytest.approx(0.3, abs=0.04)
    assert tag["plateau_n"] == pytest.approx(FLUID_N, rel=1e-6)
    # the climb is the top band's median (0.85-1 m): between its ends, 3 and 6 kN
    assert 3e3 < tag["climb_n"] < 6e3
    x2, f2 = _card(tag_from_m=0.95)  # a climb of at most 1 kN, 10 % of the range: not read as a tag
    assert tag_from_diagnosis(x2, f2) is None


FIG3 = "paper_fig3_vertical"


def test_a_given_tubing_stiffness_replaces_the_one_from_its_size():
    free = Simulator(load_config(FIG3, ["tubing.anchored=false"]))
    k = free.tubing_stiffness_n_m
    given = Simulator(load_config(FIG3, ["tubing.anchored=false", f"tubing.stiffness_n_m={k!r}"]))
    assert given.tubing_stiffness_n_m == k
    a, b = free.run_stroke().trace, given.run_stroke().trace
    assert np.array_equal(a["polished_rod_load_n"], b["polished_rod_load_n"])  # the same spring, bit for bit
    soft = Simulator(load_config(FIG3, ["tubing.anchored=false", f"tubing.stiffness_n_m={k / 2!r}"]))
    c = soft.run_stroke().trace
    # half the stiffness, twice the travel of the load transfer (and the reading finds it)
    t_free = transfer_travel_m(a["pump_position_m"], a["pump_load_n"])["up"]
    assert transfer_travel_m(c["pump_position_m"], c["pump_load_n"])["up"] == pytest.approx(2 * t_free, rel=0.1)
    assert series_stiffness_n_m(a["pump_position_m"], a["pump_load_n"]) == pytest.approx(k, rel=0.1)
    with pytest.raises(ConfigError, match="tubing.stiffness_n_m"):
        load_config(FIG3, ["tubing.stiffness_n_m=1e5"])  # anchored tubing has no stretch to give
