"""Bad configs are refused with one clear line naming the field, the value and the unit.

Every case goes through the CLI (``srenv.tools.cli.main`` in-process, a few through a real subprocess): exit
status 2, exactly one line on stderr, no traceback, and neither the ``--out`` CSV nor the ``--plot`` PNG
(nor a temporary file of the atomic writer) left behind.
"""

from __future__ import annotations

import copy
import dataclasses
import math
import re
import subprocess
import sys
import warnings
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest
import yaml

from srenv.config import CONFIG_DIR, load_config, read_raw
from srenv.errors import ConfigError
from srenv.tools.cli import EXIT_BAD_INPUT, main

FIG3 = "paper_fig3_vertical"
FIG4 = "paper_fig4_deviated"
FIG6 = "paper_fig6_nonmonotone"
# Fig. 6 with v0 = 0.3 m/s: the nonmonotone slope (P0 - Pinf)/v0 = 13.3 kN*s/m sits between the condensed
# pump stiffness at dt = 5 ms (15.7 kN*s/m, convex) and at dt = 20 ms (11.6 kN*s/m, not convex).
STEEP_FIG6 = ["pump.reference_velocity_m_s=0.3"]


@dataclasses.dataclass(frozen=True)
class Case:
    """A bad config: a shipped base, ``--set`` overrides and/or an edit of the raw YAML mapping."""

    base: str
    sets: tuple[str, ...] = ()
    edit: Callable[[dict], Any] | None = None
    # what the one-line message must contain
    field: str = ""
    value: str = ""
    expect: str = ""


def _drop(path: list[Any]) -> Callable[[dict], None]:
    def edit(data: dict) -> None:
        node = data
        for key in path[:-1]:
            node = node[key]
        del node[path[-1]]
    return edit


def _put(path: list[Any], value: Any) -> Callable[[dict], None]:
    def edit(data: dict) -> None:
        node = data
        for key in path[:-1]:
            node = node[key]
        node[path[-1]] = value
    return edit


def _case(base: str, *sets: str, edit: Callable[[dict], Any] | None = None, field: str, value: str,
          expect: str, id: str) -> Any:
    return pytest.param(Case(base, sets, edit, field, value, expect), id=id)


