"""The kernel's named calling convention (docs/kernel.md): what ``kernel.advance`` reads and writes, and
:func:`build`, the one function every caller (``Simulator._run``, ``hopf.SpringBlock.simulate``) uses
to put it together.

Scalars travel in numpy structured arrays of one element (numba reads their fields by name, at the cost
of an array load); arrays travel in named tuples. What is constant during a run is apart from what the
kernel changes:

  Constants      numerics and the prescribed top node's own coefficients (read only)
  rod_friction   the rod friction law's record (srenv.laws.rod_friction.PARAMS, read only)
  valve          the valve law's record (srenv.laws.valve.PARAMS): its interval, fluid-pound plan and gas
                 chamber state; the kernel and the caller (between calls, at valve events) update it
  Progress       the protocol between kernel and caller: step index, QP hand-over, plunger direction and
                 event, plunger extremes since the caller last reset them
  Counters       per-run counts of certified / corrected / QP steps, DC iterations, recorded columns
  Model          K* (per dt) and the free nodes' stiffness, mass, damping, loads; element EA/L
  SideForce      the rod friction's side-force coefficients (srenv.laws.rod_friction)
  State          the string's state (u, v, a of the free nodes, the top, active-set pattern, last step's
                 reactions, velocities and stuck flags): carried from run to run by the caller
  Work           scratch of the step (no allocation per step); wb/wlo/whi/wv the QP hand-over
  Output         the per-step record, energy accumulators, element force envelope, stick episodes
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

# return codes of kernel.advance
DONE, NEED_QP, EVENT = 0, 1, 2
# path codes recorded per step
PATH_CERTIFIED, PATH_CORRECTED, PATH_QP = 0, 1, 2
# rows of the per-step record (one column per step; upward positions and velocities, true loads)
R_T, R_UA, R_PRL, R_UB, R_VB, R_PUMP, R_PATH, R_VA = 0, 1, 2, 3, 4, 5, 6, 7
N_REC = 8
# energy accumulators
E_TOP, E_GRAV, E_REACT, E_VISC = 0, 1, 2, 3
N_ENERGY = 4
# the prescribed top node's state, State.top: displacement, velocity, acceleration (positive down) and the
# polished-rod load in equivalent force
TOP_U, TOP_V, TOP_A, TOP_PRL = 0, 1, 2, 3
N_TOP = 4

CONSTANTS = np.dtype([
    ("dt_s", "f8"), ("beta", "f8"), ("gamma", "f8"),
    ("tol_v_m_s", "f8"),       # |v| below this is an exact rest in the certificate
    ("tol_lambda", "f8"),      # multiplier slack, relative to the interval's size
    ("dc_tol_m_s", "f8"), ("max_corrections", "i8"), ("dc_max_iterations", "i8"),
    ("always_qp", "i8"),       # 1: the QP at every step (the reference path)
    ("nonsmooth", "i8"),       # 0: no friction, no valve law (a plain linear Newmark step; bench only)
    ("record", "i8"),
    # the top node's own row: diagonal and coupling mass, damping, load, coupling stiffness, EA/L of the
    # first element (the polished-rod load and the top's column moved to the right-hand side)
    ("top_mass_kg", "f8"), ("top_coupling_mass_kg", "f8"), ("top_damping_n_s_m", "f8"),
    ("top_load_n", "f8"), ("top_coupling_stiffness_n_m", "f8"), ("top_ea_len_n_m", "f8"),
    # p A at the pump and at the top: equivalent force -> true load in the record
    ("pump_pressure_force_n", "f8"), ("top_pressure_force_n", "f8"),
    # Kelvin-Voigt (stiffness-proportional) damping C_K = tau K: enters K*, the top element's force and the
    # viscous work; 0 leaves every formula as it was (docs/realism.md)
    ("kv_tau_s", "f8"),
    # viscous damping per stroke direction: C times damp_up in a step that ends with the polished rod rising
    # (its prescribed velocity), times damp_down falling, the last factor at rest (K* changes at the turns
    # only); damp_split 0 = off
    ("damp_up", "f8"), ("damp_down", "f8"), ("damp_split", "i8"),
])
PROGRESS = np.dtype([("step", "i8"), ("dc_iterations", "i8"), ("have_qp", "i8"), ("plunger_dir", "i8"),
                     ("event", "i8"), ("ub_max_m", "f8"), ("ub_min_m", "f8"),
                     # the factor on C that K* holds in this step, and the previous step's
                     ("damp_s", "f8"), ("damp_prev", "f8")])
COUNTERS = np.dtype([("certified", "i8"), ("corrected", "i8"), ("qp", "i8"), ("dc_iterations", "i8"),
                     ("recorded", "i8")])


class Model(NamedTuple):
    ksd: np.ndarray  # K* = M/(gamma dt) + C + beta dt/gamma K on the free nodes: diagonal, off-diagonal
    kso: np.ndarray
    kd: np.ndarray   # stiffness, mass (diagonal and off-diagonal), damping diagonal, loads: free nodes
    ko: np.ndarray
    md: np.ndarray
    mo: np.ndarray
    cd: np.ndarray
    f: np.ndarray
    ea_len: np.ndarray  # EA/L per element (element 0 joins the top)


class State(NamedTuple):
    u: np.ndarray
    v: np.ndarray
    a: np.ndarray
    top: np.ndarray       # TOP_* (u_A, v_A, a_A, PRL_eq)
    status: np.ndarray    # +1 sliding down, -1 sliding up, 0 stuck
    prev_lam: np.ndarray
    prev_v: np.ndarray
    prev_stuck: np.ndarray


class Work(NamedTuple):
    lo: np.ndarray
    hi: np.ndarray
    ns: np.ndarray      # nonsmooth node (an interval of positive length)
    lam: np.ndarray
    b: np.ndarray
    b0: np.ndarray
    shift: np.ndarray   # j2'(v_k) of the nonmonotone laws
    vk: np.ndarray
    rhs: np.ndarray
    stuck: np.ndarray
    cp: np.ndarray
    dp: np.ndarray
    nforce: np.ndarray
    fric_s: np.ndarray  # side force per node
    wv: np.ndarray
    wb: np.ndarray
    wlo: np.ndarray
    whi: np.ndarray


class Output(NamedTuple):
    rec: np.ndarray
    energy: np.ndarray
    emax: np.ndarray
    emin: np.ndarray
    stick: np.ndarray


class Stepper(NamedTuple):
    """Everything ``kernel.advance`` takes besides the top's velocity series: ``kernel.run`` unpacks it."""

    const: np.ndarray
    rod_friction: np.ndarray
    valve: np.ndarray
    progress: np.ndarray
    counters: np.ndarray
    model: Model
    side: tuple
    state: State
    work: Work
    out: Output


