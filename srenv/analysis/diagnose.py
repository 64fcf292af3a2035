"""Downhole (pump) card from a surface card: Gibbs' Fourier method, marched down the string taper by taper,
with a split-step correction for Coulomb rod-tubing friction in deviated wells.

The rod obeys (design §2, u positive down, N = N_eq equivalent axial force)
    dN/dx = rho*A u_tt + c u_t - w - q_t,    du/dx = N / (E A),
w = (rho - rho_f) g A cos(alpha) the buoyed weight per length, q_t the friction per length (positive down).
Given u(0, t) and N(0, t) over one (periodic) stroke, this is a Cauchy problem in x, solved per harmonic n
of the stroke frequency w0: without friction each harmonic travels exactly through a uniform segment of
length h,
    [U, N](x + h) = [[cosh(lh), sinh(lh)/(EA l)], [EA l sinh(lh), cosh(lh)]] [U, N](x),
    (EA) l^2 = -rho A (n w0)^2 + i n w0 c   (Gibbs 1963; n = 0: U += N h / EA),
so the taper steps are exact (U and N_eq are continuous at a shoulder; the true load jumps by p dA).
Friction is not linear in the harmonics: each segment is a Strang split step, half a step of the weight
and friction sources in the time domain (N -= h/2 (w + q_t)), the exact linear transfer, the other half.
The friction per length is q_t = -mu q_n sgn(u_t), q_n = |w_b sin(alpha) - N dalpha/ds| the soft-string side
force with the local axial force (the simulator's law), and sgn regularised as tanh(v / v_eps) (the stuck
reaction of the exact model is not known from the surface; v_eps is a small fraction of the peak rod speed).

Harmonics above ``harmonics`` are dropped at the top (a measured card's noise would otherwise be marched
down; the transfer of a high harmonic grows like exp(c L / (2 rho A a)) only, but sensor noise is broad).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..config import WellConfig
from ..physics.fluid import tubing_pressure_pa
from ..physics.pump_inputs import column_below_rods_pa
from ..physics.rod import GRAVITY_M_S2, build_mesh, coupling_buoyancy_n_m, damping_per_length
from ..physics.survey import Survey
from ..surface_unit.measured_motion import read_card_csv, stroke_period_s

CARD_COLUMNS = ("t_s", "polished_rod_position_m", "polished_rod_load_n")
PUMP_COLUMNS = ("t_s", "pump_position_m", "pump_load_n")
DEFAULT_HARMONICS = 60
LOAD_CONVENTIONS = ("true", "effective")


def load_in_convention(true_load_n, convention: str, rod_end_pressure_pa: float, rod_end_area_m2: float):
    """A true rod-end load in the named convention: ``true`` as it is, ``effective`` (buoyant, the vendors'
    pump cards) = true + p A with p the tubing pressure at the rod end and A the bottom rod's area. The one
    conversion of ``srenv diagnose`` and ``srenv validate`` (docs/realism.md)."""
    if convention not in LOAD_CONVENTIONS:
        raise ValueError(f"load convention {convention!r}: expected one of {', '.join(LOAD_CONVENTIONS)}")
    shift = rod_end_pressure_pa * rod_end_area_m2 if convention == "effective" else 0.0
    return true_load_n + shift


@dataclass(frozen=True)
class Segments:
    """The string cut into short uniform segments, top-down, with what the march needs on each."""

    h_m: np.ndarray
    ea_n: np.ndarray
    rho_a_kg_m: np.ndarray
    c_n_s_m2: np.ndarray          # viscous damping per length
    w_n_m: np.ndarray             # buoyed weight per length along the string (cos alpha included)
    fw_n_m: np.ndarray            # mu * w_b sin(alpha)
    fa_1_m: np.ndarray            # mu * dalpha/ds
    fc_1_m: np.ndarray            # mu * sin(alpha) dphi/ds (3-D survey only)
    top_area_m2: float
    bottom_area_m2: float


def segments(cfg: WellConfig, segment_length_m: float | None = None, damping_scale: float = 1.0) -> Segments:
    seg = segment_length_m or min(cfg.simulation.element_length_m, 25.0)
    mesh = build_mesh(cfg.rod, seg)
    survey = Survey.from_config(cfg.survey, cfg.rod_length_m)
    xm = 0.5 * (mesh.x_m[1:] + mesh.x_m[:-1])
    incl = survey.inclination(xm)
    rho_rod = mesh.rho_a_kg_m / mesh.area_m2
    w_b = (rho_rod - cfg.fluid.density_kg_m3) * GRAVITY_M_S2 * mesh.area_m2 - coupling_buoyancy_n_m(
        mesh, cfg.fluid.density_kg_m3)
    mu = cfg.friction.coefficient
    turn = survey.turn_rate(xm) if cfg.survey.three_d else np.zeros_like(xm)
    c = damping_per_length(mesh, cfg.damping)
    return Segments(mesh.length_m, mesh.ea_n, mesh.rho_a_kg_m, c * damping_scale if damping_scale != 1.0 else c,
                    w_b * np.cos(incl), mu * w_b * np.sin(incl), mu * survey.build_rate(xm),
                    mu * np.sin(incl) * turn, float(mesh.area_m2[0]), float(mesh.area_m2[-1]))


@dataclass
class PumpCard:
    t_s: np.ndarray
    pump_position_m: np.ndarray   # upward, as srenv simulate writes it
    pump_load_n: np.ndarray       # true load at the pump, tension positive
    pump_velocity_m_s: np.ndarray
    polished_rod_position_m: np.ndarray
    polished_rod_load_n: np.ndarray
    period_s: float
    harmonics: int
    rod_end_pressure_pa: float = 0.0   # tubing pressure at the rod end: effective load = true + p A
    rod_end_area_m2: float = 0.0       # the bottom rod's area


def _resample_periodic(t: np.ndarray, y: np.ndarray, t0: float, period: float, m: int) -> np.ndarray:
    """Linear periodic interpolation onto m equally spaced times from t0 (a no-op for uniform samples)."""
    tt = t0 + np.arange(m) * (period / m)
    tp = np.r_[t, t[0] + period]
    yp = np.r_[y, y[0]]
    return np.interp(tt, tp, yp)


def march(cfg: WellConfig, u0_m: np.ndarray, n0_eq_n: np.ndarray, period_s: float, harmonics: int,
          segment_length_m: float | None = None, friction: bool = True, v_eps_fraction: float = 0.02,
          kv_tau_s: float = 0.0, damping_scale: float = 1.0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """March (u, N_eq) from the polished rod to the pump over one periodic stroke sampled at m equal times
    (the viscous damping times ``damping_scale``). Returns (u, N_eq, u_t) at the pump, u positive down."""
    sg = segments(cfg, segment_length_m, damping_scale)
    m = len(u0_m)
    nh = min(harmonics, m // 2 - 1)
    w0 = 2 * math.pi / period_s
    n = np.arange(nh + 1)
    iw = 1j * n * w0

    def spec(y: np.ndarray) -> np.ndarray:
        return np.fft.rfft(y)[: nh + 1]

    def time(c: np.ndarray) -> np.ndarray:
        full = np.zeros(m // 2 + 1, dtype=complex)
        full[: nh + 1] = c
        return np.fft.irfft(full, m)

    uh, nhat = spec(u0_m), spec(n0_eq_n)
    use_friction = friction and (np.any(sg.fw_n_m) or np.any(sg.fa_1_m) or np.any(sg.fc_1_m))
    v_eps = None

    def source(uh: np.ndarray, nhat: np.ndarray, k: int, half: float) -> np.ndarray:
        nonlocal v_eps
        dn = np.zeros(nh + 1, dtype=complex)
        dn[0] = -half * sg.h_m[k] * sg.w_n_m[k] * m  # weight: the mean (rfft scaling: sum, not mean)
        if use_friction and (sg.fw_n_m[k] or sg.fa_1_m[k] or sg.fc_1_m[k]):
            v = time(iw * uh)
            if v_eps is None:
                v_eps = max(v_eps_fraction * float(np.max(np.abs(v))), 1e-6)
            nt = time(nhat)
            qn = np.hypot(sg.fw_n_m[k] - sg.fa_1_m[k] * nt, sg.fc_1_m[k] * nt)
            q_t = -qn * np.tanh(v / v_eps)
            dn -= half * sg.h_m[k] * spec(q_t)
        return nhat + dn

    for k in range(len(sg.h_m)):
        nhat = source(uh, nhat, k, 0.5)
        ea, h = sg.ea_n[k], sg.h_m[k]
        if kv_tau_s:  # Kelvin-Voigt: the complex modulus EA (1 + i w tau) per harmonic
            ea = ea * (1.0 + iw * kv_tau_s)
        lam = np.sqrt((-sg.rho_a_kg_m[k] * (n * w0) ** 2 + iw * sg.c_n_s_m2[k]) / ea + 0j)
        ch = np.cosh(lam * h)
        lh = lam * h
        # sinh(lh)/l and l sinh(lh), finite at l = 0 (the mean)
        sinc = np.where(np.abs(lh) > 1e-12, np.sinh(lh) / np.where(lam == 0, 1, lam), h)
        ls = lam * np.sinh(lh)
        uh, nhat = ch * uh + sinc * nhat / ea, ea * ls * uh + ch * nhat
        nhat = source(uh, nhat, k, 0.5)
    return time(uh), time(nhat), time(iw * uh)


KV_MAX_GAIN = 10.0


def kv_harmonic_cap(cfg: WellConfig, period_s: float) -> int:
    """With Kelvin-Voigt damping (tau > 0) the march from the surface amplifies harmonic n by about
    exp(zeta_n w_n T), zeta_n = tau w_n / 2, T the string's wave travel time: harmonics beyond a gain of
    KV_MAX_GAIN would amplify the card's noise more than they carry signal, and are dropped."""
    tau = cfg.damping.stiffness_proportional_s
    if not tau > 0:
        return 10**9
    mesh = build_mesh(cfg.rod, min(cfg.simulation.element_length_m, 25.0))
    travel = float(np.sum(mesh.length_m / np.sqrt(mesh.ea_n / mesh.rho_a_kg_m)))
    w_max = math.sqrt(2.0 * math.log(KV_MAX_GAIN) / (tau * travel))
    return max(4, int(w_max * period_s / (2 * math.pi)))


