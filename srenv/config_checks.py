"""Cross-field consistency of a well config and the resource bounds checked before any work (nodes, dense
arrays, steps per stroke, recorded samples); each refusal names the field, the value and what is expected."""

from __future__ import annotations

import math
from typing import Any

from .config_sections import SurfaceConfig, WellConfig
from .errors import ConfigError
from .surface_unit.inline_unit import check_surface as check_inline_unit
from .surface_unit.unit_catalogue import conventional_unit


def _check_consistency(cfg: WellConfig) -> None:
    """Cross-field checks (each names the offending field), section by section."""
    if not cfg.rod.tapers:
        raise ConfigError("rod.tapers", [], "at least one taper")
    _check_pump(cfg)
    _check_chamber_conditions(cfg)
    _check_pump_inputs(cfg)
    _check_tubing(cfg)
    f = cfg.friction
    if f.law == "nonmonotone" and f.kinetic_coefficient > f.coefficient:
        raise ConfigError("friction.kinetic_coefficient", f.kinetic_coefficient,
                          f"a coefficient <= friction.coefficient = {f.coefficient} (static)")
    _check_survey(cfg)
    if cfg.surface.motion == "conventional":
        _check_conventional_unit(cfg.surface)
    check_inline_unit(cfg.surface)  # surface.beam_unit: the unit by its nameplate
    if cfg.surface.motion == "measured":  # a bad card file is refused at load time, before any work
        from .surface_unit.measured_motion import load_measured_motion

        load_measured_motion(cfg.surface.measured_card_csv, cfg.surface.measured_spm)
    _check_control(cfg)
    _check_intake_and_diameters(cfg)


def _check_pump(cfg: WellConfig) -> None:
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
    if p.fillage < 1 and (p.intake_gas_fraction > 0 or p.intake_glr_m3_m3 > 0 or cfg.inflow.model != "none"):
        raise ConfigError("pump.fillage", p.fillage, "1 when pump.intake_gas_fraction, pump.intake_glr_m3_m3 or "
                          "an inflow model sets the pump's fill (one measure of it)")
    if p.intake_gas_fraction > 0 or p.intake_glr_m3_m3 > 0 or p.fillage < 1:
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
    if p.liquid_compressibility_per_pa > 0 and p.law != "constant":
        raise ConfigError("pump.liquid_compressibility_per_pa", p.liquid_compressibility_per_pa,
                          "0 with pump.law 'nonmonotone' (the liquid spring carries the constant law only)")
    gas = p.intake_gas_fraction > 0 or p.intake_glr_m3_m3 > 0 or p.fillage < 1
    if p.clearance_gas_fraction > 0 and not gas:
        raise ConfigError("pump.clearance_gas_fraction", p.clearance_gas_fraction,
                          "0 without free gas at the intake (the clearance's gas comes with it)")
    if (p.liquid_compressibility_per_pa > 0 and not gas and p.liquid_chamber_volume == "per_transfer"
            and not p.clearance_volume_fraction > 0):  # the upstroke's transfer decompresses the clearance's liquid
        raise ConfigError("pump.clearance_volume_fraction", p.clearance_volume_fraction,
                          "a fraction > 0 with pump.liquid_compressibility_per_pa > 0 and no free gas (the "
                          "upstroke's load transfer decompresses the clearance's liquid)")


# the pump-condition laws the kernel's chamber spring does not carry: with free gas, a compressible chamber liquid
# or unanchored tubing the plunger meets the chamber law instead of the valve law these act through, so they
# would be dropped without a word (measured: the card identical to the same well without them). The valve leaks
# move the valve interval the chamber's spring replaces; a leak through a closed valve would
# change what the chamber holds (docs/conditions.md), which the spring law does not model yet. The tubing leak
# drains the column the spring pushes on (laws.pump_conditions.drain_discharge) and tagging's contact adds to
# the spring (contact_force), but tagging holds the pump's ends fixed, which an unanchored barrel is not (it
# travels with the tubing's stretch, and the contact would load the tubing in series)
_NOT_WITH_A_SPRING = ("travelling_valve_leak_fraction", "standing_valve_leak_fraction")
_NOT_WITH_FREE_TUBING = ("tag_top_overtravel_m", "tag_bottom_overtravel_m")


