"""The pump's valve cycle between kernel calls: fluid-pound planning at the bottom, fillage and production
at the top, the gas chamber's start, and the idle-time hooks of the v1 env (a mix-in of Simulator).

The kernel stops at every plunger reversal (EVENT); :meth:`PumpCycle._on_event` decides whether it is a
valve cycle and updates the valve law's record (srenv.physics.laws.valve.PARAMS) and the plunger extremes
(kernel_layout.PROGRESS) for the rest of the run.
"""

from __future__ import annotations

import numpy as np

from ..physics.laws import pump_conditions
from ..physics.laws import valve as valve_law_record
from ..physics.pump import plunger_area_m2

# gas whose compression from the intake to the discharge pressure spans less than this fraction of the stroke
# leaves the valve law rigid: a spring far stiffer than the rod, whose transfer would span a step or two
GAS_MIN_DELAY_FRACTION = 0.01


class PumpCycle:
    """Valve-cycle bookkeeping of :class:`srenv.simulation.simulator.Simulator` (uses its cfg, annulus, gas, law)."""

    # a tagging condition's contact ends, once placed, stay where they are through a stop at the bottom (v3: a
    # spacing drift is a fixed position); False (v2 and the cards): a stop's reset clears them and the first
    # stroke after the restart places them again, relative to that stroke
    fixed_contact_ends = False

    def _intake_pa(self) -> float:
        return self.annulus.intake_pressure_pa() if self.annulus is not None else self.cfg.pump.intake_pressure_pa

    def gas_liquid_fraction(self, stroke_in_barrel_m: float) -> float:
        """The share of the plunger's stroke in the barrel that liquid fills at today's intake pressure (the free
        gas takes the rest; 1 without gas): one formula for the exact strokes and the interval's fast-forward."""
        if self.gas is None:
            return 1.0
        return self.gas.liquid_fraction(self._intake_pa(), self.p_pump_pa + self.cfg.pump.discharge_overpressure_pa,
                                        stroke_in_barrel_m)

    def _gas_start(self) -> None:
        """The chamber at the bottom of the stroke after reset: the clearance holds the compressed mixture
        (gas at p_d); from here the kernel follows it (laws.gas_spring.valves)."""
        p_in, p_d = self._intake_pa(), self.p_pump_pa + self.cfg.pump.discharge_overpressure_pa
        vg = self.gas.clearance_gas_m3(p_in, p_d)
        self._gas[:] = (1.0, float(self.u[-1]), vg, p_d, self.gas.clearance_m3 - vg)

    def _plan_upstroke(self, u_bottom_m: float, time_s: float, period_s: float) -> float:
        """At the bottom: the liquid the coming upstroke can draw (annulus + inflow during the upstroke)
        fixes the liquid level in the barrel; above it the plunger meets no liquid (fluid pound). Returns
        that level (positive down, the valve law's void_until_m)."""
        self.annulus.accumulate(time_s)
        rising_s = self.upstroke_s(period_s)  # the standing valve is open while the plunger rises
        available_m3 = self.annulus.volume_m3 + self.annulus.inflow_m3_s() * rising_s
        self._liquid_stroke_m = available_m3 / plunger_area_m2(self.cfg.pump)
        return u_bottom_m - self._liquid_stroke_m

    def _on_event(self, direction: int, valve: np.ndarray, progress: np.ndarray, time_s: float, events: list,
                  fillage: float, stroke_m: float, period_s: float) -> float:
        """A plunger reversal. Short reversals inside a stroke (stick-slip chatter, the bounce when a pounding
        plunger meets liquid) are not valve cycles: a reversal counts only after a travel of a quarter of the
        surface stroke, and the stroke is measured between position extremes, not reversal points."""
        ub = float(self.u[-1])
        min_travel = 0.25 * stroke_m
        ub_max, ub_min = float(progress["ub_max_m"][0]), float(progress["ub_min_m"][0])
        if direction > 0 and self._pump_phase == "up":  # top: the barrel holds what the upstroke drew
            upstroke = ub_max - ub_min  # since the last accepted top
            if upstroke <= min_travel:
                return fillage
            self._top_ub = ub_min
            self._rising_s = time_s - self._t_bottom
            stroke_in_barrel = upstroke
            if self.tubing_stiffness_n_m > 0:  # the barrel rose with the plunger while the load transferred
                stretch = (self.law.up_eq_n - self.law.down_eq_n) / self.tubing_stiffness_n_m
                stroke_in_barrel = max(upstroke - stretch, 0.0)
            liquid_m = stroke_in_barrel
            if self.gas is not None:  # the gas takes its share of the plunger's stroke in the barrel
                liquid_m = stroke_in_barrel * self.gas_liquid_fraction(stroke_in_barrel)
                fillage = liquid_m / max(stroke_in_barrel, 1e-12)
            if self.annulus is not None:
                liquid_m = min(self._liquid_stroke_m, liquid_m)
                # book what the annulus actually gave: the plan at the bottom predicted the inflow of the
                # upstroke, and the pump cannot lift liquid the annulus does not hold (mass conservation)
                liquid_m *= self.annulus.take(plunger_area_m2(self.cfg.pump) * liquid_m, time_s)
                fillage = liquid_m / upstroke
            self._pumped_m3 += plunger_area_m2(self.cfg.pump) * liquid_m
            self._pump_phase = "down"
            pump_conditions.on_reversal(valve, True, ub_min)
            progress["ub_max_m"] = ub
            events.append(("top", time_s, ub, fillage))
        elif direction < 0 and self._pump_phase == "down":  # bottom: intake pressure sets the next P-
            # travel from the highest point since the top was accepted (ub_min is not reset there: a top
            # accepted early, e.g. a mid-upstroke bounce on gas, must not hide the rest of the upstroke)
            if ub_max - min(self._top_ub, ub_min) <= min_travel:
                return fillage
            if self.annulus is not None:
                self.law = self.valve_law_now()
                valve["lo_n"] = -self.law.up_eq_n
                valve["void_until_m"] = self._plan_upstroke(ub_max, time_s, period_s)
                valve["void"] = 1
            if self.gas is not None:  # the intake pressure of the coming upstroke (inflow model)
                valve["p_in_pa"] = self._intake_pa()
                valve["phi"] = self.gas.fraction(float(valve["p_in_pa"][0]))
            self._pump_phase = "up"
            pump_conditions.on_reversal(valve, False, ub_max)
            self._t_bottom = time_s
            progress["ub_min_m"] = ub
            events.append(("bottom", time_s, ub, fillage))
        return fillage

    def _valve_record(self) -> np.ndarray:
        """The valve law's kernel record for a run: the law, the fluid-pound plan and the gas chamber."""
        rec = valve_law_record.make(self.law, self.void, self.void_until)
        rec["fluid_kg"] = self.cfg.pump.fluid_column_mass_kg
        cfg = self.cfg
        if not hasattr(self, "_cond_state"):
            self._cond_reset()
        pump_conditions.configure(rec, cfg.pump)
        for name, value in self._cond_state.items():
            rec[name] = value
        if self.gas is not None:
            rec["gas_mode"] = int(self._gas[0])
            rec["u0_m"], rec["gas_m3"], rec["p0"], rec["liquid_m3"] = self._gas[1:5]
            rec["k"], rec["area_m2"] = self.gas.exponent, self.gas.area_m2
            rec["p_in_pa"] = self._intake_pa()
            rec["phi"] = self.gas.fraction(float(rec["p_in_pa"][0]))
            rec["p_d_pa"] = self.p_pump_pa + cfg.pump.discharge_overpressure_pa
            rec["p_out_pa"], rec["gas_friction_n"] = self.p_pump_pa, cfg.pump.plunger_friction_n
            rec["p_d_full_pa"], rec["p_out_full_pa"] = rec["p_d_pa"], rec["p_out_pa"]  # a tubing leak drains them
            rec["liq_c"] = cfg.pump.liquid_compressibility_per_pa
            rec["gas_keep_m3"] = self.gas.kept_m3
            if self.tubing_stiffness_n_m > 0:  # unanchored: the barrel's travel in series with the chamber
                rec["tub_c"] = self.gas.area_m2 ** 2 / self.tubing_stiffness_n_m
            rec["v_min_m3"] = self.gas.area_m2 * GAS_MIN_DELAY_FRACTION * self.surface.stroke_length_m(
                cfg.surface.stroke_length_m)
        elif self.tubing_stiffness_n_m > 0:  # mode 2: a plunger area of 0 marks the tubing spring
            rec["gas_mode"] = 2
            rec["u0_m"], rec["p0"] = self._gas[1], self._gas[3]
            rec["k"], rec["area_m2"] = self.tubing_stiffness_n_m, 0.0
            rec["k_top"] = self.tubing_top_stiffness_n_m  # the downstroke's transfer (0: k)
        return rec

    def _cond_reset(self) -> None:
        """The pump conditions' state at the bottom of the stroke after reset (laws.pump_conditions)."""
        stroke = self.surface.stroke_length_m(self.cfg.surface.stroke_length_m)
        kept = getattr(self, "_cond_state", None) if self.fixed_contact_ends else None
        self._cond_state = pump_conditions.initial_state(float(self.u[-1]), stroke)
        if kept is not None:
            self._cond_state.update({name: kept[name] for name in pump_conditions.CONTACT_FIELDS})

    def fix_contact_ends(self) -> None:
        """From now on a stop at the bottom keeps the tagging contact's ends (:attr:`fixed_contact_ends`)."""
        self.fixed_contact_ends = True

    def contact_ends(self) -> dict:
        """The tagging contact's ends (kernel sign, positive down) and whether each is placed (laws.pump_conditions)."""
        if not hasattr(self, "_cond_state"):
            self._cond_reset()
        return {name: self._cond_state[name] for name in pump_conditions.CONTACT_FIELDS}

    def _cond_keep(self, valve: np.ndarray) -> None:
        """After a run: the plunger's travel, direction and the contact ends carry over to the next."""
        self._cond_state = {name: valve[name][0].item() for name in pump_conditions.STATE_FIELDS}

    # ------------------------------------------------------------------------------------------ idle time
    # The v1 env stops the unit between strokes (intermittent pumping) and fast-forwards quasi-steady
    # strokes; these keep the annulus, the clock and the fluid-pound plan consistent when it does.
    def stop_at_bottom(self) -> None:
        """The unit stops at the bottom of a stroke: the string settles to its static state (plunger at rest
        holding P+); the annulus contents and the clock are kept."""
        t = self.time_s
        if self.annulus is not None:
            self.annulus.accumulate(t)  # the inflow since the stroke's last valve event
        vol = self.annulus.volume_m3 if self.annulus is not None else 0.0
        self.reset(self.annulus.level_m if self.annulus is not None else None)
        self.time_s = t
        self._t_bottom = t
        if self.annulus is not None:
            self.annulus.volume_m3 = vol
            self.annulus.last_time_s = t

    def idle(self, duration_s: float) -> None:
        """Let `duration_s` pass with the unit stopped: the annulus refills, no rod dynamics."""
        self.time_s += max(float(duration_s), 0.0)
        if self.annulus is not None:
            self.annulus.accumulate(self.time_s)

    def set_inflow_multiplier(self, multiplier: float) -> None:
        """The reservoir's deliverability from now on (v1's inflow schedule); no effect without an annulus."""
        if self.annulus is not None:
            self.annulus.rate_multiplier = multiplier

    def return_liquid(self, volume_m3: float) -> None:
        """Liquid the pump lifted that falls back into the annulus: the part of a stroke an interval does not own
        (the interval runner books it in the next), or what a leak or parted rods lose (v2)."""
        if self.annulus is not None:
            self.annulus.give_back(volume_m3)

    def fast_forward(self, until_s: float, displaced_m3: float, draw_at_s: float | None = None) -> float:
        """A stroke not simulated (the interval runner's fast-forward): the pump draws up to `displaced_m3` from
        the annulus filled to `draw_at_s` (default `until_s`), the annulus fills on to `until_s` and the clock
        moves there; returns the volume drawn (all of `displaced_m3` without an annulus). The rod state is not
        touched. Drawing at the upstroke's end, as an exact stroke does, leaves the downstroke's inflow in the
        annulus at the bottom, where the next exact stroke expects it."""
        if self.annulus is None:
            taken = displaced_m3
        elif draw_at_s is not None and draw_at_s < until_s:
            taken = self.annulus.draw(displaced_m3, draw_at_s)
            self.annulus.accumulate(until_s)
        else:
            taken = self.annulus.draw(displaced_m3, until_s)
        self.time_s = until_s
        return taken

    def upstroke_s(self, period_s: float) -> float:
        """How long the standing valve stays open in a stroke of `period_s`: the last measured upstroke (the
        plunger rests at both ends, so it is shorter than half the period), half the period before there is one."""
        rising_s = getattr(self, "_rising_s", None)
        return 0.5 * period_s if rising_s is None or rising_s > period_s else rising_s

    def replan_upstroke(self, period_s: float) -> None:
        """Re-plan the coming upstroke's liquid (fluid pound) after the annulus changed outside a stroke."""
        if self.annulus is None or self._pump_phase != "up":
            return
        self.void, self.void_until = 1, self._plan_upstroke(self._ub_max, self.time_s, period_s)
