"""The damping a diagnosis uses, read off the card by an energy balance (docs/realism.md, "The damping a
diagnosis should use").

Gibbs (1963, the damping of the wave-equation method) and the programs after it (Everitt & Jennings, SPE
Production Engineering 1992, SPE-18189-PA: "a consistent method of computing the viscous damping term")
choose the damping per card: the polished-rod work per stroke minus the pump's work is what the string
dissipates, so the damping is the one that dissipates exactly that. Gibbs took the pump's work as the
hydraulic work (the liquid lifted against the net lift); Everitt & Jennings iterate with the diagnosed card's
area in its place, the damping of each pass from the previous pass's card.

srenv's march (``diagnose.march``) is exact for the damped wave equation, so W_PR - W_pump(nu) equals the
string's dissipation for *every* nu (an identity, ``tests/srenv/analysis/test_damping_balance.py``): the
balance picks a damping only against a pump work known apart from the card being diagnosed. Here it is
Gibbs' hydraulic work, the plunger's valve interval times the liquid it displaces:

    W_pump(nu) = F_v * fillage(nu) * S_p(nu),   F_v = P- - P+ = (p_d - p_in + dp_valve) A_pl + 2 P_f,

F_v from the config (the valve law's interval at the pump: the intake from a record's analysis, a fluid level
or the config, never from the same card), S_p and the fillage (the transfer's end, ``pump_intake.load_lines``)
from the card diagnosed with nu. The displacement rather than the surface production: slippage and a leaking
tubing are the pump's and the tubing's losses, not the rods' damping. One balance fixes one number: the Gibbs
factor nu of the viscous damping (the Kelvin-Voigt tau, the high-mode law, stays as configured). Solved by
Brent's method on nu in NU_BRACKET; the pump's work falls as nu grows (each extra unit of nu dissipates about
the same work), so a root is unique when bracketed, and a card with none is said (``bracketed: false``).

Read off the card's own load lines instead (p_in = p_d - F_o/A_pl, what ``validate`` does for a record without
an analysis), the balance is degenerate: the damping moves the lines as much as the area, and a card's area
equals its lines' rectangle within 1.5 % for nu from 0.005 to 0.4 (measured on 11708328's described string).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np

from ..config import WellConfig
from ..errors import ConfigError

RULES = ("fixed", "energy-balance")
NU_BRACKET = (1e-4, 2.0)   # Gibbs factors searched: from almost none to twice critical for the first mode
WORK_TOLERANCE = 1e-4      # the balance holds to this share of the pump's work
MAX_ITERATIONS = 60


def loop_work_j(position_m, load_n) -> float:
    """The work per stroke, the card's loop integral of F dx over one periodic stroke (position upward, time
    forward: positive when the rod does work on what it drives)."""
    x = np.r_[np.asarray(position_m, float), position_m[0]]
    f = np.r_[np.asarray(load_n, float), load_n[0]]
    return float(np.sum(0.5 * (f[1:] + f[:-1]) * np.diff(x)))


@dataclass(frozen=True)
class PumpTerms:
    """What the config says about the pump's work: the valve interval F_v and, with pressures given, the
    pressures the free gas is compressed between (at the pump), the plunger area and the gas law's k."""

    valve_interval_n: float
    intake_pa: float | None = None
    discharge_pa: float | None = None
    plunger_area_m2: float = 0.0
    polytropic_k: float = 1.0

    def work_j(self, fillage: float, stroke_m: float) -> float:
        """F_v * fillage * S_p plus the work of compressing the free gas of the unfilled (1 - fillage) of the
        stroke from p_in to p_d (the plunger carries that before the travelling valve opens: a pump loss, not
        the rods'); the clearance's re-expansion is left out (its volume is a few % of the stroke's)."""
        w = self.valve_interval_n * fillage * stroke_m
        if self.intake_pa is None or not fillage < 1.0 or self.discharge_pa <= self.intake_pa:
            return w
        r, k = self.discharge_pa / self.intake_pa, self.polytropic_k
        swept = (1.0 - fillage) * stroke_m * self.plunger_area_m2       # V0 - V1, the compression's travel
        v0 = swept / (1.0 - r ** (-1.0 / k))
        on_gas = v0 * self.intake_pa * (math.log(r) if k == 1.0 else (r ** (1.0 - 1.0 / k) - 1.0) / (k - 1.0))
        return w + on_gas - self.intake_pa * swept