def work(n: int) -> Work:
    """Scratch arrays for n free nodes, allocated once per caller (no per-step allocation)."""
    fields = {name: (np.zeros(n, dtype=np.bool_) if name in ("ns", "stuck") else np.zeros(n))
              for name in Work._fields}
    return Work(**fields)


def kstar(stiffness, mass, damping, dt_s: float, beta: float, gamma: float, kv_tau_s: float = 0.0
          ) -> tuple[np.ndarray, np.ndarray]:
    """K* on the free nodes from the whole string's (diagonal, off-diagonal) stiffness and mass and damping
    diagonal (top node first); a Kelvin-Voigt damping tau K adds tau to K's factor (the velocity form's
    K* = M/(gamma dt) + C + (beta dt/gamma + tau) K stays tridiagonal)."""
    (kd, ko), (md, mo), cd = stiffness, mass, damping
    c1, c2 = 1.0 / (gamma * dt_s), beta * dt_s / gamma
    if kv_tau_s:
        c2 = c2 + kv_tau_s
    return (c1 * md + cd + c2 * kd)[1:].copy(), (c1 * mo + c2 * ko)[1:].copy()


class Shared(NamedTuple):
    """What a run's arguments share with the next run's at one model, time step and record flag
    (:func:`shared`); :func:`for_run` adds a run's own."""

    const: np.ndarray
    rod_friction: np.ndarray
    side: tuple
    model: Model                  # K* of the factor 1 on C; the others' in kstar_by_factor
    matrices: tuple               # (stiffness, mass, damping) of the whole string, for K* at another factor
    kstar_by_factor: dict         # damping factor -> (ksd, kso) as kstar gives them (never handed to a run)


def build(*, dt_s: float, beta: float, gamma: float, stiffness, mass, damping: np.ndarray, load_n: np.ndarray,
          ea_len_n_m: np.ndarray, side, rod_friction: np.ndarray, valve: np.ndarray, state: State,
          scratch: Work, energy: np.ndarray, n_steps: int, record: bool, max_corrections: int,
          dc_max_iterations: int, dc_tolerance_m_s: float, tol_v_m_s: float = 1e-13, tol_lambda: float = 1e-12,
          always_qp: bool = False, nonsmooth: bool = True, pump_pressure_force_n: float = 0.0,
          top_pressure_force_n: float = 0.0, plunger_dir: int = 0, ub_extremes_m=(0.0, 0.0),
          kv_tau_s: float = 0.0, damping_factors: tuple[float, float] = (1.0, 1.0),
          damping_now: float = 1.0) -> Stepper:
    """The kernel's arguments for one run of `n_steps` steps from the whole string's matrices (top node first:
    ``stiffness`` and ``mass`` as (diagonal, off-diagonal), ``damping`` and ``load_n`` diagonals): :func:`shared`
    and :func:`for_run` (a caller that runs often keeps the first, srenv.simulation.kernel_args)."""
    sh = shared(dt_s=dt_s, beta=beta, gamma=gamma, stiffness=stiffness, mass=mass, damping=damping, load_n=load_n,
                ea_len_n_m=ea_len_n_m, side=side, rod_friction=rod_friction, record=record,
                max_corrections=max_corrections, dc_max_iterations=dc_max_iterations,
                dc_tolerance_m_s=dc_tolerance_m_s, tol_v_m_s=tol_v_m_s, tol_lambda=tol_lambda, always_qp=always_qp,
                nonsmooth=nonsmooth, pump_pressure_force_n=pump_pressure_force_n,
                top_pressure_force_n=top_pressure_force_n, kv_tau_s=kv_tau_s, damping_factors=damping_factors)
    return for_run(sh, valve=valve, state=state, scratch=scratch, energy=energy, n_steps=n_steps,
                   plunger_dir=plunger_dir, ub_extremes_m=ub_extremes_m, damping_now=damping_now)


