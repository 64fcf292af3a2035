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
import os
import re
import types
import typing
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import yaml

from .errors import ConfigError, short_repr
from .shipped import shipped_dir
from .unit_catalogue import conventional_unit

# Bounds on what a YAML document may ask of the loader (a config is a few hundred nodes; see
# docs/reliability.md): bytes read, nesting depth, and nodes after alias expansion - a 600-byte "billion
# laughs" document expands to millions of nodes, and anything walking or printing it would do that work.
MAX_YAML_BYTES = 1_000_000
MAX_YAML_DEPTH = 50
MAX_YAML_NODES = 100_000


class _ConfigLoader(yaml.SafeLoader):
    """``yaml.SafeLoader`` (no tags that construct Python objects) that also reads ``1e-3`` as a float,
    refuses duplicate mapping keys and bounds the document's expanded size and depth.

    PyYAML follows YAML 1.1, where a float needs a dot (``1.0e-3``), so ``time_step_s: 1e-3`` would arrive
    as the *string* '1e-3' and be refused as "not a number" - a baffling error for a valid value. YAML 1.2
    (and every other tool) reads it as a number; so do we. ``nan``/``inf`` spelt without the dot stay strings.
    A key given twice is an error (YAML 1.2 requires unique keys; PyYAML silently keeps the last one, so
    ``spm: 6`` then ``spm: 30`` would run at 30 without a word).
    """

    def __init__(self, stream: Any) -> None:
        super().__init__(stream)
        self._expanded: dict[int, int] = {}  # id(node) -> node count with aliases expanded
        self._depth = 0

    def compose_node(self, parent: Any, index: Any) -> Any:
        self._depth += 1
        try:
            if self._depth > MAX_YAML_DEPTH:
                raise yaml.composer.ComposerError(None, None, f"nesting deeper than {MAX_YAML_DEPTH} levels",
                                                  self.peek_event().start_mark)
            node = super().compose_node(parent, index)
        finally:
            self._depth -= 1
        size = self._expanded.get(id(node))
        if size is None:
            if isinstance(node, yaml.SequenceNode):
                size = 1 + sum(self._expanded.get(id(c), 1) for c in node.value)
            elif isinstance(node, yaml.MappingNode):
                size = 1 + sum(self._expanded.get(id(k), 1) + self._expanded.get(id(v), 1) for k, v in node.value)
            else:
                size = 1
            self._expanded[id(node)] = size
        if size > MAX_YAML_NODES:
            raise yaml.composer.ComposerError(None, None, f"more than {MAX_YAML_NODES} values once aliases are "
                                              "expanded (an alias bomb?)", node.start_mark)
        return node

    def construct_mapping(self, node: Any, deep: bool = False) -> Any:
        if isinstance(node, yaml.MappingNode):
            seen: set = set()
            for key_node, _ in node.value:
                if key_node.tag == "tag:yaml.org,2002:merge" or not isinstance(key_node, yaml.ScalarNode):
                    continue  # merged keys may be overridden by explicit ones (YAML merge semantics)
                key = self.construct_object(key_node)
                if key in seen:
                    raise yaml.constructor.ConstructorError(None, None, f"duplicate key {short_repr(key)}",
                                                            key_node.start_mark)
                seen.add(key)
        return super().construct_mapping(node, deep=deep)


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


def num(default: Any = dataclasses.MISSING, *, unit: str, check: str = "positive", doc: str = "",
        lo: float | None = None, hi: float | None = None) -> Any:
    """A numeric config field with its unit, validity check and physical range [lo, hi] (both inclusive).

    Every numeric field has a finite upper bound: a value far outside any physical range (1e308 N, a
    1e-300 m element) either overflows to NaN or asks for unbounded memory, so it is refused at load time.
    """
    meta = {"unit": unit, "check": check, "doc": doc}
    if lo is not None:
        meta["lo"] = lo
    if hi is not None:
        meta["hi"] = hi
    return field(default=default, metadata=meta)


def choice(default: str, options: tuple[str, ...], doc: str = "") -> Any:
    return field(default=default, metadata={"options": options, "doc": doc})


def opt(default: Any = None, doc: str = "", **kw: Any) -> Any:
    return field(default=default, metadata={"doc": doc, **kw})


