"""Typed, validated well configs.

Every section is a frozen dataclass; every numeric field carries its unit in its name and a check in its
metadata. ``load_config`` reads YAML with ``yaml.safe_load`` only, applies ``key.path=value`` overrides,
and raises one :class:`~srenv.errors.ConfigError` naming the field, the value and the expected unit.
Nothing in a config is ever evaluated as code. ``docs/config.md`` is generated from these classes
(``srenv config-doc``), so the table of fields, units and defaults cannot drift from the code.
"""

from __future__ import annotations

import dataclasses
import math
import re
import types
import typing
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import yaml

from .errors import ConfigError


class _ConfigLoader(yaml.SafeLoader):
    """``yaml.SafeLoader`` (no tags that construct Python objects) that also reads ``1e-3`` as a float.

    PyYAML follows YAML 1.1, where a float needs a dot (``1.0e-3``), so ``time_step_s: 1e-3`` would arrive
    as the *string* '1e-3' and be refused as "not a number" - a baffling error for a valid value. YAML 1.2
    (and every other tool) reads it as a number; so do we. ``nan``/``inf`` spelt without the dot stay strings.
    """


_ConfigLoader.add_implicit_resolver(
    "tag:yaml.org,2002:float",
    re.compile(r"^[-+]?[0-9][0-9_]*(?:\.[0-9_]*)?[eE][-+]?[0-9]+$"),
    list("-+0123456789"),
)


def _yaml_load(stream: Any) -> Any:
    return yaml.load(stream, Loader=_ConfigLoader)  # a SafeLoader subclass: still no Python tags


# check name -> (predicate, phrase used in the error message)
_CHECKS: dict[str, tuple[typing.Callable[[float], bool], str]] = {
    "positive": (lambda x: x > 0, "a positive number"),
    "nonneg": (lambda x: x >= 0, "a non-negative number"),
    "any": (lambda x: True, "a finite number"),
    "unit_interval": (lambda x: 0 <= x <= 1, "a number in [0, 1]"),
    "angle": (lambda x: 0 <= x <= 180, "an angle in [0, 180]"),
    "azimuth": (lambda x: -360 <= x <= 360, "an angle in [-360, 360]"),
}


def num(default: Any = dataclasses.MISSING, *, unit: str, check: str = "positive", doc: str = "") -> Any:
    """A numeric config field with its unit and validity check."""
    return field(default=default, metadata={"unit": unit, "check": check, "doc": doc})


def choice(default: str, options: tuple[str, ...], doc: str = "") -> Any:
    return field(default=default, metadata={"options": options, "doc": doc})


def opt(default: Any = None, doc: str = "", **kw: Any) -> Any:
    return field(default=default, metadata={"doc": doc, **kw})


# ----------------------------------------------------------------------------------------------- sections
@dataclass(frozen=True)
class TaperConfig:
    diameter_mm: float = num(unit="mm", doc="rod body diameter")
    length_m: float = num(unit="m", doc="taper length along measured depth")
    grade: str = choice("D", ("C", "K", "D"), "API rod grade (sets tensile strength for Goodman)")
    youngs_modulus_pa: float = num(2.0e11, unit="Pa")
    density_kg_m3: float = num(7850.0, unit="kg/m^3")
    coupling_mass_kg_per_m: float = num(0.0, unit="kg/m", check="nonneg",
                                        doc="couplings / sinker-bar extra mass smeared per metre")


@dataclass(frozen=True)
class RodConfig:
    tapers: tuple[TaperConfig, ...] = opt((), doc="tapers listed TOP-DOWN (polished rod first)")
    mass_matrix: str = choice("lumped", ("lumped", "consistent"))


@dataclass(frozen=True)
class DampingConfig:
    model: str = choice("dimensionless", ("dimensionless", "annulus_shear", "none"),
                        "dimensionless: Gibbs factor; annulus_shear: Couette flow rod-tubing")
    damping_factor: float = num(0.05, unit="-", check="nonneg",
                                doc="Gibbs dimensionless factor nu: c = rho*A*pi*a*nu/(2L)")
    fluid_viscosity_pa_s: float = num(0.01, unit="Pa*s", check="nonneg")
    tubing_inner_diameter_mm: float = num(62.0, unit="mm")