CASES = [
    # negative
    _case(FIG3, "surface.spm=-6", field="surface.spm", value="-6", expect="strokes/min", id="negative-spm"),
    _case(FIG3, "rod.tapers.0.length_m=-624", field="rod.tapers[0].length_m", value="-624",
          expect="positive number in m", id="negative-taper-length"),
    _case(FIG3, "fluid.density_kg_m3=-850", field="fluid.density_kg_m3", value="-850",
          expect="non-negative number in kg/m^3", id="negative-fluid-density"),
    _case(FIG3, "pump.plunger_friction_n=-500", field="pump.plunger_friction_n", value="-500",
          expect="non-negative number in N", id="negative-plunger-friction"),
    _case(FIG4, "friction.coefficient=-0.1", field="friction.coefficient", value="-0.1",
          expect="non-negative number", id="negative-friction"),
    # zero
    _case(FIG3, "simulation.time_step_s=0", field="simulation.time_step_s", value="0",
          expect="positive number in s", id="zero-time-step"),
    _case(FIG3, "rod.tapers.1.diameter_mm=0", field="rod.tapers[1].diameter_mm", value="0",
          expect="positive number in mm", id="zero-diameter"),
    _case(FIG3, "rod.tapers.0.youngs_modulus_pa=0", field="rod.tapers[0].youngs_modulus_pa", value="0",
          expect="positive number in Pa", id="zero-youngs-modulus"),
    _case(FIG3, "surface.stroke_length_m=0", field="surface.stroke_length_m", value="0",
          expect="positive number in m", id="zero-stroke"),
    # NaN (YAML's .nan arrives as a float: finiteness, not type, must catch it)
    _case(FIG3, "pump.upstroke_load_n=.nan", field="pump.upstroke_load_n", value="nan",
          expect="finite number in N", id="nan-load"),
    _case(FIG3, "rod.tapers.0.density_kg_m3=.nan", field="rod.tapers[0].density_kg_m3", value="nan",
          expect="kg/m^3", id="nan-density"),
    _case(FIG3, edit=_put(["simulation", "element_length_m"], float("nan")), field="simulation.element_length_m",
          value="nan", expect="positive number in m", id="nan-in-yaml-file"),
    # infinite
    _case(FIG3, "surface.spm=.inf", field="surface.spm", value="inf", expect="strokes/min", id="inf-spm"),
    _case(FIG3, "pump.downstroke_load_n=-.inf", field="pump.downstroke_load_n", value="-inf",
          expect="finite number in N", id="minus-inf-load"),
    _case(FIG3, edit=_put(["rod", "tapers", 0, "length_m"], math.inf), field="rod.tapers[0].length_m",
          value="inf", expect="m", id="inf-in-yaml-file"),
    # strings where numbers belong
    _case(FIG3, "surface.spm=fast", field="surface.spm", value="'fast'", expect="strokes/min", id="string-spm"),
    _case(FIG3, "pump.upstroke_load_n=9.5 kN", field="pump.upstroke_load_n", value="'9.5 kN'",
          expect="in N", id="string-with-unit"),
    _case(FIG3, "simulation.time_step_s=nan", field="simulation.time_step_s", value="'nan'",
          expect="in s", id="string-nan"),
    _case(FIG4, "survey.stations.1.inclination_deg=abc", field="survey.stations[1].inclination_deg",
          value="'abc'", expect="angle in [0, 180] in deg", id="string-inclination"),
    _case(FIG3, "simulation.dc_max_iterations=2.5", field="simulation.dc_max_iterations", value="2.5",
          expect="integer", id="fractional-integer"),
    _case(FIG3, "simulation.always_qp=1", field="simulation.always_qp", value="1", expect="true or false",
          id="int-for-bool"),
    _case(FIG3, "surface.motion=rotary", field="surface.motion", value="'rotary'",
          expect="one of harmonic, conventional, pullout", id="unknown-motion"),
    # unknown keys
    _case(FIG3, "pump.upstroke_load_kn=9.5", field="pump.upstroke_load_kn", value="9.5",
          expect="no such field", id="unknown-key"),
    _case(FIG3, edit=_put(["wells"], 1), field="wells", value="1", expect="no such field", id="unknown-section"),
    _case(FIG3, edit=_put(["rod", "tapers", 0, "diameter_in"], 0.875), field="rod.tapers[0].diameter_in",
          value="0.875", expect="no such field", id="unknown-taper-key"),
    # missing keys
    _case(FIG3, edit=_drop(["rod", "tapers", 1, "length_m"]), field="rod.tapers[1].length_m", value="None",
          expect="required) in m", id="missing-taper-length"),
    _case(FIG3, edit=_drop(["rod", "tapers", 0, "diameter_mm"]), field="rod.tapers[0].diameter_mm",
          value="None", expect="required) in mm", id="missing-diameter"),
    _case(FIG4, edit=_drop(["survey", "stations", 1, "md_m"]), field="survey.stations[1].md_m", value="None",
          expect="required) in m", id="missing-survey-depth"),
    _case(FIG3, edit=_put(["rod", "tapers"], []), field="rod.tapers", value="[]", expect="at least one taper",
          id="no-tapers"),
    # inconsistencies
    _case(FIG3, "pump.downstroke_load_n=9500", field="pump.downstroke_load_n", value="9500",
          expect="below pump.upstroke_load_n = 9500.0", id="p-plus-equals-p-minus"),
    _case(FIG3, "pump.downstroke_load_n=12000", field="pump.downstroke_load_n", value="12000",
          expect="load in N below", id="p-plus-above-p-minus"),
    _case(FIG4, "survey.stations.1.md_m=0", field="survey.stations[1].md_m", value="0.0",
          expect="depth in m greater than the previous", id="survey-depth-repeated"),
    _case(FIG4, "survey.stations.1.md_m=1000", field="survey.stations[2].md_m", value="992.0",
          expect="depth in m greater than the previous station's 1000", id="survey-depth-decreasing"),
    _case(FIG4, "survey.stations.2.md_m=900", field="survey.stations[2].md_m", value="900",
          expect="reaching the pump at 992.0 m", id="survey-shorter-than-string"),
    _case(FIG4, "rod.tapers.0.length_m=400", field="survey.stations[2].md_m", value="992.0",
          expect="reaching the pump at 1064.0 m", id="tapers-beyond-survey"),
    _case(FIG3, "surface.motion=conventional", "surface.crank_hole=3", field="surface.crank_hole", value="3",
          expect="0..2 (0 = longest stroke)", id="crank-hole-beyond-unit"),
    _case(FIG3, "surface.motion=conventional", "surface.unit=C-999D-999-999", field="surface.unit",
          value="'C-999D-999-999'", expect="designation from the unit catalogue", id="unknown-unit"),
    _case(FIG6, *STEEP_FIG6, "simulation.time_step_s=0.02", field="simulation.time_step_s", value="0.02",
          expect="a time step in s below", id="time-step-breaks-convexity"),
    _case(FIG3, "simulation.qp_solver=gurobi", field="simulation.qp_solver", value="'gurobi'",
          expect="installed qpsolvers backend", id="unknown-qp-solver"),
    _case(FIG3, "simulation.element_length_m=2000", field="simulation.element_length_m", value="2000",
          expect="no longer than the rod (1064.0 m)", id="element-longer-than-rod"),
    _case(FIG3, "control.spm_min=12", field="control.spm_max", value="10.0", expect="strokes/min above",
          id="spm-range-empty"),
    _case(FIG3, "simulation.newmark_beta=0.1", field="simulation.newmark_beta", value="0.1",
          expect="unconditional stability", id="newmark-unstable"),
    _case(FIG4, "friction.law=nonmonotone", "friction.kinetic_coefficient=0.2",
          field="friction.kinetic_coefficient", value="0.2", expect="<= friction.coefficient",
          id="kinetic-above-static"),
    _case("default", "inflow.tubing_outer_diameter_mm=130", field="inflow.tubing_outer_diameter_mm",
          value="130", expect="diameter in mm below", id="tubing-wider-than-casing"),
    # the override syntax itself
    _case(FIG3, "surface.spm", field="--set", value="'surface.spm'", expect="key.path=value", id="set-no-equals"),
    _case(FIG3, "surface.spm.x=1", field="surface.spm.x", value="1", expect="path through mappings",
          id="set-through-a-value"),
    _case(FIG3, "rod.tapers.7.length_m=1", field="rod.tapers.7.length_m", value="1", expect="valid list index",
          id="set-bad-index"),
]