# ----------------------------------------------------------------------------------------------- sections
@dataclass(frozen=True)
class TaperConfig:
    diameter_mm: float = num(unit="mm", doc="rod body diameter", hi=200.0)
    length_m: float = num(unit="m", doc="taper length along measured depth", lo=1.0, hi=1.0e4)
    grade: str = choice("D", ("C", "K", "D"), "API rod grade (sets tensile strength for Goodman)")
    youngs_modulus_pa: float = num(2.0e11, unit="Pa", lo=1.0e9, hi=1.0e12)
    density_kg_m3: float = num(7850.0, unit="kg/m^3", lo=100.0, hi=2.0e4)
    coupling_mass_kg_per_m: float = num(0.0, unit="kg/m", check="nonneg", hi=1.0e3,
                                        doc="couplings / sinker-bar extra mass smeared per metre")
    material: str = choice("steel", ("steel", "fiberglass", "sinker_bar"),
                           "fiberglass / sinker_bar: E, density and strength default to the material's "
                           "(MATERIAL_DEFAULTS) unless given")
    tensile_strength_pa: float = num(0.0, unit="Pa", check="nonneg", hi=1.0e10,
                                     doc="T for Goodman; 0 = from the grade (steel, sinker bar) or the material")


# Per-material defaults filled in for fields a taper does not give (config_from_dict). Fiberglass: a typical
# API 11C rod body (E 48 GPa ~ 7e6 psi, 2 000 kg/m^3 with its steel end fittings smeared, 690 MPa); sinker
# bars are steel (the grade sets T).
MATERIAL_DEFAULTS: dict[str, dict[str, float]] = {
    "fiberglass": {"youngs_modulus_pa": 4.8e10, "density_kg_m3": 2000.0, "tensile_strength_pa": 6.9e8},
    "sinker_bar": {"youngs_modulus_pa": 2.0e11, "density_kg_m3": 7850.0},
}


@dataclass(frozen=True)
class RodConfig:
    tapers: tuple[TaperConfig, ...] = opt((), doc="tapers listed TOP-DOWN (polished rod first)")
    mass_matrix: str = choice("lumped", ("lumped", "consistent"))


@dataclass(frozen=True)
class DampingConfig:
    model: str = choice("dimensionless", ("dimensionless", "annulus_shear", "none"),
                        "dimensionless: Gibbs factor; annulus_shear: Couette flow rod-tubing")
    damping_factor: float = num(0.05, unit="-", check="nonneg", hi=10.0,
                                doc="Gibbs dimensionless factor nu: c = rho*A*pi*a*nu/(2L)")
    fluid_viscosity_pa_s: float = num(0.01, unit="Pa*s", check="nonneg", hi=100.0)
    tubing_inner_diameter_mm: float = num(62.0, unit="mm", hi=500.0)


@dataclass(frozen=True)
class SurveyStation:
    md_m: float = num(unit="m", check="nonneg", doc="measured depth", hi=1.0e5)
    inclination_deg: float = num(0.0, unit="deg", check="angle", doc="zenith angle")
    azimuth_deg: float = num(0.0, unit="deg", check="azimuth")


@dataclass(frozen=True)
class SurveyConfig:
    stations: tuple[SurveyStation, ...] = opt((), doc="(MD, inclination, azimuth) table; empty = vertical")
    three_d: bool = opt(False, doc="include the azimuth (dogleg) term in the side force")


@dataclass(frozen=True)
class FrictionConfig:
    law: str = choice("coulomb", ("coulomb", "nonmonotone"))
    coefficient: float = num(0.0, unit="-", check="nonneg", hi=10.0, doc="Coulomb rod-tubing mu (static for nonmonotone)")
    kinetic_coefficient: float = num(0.0, unit="-", check="nonneg", hi=10.0, doc="mu_k of the nonmonotone law")
    reference_velocity_m_s: float = num(0.1, unit="m/s", lo=1e-6, hi=100.0, doc="v0 of mu(v) = mu_k + (mu_s-mu_k) e^(-|v|/v0)")


@dataclass(frozen=True)
class FluidConfig:
    density_kg_m3: float = num(850.0, unit="kg/m^3", check="nonneg", hi=2.0e4, doc="produced liquid density")
    wellhead_pressure_pa: float = num(0.0, unit="Pa", check="nonneg", hi=1.0e9, doc="tubing-head pressure")