def _check_chamber_conditions(cfg: WellConfig) -> None:
    p = cfg.pump
    gas = p.intake_gas_fraction > 0 or p.intake_glr_m3_m3 > 0 or p.fillage < 1
    spring = ("free gas at the intake" if gas else "pump.liquid_compressibility_per_pa > 0"
              if p.liquid_compressibility_per_pa > 0 else "unanchored tubing" if not cfg.tubing.anchored else None)
    if spring is None:
        return
    for name in _NOT_WITH_A_SPRING + (("flow_through_fraction",) if gas else ()):
        value = getattr(p, name)
        if value > 0:
            raise ConfigError(f"pump.{name}", value, f"0 with {spring}: the chamber's spring law does not carry "
                              "this condition yet (the card would be the same as without it)")
    for name in _NOT_WITH_FREE_TUBING if not cfg.tubing.anchored else ():
        value = getattr(p, name)
        if value > 0:
            raise ConfigError(f"pump.{name}", value, "0 with unanchored tubing (a spring on the plunger): the "
                              "tagging law holds the pump's ends fixed, and a free barrel moves with the tubing")


def _check_pump_inputs(cfg: WellConfig) -> None:
    """The predictive inputs (physics.pump_inputs): a pump at or below the rods' end, a fluid level above the
    pump with its casing pressure, neither where the loads are given or an inflow model keeps its own level."""
    p = cfg.pump
    if p.depth_m is not None and p.depth_m < cfg.rod_length_m:
        raise ConfigError("pump.depth_m", p.depth_m, f"a depth in m at or below the rod string's end "
                          f"({cfg.rod_length_m:g} m, the sum of taper lengths), or null")
    if (p.fluid_level_m is None) != (p.casing_pressure_pa is None):
        field, value = (("pump.casing_pressure_pa", p.casing_pressure_pa) if p.fluid_level_m is None
                        else ("pump.fluid_level_m", p.fluid_level_m))
        raise ConfigError(field, value, "given together with "
                          + ("pump.fluid_level_m" if p.fluid_level_m is None else "pump.casing_pressure_pa")
                          + " (a fluid-level shot is the level and its casing pressure), or both null")
    depth = cfg.rod_length_m if p.depth_m is None else p.depth_m
    if p.fluid_level_m is not None and p.fluid_level_m > depth:
        raise ConfigError("pump.fluid_level_m", p.fluid_level_m, f"a level in m from the surface at or above the "
                          f"pump ({depth:g} m)")
    for name in ("depth_m", "fluid_level_m"):
        value = getattr(p, name)
        if value is not None and p.load_source != "pressures":
            raise ConfigError(f"pump.{name}", value, "null when pump.load_source is 'loads' (the plunger loads are "
                              "given at the rod end)")
        if value is not None and cfg.inflow.model != "none":
            raise ConfigError(f"pump.{name}", value, "null with an inflow model (its annulus sets the level and "
                              "the pump is at the rod end)")