@dataclass(frozen=True)
class SurveyStation:
    md_m: float = num(unit="m", check="nonneg", doc="measured depth")
    inclination_deg: float = num(0.0, unit="deg", check="angle", doc="zenith angle")
    azimuth_deg: float = num(0.0, unit="deg", check="azimuth")


@dataclass(frozen=True)
class SurveyConfig:
    stations: tuple[SurveyStation, ...] = opt((), doc="(MD, inclination, azimuth) table; empty = vertical")
    three_d: bool = opt(False, doc="include the azimuth (dogleg) term in the side force")


@dataclass(frozen=True)
class FrictionConfig:
    law: str = choice("coulomb", ("coulomb", "nonmonotone"))
    coefficient: float = num(0.0, unit="-", check="nonneg", doc="Coulomb rod-tubing mu (static for nonmonotone)")
    kinetic_coefficient: float = num(0.0, unit="-", check="nonneg", doc="mu_k of the nonmonotone law")
    reference_velocity_m_s: float = num(0.1, unit="m/s", doc="v0 of mu(v) = mu_k + (mu_s-mu_k) e^(-|v|/v0)")


@dataclass(frozen=True)
class FluidConfig:
    density_kg_m3: float = num(850.0, unit="kg/m^3", check="nonneg", doc="produced liquid density")
    wellhead_pressure_pa: float = num(0.0, unit="Pa", check="nonneg", doc="tubing-head pressure")


@dataclass(frozen=True)
class PumpConfig:
    load_source: str = choice("loads", ("loads", "pressures"),
                              "loads: the two plunger loads given; pressures: from diameters and pressures")
    upstroke_load_n: float = num(10000.0, unit="N", check="any", doc="P- (true load at the rod end)")
    downstroke_load_n: float = num(-2000.0, unit="N", check="any", doc="P+ (true load, negative = compression)")
    plunger_diameter_mm: float = num(44.45, unit="mm")
    intake_pressure_pa: float = num(1.0e6, unit="Pa", check="nonneg", doc="p_in (ignored when inflow model)")
    plunger_friction_n: float = num(500.0, unit="N", check="nonneg")
    discharge_overpressure_pa: float = num(0.0, unit="Pa", check="nonneg",
                                           doc="delta p_out of the downstroke (travelling valve loss)")
    law: str = choice("constant", ("constant", "nonmonotone"), "plunger upstroke law (paper eq. 32)")
    dynamic_load_n: float = num(7090.0, unit="N", check="any", doc="P_inf of the nonmonotone law (true load)")
    reference_velocity_m_s: float = num(1.0, unit="m/s", doc="v0 of the nonmonotone law")


@dataclass(frozen=True)
class SurfaceConfig:
    motion: str = choice("harmonic", ("harmonic", "conventional", "pullout"))
    spm: float = num(6.0, unit="strokes/min")
    stroke_length_m: float = num(2.4, unit="m")
    pull_velocity_m_s: float = num(0.1, unit="m/s", doc="pull-out: constant upward speed of the top")
    pull_ramp_s: float = num(0.5, unit="s", check="nonneg", doc="pull-out: half-cosine ramp up to speed")
    unit: str = opt("C-228D-213-86", doc="conventional: API designation from configs/units/catalogue.yaml")
    crank_hole: int = num(0, unit="-", check="nonneg", doc="conventional: 0 = longest stroke")
    counterbalance_moment_nm: float = num(0.0, unit="N*m", check="nonneg",
                                          doc="conventional: max moment M of the crank counterweights")
    counterbalance_offset_deg: float = num(0.0, unit="deg", check="azimuth",
                                           doc="conventional: lead of the counterweight arm over the pin")
    motor_efficiency: float = num(0.85, unit="-",
                                  doc="conventional: crank-shaft power / electric input, in (0, 1]")


@dataclass(frozen=True)
class InflowConfig:
    model: str = choice("none", ("none", "linear", "vogel"), "reservoir inflow performance")
    reservoir_pressure_pa: float = num(8.0e6, unit="Pa")
    productivity_index_m3_day_pa: float = num(2.0e-6, unit="m^3/day/Pa", doc="linear PI")
    max_rate_m3_day: float = num(30.0, unit="m^3/day", doc="Vogel AOF (q at p_wf = 0)")
    casing_pressure_pa: float = num(2.0e5, unit="Pa", check="nonneg")
    initial_fluid_level_m: float = num(100.0, unit="m", check="nonneg", doc="liquid column above the pump")
    casing_inner_diameter_mm: float = num(124.0, unit="mm")
    tubing_outer_diameter_mm: float = num(73.0, unit="mm")