@dataclass(frozen=True)
class PumpConfig:
    load_source: str = choice("loads", ("loads", "pressures"),
                              "loads: the two plunger loads given; pressures: from diameters and pressures")
    upstroke_load_n: float = num(10000.0, unit="N", check="any", lo=-1.0e7, hi=1.0e7, doc="P- (true load at the rod end)")
    downstroke_load_n: float = num(-2000.0, unit="N", check="any", lo=-1.0e7, hi=1.0e7, doc="P+ (true load, negative = compression)")
    plunger_diameter_mm: float = num(44.45, unit="mm", hi=500.0)
    intake_pressure_pa: float = num(1.0e6, unit="Pa", check="nonneg", hi=1.0e9, doc="p_in (ignored when inflow model)")
    plunger_friction_n: float = num(500.0, unit="N", check="nonneg", hi=1.0e7)
    discharge_overpressure_pa: float = num(0.0, unit="Pa", check="nonneg", hi=1.0e9,
                                           doc="delta p_out of the downstroke (travelling valve loss)")
    law: str = choice("constant", ("constant", "nonmonotone"), "plunger upstroke law (paper eq. 32)")
    dynamic_load_n: float = num(7090.0, unit="N", check="any", lo=-1.0e7, hi=1.0e7, doc="P_inf of the nonmonotone law (true load)")
    reference_velocity_m_s: float = num(1.0, unit="m/s", lo=1e-6, hi=100.0, doc="v0 of the nonmonotone law")
    intake_gas_fraction: float = num(0.0, unit="-", check="unit_interval", hi=1.0,
                                     doc="free-gas volume fraction of the intake mixture at p_in (gas interference)")
    intake_glr_m3_m3: float = num(0.0, unit="m^3/m^3", check="nonneg", hi=1.0e4,
                                  doc="free gas-liquid ratio at standard conditions (instead of the fraction)")
    gas_polytropic_exponent: float = num(1.0, unit="-", lo=1.0, hi=2.0, doc="k of p V^k = const in the chamber (1 = isothermal)")
    clearance_volume_fraction: float = num(0.05, unit="-", check="nonneg", hi=10.0,
                                           doc="unswept chamber volume / swept volume at surface.stroke_length_m")


@dataclass(frozen=True)
class SurfaceConfig:
    motion: str = choice("harmonic", ("harmonic", "conventional", "pullout", "measured"),
                         "measured: the polished-rod position of surface.measured_card_csv (docs/field.md)")
    spm: float = num(6.0, unit="strokes/min", lo=0.1, hi=60.0)
    stroke_length_m: float = num(2.4, unit="m", hi=20.0)
    pull_velocity_m_s: float = num(0.1, unit="m/s", hi=100.0, doc="pull-out: constant upward speed of the top")
    pull_ramp_s: float = num(0.5, unit="s", check="nonneg", hi=1.0e4, doc="pull-out: half-cosine ramp up to speed")
    unit: str = opt("C-228D-213-86", doc="conventional: API designation from configs/units/catalogue.yaml")
    crank_hole: int = num(0, unit="-", check="nonneg", hi=100, doc="conventional: 0 = longest stroke")
    counterbalance_moment_nm: float = num(0.0, unit="N*m", check="nonneg", hi=1.0e8,
                                          doc="conventional: max moment M of the crank counterweights")
    counterbalance_offset_deg: float = num(0.0, unit="deg", check="azimuth",
                                           doc="conventional: lead of the counterweight arm over the pin")
    motor_efficiency: float = num(0.85, unit="-", hi=1.0,
                                  doc="conventional: crank-shaft power / electric input, in (0, 1]")
    measured_card_csv: str = opt("", doc="measured: CSV with t_s, polished_rod_position_m (one stroke or "
                                 "more; the last full stroke is used); a relative path is from the working directory")
    measured_spm: float = num(0.0, unit="strokes/min", hi=60.0, check="nonneg",
                              doc="measured: the card's stroke rate; 0 = from its t_s column (required without one)")
    stuffing_box_friction_n: float = num(0.0, unit="N", check="nonneg", hi=1.0e6,
                                         doc="Coulomb friction of the polished rod in the stuffing box (adds to "
                                         "the load going up, subtracts going down)")


