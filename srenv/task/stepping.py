"""Opt-in stepping options of the interval runner that trade exact strokes for accuracy (docs/speed.md §2g).
Both are off by default, so v1's and v2's results are unchanged.

- ``exact_min`` = K: every interval that pumps simulates at least K strokes exactly (no reuse of an earlier
  interval's stroke), and its fast-forward repeats the mean of the interval's settled exact strokes
  (:func:`srenv.task.reuse.mean_stroke`) instead of the last one. K at or above an interval's strokes simulates
  every stroke, as ``IntervalRunner.run(..., fast_forward=False)`` does.
- ``follow_drift``: the fast-forward moves the repeated stroke's figures along the intake-pressure slopes of two
  strokes kept at the setpoint (the carry's, :mod:`srenv.task.reuse`) as the annulus moves the pressure through
  the run, instead of holding the figures where the last exact stroke left them; the fatigue damage follows the
  Goodman loading through its power law (carried linearly it falls behind as the loading grows). Needs ``carry``.
"""

from __future__ import annotations

from . import boundary, reuse


def check(exact_min, follow_drift, carry: bool) -> tuple[int, bool]:
    """The options, validated: ValueError (TypeError for a follow_drift not a bool) naming the option, its value
    and what was expected."""
    from .runner_options import check_option

    exact_min, follow_drift = check_option("exact_min", exact_min), check_option("follow_drift", follow_drift)
    if follow_drift and not carry:
        raise ValueError("follow_drift = True: expected carry = True (it follows the carry's slopes)")
    return exact_min, follow_drift


def fast_forward(runner, res, exact: list, pressures: list, settled: int, key: tuple, period: float,
                 n_total: float, done: float, t_end: float, exact_max: int, need_exact: bool) -> tuple[float, bool]:
    """The runner's fast-forward with the options applied: the stroke repeated (the last exact one, or with
    ``exact_min`` the mean of the settled ones, ``exact[settled:]``), and with ``follow_drift`` its figures moved
    along the slopes over the run. ``pressures[i]`` is the intake pressure ``exact[i]``'s figures hold at."""
    f, p_f = exact[-1], pressures[-1]
    if runner.exact_min and len(exact) - settled > 1:
        f = reuse.mean_stroke(exact[settled:])
        held = pressures[settled:]
        p_f = sum(held) / len(held) if None not in held else None
    kept = runner._periodic.get(key)
    s = runner._slopes.get(key) if (runner.follow_drift or runner.boundary_strokes) and kept and \
        kept[2] is runner.sim.cfg else None
    p_start, w_start = runner._intake_pa(), res.fast_forward_strokes
    if runner.boundary_strokes:  # opt-in: stop at a predicted regime boundary for an exact stroke (boundary.py)
        done, need_exact = boundary.fast_forward(runner, res, f, p_f, s, period, n_total, done, t_end, len(exact),
                                                 exact_max, need_exact)
    else:
        done, need_exact = runner._repeat_stroke(res, f, period, n_total, done, t_end, len(exact), exact_max,
                                                 need_exact)
    s = s if runner.follow_drift else None
    w = res.fast_forward_strokes - w_start
    if s is not None and p_f is not None and w > 0:
        econ = runner.econ
        sums, peaks = reuse.drift(f, s, p_f, w, p_start, runner._intake_pa(), lambda g: reuse.fatigue_damage(
            g, econ.fatigue_exponent, econ.fatigue_life_cycles))
        for k, v in sums.items():
            setattr(res, k, getattr(res, k) + v)
        for m in peaks:
            runner._add_peaks(res, m)
    return done, need_exact