@dataclass(frozen=True)
class SimulationConfig:
    element_length_m: float = num(25.0, unit="m", doc="target FE element length (tapers get whole elements)")
    time_step_s: float = num(0.005, unit="s")
    newmark_beta: float = num(0.25, unit="-")
    newmark_gamma: float = num(0.5, unit="-")
    qp_solver: str = opt("proxqp", doc="qpsolvers backend of the fallback/reference solve")
    qp_eps_abs: float = num(1e-11, unit="-", doc="absolute tolerance on the normalised dual QP")
    always_qp: bool = opt(False, doc="solve every step's QP with the solver (reference mode)")
    max_corrections: int = num(8, unit="-", check="nonneg", doc="active-set corrections before the QP")
    dc_tolerance_m_s: float = num(1e-10, unit="m/s", doc="DC iterations stop when max |dv| below this")
    dc_max_iterations: int = num(50, unit="-", doc="1 = the paper's single pass")
    nonconvex_step: str = choice("error", ("error", "warn"),
                                 "a nonmonotone law steeper than the condensed stiffness: refuse, or warn and run")


@dataclass(frozen=True)
class ControlConfig:
    spm_min: float = num(3.0, unit="strokes/min")
    spm_max: float = num(10.0, unit="strokes/min")
    stroke_min_m: float = num(1.0, unit="m")
    stroke_max_m: float = num(2.0, unit="m")
    spm_rate_limit: float = num(0.0, unit="strokes/min per step", check="nonneg", doc="0 = unlimited")
    strokes_per_step: int = num(1, unit="strokes", doc="control interval")
    max_episode_steps: int = num(400, unit="steps", doc="truncation by step count (a cap)")
    max_episode_s: float = num(1000.0, unit="s", doc="truncation by simulated time (the episode's horizon)")
    randomize: bool = opt(True, doc="domain randomisation of well parameters on reset")
    randomize_fraction: float = num(0.1, unit="-", check="unit_interval")


@dataclass(frozen=True)
class RewardConfig:
    production_weight: float = num(1.0, unit="-", check="nonneg")
    stick_slip_weight: float = num(1.0, unit="-", check="nonneg")
    peak_load_weight: float = num(5.0, unit="-", check="nonneg")
    goodman_limit_pct: float = num(100.0, unit="%")
    pprl_rating_n: float = num(60000.0, unit="N")
    failure_penalty: float = num(50.0, unit="-", check="nonneg")
    failure_goodman_pct: float = num(130.0, unit="%", doc="rod failure (episode ends) above this Goodman loading")
    reference_duration_s: float = num(10.0, unit="s", doc="rate terms are weighted by step duration / this, "
                                      "so an episode's return integrates over time, not over strokes")
    production_scale_m3_day: float = num(10.0, unit="m^3/day", doc="production that earns one unit of reward "
                                         "times production_weight")