@dataclass(frozen=True)
class InflowConfig:
    model: str = choice("none", ("none", "linear", "vogel"), "reservoir inflow performance")
    reservoir_pressure_pa: float = num(8.0e6, unit="Pa", hi=1.0e9)
    productivity_index_m3_day_pa: float = num(2.0e-6, unit="m^3/day/Pa", hi=1.0e-2, doc="linear PI")
    max_rate_m3_day: float = num(30.0, unit="m^3/day", hi=1.0e5, doc="Vogel AOF (q at p_wf = 0)")
    casing_pressure_pa: float = num(2.0e5, unit="Pa", check="nonneg", hi=1.0e9)
    initial_fluid_level_m: float = num(100.0, unit="m", check="nonneg", hi=1.0e5, doc="liquid column above the pump")
    casing_inner_diameter_mm: float = num(124.0, unit="mm", hi=1000.0)
    tubing_outer_diameter_mm: float = num(73.0, unit="mm", hi=1000.0)


@dataclass(frozen=True)
class SimulationConfig:
    element_length_m: float = num(25.0, unit="m", lo=1.0, hi=1.0e4, doc="target FE element length (tapers get whole elements)")
    time_step_s: float = num(0.005, unit="s", lo=1.0e-5, hi=0.05)
    newmark_beta: float = num(0.25, unit="-", hi=10.0)
    newmark_gamma: float = num(0.5, unit="-", hi=10.0)
    qp_solver: str = opt("proxqp", doc="qpsolvers backend of the fallback/reference solve")
    qp_eps_abs: float = num(1e-11, unit="-", lo=1e-15, hi=1.0, doc="absolute tolerance on the normalised dual QP")
    always_qp: bool = opt(False, doc="solve every step's QP with the solver (reference mode)")
    max_corrections: int = num(8, unit="-", check="nonneg", hi=1000, doc="active-set corrections before the QP")
    dc_tolerance_m_s: float = num(1e-10, unit="m/s", lo=1e-15, hi=1.0, doc="DC iterations stop when max |dv| below this")
    dc_max_iterations: int = num(50, unit="-", hi=1000, doc="1 = the paper's single pass")
    nonconvex_step: str = choice("error", ("error", "warn"),
                                 "a nonmonotone law steeper than the condensed stiffness: refuse, or warn and run")


@dataclass(frozen=True)
class ControlConfig:
    spm_min: float = num(3.0, unit="strokes/min", lo=0.1, hi=60.0)
    spm_max: float = num(10.0, unit="strokes/min", lo=0.1, hi=60.0)
    stroke_min_m: float = num(1.0, unit="m", hi=20.0)
    stroke_max_m: float = num(2.0, unit="m", hi=20.0)
    spm_rate_limit: float = num(0.0, unit="strokes/min per step", check="nonneg", hi=60.0, doc="0 = unlimited")
    strokes_per_step: int = num(1, unit="strokes", hi=100, doc="control interval")
    max_episode_steps: int = num(400, unit="steps", hi=10**6, doc="truncation by step count (a cap)")
    max_episode_s: float = num(1000.0, unit="s", hi=1.0e7, doc="truncation by simulated time (the episode's horizon)")
    randomize: bool = opt(True, doc="domain randomisation of well parameters on reset")
    randomize_fraction: float = num(0.1, unit="-", check="unit_interval")


@dataclass(frozen=True)
class RewardConfig:
    production_weight: float = num(1.0, unit="-", check="nonneg", hi=1.0e6)
    stick_slip_weight: float = num(1.0, unit="-", check="nonneg", hi=1.0e6)
    peak_load_weight: float = num(5.0, unit="-", check="nonneg", hi=1.0e6)
    goodman_limit_pct: float = num(100.0, unit="%", hi=1.0e4)
    pprl_rating_n: float = num(60000.0, unit="N", hi=1.0e7)
    failure_penalty: float = num(50.0, unit="-", check="nonneg", hi=1.0e6)
    failure_goodman_pct: float = num(130.0, unit="%", hi=1.0e4, doc="rod failure (episode ends) above this Goodman loading")
    reference_duration_s: float = num(10.0, unit="s", hi=1.0e6, doc="rate terms are weighted by step duration / this, "
                                      "so an episode's return integrates over time, not over strokes")
    production_scale_m3_day: float = num(10.0, unit="m^3/day", hi=1.0e6, doc="production that earns one unit of reward "
                                         "times production_weight")