def _materialise(case: Case, tmp_path: Path) -> str:
    """The config argument for the CLI: the shipped name, or a YAML file with the case's edit applied."""
    if case.edit is None:
        return case.base
    data = read_raw(case.base)
    case.edit(data)
    path = tmp_path / "case.yaml"
    path.write_text(yaml.safe_dump(data))
    return str(path)


def _run_cli(config: str, sets: tuple[str, ...] | list[str], tmp_path: Path,
             capsys: pytest.CaptureFixture[str]) -> str:
    """Run ``srenv simulate`` in-process with --out and --plot; assert the clean-refusal contract; return
    the single error line."""
    out, plot = tmp_path / "out.csv", tmp_path / "cards.png"
    before = set(tmp_path.iterdir())
    argv = ["simulate", config, "--strokes", "1", "--out", str(out), "--plot", str(plot)]
    for s in sets:
        argv += ["--set", s]
    rc = main(argv)
    cap = capsys.readouterr()
    assert rc == EXIT_BAD_INPUT, cap.err
    assert "Traceback" not in cap.err + cap.out
    assert cap.out == ""
    lines = cap.err.strip().splitlines()
    assert len(lines) == 1, cap.err
    assert not out.exists() and not plot.exists()
    assert set(tmp_path.iterdir()) == before  # no temporary file of the atomic writer either
    return lines[0]


@pytest.mark.parametrize("case", CASES)
def test_bad_config_is_refused_through_the_cli(case: Case, tmp_path: Path,
                                               capsys: pytest.CaptureFixture[str]) -> None:
    line = _run_cli(_materialise(case, tmp_path), case.sets, tmp_path, capsys)
    assert line.startswith(f"srenv: error: config field '{case.field}' = "), line
    assert f"= {case.value}" in line, line
    assert case.expect in line, line


def test_enough_kinds_of_bad_config() -> None:
    assert len(CASES) >= 30


