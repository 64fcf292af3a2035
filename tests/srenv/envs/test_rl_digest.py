"""v1 (default and ``fast_stepping``) and v2 give the observations, rewards and infos of 25d9225, to the bit,
under random (a new action every step: an RL agent) and constant actions: the changing-action step's fast paths
(issue 25, docs/speed.md §2d) move no result. The digests were computed by ``scripts/rl_digest.py`` on a checkout
of 25d9225 (``PYTHONPATH=/tmp/rl_before python scripts/rl_digest.py``) on an AVX2 machine; they are recomputed in a
fresh interpreter on numpy's AVX2 kernels (conftest.run_on_avx2_numpy), so they hold on AVX-512 CPUs too."""

from __future__ import annotations

import importlib.util
from pathlib import Path

import pytest
from conftest import run_on_avx2_numpy

AT_25D9225 = {
    "v1/random": "11199c5c867f5179f93a34f85a2efb24d4aecfb8a991daad0f4e063d74558dc3",
    "v1/constant": "736c2ef7edfead7b0c11c3f2d1dae400489d96dd52b0d186e0217aee7698a2a3",
    "v1_fast/random": "11199c5c867f5179f93a34f85a2efb24d4aecfb8a991daad0f4e063d74558dc3",
    "v1_fast/constant": "d76048af02780fa88335f1e5dcce7fe1c39350997f9083850472c0afb07fd11c",
    "v2/random": "62b47d5f9b25c2f94cab29999e64d70739cd1a53b38ce43b3d43d4a6a959d173",
    "v2/constant": "0a8ffad33fa2557f3876619e9454be056339e81dc3df474cc4585d142083f9c6",
}


def _pinned(call: str) -> str:
    """``rl_digest.CALL`` on numpy's AVX2 kernels (conftest.run_on_avx2_numpy: how the digests were made)."""
    return run_on_avx2_numpy(f"import sys; sys.path.insert(0, 'scripts'); import rl_digest; print(rl_digest.{call})").strip()


def _digest_module():
    spec = importlib.util.spec_from_file_location("rl_digest", Path(__file__).parents[3] / "scripts" / "rl_digest.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


# v1_fast/random is v1/random's digest (random actions never hold a setpoint for fast_stepping's reuse): not rerun
@pytest.mark.parametrize("case", ["v1/random", "v1/constant", "v1_fast/constant", "v2/random", "v2/constant"])
def test_episodes_are_those_of_25d9225_to_the_bit(case: str) -> None:
    mod = _digest_module()
    name, policy = case.split("/")
    env_id, kwargs = mod.CASES[name]
    assert _pinned(f"digest({env_id!r}, {kwargs!r}, {policy!r})") == AT_25D9225[case]


def test_the_digest_sees_a_changed_bit() -> None:
    mod = _digest_module()
    env_id, kwargs = mod.CASES["v2"]
    assert mod.digest(env_id, kwargs, "random", seeds=(1,), steps=2) \
        != mod.digest(env_id, kwargs, "random", seeds=(2,), steps=2)


# The acceptance's speed protocol (acceptance/speed: warm-up step on seed 3, then seeds 11 and 12, 12 steps each at
# a constant action), computed by scripts/rl_digest.py on a checkout of 67d2e08 (main before issue 25's fifth round,
# docs/speed.md §2e): its fast paths move no result of v1 or v2.
AT_67D2E08 = {
    "v1/acceptance_full_speed": "2f9954d13483b2540627f83b222ef997760cdfa3326cb413d2c75380ed9aefa0",
    "v1/acceptance_vsd_minimum": "79bd8cfa6b2bd36182ce19b3698c24bf6280f210ea1c62e81c157846269097ab",
    "v2/acceptance_full_speed": "41f179cfc7076d6ca68d616d0865f08c1001254fe22226fb6539b817581ab553",
    "v2/acceptance_vsd_minimum": "43dec696259b827da09d5dbc862d0e69d1712451083a6c354fb90ce26504c9ea",
}


@pytest.mark.parametrize("case", sorted(AT_67D2E08))
def test_acceptance_protocol_is_that_of_67d2e08_to_the_bit(case: str) -> None:
    mod = _digest_module()
    name, protocol = case.split("/")
    a0 = mod.ACCEPTANCE_ACTIONS[protocol.removeprefix("acceptance_")]
    assert _pinned(f"acceptance_digest('srenv/SuckerRod-{name}', {a0!r})") == AT_67D2E08[case]