def pump_terms(cfg: WellConfig) -> PumpTerms:
    """The pump's terms from the config, through the valve law the simulator uses (intake from the config or
    a fluid level, referred to the rod end for a deeper pump)."""
    from ..physics.fluid import tubing_pressure_pa
    from ..physics.pump import plunger_area_m2, valve_law
    from ..physics.pump_inputs import pump_at_rod_end
    from ..physics.rod import build_mesh
    from ..physics.survey import Survey

    survey = Survey.from_config(cfg.survey, cfg.rod_length_m)
    pump = pump_at_rod_end(cfg, survey).pump
    p_end = float(tubing_pressure_pa(cfg.fluid, survey.tvd(cfg.rod_length_m)))
    area = float(build_mesh(cfg.rod, min(cfg.simulation.element_length_m, 25.0)).area_m2[-1])
    law = valve_law(pump, p_end, area)
    f_v = float(law.up_eq_n - law.down_eq_n)
    if pump.load_source != "pressures":
        return PumpTerms(f_v)
    return PumpTerms(f_v, float(pump.intake_pressure_pa), p_end + float(pump.discharge_overpressure_pa),
                     plunger_area_m2(pump), float(pump.gas_polytropic_exponent))


def check_rule(rule: str, cfg: WellConfig, flag: str = "--damping") -> None:
    """One line for a rule the config cannot take (ConfigError: exit 2)."""
    if rule not in RULES:
        raise ConfigError(flag, rule, f"one of {', '.join(RULES)}")
    if rule == "fixed":
        return
    if cfg.damping.model != "dimensionless":
        raise ConfigError("damping.model", cfg.damping.model, f"dimensionless (a Gibbs factor) for {flag} {rule}")
    if cfg.inflow.model != "none":
        raise ConfigError("inflow.model", cfg.inflow.model, f"none for {flag} {rule} (a set intake pressure)")


def with_factor(cfg: WellConfig, nu: float) -> WellConfig:
    return dataclasses.replace(cfg, damping=dataclasses.replace(cfg.damping, damping_factor=float(nu)))


@dataclass(frozen=True)
class Balance:
    damping_factor: float          # the Gibbs factor the balance found (or the config's when not bracketed)
    configured_factor: float
    bracketed: bool
    iterations: int
    polished_rod_work_j: float
    pump_work_j: float             # the diagnosed card's loop work with the factor found
    hydraulic_work_j: float        # PumpTerms.work_j of that card (F_v * fillage * S_p + the gas's compression)
    valve_interval_n: float
    fillage: float
    plunger_stroke_m: float

    def as_json(self) -> dict:
        return {"rule": "energy-balance", **dataclasses.asdict(self),
                "dissipated_j": self.polished_rod_work_j - self.pump_work_j}


def energy_balance(cfg: WellConfig, diagnose):
    """The Gibbs factor whose diagnosis balances the card's energy (module docstring). ``diagnose(cfg)`` is
    the caller's diagnosis of its card with a config (``diagnose.diagnose_card`` with its arguments bound), so
    ``srenv diagnose`` and ``srenv validate`` share this one rule. Returns (config with the factor, its
    PumpCard, Balance)."""
    from scipy.optimize import brentq

    from .pump_intake import load_lines

    terms = pump_terms(cfg)
    seen: dict[float, tuple] = {}

    def parts(nu: float):
        if nu not in seen:
            card = diagnose(with_factor(cfg, nu))
            fill = load_lines(card.pump_position_m, card.pump_load_n)["fillage"]
            stroke = float(np.ptp(card.pump_position_m))
            seen[nu] = (card, loop_work_j(card.pump_position_m, card.pump_load_n), terms.work_j(fill, stroke), fill,
                        stroke)
        return seen[nu]

    def gap(nu: float) -> float:
        _, w, w_h, _, _ = parts(nu)
        return w - w_h

    lo, hi = NU_BRACKET
    bracketed = gap(lo) > 0.0 > gap(hi)
    nu = cfg.damping.damping_factor
    if bracketed:
        nu = brentq(gap, lo, hi, xtol=1e-7, rtol=1e-6, maxiter=MAX_ITERATIONS)
    card, w, w_h, fill, stroke = parts(nu)
    w_pr = loop_work_j(card.polished_rod_position_m, card.polished_rod_load_n)
    result = Balance(float(nu), float(cfg.damping.damping_factor), bool(bracketed), len(seen), w_pr, w, w_h,
                     terms.valve_interval_n,
                     float(fill), stroke)
    return with_factor(cfg, nu), card, result


def diagnose_with_rule(cfg: WellConfig, rule: str, diagnose, flag: str = "--damping"):
    """The one entry of ``srenv diagnose`` and ``srenv validate``: the diagnosis with the configured damping
    (``fixed``) or the energy balance's; returns (config used, PumpCard, the JSON entry ``damping``)."""
    check_rule(rule, cfg, flag)
    if rule == "fixed":
        return cfg, diagnose(cfg), {"rule": "fixed", "damping_factor": float(cfg.damping.damping_factor)}
    used, card, balance = energy_balance(cfg, diagnose)
    return used, card, balance.as_json()
