"""The fast paths of a changing-action step (issue 25, docs/speed.md §2d) give the numbers, to the bit, of the
forms they replaced: the beam unit's linkage rates with each sine and cosine computed once, np.percentile's
linear rule without its Python, the crank radius of a stroke found without building a unit per secant step."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from srenv.analysis import card_features as cf
from srenv.config_sections import BeamUnitConfig
from srenv.surface_unit import beam_unit as bu
from srenv.surface_unit.inline_unit import inline_unit, unit_for_stroke
from srenv.surface_unit.unit_catalogue import conventional_unit

UNITS = {  # tests/srenv/surface_unit/test_unit_geometry.py's Class III nameplates (SI)
    "mark_ii": {"a_m": 2.032, "c_m": 1.166, "i_m": 1.161, "k_m": 1.732, "p_m": 1.437, "r_m": 0.4526,
                "rotation": "counterclockwise", "torque_rating_nm": 18077.6},
    "air_balanced": {"a_m": 3.0, "c_m": 1.5, "i_m": 1.45, "k_m": 2.25, "p_m": 1.75, "r_m": 0.6,
                     "rotation": "clockwise", "torque_rating_nm": 36155.1},
}


def _units() -> list[bu.ConventionalUnit]:
    return [conventional_unit("C-228D-213-86", 0), conventional_unit("C-228D-213-86", 2),
            *(inline_unit(BeamUnitConfig(geometry=k, **v)) for k, v in UNITS.items())]


# ------------------------------------------------------------------ the forms replaced (25d9225), verbatim
def _old_angles(u: bu.ConventionalUnit, psi):
    g = u.geometry
    qx = u.crank_radius_m * np.sin(psi)
    qy = u.crank_radius_m * np.cos(psi)
    vx, vy = qx - u._saddle[0], qy - u._saddle[1]
    dist = np.hypot(vx, vy)
    cos_gamma = (g.c_m**2 + dist**2 - g.p_m**2) / (2.0 * g.c_m * dist)
    delta = np.arctan2(vy, vx) - u._lever * np.arccos(np.clip(cos_gamma, -1.0, 1.0))
    ex = u._saddle[0] + g.c_m * np.cos(delta)
    ey = u._saddle[1] + g.c_m * np.sin(delta)
    return delta, np.arctan2(ey - qy, ex - qx)


def _old_beam_rates(u: bu.ConventionalUnit, psi):
    g = u.geometry
    delta, eps = _old_angles(u, psi)
    m1 = tuple(g.c_m * n for n in (-np.sin(delta), np.cos(delta)))
    m2 = tuple(-g.p_m * n for n in (-np.sin(eps), np.cos(eps)))
    r = u.crank_radius_m
    d1, e1 = bu._solve_columns(m1, m2, (r * np.cos(psi), -r * np.sin(psi)))
    ud, ue = (np.cos(delta), np.sin(delta)), (np.cos(eps), np.sin(eps))
    rhs2 = tuple(-r * trig + g.c_m * d1**2 * ud[j] - g.p_m * e1**2 * ue[j]
                 for j, trig in enumerate((np.sin(psi), np.cos(psi))))
    d2, _ = bu._solve_columns(m1, m2, rhs2)
    return delta, d1, d2


def _old_unit_for_stroke(u: BeamUnitConfig, stroke_m: float) -> bu.ConventionalUnit:
    full = inline_unit(u)
    if stroke_m >= full.stroke_m:
        return full
    r0, s0 = u.r_m, full.stroke_m
    r1 = u.r_m * stroke_m / s0
    s1 = inline_unit.__wrapped__(dataclasses.replace(u, r_m=r1)).stroke_m
    for _ in range(20):
        if abs(s1 - stroke_m) < 1e-10:
            break
        r0, s0, r1 = r1, s1, r1 + (stroke_m - s1) * (r1 - r0) / (s1 - s0)
        s1 = inline_unit.__wrapped__(dataclasses.replace(u, r_m=r1)).stroke_m
    return inline_unit.__wrapped__(dataclasses.replace(u, r_m=r1))


# ------------------------------------------------------------------ pins
def test_linkage_rates_are_the_old_ones_to_the_bit() -> None:
    rng = np.random.default_rng(11)
    for unit in _units():
        for psi in (rng.uniform(-7.0, 7.0, 3001), np.linspace(0.0, 2 * np.pi, 720), np.array([0.3]),
                    np.array(unit.theta_top)):
            old = _old_beam_rates(unit, psi)
            new = unit._beam_rates(psi)
            assert all(np.array_equal(a, b) for a, b in zip(old, new))
            first = unit._beam_rates(psi, second=False)
            assert np.array_equal(first[0], old[0]) and np.array_equal(first[1], old[1]) and first[2] is None
            assert all(np.array_equal(a, b) for a, b in zip(_old_angles(unit, psi), unit._angles(psi)))
        theta = unit.theta_bottom + np.linspace(0.0, 2 * np.pi, 1500)
        unit._tf_cache.clear()
        tf = unit.torque_factor_m(theta)  # the kept-array path and the query path
        assert np.array_equal(tf, unit.geometry.a_m * unit._sign * _old_beam_rates(unit, unit._psi(theta))[1])
        assert unit.torque_factor_m(0.7) == float(unit.geometry.a_m * unit._sign
                                                  * _old_beam_rates(unit, unit._psi(np.asarray(0.7)))[1])


@pytest.mark.parametrize("n", [3, 4, 10, 11, 12, 1000, 1001, 4321])
def test_percentiles_are_np_percentile_to_the_bit(n: int) -> None:
    rng = np.random.default_rng(n)
    for a in (rng.normal(0.0, 1e4, n), np.round(rng.normal(0.0, 3.0, n)), np.full(n, 2.5),
              np.sort(rng.uniform(-1.0, 1.0, n))):
        for qs in ((90, 10), (10, 90), (85,), (0, 100), (50, 99.9, 0.1)):
            want = tuple(float(x) for x in np.percentile(a, qs))
            got = cf.percentiles_linear(a, qs)
            assert got == want, (n, qs)
    a = rng.normal(0.0, 1.0, n)
    a[n // 2] = np.nan
    assert all(np.isnan(cf.percentiles_linear(a, (90, 10))))


def test_stroke_on_a_radius_is_the_built_units_and_the_secant_the_old_one() -> None:
    from srenv.surface_unit import inline_unit as iu

    rng = np.random.default_rng(4)
    for kind, fields in UNITS.items():
        u = BeamUnitConfig(geometry=kind, crank_follows_stroke=True, **fields)
        full = inline_unit(u)
        for r in rng.uniform(0.3, 1.0, 20) * u.r_m:
            assert iu._stroke_on_radius(full, float(r)) \
                == inline_unit.__wrapped__(dataclasses.replace(u, r_m=float(r))).stroke_m
        for s in [*rng.uniform(0.4, 1.0, 30) * full.stroke_m, full.stroke_m, 2.0 * full.stroke_m]:
            old, new = _old_unit_for_stroke(u, float(s)), unit_for_stroke.__wrapped__(u, float(s))
            assert (new.crank_radius_m, new.stroke_m, new.geometry) == (old.crank_radius_m, old.stroke_m, old.geometry)


def test_gearbox_analysis_takes_torque_factor_and_arm_once_with_the_old_figures() -> None:
    from srenv.surface_unit import gearbox

    rng = np.random.default_rng(9)
    for unit in _units():
        theta = unit.theta_bottom + np.linspace(0.0, 2 * np.pi, 1200)
        su = unit.geometry.structural_unbalance_n
        base = 4e4 + 2e4 * np.sin(theta - unit.theta_bottom)
        exact_su = base.copy()
        exact_su[::5] = su  # the well's torque exactly zero (a signed zero) at every fifth sample
        for load in (base, base + rng.normal(0.0, 3e3, theta.size), exact_su):
            for moment, offset in ((3e4, 0.0), (5e4, 0.17), (0.0, -0.2)):
                rep = gearbox.analyse(unit, theta, load, np.zeros_like(theta), 1.0, 0.01,
                                      counterbalance_moment_nm=moment, counterbalance_offset_rad=offset)
                m, f = (0.0, moment) if unit.air_balanced else (moment, 0.0)
                assert np.array_equal(rep.net_torque_nm, unit.net_torque_nm(theta, load, m, offset, f))
                assert np.array_equal(np.signbit(rep.net_torque_nm), np.signbit(unit.net_torque_nm(theta, load, m,
                                                                                                   offset, f)))
                assert rep.optimal_counterbalance_nm == gearbox.optimal_counterbalance_nm(unit, theta, load, offset)


def _numpy_bisection(well: np.ndarray, arm: np.ndarray) -> float:
    """optimal_counterbalance_nm's bisection as written in numpy before issue 25 (every pass reads every sample)."""
    from srenv.surface_unit import gearbox

    lo, hi = 0.0, 2.0 * float(np.max(np.abs(well))) / float(np.max(np.abs(arm)))
    for _ in range(gearbox._BISECTION_PASSES):
        if hi - lo <= gearbox._BISECTION_RTOL * max(hi, 1.0):
            break
        mid = 0.5 * (lo + hi)
        torque = well - mid * arm
        worst = int(np.argmax(np.abs(torque)))
        slope = -arm[worst] * np.copysign(1.0, torque[worst])
        if slope > 0.0:
            hi = mid
        elif slope < 0.0:
            lo = mid
        else:
            return mid
    return 0.5 * (lo + hi)


