"""The sections of a well config: frozen dataclasses whose numeric fields carry their unit, check and range.

``srenv.config`` parses YAML into these and re-exports them; ``docs/config.md`` is generated from them.
"""

from __future__ import annotations

import typing
from dataclasses import dataclass, field

from .config_fields import _CHECKS, choice, num, opt  # noqa: F401  (_CHECKS re-exported for the loader)
from .config_unit import GEOMETRIES, ROTATIONS, BeamUnitConfig, MotorConfig  # noqa: F401  (re-exported with the sections)


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
    damping_scale: float = num(1.0, unit="-", check="nonneg", hi=100.0,
                               doc="this taper's viscous damping per length = the string's (damping.*) x this "
                                   "factor (e.g. guided rods, sinker bars in a tight annulus); 1 = as the string")


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
    stiffness_proportional_s: float = num(0.0, unit="s", check="nonneg", hi=1.0,
                                          doc="Kelvin-Voigt retardation time tau: element force EA/L (du + tau dv); "
                                              "damps mode k by zeta_k = tau w_k / 2 (the string's high modes: "
                                              "couplings, guides, fluid); 0 = off (docs/realism.md)")
    upstroke_factor: float = num(1.0, unit="-", check="nonneg", hi=100.0,
                                 doc="the viscous damping (above, not tau) times this while the polished rod rises "
                                     "(a vendor's upstroke coefficient / the string's); chosen from the polished "
                                     "rod's velocity at the previous step (docs/realism.md); 1 = as the string")
    downstroke_factor: float = num(1.0, unit="-", check="nonneg", hi=100.0,
                                   doc="the same while the polished rod falls; 1 = as the string")


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
    # a set fluid level excludes the intake pressure (config._check_exclusive, to_dict)
    EXCLUDES: typing.ClassVar[dict[str, str]] = {"fluid_level_m": "intake_pressure_pa"}
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
    fluid_column_mass_kg: float = num(0.0, unit="kg", check="nonneg", hi=1.0e6,
                                      doc="liquid column lifted with the rising plunger, as a mass at the plunger "
                                          "(rho L A_pl^2 / (A_t - A_r), physics/pump.fluid_column_mass_kg); its "
                                          "inertia adds to the pump load on the upstroke; 0 = off (docs/realism.md)")
    fillage: float = num(1.0, unit="-", hi=1.0,
                         doc="predictive input: liquid share of the plunger's displacement; < 1 is free gas at the "
                             "intake whose compression takes 1 - fillage of the stroke at pump.intake_pressure_pa "
                             "(physics/pump.py); 1 = full (docs/realism.md)")
    # pump conditions (srenv.physics.laws.pump_conditions, docs/conditions.md); 0 = off everywhere
    travelling_valve_leak_fraction: float = num(0.0, unit="-", check="nonneg", hi=100.0,
                                                doc="leak through the closed travelling valve at the full pressure "
                                                "difference / the plunger's peak displacement rate (0 = tight)")
    standing_valve_leak_fraction: float = num(0.0, unit="-", check="nonneg", hi=100.0,
                                              doc="leak through the closed standing valve, same measure")
    tubing_leak_fraction: float = num(0.0, unit="-", check="unit_interval", hi=1.0,
                                      doc="share of the fluid load lost to a tubing leak by the top of the upstroke")
    flow_through_fraction: float = num(0.0, unit="-", check="nonneg", hi=0.95,
                                       doc="share of the fluid load carried by the well flowing through the pump")
    tag_top_overtravel_m: float = num(0.0, unit="m", check="nonneg", hi=20.0,
                                      doc="tagging up: the pump's top this far inside the plunger's first free "
                                      "upstroke (0 = no contact)")
    tag_bottom_overtravel_m: float = num(0.0, unit="m", check="nonneg", hi=20.0,
                                         doc="tagging down: the pump's bottom this far inside the first free "
                                         "downstroke (0 = no contact)")
    tag_stiffness_n_m: float = num(2.0e5, unit="N/m", lo=1.0e3, hi=1.0e8,
                                   doc="contact stiffness of the pump's ends (explicit: keep k dt^2 below the "
                                   "plunger node's mass)")
    liquid_compressibility_per_pa: float = num(
        0.0, unit="1/Pa", check="nonneg", hi=1.0e-6,
        doc="gradual load transfer: the pumped liquid's compressibility (water 4.5e-10); the chamber's liquid "
            "(and free gas, and unanchored tubing) is a spring in series with the valve law, so the load "
            "transfers over a plunger travel instead of at once; 0 = incompressible (docs/realism.md)")
    clearance_gas_fraction: float = num(
        0.0, unit="-", check="unit_interval", hi=1.0,
        doc="gas share of the clearance at the discharge pressure that the open travelling valve does not pass "
            "(trapped where the plunger does not sweep): it re-expands on every upstroke before the standing "
            "valve opens; with pump.fillage the intake's gas is the rest of the fillage's; 0 = the chamber "
            "expels its own mixture (docs/realism.md)")
    liquid_chamber_volume: str = choice(
        "per_transfer", ("per_transfer", "top_of_stroke"),
        "without free gas, the chamber liquid each load transfer compresses: per_transfer = the clearance at the "
        "bottom (upstroke), clearance + swept at the top (downstroke); top_of_stroke = the top's for both (the "
        "earlier law, kept for the classifier's card sets)")
    # predictive inputs (docs/realism.md, "Predictive inputs"); None = not given
    depth_m: float | None = num(None, unit="m", lo=1.0, hi=1.0e5,
                                doc="measured depth of the pump when it sits below the rod string's end (the "
                                    "pump's own length, a pull tube; sinker bars are a taper): the liquid column "
                                    "between rod end and pump enters the valve law as an intake pressure lower by "
                                    "its weight; at or below the sum of taper lengths; null = at the rod end")
    fluid_level_m: float | None = num(None, unit="m", check="nonneg", hi=1.0e5,
                                      doc="annulus fluid level measured from the surface along the hole (an acoustic "
                                          "sounder's shot): the intake pressure follows, pump.casing_pressure_pa + "
                                          "rho_f g (TVD of the pump - TVD of the level); instead of "
                                          "pump.intake_pressure_pa; null = not given")
    casing_pressure_pa: float | None = num(None, unit="Pa", check="nonneg", hi=1.0e9,
                                           doc="casing-head pressure of the fluid-level shot (the same reference as "
                                               "pump.intake_pressure_pa); given with pump.fluid_level_m only")


@dataclass(frozen=True)
class SurfaceConfig:
    motion: str = choice("harmonic", ("harmonic", "conventional", "pullout", "measured", "beam_unit"),
                         "measured: the polished-rod position of surface.measured_card_csv (docs/field.md); "
                         "conventional: the catalogue unit surface.unit; beam_unit: the unit surface.beam_unit")
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
    beam_unit: BeamUnitConfig | None = field(default=None, metadata={"doc": (
        "motion beam_unit: the unit by its nameplate (API 11E dimensions; docs/surface_unit.md) instead of a "
        "catalogue designation")})
    motor: MotorConfig | None = field(default=None, metadata={"doc": (
        "motion conventional or beam_unit: the unit's motor; its slip lets the crank speed follow the gearbox "
        "torque through the stroke at the same SPM (docs/surface_unit.md, 'The motor'); null = constant crank speed")})


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
    stiffness_n_m: float = num(0.0, unit="N/m", check="nonneg", hi=1.0e10,
                               doc="with anchored false: the free tubing's stiffness at the pump where it is known "
                                   "otherwise than from its size (read off a diagnosed pump card's load transfer, "
                                   "docs/realism.md); 0 = E A / free length")


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