@dataclass(frozen=True)
class EconomicsConfig:
    """Prices and costs of the v1 reward (USD; every term is a rate in USD per hour of well time)."""

    oil_price_usd_m3: float = num(440.0, unit="USD/m^3", check="nonneg", hi=1.0e5, doc="netback oil price (70 USD/bbl)")
    water_handling_usd_m3: float = num(6.3, unit="USD/m^3", check="nonneg", hi=1.0e4, doc="water lifting and disposal (1 USD/bbl)")
    water_cut: float = num(0.5, unit="-", check="unit_interval", hi=1.0, doc="water fraction of the produced liquid")
    electricity_usd_kwh: float = num(0.12, unit="USD/kWh", check="nonneg", hi=100.0)
    motor_efficiency: float = num(0.8, unit="-", lo=0.01, hi=1.0, doc="electric input -> polished-rod work")
    workover_usd: float = num(30000.0, unit="USD", check="nonneg", hi=1.0e8, doc="cost of one rod-string failure (pulling job)")
    fatigue_life_cycles: float = num(1.0e7, unit="cycles", lo=1.0e3, hi=1.0e12, doc="rod life at 100 % Goodman loading (API RP 11BR basis)")
    fatigue_exponent: float = num(6.0, unit="-", lo=1.0, hi=20.0, doc="S-N exponent m: damage per cycle (G/100)^m / life")
    stick_slip_usd_per_j: float = num(0.0002, unit="USD/J", check="nonneg", hi=1.0e3,
                                      doc="price of the elastic energy released by extra plunger stick-slip")
    overload_usd_h: float = num(2000.0, unit="USD/h", check="nonneg", hi=1.0e7,
                                doc="cost rate at 100 % over a rating (quadratic in the excess)")
    pound_usd_per_m2_s2: float = num(0.15, unit="USD/(m/s)^2", check="nonneg", hi=1.0e6,
                                     doc="per stroke, times the squared plunger speed when it meets the liquid")
    ramp_usd_per_spm2: float = num(0.1, unit="USD/SPM^2", check="nonneg", hi=1.0e6,
                                   doc="VSD ramp: per change of the average SPM between intervals, squared")
    failure_usd: float = num(30000.0, unit="USD", check="nonneg", hi=1.0e9, doc="rod failure (ends the episode)")
    pprl_rating_n: float = num(80000.0, unit="N", lo=1.0e3, hi=1.0e7, doc="unit structure rating")


@dataclass(frozen=True)
class TaskConfig:
    """The v1 control task: control interval, horizon, inflow schedule, observation extras."""

    interval_s: float = num(300.0, unit="s", lo=10.0, hi=86400.0, doc="one env step of well time (idle or pumping)")
    episode_hours: float = num(12.0, unit="h", lo=0.01, hi=8760.0, doc="horizon; truncated after it")
    exact_strokes_max: int = num(4, unit="strokes", lo=1, hi=1000, doc="strokes simulated exactly per interval; the rest is "
                                 "fast-forwarded quasi-steadily (annulus mass balance, last exact stroke's loads)")
    fast_forward_fillage_tol: float = num(0.05, unit="-", check="unit_interval", hi=1.0,
                                          doc="re-simulate exactly when the fast-forwarded fillage drifts this much")
    level_shot_interval_h: float = num(4.0, unit="h", lo=0.01, hi=1.0e4, doc="acoustic fluid-level shot every this many hours")
    inflow_decline_per_day: float = num(0.05, unit="1/day", check="nonneg", hi=10.0, doc="exponential inflow decline")
    inflow_step_fraction: float = num(0.0, unit="-", check="any", lo=-0.99, hi=10.0,
                                      doc="fixed-well scenario: step of the inflow multiplier at mid-episode")
    failure_goodman_pct: float = num(150.0, unit="%", lo=1.0, hi=1000.0, doc="rod failure above this Goodman loading")
    fillage_estimator: str = choice("pump_card", ("pump_card", "diagnose", "surface"),
                                    "the controller's fillage: read off the downhole card (pump_card: the "
                                    "simulated one, a perfect diagnostic; diagnose: Gibbs' method on the surface "
                                    "card, ~10 ms per interval; surface: the surface card's load drop, which deep "
                                    "wells' rod dynamics hide)")