def test_pruned_bisection_takes_the_same_steps_as_the_full_one() -> None:
    from srenv.surface_unit import gearbox

    rng = np.random.default_rng(21)
    cases = []
    for unit in _units():
        theta = unit.theta_bottom + np.linspace(0.0, 2 * np.pi, 2400)
        load = 4e4 + 2e4 * np.sin(theta - unit.theta_bottom) + rng.normal(0.0, 2e3, theta.size)
        well = np.asarray(unit.net_torque_nm(theta, load, 0.0))
        for arm in (unit.counterbalance_arm(theta, 0.0), unit.counterbalance_arm(theta, 0.3),
                    np.asarray(unit.torque_factor_m(theta))):
            cases.append((well, arm))
    for _ in range(300):  # random torques, plateaus and exact ties of |T| (mirrored and repeated samples)
        n = int(rng.integers(2, 400))
        w, s = rng.normal(0.0, 1e4, n), rng.normal(0.0, 1.0, n)
        if rng.random() < 0.3:
            w, s = np.r_[w, -w], np.r_[s, -s]
        if rng.random() < 0.3:
            w, s = np.round(w / 1e3) * 1e3, np.round(s * 4) / 4
            s[s == 0] = 0.5
        cases.append((w, s))
    for well, arm in cases:
        hi = 2.0 * float(np.max(np.abs(well))) / float(np.max(np.abs(arm)))
        assert gearbox._bisect(np.ascontiguousarray(well), np.ascontiguousarray(arm), hi) \
            == _numpy_bisection(well, arm)
    # the pruning drops most of a stroke's samples once the bracket is narrow (what makes it faster)
    well, arm = cases[0]
    best = _numpy_bisection(well, arm)
    kept, _ = gearbox._prune(well, arm, best * (1 - 1e-3), best * (1 + 1e-3), 1e-6)
    assert 0 < kept.size < well.size // 4


