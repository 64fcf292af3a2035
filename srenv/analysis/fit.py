"""Fitting a well model to a measured surface card: ``srenv fit CARD.csv --config WELL --param KEY ...``.

The model is driven by the card's own polished-rod motion (``surface.motion: measured``); the named
config fields (damping factor, friction coefficient, pump intake or tubing-head pressure, plunger
friction, or any other numeric field) are adjusted by ``scipy.optimize.least_squares`` (trust-region
reflective, bounds from the fields' checks) so that the simulated polished-rod load of the last of
``strokes`` strokes matches the measured load at the same phase of the stroke. Residuals are load
differences divided by the measured PPRL, so the reported card RMS is in % of PPRL.

Uncertainty: the Gauss-Newton covariance s^2 (J'J)^-1 at the solution, s^2 = SSR / (m - p), from the
Jacobian least_squares already built (finite differences), i.e. cheap; the m residuals are serially
correlated along the card, so read it as a lower bound (and it says nothing about model error).
"""

from __future__ import annotations

import dataclasses
import math
import typing
from pathlib import Path

import numpy as np

from ..config import ConfigError, apply_overrides, config_from_dict, read_raw, to_dict
from ..surface_unit.measured_motion import read_card_csv, stroke_period_s

DEFAULT_STROKES = 4


def _field_meta(key: str, flag: str = "--param") -> tuple[type, dict]:
    """Type and metadata of a dotted config field (numeric fields only); ``flag`` names it in a refusal."""
    from ..config import WellConfig

    cls: typing.Any = WellConfig
    parts = key.split(".")
    for i, part in enumerate(parts):
        hints = typing.get_type_hints(cls)
        fields = {f.name: f for f in dataclasses.fields(cls)}
        if part not in fields:
            raise ConfigError(flag, key, "a numeric config field such as damping.damping_factor, "
                              "friction.coefficient, pump.intake_pressure_pa, fluid.wellhead_pressure_pa, "
                              "pump.plunger_friction_n")
        tp = hints[part]
        if i < len(parts) - 1:
            if not (isinstance(tp, type) and dataclasses.is_dataclass(tp)):
                raise ConfigError(flag, key, "a path to a numeric field (tapers are not fitted)")
            cls = tp
        else:
            if tp is not float:
                raise ConfigError(flag, key, "a real-valued (float) config field")
            return tp, dict(fields[part].metadata)
    raise ConfigError(flag, key, "a numeric config field")


def _get(cfg_dict: dict, key: str) -> float:
    node: typing.Any = cfg_dict
    for part in key.split("."):
        node = node[part]
    return float(node)


