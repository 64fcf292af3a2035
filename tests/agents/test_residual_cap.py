"""A residual's bounded correction (agents/policies/residual.py ``cap``, issue 24, helper f24): no cap is today's
correction bit for bit, a cap bounds it (scaled, its rate entry at most ``spm_cap``), and every bad field is refused
in one line naming it (cases generated from :data:`CAP_FIELDS`)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from agents.policies.residual import CAP_FIELDS, ResidualAgentPolicy, bound_correction, check_cap, compose

RNG = np.random.default_rng(0)
R = RNG.uniform(-1, 1, size=(64, 2)).astype(np.float32)
B = RNG.uniform(-1, 1, size=(64, 2)).astype(np.float32)


class _Stub:
    """A model whose correction is fixed."""

    def __init__(self, r: np.ndarray) -> None:
        self.r = r

    def predict(self, obs, state=None, episode_start=None, deterministic=True):
        return self.r, state


class _Base:
    def __init__(self, b: np.ndarray) -> None:
        self.b = b

    def act(self, obs):
        return self.b


def _act(r: np.ndarray, b: np.ndarray, cap) -> np.ndarray:
    pol = ResidualAgentPolicy(_Stub(r), "pump_off", {}, 0.5, None, 1, cap)
    pol.base = _Base(b)
    return pol.predict(np.zeros(4, np.float32))[0]


def test_no_cap_is_todays_correction_bit_for_bit():
    assert bound_correction(R, None) is R
    for r, b in zip(R, B):
        assert np.array_equal(_act(r, b, None), compose(b, r, 0.5))


def test_a_cap_bounds_the_correction():
    cap = {"correction_scale": 0.5, "spm_cap": 0.0}
    r = bound_correction(R, cap)
    assert np.all(r[:, 0] <= 0.0) and np.allclose(r[:, 1], 0.5 * R[:, 1])
    np.testing.assert_allclose(r[:, 0], np.minimum(0.5 * R[:, 0], 0.0))
    assert np.array_equal(bound_correction(R, {"correction_scale": 1.0}), R)
    for r0, b in zip(R, B):  # the capped policy never pumps faster than its base
        a = _act(r0, b, {"spm_cap": 0.0})
        assert a[0] <= max(b[0], -1.0) + 1e-7 and a[1] == compose(b, r0, 0.5)[1]


def _bad_values():
    for k, (lo, hi, closed) in CAP_FIELDS.items():
        for v in (hi + 0.1, lo - 0.1, math.nan, math.inf, True, "0.5", None) + (() if closed else (lo,)):
            yield k, v


@pytest.mark.parametrize("field, value", list(_bad_values()))
def test_bad_fields_refused_in_one_line(field, value):
    with pytest.raises(ValueError) as e:
        check_cap({field: value})
    msg = str(e.value)
    assert "\n" not in msg and f"residual.cap.{field} = {value!r}" in msg and "expected a number in" in msg
    with pytest.raises(ValueError, match=f"residual.cap.{field}"):
        ResidualAgentPolicy(_Stub(R[0]), "pump_off", {}, 0.5, cap={field: value})


@pytest.mark.parametrize("cap", [{}, {"spm": 0.0}, [0.5], "spm_cap"])
def test_bad_cap_refused_in_one_line(cap):
    with pytest.raises(ValueError, match=r"residual.cap = .*: expected a mapping of correction_scale, spm_cap"):
        check_cap(cap)


def test_bounds_accepted():
    for k, (lo, hi, closed) in CAP_FIELDS.items():
        check_cap({k: hi})
        check_cap({k: lo} if closed else {k: lo + 1e-6})


def test_a_reports_capped_residual_replays_capped_and_a_bad_cap_is_refused() -> None:
    """replay reads ``residual_on.cap`` (a capped design's report would otherwise replay uncapped, silently)."""
    import copy
    from pathlib import Path

    from agents.evaluation.replay import ReplayError, load_report, policy_specs

    report = Path(__file__).resolve().parents[2] / "docs/v2/benchmark.json"
    rep = load_report(report)
    assert "cap" not in policy_specs(rep, "oracle_distilled_ensemble", report.parent)[0]["residual"]
    capped = copy.deepcopy(rep)
    capped["policies"]["oracle_distilled_ensemble"]["residual_on"]["cap"] = {"spm_cap": 0.0}
    spec = policy_specs(capped, "oracle_distilled_ensemble", report.parent)[0]
    assert spec["residual"]["cap"] == {"spm_cap": 0.0}
    capped["policies"]["oracle_distilled_ensemble"]["residual_on"]["cap"] = {"spm_cap": 7.0}
    with pytest.raises(ReplayError, match="spm_cap"):
        policy_specs(capped, "oracle_distilled_ensemble", report.parent)