@dataclass(frozen=True)
class EconomicsConfig:
    """Prices and costs of the v1 reward (USD; every term is a rate in USD per hour of well time)."""

    oil_price_usd_m3: float = num(440.0, unit="USD/m^3", check="nonneg", doc="netback oil price (70 USD/bbl)")
    water_handling_usd_m3: float = num(6.3, unit="USD/m^3", check="nonneg", doc="water lifting and disposal (1 USD/bbl)")
    water_cut: float = num(0.5, unit="-", check="unit_interval", doc="water fraction of the produced liquid")
    electricity_usd_kwh: float = num(0.12, unit="USD/kWh", check="nonneg")
    motor_efficiency: float = num(0.8, unit="-", check="unit_interval", doc="electric input -> polished-rod work")
    workover_usd: float = num(30000.0, unit="USD", check="nonneg", doc="cost of one rod-string failure (pulling job)")
    fatigue_life_cycles: float = num(1.0e7, unit="cycles", doc="rod life at 100 % Goodman loading (API RP 11BR basis)")
    fatigue_exponent: float = num(6.0, unit="-", doc="S-N exponent m: damage per cycle (G/100)^m / life")
    stick_slip_usd_per_j: float = num(0.0002, unit="USD/J", check="nonneg",
                                      doc="price of the elastic energy released by extra plunger stick-slip")
    overload_usd_h: float = num(2000.0, unit="USD/h", check="nonneg",
                                doc="cost rate at 100 % over a rating (quadratic in the excess)")
    pound_usd_per_m2_s2: float = num(0.15, unit="USD/(m/s)^2", check="nonneg",
                                     doc="per stroke, times the squared plunger speed when it meets the liquid")
    ramp_usd_per_spm2: float = num(0.1, unit="USD/SPM^2", check="nonneg",
                                   doc="VSD ramp: per change of the average SPM between intervals, squared")
    failure_usd: float = num(30000.0, unit="USD", check="nonneg", doc="rod failure (ends the episode)")
    pprl_rating_n: float = num(80000.0, unit="N", doc="unit structure rating")


@dataclass(frozen=True)
class TaskConfig:
    """The v1 control task: control interval, horizon, inflow schedule, observation extras."""

    interval_s: float = num(300.0, unit="s", doc="one env step of well time (idle or pumping)")
    episode_hours: float = num(12.0, unit="h", doc="horizon; truncated after it")
    exact_strokes_max: int = num(4, unit="strokes", doc="strokes simulated exactly per interval; the rest is "
                                 "fast-forwarded quasi-steadily (annulus mass balance, last exact stroke's loads)")
    fast_forward_fillage_tol: float = num(0.05, unit="-", check="unit_interval",
                                          doc="re-simulate exactly when the fast-forwarded fillage drifts this much")
    level_shot_interval_h: float = num(4.0, unit="h", doc="acoustic fluid-level shot every this many hours")
    inflow_decline_per_day: float = num(0.05, unit="1/day", check="nonneg", doc="exponential inflow decline")
    inflow_step_fraction: float = num(0.0, unit="-", check="any",
                                      doc="fixed-well scenario: step of the inflow multiplier at mid-episode")
    failure_goodman_pct: float = num(150.0, unit="%", doc="rod failure above this Goodman loading")


@dataclass(frozen=True)
class WellConfig:
    name: str = opt("well")
    description: str = opt("")
    rod: RodConfig = field(default_factory=RodConfig)
    damping: DampingConfig = field(default_factory=DampingConfig)
    survey: SurveyConfig = field(default_factory=SurveyConfig)
    friction: FrictionConfig = field(default_factory=FrictionConfig)
    fluid: FluidConfig = field(default_factory=FluidConfig)
    pump: PumpConfig = field(default_factory=PumpConfig)
    surface: SurfaceConfig = field(default_factory=SurfaceConfig)
    inflow: InflowConfig = field(default_factory=InflowConfig)
    simulation: SimulationConfig = field(default_factory=SimulationConfig)
    control: ControlConfig = field(default_factory=ControlConfig)
    reward: RewardConfig = field(default_factory=RewardConfig)
    economics: EconomicsConfig = field(default_factory=EconomicsConfig)
    task: TaskConfig = field(default_factory=TaskConfig)

    @property
    def rod_length_m(self) -> float:
        return float(sum(t.length_m for t in self.rod.tapers))


# ----------------------------------------------------------------------------------------------- parsing
def _is_dataclass_type(tp: Any) -> bool:
    return isinstance(tp, type) and dataclasses.is_dataclass(tp)