@dataclass(frozen=True)
class TubingConfig:
    anchored: bool = opt(True, doc="false: the tubing stretches under the fluid load (shortens the pump stroke)")
    outer_diameter_mm: float = num(73.0, unit="mm", lo=10.0, hi=500.0, doc="tubing body OD (2 7/8 in)")
    inner_diameter_mm: float = num(62.0, unit="mm", lo=5.0, hi=500.0)
    youngs_modulus_pa: float = num(2.07e11, unit="Pa", lo=1.0e9, hi=1.0e12)
    anchor_depth_m: float = num(0.0, unit="m", check="nonneg", hi=2.0e4,
                                doc="MD of a tubing anchor above the pump; 0 = none (free from the surface)")


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
    tubing: TubingConfig = field(default_factory=TubingConfig)
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
        lo, hi = meta.get("lo"), meta.get("hi")
        what += _range_phrase(lo, hi)
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise ConfigError(path, value, what)
        if isinstance(value, int):
            # compare exactly before any float(): float(10**400) overflows (and no field is that large)
            if abs(value) > _MAX_INT_MAGNITUDE:
                raise ConfigError(path, value, what)
        elif not math.isfinite(value) or (tp is int and not value.is_integer()):
            raise ConfigError(path, value, what)
        x = tp(value)
        if not pred(float(x)) or (lo is not None and x < lo) or (hi is not None and x > hi):
            raise ConfigError(path, value, what)
        return x
    raise TypeError(f"unsupported config type {tp} at {path}")  # programming error, not user input


# integers beyond this are refused before any conversion to float (every bound is far below it)
_MAX_INT_MAGNITUDE = 10**15


def _range_phrase(lo: float | None, hi: float | None) -> str:
    if lo is not None and hi is not None:
        return f" within [{lo:g}, {hi:g}]"
    if hi is not None:
        return f" at most {hi:g}"
    return f" at least {lo:g}" if lo is not None else ""


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
    if p.intake_gas_fraction > 0 or p.intake_glr_m3_m3 > 0:
        if p.intake_gas_fraction > 0 and p.intake_glr_m3_m3 > 0:
            raise ConfigError("pump.intake_glr_m3_m3", p.intake_glr_m3_m3,
                              "0 when pump.intake_gas_fraction is given (one measure of the free gas)")
        if p.intake_gas_fraction >= 1:
            raise ConfigError("pump.intake_gas_fraction", p.intake_gas_fraction, "a fraction below 1")
        if p.load_source != "pressures" or p.law != "constant":
            raise ConfigError("pump.load_source", p.load_source, "'pressures' with pump.law 'constant' when the "
                              "intake carries free gas (the chamber pressure sets the plunger load)")
        if p.gas_polytropic_exponent < 1:
            raise ConfigError("pump.gas_polytropic_exponent", p.gas_polytropic_exponent,
                              "an exponent >= 1 (1 isothermal, 1.3 adiabatic natural gas)")
    tb = cfg.tubing
    if not tb.anchored:
        if tb.inner_diameter_mm >= tb.outer_diameter_mm:
            raise ConfigError("tubing.inner_diameter_mm", tb.inner_diameter_mm,
                              f"a diameter in mm below tubing.outer_diameter_mm = {tb.outer_diameter_mm}")
        if tb.anchor_depth_m >= cfg.rod_length_m:
            raise ConfigError("tubing.anchor_depth_m", tb.anchor_depth_m,
                              f"a depth in m above the pump ({cfg.rod_length_m} m)")
        if p.intake_gas_fraction > 0 or p.intake_glr_m3_m3 > 0:
            raise ConfigError("tubing.anchored", tb.anchored, "true when the intake carries free gas (the "
                              "two chamber models are not combined)")
        if p.law != "constant":
            raise ConfigError("tubing.anchored", tb.anchored, "true with pump.law 'nonmonotone'")
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
    if cfg.surface.motion == "measured":  # a bad card file is refused at load time, before any work
        from .measured_motion import load_measured_motion

        load_measured_motion(cfg.surface.measured_card_csv, cfg.surface.measured_spm)
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


# Derived resource bounds (docs/reliability.md): checked when a config is loaded, before any allocation.
MAX_NODES = 2000  # FE nodes of the rod string (a 10 km string at 5 m elements)
MAX_DENSE_NODES = 500  # consistent mass (dense eigenproblem) or always_qp (dense QP every step): n^2 arrays
MAX_STEPS_PER_STROKE = 200_000  # time steps of one stroke (memory of its recorded trace: 13 MB)
MAX_RUN_SAMPLES = 1_000_000  # recorded time steps of one CLI run / sweep case (the CSV's rows, ~100 MB)