def _old_stick_slip_energy_j(x, v, f, stiffness_n_m, end_fraction=0.02, ramp_fraction=0.05) -> float:
    """card_features.stick_slip_energy_j in numpy, as it was before issue 25's compiled pass."""
    rest = np.abs(v) <= cf.REST_TOL_M_S
    if not rest.any():
        return 0.0
    d = np.diff(np.concatenate(([0], rest.astype(np.int8), [0])))
    starts, ends = np.flatnonzero(d == 1), np.flatnonzero(d == -1)
    runs = [(int(s), int(e)) for s, e in zip(starts, ends) if e - s >= 2]
    if not runs:
        return 0.0
    lo, hi = float(x.min()), float(x.max())
    travel = max(hi - lo, 1e-6)
    d0, ramp = end_fraction * travel, ramp_fraction * travel
    total = 0.0
    for s, e in runs:
        seg = f[max(s - 1, 0): min(e + 1, len(f))]
        df = float(seg.max() - seg.min())
        dist = min(float(x[s]) - lo, hi - float(x[s]))
        total += min(1.0, max(0.0, dist - d0) / ramp) * df * df
    return total / (2.0 * stiffness_n_m)


def _old_impact_speed_m_s(x, v, f) -> float:
    if len(f) < 3:
        return 0.0
    hi, lo = (float(q) for q in np.percentile(f, (90, 10)))
    if hi - lo <= 1.0:
        return 0.0
    mid = 0.5 * (hi + lo)
    top = int(np.argmax(x))
    below = np.flatnonzero(f[top:] < mid)
    if len(below) == 0:
        return 0.0
    k = top + int(below[0])
    return float(max(0.0, -v[max(k - 1, top)]))