def _parse_scalar(tp: Any, value: Any, path: str, meta: dict) -> Any:
    unit = meta.get("unit", "")
    if tp is bool:
        if isinstance(value, bool):
            return value
        raise ConfigError(path, value, "true or false")
    if tp is str:
        if not isinstance(value, str):
            raise ConfigError(path, value, "a string")
        opts = meta.get("options")
        if opts and value not in opts:
            raise ConfigError(path, value, "one of " + ", ".join(opts))
        return value
    if tp in (int, float):
        check = meta.get("check", "any")
        pred, phrase = _CHECKS[check]
        what = f"{'an integer' if tp is int else phrase} in {unit}" if unit and unit != "-" else (
            "an integer" if tp is int else phrase)
        if tp is int:
            what = f"{'a non-negative' if check == 'nonneg' else 'a positive'} integer" + (
                f" in {unit}" if unit not in ("", "-") else "")
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise ConfigError(path, value, what)
        if tp is int and (not float(value).is_integer() if math.isfinite(value) else True):
            raise ConfigError(path, value, what)
        x = tp(value) if tp is float or math.isfinite(value) else value
        if not math.isfinite(float(x)) or not pred(float(x)):
            raise ConfigError(path, value, what)
        return x
    raise TypeError(f"unsupported config type {tp} at {path}")  # programming error, not user input


def _parse(cls: type, data: Any, path: str) -> Any:
    if not isinstance(data, dict):
        raise ConfigError(path or "<root>", data, f"a mapping of {cls.__name__} fields")
    hints = typing.get_type_hints(cls)
    fields = {f.name: f for f in dataclasses.fields(cls)}
    unknown = [k for k in data if k not in fields]
    if unknown:
        key = unknown[0]
        where = f"{path}.{key}" if path else str(key)
        raise ConfigError(where, data[key], "no such field; known fields: " + ", ".join(fields))
    kwargs = {}
    for name, f in fields.items():
        where = f"{path}.{name}" if path else name
        if name not in data:
            if f.default is dataclasses.MISSING and f.default_factory is dataclasses.MISSING:
                raise ConfigError(where, None, "a value (this field is required)"
                                  + (f" in {f.metadata['unit']}" if "unit" in f.metadata else ""))
            continue
        tp = hints[name]
        value = data[name]
        origin = typing.get_origin(tp)
        if origin is tuple:
            (item_tp, _ellipsis) = typing.get_args(tp)
            if not isinstance(value, list):
                raise ConfigError(where, value, f"a list of {item_tp.__name__} entries")
            kwargs[name] = tuple(_parse(item_tp, v, f"{where}[{i}]") for i, v in enumerate(value))
        elif _is_dataclass_type(tp):
            kwargs[name] = _parse(tp, value, where)
        elif origin in (typing.Union, types.UnionType):
            raise TypeError(f"unsupported union at {where}")
        else:
            kwargs[name] = _parse_scalar(tp, value, where, dict(f.metadata))
    return cls(**kwargs)