def shared(*, dt_s: float, beta: float, gamma: float, stiffness, mass, damping: np.ndarray, load_n: np.ndarray,
           ea_len_n_m: np.ndarray, side, rod_friction: np.ndarray, record: bool, max_corrections: int,
           dc_max_iterations: int, dc_tolerance_m_s: float, tol_v_m_s: float = 1e-13, tol_lambda: float = 1e-12,
           always_qp: bool = False, nonsmooth: bool = True, pump_pressure_force_n: float = 0.0,
           top_pressure_force_n: float = 0.0, kv_tau_s: float = 0.0,
           damping_factors: tuple[float, float] = (1.0, 1.0)) -> Shared:
    """The arguments of :func:`build` that do not change from run to run (the kernel reads them only)."""
    (kd, ko), (md, mo) = stiffness, mass
    const = np.zeros(1, CONSTANTS)
    c = const[0]
    c["dt_s"], c["beta"], c["gamma"] = dt_s, beta, gamma
    c["tol_v_m_s"], c["tol_lambda"], c["dc_tol_m_s"] = tol_v_m_s, tol_lambda, dc_tolerance_m_s
    c["max_corrections"], c["dc_max_iterations"] = max_corrections, dc_max_iterations
    c["always_qp"], c["nonsmooth"], c["record"] = int(always_qp), int(nonsmooth), int(record)
    c["top_mass_kg"], c["top_coupling_mass_kg"], c["top_damping_n_s_m"] = md[0], mo[0], damping[0]
    c["top_load_n"], c["top_coupling_stiffness_n_m"], c["top_ea_len_n_m"] = load_n[0], ko[0], ea_len_n_m[0]
    c["pump_pressure_force_n"], c["top_pressure_force_n"] = pump_pressure_force_n, top_pressure_force_n
    c["kv_tau_s"] = kv_tau_s
    c["damp_up"], c["damp_down"] = damping_factors
    c["damp_split"] = int(tuple(damping_factors) != (1.0, 1.0))
    ksd, kso = kstar(stiffness, mass, damping, dt_s, beta, gamma, kv_tau_s)
    model = Model(ksd, kso, kd[1:], ko[1:], md[1:], mo[1:], damping[1:], load_n[1:], ea_len_n_m)
    return Shared(const, rod_friction, tuple(side), model, (stiffness, mass, damping), {1.0: (ksd, kso)})


def for_run(sh: Shared, *, valve: np.ndarray, state: State, scratch: Work, energy: np.ndarray, n_steps: int,
            plunger_dir: int = 0, ub_extremes_m=(0.0, 0.0), damping_now: float = 1.0) -> Stepper:
    """One run's arguments on ``sh``: its valve record, state, scratch and energy arrays, fresh progress,
    counters and output, and a fresh copy of K* (the kernel adds the gas spring and the direction's damping to
    its diagonal in place) with the factor on C that the last run ended with (damping per direction)."""
    c = sh.const[0]
    split = int(c["damp_split"])
    factor = damping_now if split else 1.0
    progress = np.zeros(1, PROGRESS)
    progress["damp_s"] = progress["damp_prev"] = factor
    progress["plunger_dir"] = plunger_dir
    progress["ub_max_m"], progress["ub_min_m"] = ub_extremes_m
    pair = sh.kstar_by_factor.get(factor)
    if pair is None:
        stiffness, mass, damping = sh.matrices
        pair = kstar(stiffness, mass, damping * factor, float(c["dt_s"]), float(c["beta"]), float(c["gamma"]),
                     float(c["kv_tau_s"]))
        sh.kstar_by_factor[factor] = pair
    model = sh.model._replace(ksd=pair[0].copy(), kso=pair[1].copy())
    n = len(model.ksd)
    out = Output(np.empty((N_REC, n_steps if c["record"] else 0)), energy, np.full(n, -np.inf), np.full(n, np.inf),
                 np.zeros(n, dtype=np.int64))
    return Stepper(sh.const, sh.rod_friction, valve, progress, np.zeros(1, COUNTERS), model, sh.side, state,
                   scratch, out)
