"""v2's reset parses a split well's config once (docs/speed.md §2j): the family's mapping with v2's per-well
physics applied gives the config v1's way gives (the family's config parsed, then parsed again through
``load_config`` with the physics), equal field by field, on every well of the train, test and validation
splits; overrides that change the well take v1's way (they are applied before the physics)."""

from __future__ import annotations

import gymnasium as gym
import pytest

import srenv  # noqa: F401
from srenv.config import apply_overrides, config_from_dict, load_config
from srenv.envs import sucker_rod_v1
from srenv.envs.sucker_rod_v2 import physics_overrides
from srenv.task import v2_physics as vp
from srenv.task import well_family as wf

ID = "srenv/SuckerRod-v2"
REGISTERED = {"task.episode_hours": 12.0, "task.interval_s": 300.0}  # what gym.make passes (restated)


def _two_parses(split: str, index: int, overrides: dict) -> object:
    """v1's way (before docs/speed.md §2j): the family's config, the env's overrides, then the physics on top."""
    spec = wf.build_spec(split, index)
    if not all(sucker_rod_v1.restates(spec.cfg, k, v) for k, v in overrides.items()):
        spec = wf.WellSpec(spec.well_id, spec.params, load_config(spec.cfg, overrides), spec.nominal_rate_m3_day,
                           spec.design)
    return load_config(spec.cfg, vp.yield_to(physics_overrides(spec), overrides))


@pytest.mark.parametrize("split", ["train", "test", "validation"])
def test_one_parse_gives_the_two_parses_config_on_every_well(split: str) -> None:
    for index in range(wf.split_size(split)):
        pre = wf.build_spec(split, index, parse=False)
        assert pre.cfg is None and pre.raw is not None
        parsed = wf.build_spec(split, index)
        assert parsed.params == pre.params and parsed.design == pre.design
        assert vp.installed_point(pre) == vp.installed_point(parsed)  # the mapping's numbers are the config's
        over = vp.yield_to(physics_overrides(pre), REGISTERED)
        assert over == physics_overrides(parsed)
        one = config_from_dict(apply_overrides(pre.raw, over, owned=True))
        assert one == _two_parses(split, index, REGISTERED), (split, index)


def test_the_env_parses_a_new_well_once_and_keeps_it(monkeypatch: pytest.MonkeyPatch) -> None:
    import srenv.config

    env = gym.make(ID, scenario="train").unwrapped
    parses: list[str] = []

    def counted(module, name: str) -> None:
        real = getattr(module, name)
        monkeypatch.setattr(module, name, lambda *a, **k: parses.append(name) or real(*a, **k))

    counted(sucker_rod_v1, "load_config")  # v1's overrides
    counted(srenv.config, "load_config")  # v1's way of the physics (sucker_rod_v2._with_physics)
    counted(wf, "config_from_dict")  # the family's own parse
    env.reset(seed=37)
    assert parses == []
    assert env.cfg == _two_parses("train", 37, REGISTERED)
    parses.clear()  # the helper's own parses
    spec = env.well
    env.reset(seed=37)  # seen: the kept spec
    assert env.well is spec and parses == []


@pytest.mark.parametrize("overrides", [
    {"economics.oil_price_usd_m3": 400.0},  # not a task field: v1's way
    {"task.interval_s": 600.0},  # a task field the well does not have: v1's way, applied
    {"task.episode_hours": 0.5},
    {"surface.motion": "harmonic"},  # the caller's motion wins over the physics' unit
])
def test_overrides_that_change_the_well_give_v1s_way(overrides: dict) -> None:
    env = gym.make(ID, scenario="train", overrides=overrides).unwrapped
    env.reset(seed=4)
    want = _two_parses("train", 4, {**REGISTERED, **overrides})
    assert env.cfg == want
    for key, value in overrides.items():
        section, name = key.split(".")
        assert getattr(getattr(env.cfg, section), name) == value