def periodic_gradient(x: np.ndarray) -> np.ndarray:
    """The per-sample change of one periodic stroke's samples (central differences across the wrap)."""
    return np.gradient(np.r_[x[-1], x, x[0]])[1:-1]


def _march_per_direction(cfg: WellConfig, xs: np.ndarray, n0: np.ndarray, period: float, harmonics: int,
                         segment_length_m: float | None, friction: bool):
    """The march with the string's damping; with damping per stroke direction (damping.upstroke_factor,
    downstroke_factor) it is marched once with each and each sample taken from the march of the polished
    rod's direction at that time (the simulator's rule; Gibbs' method is linear per harmonic, so a
    direction-dependent damping cannot enter one march: the two halves are joined at the turns, as vendors'
    up- and downstroke damping coefficients are used)."""
    d = cfg.damping
    kw = {"kv_tau_s": d.stiffness_proportional_s}
    if (d.upstroke_factor, d.downstroke_factor) == (1.0, 1.0):
        return march(cfg, -xs, n0, period, harmonics, segment_length_m, friction, **kw)
    up = march(cfg, -xs, n0, period, harmonics, segment_length_m, friction, damping_scale=d.upstroke_factor, **kw)
    down = march(cfg, -xs, n0, period, harmonics, segment_length_m, friction, damping_scale=d.downstroke_factor,
                 **kw)
    rising = periodic_gradient(xs) > 0  # the polished rod rises
    return tuple(np.where(rising, a, b) for a, b in zip(up, down))


