"""The step QP in its dual box form, solved by ProxSuite through qpsolvers (or any qpsolvers backend).

With lam zero off the nonsmooth set S and v = K*^-1 (b - lam), the step problem's dual is
    min_{lam_S}  1/2 lam_S' (K*^-1)_SS lam_S - lam_S' (K*^-1 b)_S   s.t.  lo_S <= lam_S <= hi_S,
a small dense box QP. It is normalised (forces by the largest bound, objective by the largest diagonal of
(K*^-1)_SS) so that one absolute tolerance means the same thing for every well.

The solver identifies the active set; the answer is then *polished*: the pattern read off the dual
solution is handed to the exact active-set solve of the kernel, and used only if it satisfies the KKT
conditions (so a QP-found step is as exact as a certified one). Without a certificate the raw QP velocity
is kept. If a backend reports failure the chain retries cold with tighter settings, then the other
installed backends, and finally raises :class:`~srenv.errors.SolverFailure`.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np
import qpsolvers
from scipy.sparse import csc_matrix

from ..errors import SolverFailure
from ..physics.rod import solve_tridiagonal

FALLBACK_ORDER = ("proxqp", "clarabel", "osqp", "piqp", "daqp", "highs")
SPARSE_BACKENDS = ("osqp", "clarabel", "piqp", "highs", "scs", "ecos")


def _solver_options(name: str, eps_abs: float, tight: bool) -> dict:
    eps = eps_abs * (1e-2 if tight else 1.0)
    if name == "proxqp":
        return {"eps_abs": eps, "eps_rel": 0.0, "max_iter": 10000 if tight else 1000}
    if name == "osqp":
        return {"eps_abs": max(eps, 1e-12), "eps_rel": 0.0, "max_iter": 200000, "polishing": True,
                "raise_error": False}
    if name == "clarabel":
        return {"tol_gap_abs": max(eps, 1e-12), "tol_gap_rel": 1e-12, "tol_feas": 1e-12}
    return {}


@dataclass
class QPStats:
    calls: int = 0
    retries: int = 0
    polished: int = 0
    seconds: float = 0.0
    by_solver: dict = field(default_factory=dict)


class StepQP:
    """Builds and solves the dual box QP of one step; caches K*^-1 per time step."""

    def __init__(self, solver: str = "proxqp", eps_abs: float = 1e-11, persistent: bool = False) -> None:
        self.solver = solver
        self.eps_abs = eps_abs
        self.persistent = persistent
        self.stats = QPStats()
        self._inv: dict[float, np.ndarray] = {}
        self._pqp = None  # persistent proxsuite QP
        self._pqp_key: tuple | None = None
        self.fail_injector = None  # tests: callable(name) -> bool forcing a backend to "fail"

    def inverse(self, ksd: np.ndarray, kso: np.ndarray, dt: float) -> np.ndarray:
        inv = self._inv.get(dt)
        if inv is None:
            inv = solve_tridiagonal(ksd, kso, np.eye(len(ksd)))
            if len(self._inv) > 8:  # the env varies dt slightly with SPM: keep a few
                self._inv.pop(next(iter(self._inv)))
            self._inv[dt] = inv
        return inv

    def problem(self, inv: np.ndarray, b: np.ndarray, lo: np.ndarray, hi: np.ndarray, ns: np.ndarray):
        """The normalised dual box QP as a qpsolvers.Problem, and what is needed to map back."""
        fixed = ~ns
        rhs = b - np.where(fixed, lo, 0.0)
        w = inv @ rhs
        s_idx = np.flatnonzero(ns)
        h = inv[np.ix_(s_idx, s_idx)]
        force = max(float(np.max(np.abs(np.r_[lo[s_idx], hi[s_idx]]))), 1.0)
        hscale = float(np.max(np.diag(h)))
        prob = qpsolvers.Problem(P=h / hscale, q=-w[s_idx] / (force * hscale),
                                 lb=lo[s_idx] / force, ub=hi[s_idx] / force)
        return prob, w, s_idx, force

    def _solve_persistent(self, prob: qpsolvers.Problem) -> np.ndarray | None:
        from proxsuite import proxqp

        m = prob.P.shape[0]
        key = (m,)
        if self._pqp is None or self._pqp_key != key:
            qp = proxqp.dense.QP(m, 0, 0, True)
            qp.settings.eps_abs = self.eps_abs
            qp.settings.eps_rel = 0.0
            qp.settings.initial_guess = proxqp.InitialGuess.EQUALITY_CONSTRAINED_INITIAL_GUESS
            qp.init(prob.P, prob.q, None, None, None, None, None, prob.lb, prob.ub)
            qp.solve()
            # warm start only after a first solve (proxsuite 0.8 crashes on box QPs otherwise)
            qp.settings.initial_guess = proxqp.InitialGuess.WARM_START_WITH_PREVIOUS_RESULT
            self._pqp, self._pqp_key = qp, key
        else:
            qp = self._pqp
            qp.update(H=prob.P, g=prob.q, l_box=prob.lb, u_box=prob.ub, update_preconditioner=False)
            qp.solve()
        if qp.results.info.status != proxqp.QPSolverOutput.PROXQP_SOLVED:
            return None
        return np.array(qp.results.x)

    def _solve_once(self, prob: qpsolvers.Problem, name: str, tight: bool) -> np.ndarray | None:
        """One attempt of the chain: the solution, or None for any kind of failure (not solved, non-finite,
        the backend raising, or a test's fail_injector)."""
        x = None
        if self.fail_injector is None or not self.fail_injector(name):
            try:
                if self.persistent and name == "proxqp" and not tight:
                    x = self._solve_persistent(prob)
                else:
                    if name in SPARSE_BACKENDS:  # these take CSC matrices; converting keeps qpsolvers quiet
                        prob = qpsolvers.Problem(P=csc_matrix(prob.P), q=prob.q, lb=prob.lb, ub=prob.ub)
                    sol = qpsolvers.solve_problem(prob, solver=name,
                                                  **_solver_options(name, self.eps_abs, tight))
                    x = sol.x if sol.found else None
            except Exception:  # noqa: BLE001 - a backend raising is a failure like any other: move on
                x = None
        if x is None or not np.all(np.isfinite(x)):
            if name == "proxqp":
                # the persistent QP would warm-start the next step from this failed iterate: start it cold
                self._pqp = None
            return None
        return x

    def solve(self, inv: np.ndarray, b: np.ndarray, lo: np.ndarray, hi: np.ndarray, ns: np.ndarray,
              step: int, time_s: float) -> tuple[np.ndarray, np.ndarray]:
        """Raw QP velocity and the pattern read off its dual solution."""
        t0 = time.perf_counter()
        prob, w, s_idx, force = self.problem(inv, b, lo, hi, ns)
        chain = [(self.solver, False), (self.solver, True)] + [
            (s, True) for s in FALLBACK_ORDER if s != self.solver and s in qpsolvers.available_solvers]
        x = None
        for name, tight in chain:
            x = self._solve_once(prob, name, tight)
            self.stats.calls += 1
            if x is not None:
                self.stats.by_solver[name] = self.stats.by_solver.get(name, 0) + 1
                break
            self.stats.retries += 1
        self.stats.seconds += time.perf_counter() - t0
        if x is None:
            tried = ", ".join(f"{n} ({'tight' if t else 'default'})" for n, t in chain)
            raise SolverFailure(step, time_s, f"no backend solved the step QP (tried {tried})")
        lam_s = x * force
        v = w - inv[:, s_idx] @ lam_s
        status = np.zeros(len(b), dtype=np.int64)
        tol = 1e-6 * force
        status[s_idx] = np.where(lam_s >= hi[s_idx] - tol, 1, np.where(lam_s <= lo[s_idx] + tol, -1, 0))
        return v, status