def node_count(cfg: WellConfig) -> int:
    """Nodes of the FE mesh :func:`srenv.rod.build_mesh` builds (whole elements per taper, plus the top)."""
    h = cfg.simulation.element_length_m
    return 1 + sum(max(1, math.ceil(t.length_m / h - 1e-9)) for t in cfg.rod.tapers)


def check_dense_size(cfg: WellConfig, always_qp: bool | None = None) -> None:
    """Refuse dense n x n work above MAX_DENSE_NODES (``always_qp`` may come from the command line)."""
    always = cfg.simulation.always_qp if always_qp is None else always_qp
    n = node_count(cfg)
    if n > MAX_DENSE_NODES and (always or cfg.rod.mass_matrix == "consistent"):
        why = "simulation.always_qp / --always-qp" if always else "rod.mass_matrix = consistent"
        raise ConfigError("simulation.element_length_m", cfg.simulation.element_length_m,
                          f"a length in m giving at most {MAX_DENSE_NODES} nodes with {why} (dense n^2 "
                          f"arrays; this mesh has {n} nodes)")


def steps_per_stroke(cfg: WellConfig, spm: float) -> int:
    return max(1, math.ceil(60.0 / spm / cfg.simulation.time_step_s - 1e-9))


def check_stroke_steps(cfg: WellConfig, spm: float, field_name: str) -> None:
    n = steps_per_stroke(cfg, spm)
    if n > MAX_STEPS_PER_STROKE:
        raise ConfigError("simulation.time_step_s", cfg.simulation.time_step_s,
                          f"a time step in s giving at most {MAX_STEPS_PER_STROKE} steps per stroke at "
                          f"{field_name} = {spm:g} strokes/min (this one: {n})")


def check_run_samples(n_samples: int, flag: str, value: Any) -> None:
    """Refuse a run that would record more than MAX_RUN_SAMPLES time steps (memory and output size)."""
    if n_samples > MAX_RUN_SAMPLES:
        raise ConfigError(flag, value, f"a run of at most {MAX_RUN_SAMPLES} recorded time steps (this one: "
                          f"{n_samples}; shorten it or raise simulation.time_step_s)")


def _check_resources(cfg: WellConfig) -> None:
    n = node_count(cfg)
    if n > MAX_NODES:
        raise ConfigError("simulation.element_length_m", cfg.simulation.element_length_m,
                          f"a length in m giving at most {MAX_NODES} nodes (this mesh of the "
                          f"{cfg.rod_length_m:g} m string has {n})")
    check_dense_size(cfg)
    if cfg.surface.motion != "pullout":
        check_stroke_steps(cfg, cfg.surface.spm, "surface.spm")


def _check_conventional_unit(surface: SurfaceConfig) -> None:
    """A conventional unit's stroke comes from its crank hole: the unit must exist and have that hole, or
    the stroke would be beyond what the unit can make. Checked at load time (not only when a simulator is
    built) so that every loader of a config - CLI, env, sweeps - refuses it before doing any work."""
    conventional_unit(surface.unit, surface.crank_hole)


def _known_solvers() -> list[str]:
    import qpsolvers

    return list(qpsolvers.available_solvers)


# ----------------------------------------------------------------------------------------------- loading
CONFIG_DIR = shipped_dir("wells")  # configs/wells of the checkout, or the wheel's package data


def shipped_configs() -> list[str]:
    return sorted(p.stem for p in CONFIG_DIR.glob("*.yaml"))


def _resolve(path_or_name: str | Path) -> Path:
    """A path is a path, a name is a name: anything with a path separator or a .yaml/.yml suffix (or a
    ``Path``) must be an existing, regular, readable file; a bare name must be a shipped config. (A path
    that does not exist never falls back to the shipped config of the same name.)"""
    text = str(path_or_name)
    if isinstance(path_or_name, Path) or "/" in text or os.sep in text or text.endswith((".yaml", ".yml")):
        p = Path(text)
        if not p.exists():
            raise ConfigError("config", text, "an existing YAML file (no such file); or a shipped name: "
                              + ", ".join(shipped_configs()))
        if not p.is_file():
            raise ConfigError("config", text, "a regular YAML file (this is a directory or a special file)")
        if not os.access(p, os.R_OK):
            raise ConfigError("config", text, "a readable YAML file (permission denied)")
        return p
    if text in shipped_configs():
        return CONFIG_DIR / f"{text}.yaml"
    raise ConfigError("config", text, "a YAML path or a shipped name: " + ", ".join(shipped_configs()))


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


