"""What a rod-pump controller computes from one stroke, and the physical measures the v1 costs price.

All functions take one recorded stroke's trace (``Simulator`` trace conventions: positions and velocities
upward-positive, loads true tension in N) and return SI numbers.

Fillage estimate (surface card, what a pump-off controller reads)
    Positions normalised to [0, 1] over the stroke (0 = bottom). The upstroke's fluid-carrying load ``L_up`` is the
    median load of the up branch over [0.3, 0.7]; the transferred load ``L_dn`` the median of the down branch over
    [0.05, 0.3]. The estimate is the highest down-branch position at which the load has fallen to the mid-load
    ``(L_up + L_dn)/2``, i.e. where the fluid load left the rods on the way down, linearly interpolated. A full
    pump transfers right after the top (estimate near 1, less the rod stretch); a pounding pump holds the load
    into the downstroke (estimate about the pump fillage). Continuous in the card.
Stick-slip energy
    Rest episodes of the plunger (runs of at least two samples with |v| <= 1e-12 m/s, the simulator's exact
    zero). A stop ``i`` stores and then releases the elastic energy ``dF_i^2 / (2 k_B)`` in the string, ``dF_i`` =
    the load swing over the stop, ``k_B`` = static stiffness of the string at the pump (top held). The valve
    reversals are stops too, at the two ends of the plunger's travel, and belong to every stroke: each stop is
    weighted by ``clip((d_i - 0.02 S) / (0.05 S), 0, 1)``, ``d_i`` its distance from the nearer end of the travel
    ``S`` (the 2 % absorb the millimetres by which consecutive bottoms differ), so the reversals weigh 0 and a stop
    in mid-stroke fully. The measure is 0 in a smooth regime and grows
    continuously from 0 as a stop appears (a short stop changes the load little, a reversal that splits in two
    stays at the end of the travel), unlike a count of stops.
Impact speed (fluid pound)
    The plunger speed at the moment the pump load falls through the mid-load on the downstroke. With a full
    barrel the transfer happens at rest at the top (0 m/s); with pounding the plunger is already moving down
    when it meets the liquid. Continuous in the fillage.
Polished-rod power
    ``P = load x upward velocity`` (W); mean over the stroke (= card work / period) and the peak.
"""

from __future__ import annotations

import math

import numpy as np

from .card_pass import first_below, stick_slip_sum

REST_TOL_M_S = 1e-12


