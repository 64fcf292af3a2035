"""``srenv bench``'s env modes include ``random_actions`` (issue 25: an RL agent changes the action every step),
with the same fields as the constant-action modes."""

from __future__ import annotations

import numpy as np
import pytest

from srenv.tools.bench_speed import (
    MODES,
    RANDOM_MODE,
    env_rates,
    mode_actions,
    split_bound,
    vector_actions,
    vector_rates,
)


def test_random_actions_mode_changes_the_action_every_step_from_a_fixed_seed() -> None:
    a, b = mode_actions(RANDOM_MODE), mode_actions(RANDOM_MODE)
    first = [next(a) for _ in range(5)]
    assert all(np.array_equal(x, next(b)) for x in first)  # the same actions in every run
    assert len({x.tobytes() for x in first}) == 5
    assert all(x.dtype == np.float32 and np.all(np.abs(x) <= 1.0) for x in first)
    const = mode_actions("full_speed")
    assert np.array_equal(next(const), np.float32(MODES["full_speed"]))


def test_bench_reports_random_actions_with_positive_rates() -> None:
    out = env_rates("srenv/SuckerRod-v2", steps=1, seeds=(11,))
    assert set(out) == {*MODES, RANDOM_MODE}
    row = out[RANDOM_MODE]
    assert set(row) == set(out["full_speed"])
    assert row["env_steps_per_cpu_s"] > 0 and row["with_resets_env_steps_per_cpu_s"] > 0
    assert row["exact_strokes_per_step"] >= 1  # a new setpoint: at least one exact stroke


def test_split_bound_lies_between_one_and_the_block_count() -> None:
    """The static-split bound (docs/speed.md §3): the slowest block's time summed over steps is at least the serial
    time / blocks and at most the serial time, so the bound is in [1, blocks]; one block is exactly serial."""
    out = split_bound("srenv/SuckerRod-v2", 3, steps=2)
    assert out["serial_ms_per_step"] > 0
    for key in ("contiguous_bound", "hindsight_bound"):
        assert 1.0 <= out[key] <= 2.0 + 1e-9
    one = split_bound("srenv/SuckerRod-v2", 2, steps=1, blocks=1)
    assert one["contiguous_bound"] == pytest.approx(1.0) and one["hindsight_bound"] == pytest.approx(1.0)


def test_vector_bench_modes_give_seeded_random_or_constant_actions() -> None:
    r = vector_actions(RANDOM_MODE, 3, 4)
    assert r.shape == (4, 3, 2) and r.dtype == np.float32 and np.all(np.abs(r) <= 1.0)
    assert np.array_equal(r, vector_actions(RANDOM_MODE, 3, 4)) and len({x.tobytes() for x in r[:, 0]}) == 4
    assert np.array_equal(vector_actions("idle", 2, 3), np.tile(np.float32(MODES["idle"]), (3, 2, 1)))
    out = vector_rates("srenv/SuckerRod-v1", sizes=(2,), steps=1, speedup_sizes=(2,), mode=RANDOM_MODE,
                       episode_hours=0.25)
    assert out["n2"]["env_steps_per_s"] > 0
    if out["threads"] > 1:  # a 1-core runner has no process figures
        assert out["process_speedup_by_n"]["2"] > 0