def _check_consistency(cfg: WellConfig) -> None:
    """Cross-field checks (each names the offending field)."""
    if not cfg.rod.tapers:
        raise ConfigError("rod.tapers", [], "at least one taper")
    p = cfg.pump
    if p.load_source == "loads" and not p.upstroke_load_n > p.downstroke_load_n:
        raise ConfigError("pump.downstroke_load_n", p.downstroke_load_n,
                          f"a load in N below pump.upstroke_load_n = {p.upstroke_load_n} (P+ < P-)")
    if p.law == "nonmonotone":
        if p.load_source != "loads":
            raise ConfigError("pump.law", p.law, "'constant' when pump.load_source is 'pressures'")
        if not p.downstroke_load_n < p.dynamic_load_n <= p.upstroke_load_n:
            raise ConfigError("pump.dynamic_load_n", p.dynamic_load_n,
                              "a load in N between pump.downstroke_load_n and pump.upstroke_load_n")
    f = cfg.friction
    if f.law == "nonmonotone" and f.kinetic_coefficient > f.coefficient:
        raise ConfigError("friction.kinetic_coefficient", f.kinetic_coefficient,
                          f"a coefficient <= friction.coefficient = {f.coefficient} (static)")
    st = cfg.survey.stations
    for i in range(1, len(st)):
        if not st[i].md_m > st[i - 1].md_m:
            raise ConfigError(f"survey.stations[{i}].md_m", st[i].md_m,
                              f"a depth in m greater than the previous station's {st[i - 1].md_m}")
    if st and st[-1].md_m < cfg.rod_length_m - 1e-6:
        raise ConfigError(f"survey.stations[{len(st) - 1}].md_m", st[-1].md_m,
                          f"a depth in m reaching the pump at {cfg.rod_length_m} m (sum of taper lengths)")
    if st and st[0].md_m != 0:
        raise ConfigError("survey.stations[0].md_m", st[0].md_m, "0 m (the survey starts at the surface)")
    if cfg.surface.motion == "conventional":
        _check_conventional_unit(cfg.surface)
    c = cfg.control
    if c.spm_min >= c.spm_max:
        raise ConfigError("control.spm_max", c.spm_max, f"strokes/min above control.spm_min = {c.spm_min}")
    if c.stroke_min_m > c.stroke_max_m:
        raise ConfigError("control.stroke_max_m", c.stroke_max_m,
                          f"a length in m >= control.stroke_min_m = {c.stroke_min_m}")
    s = cfg.simulation
    if not (s.newmark_gamma >= 0.5 and s.newmark_beta >= 0.25 * (0.5 + s.newmark_gamma) ** 2 - 1e-12):
        raise ConfigError("simulation.newmark_beta", s.newmark_beta,
                          "beta >= (gamma + 1/2)^2 / 4 with gamma >= 1/2 (unconditional stability)")
    if s.element_length_m > cfg.rod_length_m:
        raise ConfigError("simulation.element_length_m", s.element_length_m,
                          f"a length in m no longer than the rod ({cfg.rod_length_m} m)")
    if s.qp_solver not in _known_solvers():
        raise ConfigError("simulation.qp_solver", s.qp_solver,
                          "an installed qpsolvers backend: " + ", ".join(_known_solvers()))
    if cfg.inflow.model != "none":
        i = cfg.inflow
        if i.tubing_outer_diameter_mm >= i.casing_inner_diameter_mm:
            raise ConfigError("inflow.tubing_outer_diameter_mm", i.tubing_outer_diameter_mm,
                              f"a diameter in mm below inflow.casing_inner_diameter_mm = {i.casing_inner_diameter_mm}")
        if p.load_source != "pressures":
            raise ConfigError("pump.load_source", p.load_source,
                              "'pressures' when an inflow model sets the intake pressure")
    for i, t in enumerate(cfg.rod.tapers):
        if p.load_source == "pressures" and t is cfg.rod.tapers[-1] and t.diameter_mm >= p.plunger_diameter_mm:
            raise ConfigError("pump.plunger_diameter_mm", p.plunger_diameter_mm,
                              f"a diameter in mm larger than the bottom rod ({t.diameter_mm} mm)")
        if t.diameter_mm >= cfg.damping.tubing_inner_diameter_mm and cfg.damping.model == "annulus_shear":
            raise ConfigError(f"rod.tapers[{i}].diameter_mm", t.diameter_mm,
                              f"a diameter in mm below damping.tubing_inner_diameter_mm = "
                              f"{cfg.damping.tubing_inner_diameter_mm}")


def _check_conventional_unit(surface: SurfaceConfig) -> None:
    """A conventional unit's stroke comes from its crank hole: the unit must exist and have that hole, or
    the stroke would be beyond what the unit can make. Checked at load time (not only when a simulator is
    built) so that every loader of a config - CLI, env, sweeps - refuses it before doing any work."""
    from .surface import _conventional_unit  # the one place that resolves a unit; lazy: it imports us

    _conventional_unit(surface.unit, surface.crank_hole)


def _known_solvers() -> list[str]:
    import qpsolvers

    return list(qpsolvers.available_solvers)


# ----------------------------------------------------------------------------------------------- loading
CONFIG_DIR = Path(__file__).resolve().parents[1] / "configs" / "wells"


def shipped_configs() -> list[str]:
    return sorted(p.stem for p in CONFIG_DIR.glob("*.yaml"))


def _resolve(path_or_name: str | Path) -> Path:
    p = Path(path_or_name)
    if p.suffix in (".yaml", ".yml") and p.exists():
        return p
    cand = CONFIG_DIR / f"{p.stem}.yaml"
    if cand.exists() and (not p.suffix or not p.exists()):
        return cand
    raise ConfigError("config", str(path_or_name),
                      "an existing .yaml file or a shipped name: " + ", ".join(shipped_configs()))


def _parse_override_value(text: str) -> Any:
    # YAML scalar syntax (numbers, true/false, strings) - parsed, never evaluated.
    try:
        return _yaml_load(text)
    except yaml.YAMLError:
        return text