def _check_tubing(cfg: WellConfig) -> None:
    p = cfg.pump
    tb = cfg.tubing
    if tb.anchored and tb.stiffness_n_m > 0:
        raise ConfigError("tubing.stiffness_n_m", tb.stiffness_n_m, "0 with anchored tubing (the free tubing's "
                          "stiffness; set tubing.anchored: false)")
    if not tb.anchored:
        if tb.inner_diameter_mm >= tb.outer_diameter_mm:
            raise ConfigError("tubing.inner_diameter_mm", tb.inner_diameter_mm,
                              f"a diameter in mm below tubing.outer_diameter_mm = {tb.outer_diameter_mm}")
        if tb.anchor_depth_m >= cfg.rod_length_m:
            raise ConfigError("tubing.anchor_depth_m", tb.anchor_depth_m,
                              f"a depth in m above the pump ({cfg.rod_length_m} m)")
        gas = p.intake_gas_fraction > 0 or p.intake_glr_m3_m3 > 0 or p.fillage < 1
        if gas and not p.liquid_compressibility_per_pa > 0:
            raise ConfigError("tubing.anchored", tb.anchored, "true when the intake carries free gas, unless "
                              "pump.liquid_compressibility_per_pa > 0 (the chamber law that combines them)")
        if p.law != "constant":
            raise ConfigError("tubing.anchored", tb.anchored, "true with pump.law 'nonmonotone'")


def _check_survey(cfg: WellConfig) -> None:
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


def _check_control(cfg: WellConfig) -> None:
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


def _check_intake_and_diameters(cfg: WellConfig) -> None:
    p = cfg.pump
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
MAX_EPISODE_STEPS = 20_000  # env steps of one v1 episode (task.episode_hours / task.interval_s): a year at
#                             30-min intervals; 8760 h at 10 s would be 3.2 M steps of per-step work and logs


def node_count(cfg: WellConfig) -> int:
    """Nodes of the FE mesh :func:`srenv.physics.rod.build_mesh` builds (whole elements per taper, plus the top)."""
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


def run_spm(cfg: WellConfig) -> float:
    """The stroke rate of a run that names none: ``surface.spm``, or a measured card's own (its period, not
    ``surface.spm``, sets the steps per stroke: a 20-row card spanning 1e5 s is 1e8 steps a stroke)."""
    if cfg.surface.motion == "measured":
        from .surface_unit.measured_motion import load_measured_motion

        return load_measured_motion(cfg.surface.measured_card_csv, cfg.surface.measured_spm).spm
    return cfg.surface.spm


def _check_measured_period(cfg: WellConfig) -> None:
    spm = run_spm(cfg)
    n = steps_per_stroke(cfg, spm)
    if n > MAX_STEPS_PER_STROKE:
        s = cfg.surface
        field, value = (("surface.measured_spm", s.measured_spm) if s.measured_spm > 0
                        else ("surface.measured_card_csv", s.measured_card_csv))
        raise ConfigError(field, value, f"a card whose stroke ({60.0 / spm:.6g} s) takes at most "
                          f"{MAX_STEPS_PER_STROKE} time steps of simulation.time_step_s = "
                          f"{cfg.simulation.time_step_s:g} s (this one: {n})")


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
    steps = cfg.task.episode_hours * 3600.0 / cfg.task.interval_s
    if steps > MAX_EPISODE_STEPS:
        raise ConfigError("task.episode_hours", cfg.task.episode_hours,
                          f"a horizon in h of at most {MAX_EPISODE_STEPS} env steps of task.interval_s = "
                          f"{cfg.task.interval_s:g} s (this one: {steps:.0f}; at most "
                          f"{MAX_EPISODE_STEPS * cfg.task.interval_s / 3600.0:g} h)")
    if cfg.surface.motion == "measured":
        _check_measured_period(cfg)
    elif cfg.surface.motion != "pullout":
        check_stroke_steps(cfg, cfg.surface.spm, "surface.spm")


def _check_conventional_unit(surface: SurfaceConfig) -> None:
    """A conventional unit's stroke comes from its crank hole: the unit must exist and have that hole, or
    the stroke would be beyond what the unit can make. Checked at load time (not only when a simulator is
    built) so that every loader of a config - CLI, env, sweeps - refuses it before doing any work."""
    conventional_unit(surface.unit, surface.crank_hole)


def _known_solvers() -> list[str]:
    import qpsolvers

    return list(qpsolvers.available_solvers)