def _branches(pos: np.ndarray, load: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    lo, hi = float(pos.min()), float(pos.max())
    x = (pos - lo) / (hi - lo) if hi - lo > 1e-9 else np.zeros_like(pos)
    top = int(np.argmax(pos))
    return x[: top + 1], load[: top + 1], x[top:], load[top:]


def fillage_estimate(pos: np.ndarray, load: np.ndarray) -> float:
    """The controller's card-based fillage estimate (see the module docstring), in [0, 1]."""
    xu, lu, xd, ld = _branches(np.asarray(pos, float), np.asarray(load, float))
    if len(xd) < 3 or len(xu) < 3:
        return 1.0
    mu = (xu >= 0.3) & (xu <= 0.7)
    md = (xd >= 0.05) & (xd <= 0.3)
    l_up = float(np.median(lu[mu])) if mu.any() else float(lu.max())
    l_dn = float(np.median(ld[md])) if md.any() else float(ld.min())
    if l_up - l_dn <= 1e-6 * max(abs(l_up), 1.0):
        return 1.0
    mid = 0.5 * (l_up + l_dn)
    below = ld < mid
    if not below.any():
        return 0.0
    k = int(np.argmax(below))  # first sample (from the top, in time order) under the mid-load
    if k == 0:
        return float(xd[0])
    # interpolate between samples k-1 (above) and k (below)
    f = (ld[k - 1] - mid) / (ld[k - 1] - ld[k])
    return float(np.clip(xd[k - 1] + f * (xd[k] - xd[k - 1]), 0.0, 1.0))


def _rest_runs(v: np.ndarray) -> list[tuple[int, int]]:
    rest = np.abs(v) <= REST_TOL_M_S
    if not rest.any():
        return []
    d = np.diff(np.concatenate(([0], rest.astype(np.int8), [0])))
    starts, ends = np.flatnonzero(d == 1), np.flatnonzero(d == -1)
    return [(int(s), int(e)) for s, e in zip(starts, ends) if e - s >= 2]


def stick_slip_energy_j(pump_position_m: np.ndarray, pump_velocity_m_s: np.ndarray, pump_load_n: np.ndarray,
                        stiffness_n_m: float, end_fraction: float = 0.02, ramp_fraction: float = 0.05) -> float:
    """Elastic energy (J) stored and released by the plunger's stops away from the ends of its travel."""
    x = np.asarray(pump_position_m, float)
    v = np.asarray(pump_velocity_m_s, float)
    f = np.asarray(pump_load_n, float)
    total, any_run, finite = stick_slip_sum(np.ascontiguousarray(x), np.ascontiguousarray(v),
                                            np.ascontiguousarray(f), REST_TOL_M_S, end_fraction, ramp_fraction)
    if finite:  # the compiled pass (card_pass.py): the numpy form's numbers
        return total / (2.0 * stiffness_n_m) if any_run else 0.0
    runs = _rest_runs(v)
    if not runs:
        return 0.0
    lo, hi = float(x.min()), float(x.max())
    travel = max(hi - lo, 1e-6)
    d0, ramp = end_fraction * travel, ramp_fraction * travel
    total = 0.0
    for s, e in runs:
        seg = f[max(s - 1, 0): min(e + 1, len(f))]
        df = float(seg.max() - seg.min())
        d = min(float(x[s]) - lo, hi - float(x[s]))
        total += min(1.0, max(0.0, d - d0) / ramp) * df * df
    return total / (2.0 * stiffness_n_m)


def percentiles_linear(a: np.ndarray, qs: tuple) -> tuple:
    """``np.percentile(a, qs)`` (its default 'linear' rule) as floats, to the bit, without its Python: one
    partition of a copy at the order statistics it reads and its own interpolation (``_lerp``: from the lower
    neighbour below a fraction of 0.5, from the upper one from 0.5 on). A NaN in ``a`` goes to np.percentile.
    Pinned against np.percentile in tests/srenv/simulation/test_fast_paths.py."""
    n = a.size
    last = n - 1
    spots = []
    for q in qs:
        v = last * (q / 100)  # numpy: (n - 1) * (q / 100)
        # numpy's previous index: floor(v), or -1 (the maximum, twice) at or above the last index
        prev = -1 if v >= last else math.floor(v)
        spots.append((v, prev, last if prev < 0 else prev, last if prev < 0 else prev + 1))
    part = np.partition(a, sorted({0, last, *(k for *_, i, j in spots for k in (i, j))}))
    if math.isnan(part[last]):
        return tuple(float(x) for x in np.percentile(a, qs))
    out = []
    for v, prev, i, j in spots:
        lo, hi = float(part[i]), float(part[j])
        g = v - prev  # numpy's gamma
        d = hi - lo
        out.append(hi - d * (1 - g) if g >= 0.5 else lo + d * g)
    return tuple(out)


def impact_speed_m_s(pump_position_m: np.ndarray, pump_velocity_m_s: np.ndarray, pump_load_n: np.ndarray
                     ) -> float:
    """Plunger speed (m/s) when the load transfers on the downstroke (0 with a full barrel)."""
    x = np.asarray(pump_position_m, float)
    v = np.asarray(pump_velocity_m_s, float)
    f = np.asarray(pump_load_n, float)
    if len(f) < 3:
        return 0.0
    hi, lo = percentiles_linear(f, (90, 10))
    if hi - lo <= 1.0:
        return 0.0
    mid = 0.5 * (hi + lo)
    top = int(np.argmax(x))
    k = first_below(np.ascontiguousarray(f), top, mid)  # the first sample from the top on below the mid-load
    if k < 0:
        return 0.0
    return float(max(0.0, -v[max(k - 1, top)]))  # downward speed (velocities are upward-positive)


def polished_rod_power_w(position_m: np.ndarray, velocity_m_s: np.ndarray, load_n: np.ndarray, t_s: np.ndarray
                         ) -> tuple[float, float]:
    """(mean, peak) polished-rod power in W; the mean is the card work over the stroke's duration."""
    p = np.asarray(load_n, float) * np.asarray(velocity_m_s, float)
    t = np.asarray(t_s, float)
    if len(t) < 2:
        return 0.0, 0.0
    dt = float(t[1] - t[0])
    return float(np.sum(p) * dt / (len(t) * dt)), float(p.max())