def apply_overrides(data: dict, overrides: dict[str, Any] | list[str] | None) -> dict:
    """Apply ``{"a.b.c": value}`` or ``["a.b.c=value", ...]`` to a raw config mapping (copy)."""
    import copy

    data = copy.deepcopy(data)
    if not overrides:
        return data
    items = overrides.items() if isinstance(overrides, dict) else []
    if isinstance(overrides, list):
        pairs = []
        for s in overrides:
            if "=" not in s:
                raise ConfigError("--set", s, "key.path=value")
            k, v = s.split("=", 1)
            pairs.append((k.strip(), _parse_override_value(v.strip())))
        items = pairs
    for key, value in items:
        node: Any = data
        parts = key.split(".")
        for part in parts[:-1]:
            if isinstance(node, list):
                if not part.isdigit() or int(part) >= len(node):
                    raise ConfigError(key, value, f"a valid list index at '{part}'")
                node = node[int(part)]
            else:
                node = node.setdefault(part, {})
                if not isinstance(node, (dict, list)):
                    raise ConfigError(key, value, f"a path through mappings ('{part}' is a value)")
        last = parts[-1]
        if isinstance(node, list):
            if not last.isdigit() or int(last) >= len(node):
                raise ConfigError(key, value, f"a valid list index at '{last}'")
            node[int(last)] = value
        else:
            node[last] = value
    return data


def _yaml_problem(exc: yaml.YAMLError) -> str:
    """One line locating a YAML error: 'line L column C: problem' (the full text spans several lines)."""
    mark = getattr(exc, "problem_mark", None)
    problem = getattr(exc, "problem", None) or str(exc).splitlines()[0]
    if mark is None:
        return problem
    return f"line {mark.line + 1} column {mark.column + 1}: {problem}"


def read_raw(path_or_name: str | Path) -> dict:
    path = _resolve(path_or_name)
    try:
        with open(path) as fh:
            data = _yaml_load(fh)
    except yaml.YAMLError as exc:
        raise ConfigError("config", str(path), f"valid YAML ({_yaml_problem(exc)})") from None
    if data is None:
        data = {}
    if not isinstance(data, dict):
        raise ConfigError("config", str(path), "a YAML mapping at the top level")
    return data


def config_from_dict(data: dict) -> WellConfig:
    cfg = _parse(WellConfig, data, "")
    _check_consistency(cfg)
    return cfg


def load_config(path_or_name: str | Path | WellConfig = "default",
                overrides: dict[str, Any] | list[str] | None = None) -> WellConfig:
    """Load a well config from a YAML path or a shipped name, with optional ``key.path`` overrides."""
    if isinstance(path_or_name, WellConfig):
        if not overrides:
            return path_or_name
        return config_from_dict(apply_overrides(to_dict(path_or_name), overrides))
    return config_from_dict(apply_overrides(read_raw(path_or_name), overrides))


def to_dict(cfg: Any) -> Any:
    if dataclasses.is_dataclass(cfg):
        return {f.name: to_dict(getattr(cfg, f.name)) for f in dataclasses.fields(cfg)}
    if isinstance(cfg, tuple):
        return [to_dict(x) for x in cfg]
    return cfg


def config_doc() -> str:
    """Markdown table of every config field with unit, default and meaning."""
    lines = ["| field | unit | default | meaning |", "|---|---|---|---|"]

    def walk(cls: type, prefix: str) -> None:
        hints = typing.get_type_hints(cls)
        for f in dataclasses.fields(cls):
            tp = hints[f.name]
            key = f"{prefix}{f.name}"
            if _is_dataclass_type(tp):
                walk(tp, key + ".")
                continue
            if typing.get_origin(tp) is tuple:
                item = typing.get_args(tp)[0]
                lines.append(f"| `{key}` | list | [] | {f.metadata.get('doc', '')} |")
                walk(item, key + "[i].")
                continue
            default = "required" if f.default is dataclasses.MISSING else repr(f.default)
            doc = f.metadata.get("doc", "")
            if "options" in f.metadata:
                doc = (doc + "; " if doc else "") + "one of " + ", ".join(f.metadata["options"])
            lines.append(f"| `{key}` | {f.metadata.get('unit', '')} | {default} | {doc} |")

    walk(WellConfig, "")
    return "\n".join(lines)