def _numeric_leaves(node: Any, path: tuple = ()) -> list[tuple]:
    if isinstance(node, dict):
        return [p for k, v in node.items() for p in _numeric_leaves(v, path + (k,))]
    if isinstance(node, list):
        return [p for i, v in enumerate(node) for p in _numeric_leaves(v, path + (i,))]
    return [path] if isinstance(node, (int, float)) and not isinstance(node, bool) else []


FIG3_LEAVES = _numeric_leaves(read_raw(FIG3))


def test_fig3_has_the_numeric_leaves_the_sweep_relies_on() -> None:
    assert len(FIG3_LEAVES) >= 15


@pytest.mark.parametrize("bad", ["abc", float("nan"), float("inf"), -float("inf"), [1.0], {"x": 1.0}, None],
                         ids=["string", "nan", "inf", "minus-inf", "list", "mapping", "null"])
def test_every_numeric_field_of_fig3_refuses_non_numbers(bad: Any, tmp_path: Path,
                                                         capsys: pytest.CaptureFixture[str]) -> None:
    """The acceptance sweep, in-process and with more kinds of bad value: each leaf named in the error."""
    src = read_raw(FIG3)
    for path in FIG3_LEAVES:
        data = copy.deepcopy(src)
        _put(list(path), bad)(data)
        cfg = tmp_path / "c.yaml"
        cfg.write_text(yaml.safe_dump(data))
        line = _run_cli(str(cfg), [], tmp_path, capsys)
        dotted = ".".join(f"[{p}]" if isinstance(p, int) else p for p in path).replace(".[", "[")
        assert f"config field '{dotted}'" in line, (path, line)


@pytest.mark.parametrize("text, expect", [
    ("rod: {tapers: [\n", "valid YAML (line"),
    ("- 1\n- 2\n", "a YAML mapping at the top level"),
    ("pump:\n  upstroke_load_n: 9500\n   downstroke_load_n: -2200\n", "valid YAML (line 3"),
    ("just a string\n", "a YAML mapping at the top level"),
], ids=["unclosed-flow", "top-level-list", "bad-indent", "top-level-scalar"])
def test_bad_yaml_file_names_the_file(text: str, expect: str, tmp_path: Path,
                                      capsys: pytest.CaptureFixture[str]) -> None:
    cfg = tmp_path / "broken.yaml"
    cfg.write_text(text)
    line = _run_cli(str(cfg), [], tmp_path, capsys)
    assert line.startswith("srenv: error: config field 'config' = ") and str(cfg) in line, line
    assert expect in line, line