class CardFit:
    """Residuals of the model against one measured card, as a function of the fitted parameters."""

    def __init__(self, card_path: str, config: str, params: list[str], overrides: list[str] | None = None,
                 strokes: int = DEFAULT_STROKES, flag: str = "--param") -> None:
        self.flag = flag  # the command's flag naming the fitted fields (fit --param, validate --fit)
        cols = read_card_csv(card_path, "CARD.csv", ("t_s", "polished_rod_position_m", "polished_rod_load_n"))
        self.card_path = str(Path(card_path).resolve())
        self.params = list(params)
        if not self.params:
            raise ConfigError(flag, "", "at least one config field to fit")
        if len(set(self.params)) != len(self.params):
            raise ConfigError(flag, " ".join(self.params), "each field once")
        for k in self.params:  # the card drives the model: its period and motion are data, not parameters
            if k.startswith("surface.measured_"):
                raise ConfigError(flag, k, "a model field (the card's own period and motion are measured, "
                                  "not fitted)")
        self.meta = [_field_meta(k, flag)[1] for k in self.params]
        raw = apply_overrides(read_raw(config), list(overrides or []) + [
            "surface.motion=measured", f"surface.measured_card_csv={self.card_path}"])
        self.raw = raw
        self.base = config_from_dict(raw)  # validates the card as a motion too
        base_dict = to_dict(self.base)
        self.x0 = np.array([_get(base_dict, k) for k in self.params])
        t, x, f = cols["t_s"], cols["polished_rod_position_m"], cols["polished_rod_load_n"]
        period = 60.0 / self.base.surface.measured_spm if self.base.surface.measured_spm > 0 else \
            stroke_period_s(t, x)
        keep = t > t[-1] - period + 0.5 * float(np.median(np.diff(t)))
        self.t_card, self.load_card = t[keep], f[keep]
        self.period = period
        self.pprl = float(self.load_card.max())
        if not self.pprl > 0:  # the residuals are load differences in units of the PPRL
            raise ConfigError("CARD.csv", card_path, "a card whose peak polished-rod load is positive (the fit's "
                              f"residuals are in units of it; this one is {self.pprl:g} N)")
        self.strokes = int(strokes)
        self.evaluations = 0

    def config(self, values: np.ndarray):
        return config_from_dict(apply_overrides(self.raw, {k: float(v) for k, v in zip(self.params, values)}))

    def simulate(self, values: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(simulated, measured) polished-rod load over the last simulated stroke, at the same phases."""
        from ..simulation.simulator import Simulator

        self.evaluations += 1
        sim = Simulator(self.config(values))
        r = sim.run_strokes(self.strokes)[-1]
        tr = r.trace
        mm = sim.surface.measured
        phase = (tr["t_s"] - (tr["t_s"][0] - r.duration_s / r.n_steps)) / r.duration_s
        tau = mm.t_bottom_s + phase * mm.period_s
        measured = np.interp(tau, self.t_card, self.load_card, period=self.period)
        return tr["polished_rod_load_n"], measured

    def residuals(self, values: np.ndarray) -> np.ndarray:
        from ..errors import SolverFailure

        try:
            sim, meas = self.simulate(values)
        except (SolverFailure, ConfigError):
            return np.full(self._m, 10.0) if hasattr(self, "_m") else np.full(1, 10.0)
        res = (sim - meas) / self.pprl
        self._m = len(res)
        return res


def _bounds(meta: list[dict], x0: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    lo = np.full(len(meta), -np.inf)
    hi = np.full(len(meta), np.inf)
    for i, m in enumerate(meta):
        check = m.get("check", "any")
        if check in ("positive", "nonneg"):
            lo[i] = 0.0
        if check == "unit_interval":
            lo[i], hi[i] = 0.0, 1.0
    return lo, hi


def fit_card(fit: CardFit, max_evaluations: int = 200) -> dict:
    from scipy.optimize import least_squares

    # parameters scaled to O(1): by their start value, or by a unit of their kind when it is 0
    scale = np.where(np.abs(fit.x0) > 0, np.abs(fit.x0), 1.0)
    lo, hi = _bounds(fit.meta, fit.x0)
    z0 = fit.x0 / scale
    zl, zh = lo / scale, hi / scale
    z0 = np.clip(z0, zl + 1e-12 * (np.isfinite(zl)), zh)
    r0 = fit.residuals(fit.x0)
    try:
        sol = least_squares(lambda z: fit.residuals(z * scale), z0, bounds=(zl, zh), method="trf",
                            diff_step=1e-3, x_scale=1.0, max_nfev=max_evaluations, xtol=1e-8, ftol=1e-10)
    except ValueError as exc:  # "Residuals are not finite in the initial point" and the like
        from ..errors import NumericFailure

        raise NumericFailure("card_rms_pct_of_pprl", f"the fit's residuals are not usable ({exc})") from None
    x = sol.x * scale
    m, p = len(sol.fun), len(x)
    ssr = float(sol.fun @ sol.fun)
    sigma = np.full(p, math.nan)
    try:
        jtj = sol.jac.T @ sol.jac
        cov = np.linalg.inv(jtj) * (ssr / max(m - p, 1))
        sigma = np.sqrt(np.clip(np.diag(cov), 0, None)) * scale
    except np.linalg.LinAlgError:
        pass
    return {
        "params": {k: float(v) for k, v in zip(fit.params, x)},
        "initial_params": {k: float(v) for k, v in zip(fit.params, fit.x0)},
        # null where the covariance is singular (a parameter the card does not determine): JSON has no NaN
        "uncertainty": {k: float(s) if math.isfinite(s) else None for k, s in zip(fit.params, sigma)},
        "card_rms_pct_of_pprl": 100.0 * math.sqrt(ssr / m),
        "initial_card_rms_pct_of_pprl": 100.0 * float(np.sqrt(np.mean(r0 ** 2))),
        "measured_pprl_n": fit.pprl,
        "evaluations": fit.evaluations,
        "success": bool(sol.success),
        "message": str(sol.message),
    }


def refuse_inert(fit: CardFit) -> None:
    """Refuse, before the fit, fields that do not change the simulated card (``inert_params``): one line
    naming the command's flag."""
    inert = inert_params(fit)
    if inert:
        raise ConfigError(fit.flag, " ".join(inert), "config fields that change the simulated card (a 1 % change "
                          "of these leaves it identical, so the card cannot determine them)")


def inert_params(fit: CardFit) -> list[str]:
    """The fitted fields that do not change the simulated card at all (a 1 % step leaves every load
    bit-identical): least squares cannot fit them, and their uncertainty would be undefined."""
    lo, hi = _bounds(fit.meta, fit.x0)
    base, _ = fit.simulate(fit.x0)
    out = []
    for i, key in enumerate(fit.params):
        x = fit.x0.copy()
        step = 1e-2 * abs(x[i]) if x[i] != 0 else 1e-2
        x[i] = x[i] + step if x[i] + step <= hi[i] else x[i] - step
        x[i] = max(x[i], lo[i])
        from ..errors import SolverFailure

        try:
            moved, _ = fit.simulate(x)
        except (ConfigError, SolverFailure):  # a step the model refuses does change something
            continue
        if moved.shape == base.shape and np.array_equal(moved, base):
            out.append(key)
    return out