def diagnose_card(cfg: WellConfig, t_s: np.ndarray, position_m: np.ndarray, load_n: np.ndarray,
                  harmonics: int = DEFAULT_HARMONICS, period_s: float | None = None,
                  segment_length_m: float | None = None, friction: bool = True) -> PumpCard:
    """Pump card of the last stroke of a surface card (time, polished-rod position upward, load)."""
    period = stroke_period_s(t_s, position_m) if period_s is None else float(period_s)
    harmonics = min(harmonics, kv_harmonic_cap(cfg, period))
    dt = float(np.median(np.diff(t_s)))
    keep = t_s > t_s[-1] - period + 0.5 * dt
    t, x, f = t_s[keep], position_m[keep], load_n[keep]
    m = max(len(t), 2 * harmonics + 4)
    m += m % 2
    xs = _resample_periodic(t, x, t[0], period, m)
    fs = _resample_periodic(t, f, t[0], period, m)
    sg_top = segments(cfg, segment_length_m)
    p_top = float(cfg.fluid.wellhead_pressure_pa)
    survey = Survey.from_config(cfg.survey, cfg.rod_length_m)
    p_pump = float(tubing_pressure_pa(cfg.fluid, survey.tvd(cfg.rod_length_m)))
    f_sb = cfg.surface.stuffing_box_friction_n
    if f_sb > 0:  # the stuffing box's share of the measured load: opposite to the polished rod's velocity
        vx = periodic_gradient(xs)
        fs = fs - f_sb * np.sign(vx)
    ub, nb, vb = _march_per_direction(cfg, xs, fs + p_top * sg_top.top_area_m2, period, harmonics,
                                      segment_length_m, friction)
    tt = t[0] + np.arange(m) * (period / m)
    # back onto the input's own times (the same base as the surface card)
    pos = np.interp(t, np.r_[tt, tt[0] + period], np.r_[-ub, -ub[0]])
    load = np.interp(t, np.r_[tt, tt[0] + period], np.r_[nb, nb[0]]) - p_pump * sg_top.bottom_area_m2
    vel = np.interp(t, np.r_[tt, tt[0] + period], np.r_[-vb, -vb[0]])
    return PumpCard(t, pos, load, vel, x, f, period, min(harmonics, m // 2 - 1), p_pump, sg_top.bottom_area_m2)


# ------------------------------------------------------------------------------------------ card in, summary out
def read_surface_card(path: str, reverse: bool = False) -> dict[str, np.ndarray]:
    return read_card_csv(path, "CARD.csv", CARD_COLUMNS, reverse=reverse)


def summary(cfg: WellConfig, card: PumpCard, convention: str = "true") -> dict:
    """The diagnosis's JSON figures; the card is analysed in true loads, and its two load levels are reported
    in ``convention`` together with the rod end's pressure and area that convert them."""
    from .pump_card import analyse_pump_card

    s = analyse_pump_card(card.pump_position_m, card.pump_load_n)
    for key in ("upstroke_load_n", "downstroke_load_n"):
        if s.get(key) is not None:
            s[key] = load_in_convention(s[key], convention, card.rod_end_pressure_pa, card.rod_end_area_m2)
    survey = Survey.from_config(cfg.survey, cfg.rod_length_m)
    # the discharge pressure at the pump: the rod end's plus the liquid column down to a deeper pump
    p_out = float(tubing_pressure_pa(cfg.fluid, survey.tvd(cfg.rod_length_m))) + column_below_rods_pa(cfg, survey)
    from ..physics.pump import plunger_area_m2
    from .pump_intake import read_pump_state

    friction = cfg.pump.plunger_friction_n if cfg.pump.load_source == "pressures" else 0.0
    # the intake from the card's load lines, the field's reading (analysis/pump_intake.py, docs/realism.md);
    # with the loads given directly the config has no plunger area to turn the load into a pressure: null
    st = read_pump_state(card.pump_position_m, card.pump_load_n, p_out, plunger_area_m2(cfg.pump), friction,
                         cfg.pump.discharge_overpressure_pa)
    p_in = None if cfg.pump.load_source == "loads" else max(0.0, st["intake_pressure_pa"])
    lines = {f"{k}_n": load_in_convention(st[f"{k}_line_n"], convention, card.rod_end_pressure_pa,
                                          card.rod_end_area_m2) for k in ("upstroke", "downstroke")}
    lines.update(fluid_load_n=st["fluid_load_n"], fillage=st["fillage"])
    return {
        "period_s": card.period_s,
        "spm": 60.0 / card.period_s,
        "harmonics": card.harmonics,
        "polished_rod_stroke_m": float(np.ptp(card.polished_rod_position_m)),
        "pprl_n": float(card.polished_rod_load_n.max()),
        "mprl_n": float(card.polished_rod_load_n.min()),
        **s,
        "discharge_pressure_pa": p_out,
        "intake_pressure_pa": p_in,
        "load_lines": lines,
        "load_convention": convention,
        "rod_end_pressure_pa": card.rod_end_pressure_pa,
        "rod_end_area_m2": card.rod_end_area_m2,
    }


def save_plot(card: PumpCard, path: str, title: str = "") -> None:
    import matplotlib

    matplotlib.use("Agg", force=False)
    from matplotlib.figure import Figure

    fig = Figure(figsize=(6.5, 4.5), dpi=100)
    ax = fig.subplots()
    x = card.polished_rod_position_m
    ax.plot(x - x.min(), card.polished_rod_load_n / 1e3, lw=1.0, label="surface (measured)")
    xp = card.pump_position_m
    ax.plot(xp - xp.min(), card.pump_load_n / 1e3, lw=1.0, color="tab:red", label="pump (diagnosed)")
    ax.set(xlabel="position above the bottom of the stroke (m)", ylabel="load (kN)",
           title=title or "surface and diagnosed pump card")
    ax.grid(alpha=0.3)
    ax.legend()
    fig.tight_layout()
    fig.savefig(path)