def test_missing_config_file_is_refused(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    line = _run_cli(str(tmp_path / "nowhere.yaml"), [], tmp_path, capsys)
    assert "config field 'config'" in line and "nowhere.yaml" in line and "shipped name" in line


# ------------------------------------------------------------------------------------------ safe loading
def test_python_tag_in_yaml_is_refused_and_not_executed(tmp_path: Path,
                                                        capfd: pytest.CaptureFixture[str]) -> None:
    marker = tmp_path / "pwned"
    cfg = tmp_path / "evil.yaml"
    cfg.write_text(f'name: !!python/object/apply:os.system ["echo pwned; touch {marker}"]\n')
    with pytest.raises(ConfigError) as err:
        load_config(cfg)
    assert err.value.field == "config" and err.value.value == str(cfg)
    assert "python/object/apply" in str(err.value)
    assert not marker.exists()
    assert "pwned" not in capfd.readouterr().out


@pytest.mark.parametrize("text", ["__import__('os')", "__import__('os').system('true')", "eval('1')",
                                  "!!python/object/apply:os.system ['true']", "[1, 2]"])
def test_set_values_are_data_never_code(text: str, tmp_path: Path) -> None:
    """Override values are parsed as YAML scalars (never evaluated): code stays a string, refused by the
    numeric field's type check; a Python tag that YAML cannot build falls back to the literal text."""
    marker = tmp_path / "pwned"
    with pytest.raises(ConfigError) as err:
        load_config(FIG3, [f"surface.spm={text.replace('true', f'touch {marker}')}"])
    assert err.value.field == "surface.spm"
    assert "strokes/min" in str(err.value)
    assert not isinstance(err.value.value, (int, float))
    assert not marker.exists()


def test_python_tag_in_a_string_field_stays_a_harmless_string(tmp_path: Path) -> None:
    marker = tmp_path / "pwned"
    text = f"!!python/object/apply:os.system ['touch {marker}']"
    cfg = load_config(FIG3, [f"name={text}"])
    assert cfg.name == text
    assert not marker.exists()


def test_exponent_floats_without_a_dot_are_numbers() -> None:
    """PyYAML (YAML 1.1) reads 1e-3 as a string; the config loader reads it as the number it is."""
    cfg = load_config(FIG3, ["simulation.time_step_s=2e-3", "pump.upstroke_load_n=9.5e3"])
    assert cfg.simulation.time_step_s == 0.002
    assert cfg.pump.upstroke_load_n == 9500.0


# ------------------------------------------------------------------------------------------ convexity
def _restoring_time_step_s(message: str) -> float:
    match = re.search(r"below ([0-9.e-]+)", message)
    assert match, message
    return float(match.group(1))


def test_time_step_breaking_convexity_names_the_time_step_that_restores_it() -> None:
    """Default (DC iterations to a tolerance, nonconvex_step: error): refused, naming the largest convex
    time step; that time step is then accepted silently, so the refusal is about dt, not the law."""
    from srenv.simulation.simulator import Simulator

    with pytest.raises(ConfigError) as err:
        Simulator(load_config(FIG6, [*STEEP_FIG6, "simulation.time_step_s=0.02"]))
    assert err.value.field == "simulation.time_step_s" and err.value.value == 0.02
    restoring_dt_s = _restoring_time_step_s(err.value.expected)
    assert 0.005 < restoring_dt_s < 0.02  # the condensed pump stiffness crosses the slope between the two
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        Simulator(load_config(FIG6, [*STEEP_FIG6, f"simulation.time_step_s={0.9 * restoring_dt_s}"]))
        Simulator(load_config(FIG6))  # the paper's Fig. 6 case at its default 5 ms


def test_nonconvex_step_can_be_run_with_a_warning() -> None:
    from srenv.simulation.simulator import Simulator

    with pytest.warns(UserWarning, match=r"simulation\.time_step_s = 0\.02 s: the step problem is not convex"):
        Simulator(load_config(FIG6, [*STEEP_FIG6, "simulation.time_step_s=0.02",
                                     "simulation.nonconvex_step=warn"]))


def test_crank_hole_within_the_unit_is_accepted() -> None:
    cfg = load_config(FIG3, ["surface.motion=conventional", "surface.crank_hole=2"])
    assert cfg.surface.crank_hole == 2


def test_shipped_configs_all_load() -> None:
    for path in sorted(CONFIG_DIR.glob("*.yaml")):
        load_config(path)


# ------------------------------------------------------------------------------------------ end to end
@pytest.mark.parametrize("sets, field", [
    (["pump.upstroke_load_n=.nan"], "upstroke_load_n"),
    (["rod.tapers.0.diameter_mm=__import__('os')"], "diameter_mm"),
    (["simulation.qp_solver=nosuch"], "qp_solver"),
], ids=["nan", "code-string", "solver"])
def test_subprocess_exit_status_and_no_traceback(sets: list[str], field: str, tmp_path: Path) -> None:
    out, plot = tmp_path / "o.csv", tmp_path / "o.png"
    argv = [sys.executable, "-m", "srenv.tools.cli", "simulate", FIG3, "--strokes", "1", "--out", str(out),
            "--plot", str(plot)]
    for s in sets:
        argv += ["--set", s]
    p = subprocess.run(argv, check=False, capture_output=True, text=True, timeout=300)
    assert p.returncode == 2, p.stderr
    assert "Traceback" not in p.stderr + p.stdout
    assert len(p.stderr.strip().splitlines()) == 1 and field in p.stderr
    assert not out.exists() and not plot.exists()
    assert list(tmp_path.iterdir()) == []


def test_subprocess_python_tag_file(tmp_path: Path) -> None:
    marker = tmp_path / "pwned"
    cfg = tmp_path / "evil.yaml"
    cfg.write_text(f'name: !!python/object/apply:os.system ["touch {marker}"]\n')
    out = tmp_path / "o.csv"
    p = subprocess.run([sys.executable, "-m", "srenv.tools.cli", "simulate", str(cfg), "--out", str(out)],
                       check=False, capture_output=True, text=True, timeout=300)
    assert p.returncode == 2 and "Traceback" not in p.stderr and str(cfg) in p.stderr
    assert not out.exists() and not marker.exists()