def load_yaml_file(path: str | Path, field_name: str) -> Any:
    """Read one YAML file with the bounded, duplicate-refusing safe loader; every problem (unreadable, too
    large, not UTF-8, bad syntax) is one ConfigError naming ``field_name`` and the path."""
    try:
        with open(path, "rb") as fh:
            raw = fh.read(MAX_YAML_BYTES + 1)
    except OSError as exc:
        raise ConfigError(field_name, str(path), f"a readable YAML file ({exc.strerror or exc})") from None
    if len(raw) > MAX_YAML_BYTES:
        raise ConfigError(field_name, str(path), f"a YAML file of at most {MAX_YAML_BYTES} bytes")
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError:
        raise ConfigError(field_name, str(path), "a UTF-8 text file") from None
    try:
        return _yaml_load(text)
    except yaml.YAMLError as exc:
        raise ConfigError(field_name, str(path), f"valid YAML ({_yaml_problem(exc)})") from None
    except RecursionError:
        raise ConfigError(field_name, str(path), "valid YAML (nested too deeply)") from None


def read_raw(path_or_name: str | Path) -> dict:
    path = _resolve(path_or_name)
    data = load_yaml_file(path, "config")
    if data is None:
        data = {}
    if not isinstance(data, dict):
        raise ConfigError("config", str(path), "a YAML mapping at the top level")
    return data


def _material_defaults(data: dict) -> dict:
    """Fill a fiberglass / sinker-bar taper's unset E, density and strength from MATERIAL_DEFAULTS."""
    tapers = (data.get("rod") or {}).get("tapers") if isinstance(data.get("rod"), dict) else None
    if not isinstance(tapers, list):
        return data
    import copy

    data = copy.deepcopy(data)
    for t in data["rod"]["tapers"]:
        if isinstance(t, dict) and t.get("material") in MATERIAL_DEFAULTS:
            for key, value in MATERIAL_DEFAULTS[t["material"]].items():
                t.setdefault(key, value)
    return data


def config_from_dict(data: dict) -> WellConfig:
    cfg = _parse(WellConfig, _material_defaults(data), "")
    _check_consistency(cfg)
    _check_resources(cfg)
    return cfg


def field_bounds(key: str) -> tuple[float, float]:
    """(lo, hi) of a numeric field given as 'section.field' (-inf / inf where unbounded): lets callers that
    perturb a value (the env's domain randomisation) keep it inside what the loader accepts."""
    section, name = key.split(".")
    cls = typing.get_type_hints(WellConfig)[section]
    meta = {f.name: f.metadata for f in dataclasses.fields(cls)}[name]
    return float(meta.get("lo", -math.inf)), float(meta.get("hi", math.inf))


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


def _range_doc(meta: Any) -> str:
    """The accepted range of a numeric field, as in its error message ('' for non-numeric fields)."""
    if "check" not in meta:
        return ""
    lo_by_check = {"positive": "(0", "nonneg": "[0", "unit_interval": "[0", "angle": "[0", "azimuth": "[-360"}
    hi_by_check = {"unit_interval": "1]", "angle": "180]", "azimuth": "360]"}
    lo = f"[{meta['lo']:g}" if "lo" in meta else lo_by_check.get(meta["check"], "(-inf")
    hi = f"{meta['hi']:g}]" if "hi" in meta else hi_by_check.get(meta["check"], "inf)")
    return f"{lo}, {hi}"


def config_doc() -> str:
    """Markdown table of every config field with unit, default and meaning."""
    lines = ["| field | unit | default | range | meaning |", "|---|---|---|---|---|"]

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
                lines.append(f"| `{key}` | list | [] | | {f.metadata.get('doc', '')} |")
                walk(item, key + "[i].")
                continue
            default = "required" if f.default is dataclasses.MISSING else repr(f.default)
            doc = f.metadata.get("doc", "")
            if "options" in f.metadata:
                doc = (doc + "; " if doc else "") + "one of " + ", ".join(f.metadata["options"])
            lines.append(f"| `{key}` | {f.metadata.get('unit', '')} | {default} | {_range_doc(f.metadata)} | {doc} |")

    walk(WellConfig, "")
    return "\n".join(lines)
