"""The operator's well file (srenv/task/well_file.py): only whitelisted equipment, never hidden truth; its twin has
the well's equipment; bad files refused in one line naming the field, the value and what is expected."""

from __future__ import annotations

import json

import pytest

from srenv.config import to_dict
from srenv.envs.sucker_rod_v2 import SuckerRodV2Env
from srenv.task import well_family as wf
from srenv.task.well_file import NOMINAL, WHITELIST, read_well_file, twin_config, well_file

HIDDEN_CFG = {"inflow": ("model", "reservoir_pressure_pa", "productivity_index_m3_day_pa", "max_rate_m3_day",
                         "initial_fluid_level_m"),
              "friction": ("coefficient",), "damping": ("damping_factor",), "task": ("inflow_decline_per_day",),
              "economics": ("water_cut",)}


@pytest.fixture(scope="module")
def played():
    env = SuckerRodV2Env(scenario="train")
    env.reset(seed=31)
    return env


def _leaves(d, prefix=""):
    for k, v in d.items():
        yield prefix + k
        if isinstance(v, dict) and prefix == "":
            yield from _leaves(v, prefix + k + ".")


def test_the_file_holds_only_whitelisted_keys(played):
    f = well_file(played)
    allowed = set(WHITELIST) | {f"{s}.{k}" for s, ks in WHITELIST.items() for k in ks}
    assert set(_leaves(f)) == allowed
    for sec, keys in HIDDEN_CFG.items():  # the reservoir, friction, damping, decline: never in the file
        assert not set(keys) & set(f.get(sec, {}))
    text = json.dumps(f)  # and no hidden parameter by name anywhere
    for name in wf.PARAM_RANGES:
        if name not in ("depth_m", "unit_stroke_m", "plunger_diameter_mm"):  # equipment, under other names
            assert name not in text


def _outside_whitelist(cfg_dict):
    """Every (section, field) of a well's full config that the whitelist leaves out: generated, so a key added to
    the whitelist without cause shows here as one the reader accepts."""
    for sec, block in cfg_dict.items():
        if not isinstance(block, dict):
            yield sec, None
            continue
        for k in block:
            if k not in WHITELIST.get(sec, ()):
                yield sec, k


def test_every_key_outside_the_whitelist_is_refused(played):
    f = well_file(played)
    full = to_dict(played.unwrapped.well.cfg)
    cases = list(_outside_whitelist(full))
    assert len(cases) > 60 and ("inflow", "reservoir_pressure_pa") in cases and ("task", "inflow_decline_per_day") in cases
    for sec, k in cases:
        bad = json.loads(json.dumps(f))
        if k is None:
            bad[sec] = full[sec]
        else:
            bad.setdefault(sec, {})[k] = full[sec][k]
        with pytest.raises(ValueError) as exc:
            read_well_file(bad)
        msg = str(exc.value)
        assert (k or sec) in msg and "expected" in msg and "\n" not in msg


def test_the_twin_has_the_wells_equipment_and_nominal_unknowns(played):
    well = to_dict(played.unwrapped.well.cfg)
    twin = to_dict(twin_config(well_file(played)))
    for sec, keys in WHITELIST.items():
        for k in keys:
            assert twin[sec][k] == well[sec][k], f"{sec}.{k}"
    assert twin["simulation"] == well["simulation"]  # same discretisation of the same string
    assert twin["damping"]["stiffness_proportional_s"] == well["damping"]["stiffness_proportional_s"]
    assert twin["economics"]["water_cut"] == pytest.approx(well["economics"]["water_cut"], abs=1e-6)
    # what the file does not say is the family's nominal value, not the well's
    assert twin["friction"]["coefficient"] == NOMINAL["friction_coefficient"] != well["friction"]["coefficient"]
    assert twin["damping"]["damping_factor"] == NOMINAL["damping_factor"]
    assert twin["task"]["inflow_decline_per_day"] == 0.0 != well["task"]["inflow_decline_per_day"]
    assert twin["inflow"]["max_rate_m3_day"] == pytest.approx(played.unwrapped.well.nominal_rate_m3_day, rel=1e-5)


def test_a_file_round_trips_through_yaml(played, tmp_path):
    import yaml

    f = well_file(played)
    p = tmp_path / "well.yaml"
    p.write_text(yaml.safe_dump(f))
    assert read_well_file(p) == f
    j = tmp_path / "well.json"
    j.write_text(json.dumps(f))
    assert read_well_file(str(j)) == f


@pytest.mark.parametrize("edit,needle", [
    (lambda f: [f], "well file"),                                           # not a mapping
    (lambda f: "rod: 1", "well file"),
    (lambda f: {**f, "rod": 3}, "rod"),                                     # a section that is not a mapping
    (lambda f: {k: v for k, v in f.items() if k != "pump"}, "pump"),       # a section missing
    (lambda f: {**f, "fluid": {"density_kg_m3": 900.0}}, "wellhead_pressure_pa"),  # a field missing
    (lambda f: {**f, "fluid": {**f["fluid"], "density_kg_m3": -5.0}}, "fluid.density_kg_m3"),  # out of bounds
    (lambda f: {**f, "pump": {**f["pump"], "plunger_diameter_mm": 1e9}}, "pump.plunger_diameter_mm"),
    (lambda f: {**f, "control": {**f["control"], "spm_max": "fast"}}, "control.spm_max"),
    (lambda f: {**f, "rod": {"tapers": "steel"}}, "rod.tapers"),
])
def test_bad_files_refused_in_one_line(played, edit, needle):
    with pytest.raises(ValueError) as exc:
        read_well_file(edit(well_file(played)))
    msg = str(exc.value)
    assert needle in msg and "expected" in msg and "\n" not in msg


def test_bad_yaml_file_refused_as_data(tmp_path):
    p = tmp_path / "w.yaml"
    p.write_text("!!python/object/apply:os.system ['true']\n")
    with pytest.raises(ValueError) as exc:
        read_well_file(p)
    assert "\n" not in str(exc.value)
    with pytest.raises(ValueError, match="expected"):
        well_file(object())