def _stroke_traces() -> list[dict]:
    """Pump traces of a few simulated strokes (a sticking deviated well among them) and synthetic ones with
    plunger stops anywhere (runs of exact zeros, single zeros, stops at the ends, NaN)."""
    from srenv.config import load_config
    from srenv.simulation.simulator import Simulator

    out = [r.trace for name in ("paper_fig4_deviated", "conventional_fig4")
           for r in Simulator(load_config(name)).run_strokes(2)]
    rng = np.random.default_rng(13)
    for n in (5, 40, 700, 3001):
        x = np.cumsum(rng.normal(0.0, 0.01, n))
        v = rng.normal(0.0, 0.1, n)
        for _ in range(int(rng.integers(0, 8))):
            s = int(rng.integers(0, n))
            v[s: s + int(rng.integers(1, 30))] = 0.0
        v[: int(rng.integers(0, 3))] = 0.0
        v[n - int(rng.integers(0, 3)):] = 0.0
        f = 1e4 * np.sin(np.linspace(0.0, 6.0, n)) + rng.normal(0.0, 50.0, n)
        out.append({"pump_position_m": x, "pump_velocity_m_s": v, "pump_load_n": f})
    nan = {k: np.array(a, float) for k, a in out[-1].items()}
    nan["pump_load_n"][17] = np.nan
    return [*out, nan]


def test_compiled_stick_slip_and_impact_are_the_numpy_forms() -> None:
    stopped = 0
    for tr in _stroke_traces():
        x, v, f = (np.asarray(tr[k], float) for k in ("pump_position_m", "pump_velocity_m_s", "pump_load_n"))
        old, new = _old_stick_slip_energy_j(x, v, f, 3.7e5), cf.stick_slip_energy_j(x, v, f, 3.7e5)
        assert new == old or (np.isnan(old) and np.isnan(new))
        stopped += old > 0.0
        assert cf.impact_speed_m_s(x, v, f) == _old_impact_speed_m_s(x, v, f)
    assert stopped >= 3  # the traces hold plunger stops away from the ends: the sum is exercised


def _old_card_features(position, load) -> np.ndarray:
    """card_shape.features with np.r_ and np.roll, as it was before issue 25 (valid cards only)."""
    from srenv.analysis import card_shape as cs

    def branch(x, y):
        xm = np.maximum.accumulate(x)
        keep = np.r_[True, np.diff(xm) > 0]
        if keep.sum() < 2:
            return np.interp(cs.GRID, [0.0, 1.0], [y[0], y[-1]])
        return np.interp(cs.GRID, xm[keep], y[keep])

    x, y = np.asarray(position, dtype=np.float64), np.asarray(load, dtype=np.float64)
    xr, yr = float(x.max() - x.min()), float(y.max() - y.min())
    xc, yc = np.r_[x, x[:1]], np.r_[y, y[:1]]
    if float(np.sum(0.5 * (yc[1:] + yc[:-1]) * np.diff(xc))) < 0.0:
        x, y = x[::-1], y[::-1]
    ymax, ymin = float(y.max()), float(y.min())
    ratio = float(np.clip(ymin / ymax, -1.0, 1.0)) if ymax > 0 else 0.0
    xn, yn = (x - x.min()) / xr, (y - ymin) / yr
    b = int(np.argmin(xn))
    xn, yn = np.roll(xn, -b), np.roll(yn, -b)
    t = int(np.argmax(xn))
    up = branch(xn[: t + 1], yn[: t + 1])
    down = branch(1.0 - np.r_[xn[t:], xn[:1]], np.r_[yn[t:], yn[:1]])[::-1]
    return np.r_[up, down, ratio]


def test_card_features_without_r_and_roll_are_the_old_ones() -> None:
    from srenv.analysis import card_shape as cs

    rng = np.random.default_rng(17)
    cards = [(tr["polished_rod_position_m"], tr["polished_rod_load_n"]) for tr in _stroke_traces()[:4]]
    for n in (8, 9, 50, 1000):
        phase = np.linspace(0.0, 2 * np.pi, n, endpoint=False) + rng.uniform(0.0, 6.0)
        x = 0.5 * (1 - np.cos(phase)) + rng.normal(0.0, 0.01, n)
        y = 2e4 + 1e4 * np.sin(phase) + rng.normal(0.0, 300.0, n)
        cards += [(x, y), (x[::-1], y[::-1]), (x, -y)]
    for x, y in cards:
        new, old = cs.features(x, y), _old_card_features(x, y)
        assert new.dtype == old.dtype and new.shape == old.shape == (cs.N_FEATURES,)
        assert np.array_equal(new, old)
