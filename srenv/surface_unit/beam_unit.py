"""API 11E beam pumping units: exact four-bar kinematics, torque factor and net gearbox torque, from the unit's
API RP 11L / Spec 11E dimensions, for the three API geometries: ``conventional`` (Class I, crank-balanced),
``mark_ii`` and ``air_balanced`` (Class III: the beam pivots at its rear end, the pitmans drive it between
the pivot and the horsehead). docs/surface_unit.md gives the equations and sign conventions.

Frame
-----
Side view with the **well to the right**; x to the right, y up, origin at the crank-shaft centre O. A
conventional unit carries its gearbox behind the Samson post, so the saddle (centre) bearing G sits at
(I, H) with H = sqrt(K² - I²). The walking beam pivots at G: the equalizer bearing E is C behind G, the
horsehead arc (radius A about G) is in front. The pitman (length P) joins E to the crank pin, R from O.
Because the horsehead is an arc about G, the polished rod moves exactly A times the beam rotation.
A Class III unit (Mark II, air-balanced) pivots the beam at its rear end: G sits at (-I, H), behind the crank
shaft, and E is C in front of G, on the horsehead's side; the pin still joins E through the pitman.

Crank angle θ
-------------
θ is measured from 12 o'clock **in the direction of rotation**, so it always grows with time:
θ(t) = θ_bottom + ω t with ω = 2π·SPM/60 > 0. For a clockwise unit this is exactly the API angle
(clockwise from 12 o'clock, well to the right); a counterclockwise unit is its mirror image. The pin sits
at R·(sin ψ, cos ψ) with the geometric clockwise angle ψ = θ (clockwise) or ψ = -θ (counterclockwise).
θ = 0 is close to, but not exactly at, the bottom of the stroke: use :attr:`ConventionalUnit.theta_bottom`.

Torque
------
Net gearbox torque (positive = the gearbox drives the cranks in their direction of rotation):
T = TF(θ)·(PRL - SU) - M·sin(θ + τ). TF = d(position)/dθ is the API torque factor (m/rad, positive on the
upstroke). On a conventional unit the crank counterweights sit on the pin side of the crank, so at θ = 90°
they fall in the direction of rotation and relieve the gearbox; τ is the angle by which the counterweight
arm leads the pin in the direction of rotation (0 for ordinary conventional cranks). SU follows API 11E:
the force at the polished rod that holds the beam horizontal with the pitmans disconnected, **positive
when that force acts downward**, i.e. when the pitman side of the beam is the heavy one (a heavy pitman
side helps lift the rods, hence the minus sign).
"""

from __future__ import annotations

import dataclasses
import itertools
import math
from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt

from ..errors import ConfigError

FloatArray = npt.NDArray[np.float64]
FloatOrArray = float | FloatArray

# +1: θ grows with the geometric clockwise angle ψ; -1: the mirror image.
ROTATION_SIGNS: dict[str, float] = {"clockwise": 1.0, "counterclockwise": -1.0}
# API lever class of each geometry: +1 Class I (saddle in front of the crank, E behind G), -1 Class III
LEVER_SIGNS: dict[str, float] = {"conventional": 1.0, "mark_ii": -1.0, "air_balanced": -1.0}

_LINK_FIELDS = ("a_m", "c_m", "i_m", "k_m", "p_m")
_RATING_FIELDS = {"torque_rating_nm": "N*m", "max_stroke_m": "m", "max_load_n": "N"}


def _require_positive(name: str, value: Any, unit: str) -> None:
    if not _is_real(value) or not math.isfinite(value) or value <= 0:
        raise ConfigError(name, value, f"a positive finite length/rating in {unit}")


def _is_real(value: Any) -> bool:
    # bool is an int subclass; a YAML `yes` must not pass as the number 1
    return isinstance(value, (int, float, np.floating, np.integer)) and not isinstance(value, bool)


@dataclass(frozen=True)
class BeamUnitGeometry:
    """Dimensions and ratings of one conventional unit (API RP 11L / Spec 11E nomenclature, SI units).

    ``k_m`` is the distance crank-shaft centre to saddle-bearing centre; build from the height of the
    saddle bearing above the crank shaft with :meth:`from_height`. ``structural_unbalance_n`` follows the
    API sign (positive = downward force needed at the polished rod, pitman side heavy); see module doc.
    """

    designation: str
    a_m: float
    c_m: float
    i_m: float
    k_m: float
    p_m: float
    crank_radii_m: tuple[float, ...]
    rotation: str
    torque_rating_nm: float
    structural_unbalance_n: float
    max_stroke_m: float
    max_load_n: float
    kind: str = "conventional"

    def __post_init__(self) -> None:
        if not isinstance(self.designation, str) or not self.designation.strip():
            raise ConfigError("designation", self.designation, "an API designation like C-228D-213-86")
        for name in _LINK_FIELDS:
            _require_positive(name, getattr(self, name), "m")
        for name, unit in _RATING_FIELDS.items():
            _require_positive(name, getattr(self, name), unit)
        if not _is_real(self.structural_unbalance_n) or not math.isfinite(self.structural_unbalance_n):
            raise ConfigError("structural_unbalance_n", self.structural_unbalance_n, "a finite force in N")
        if self.rotation not in ROTATION_SIGNS:
            raise ConfigError("rotation", self.rotation, f"one of {sorted(ROTATION_SIGNS)}")
        if self.kind not in LEVER_SIGNS:
            raise ConfigError("geometry", self.kind, f"one of {', '.join(LEVER_SIGNS)}")
        self._check_crank_radii()
        if self.i_m >= self.k_m:
            raise ConfigError("i_m", self.i_m, f"m, less than k_m = {self.k_m} m (saddle above the crank)")
        self._check_assembly()

    def _check_crank_radii(self) -> None:
        radii = self.crank_radii_m
        if isinstance(radii, (str, bytes)) or not hasattr(radii, "__len__") or len(radii) == 0:
            raise ConfigError("crank_radii_m", radii, "a non-empty sequence of crank radii in m")
        for j, radius in enumerate(radii):
            _require_positive(f"crank_radii_m[{j}]", radius, "m")
        # frozen dataclass: normalise a YAML list to the declared tuple of floats
        object.__setattr__(self, "crank_radii_m", tuple(float(r) for r in radii))
        if any(later > earlier for earlier, later in itertools.pairwise(self.crank_radii_m)):
            raise ConfigError("crank_radii_m", self.crank_radii_m, "radii in m, largest (longest stroke) 1st")

    def _check_assembly(self) -> None:
        """The triangle saddle-equalizer-pin must stay non-degenerate over a full crank turn.

        The pin-to-saddle distance sweeps [K - R, K + R]; the largest hole is the worst case because the
        smaller holes' intervals nest inside it. Equality would be a toggle (lock-up) position.
        """
        radius = self.crank_radii_m[0]
        reach = self.c_m + self.p_m
        if radius >= self.k_m:
            raise ConfigError("crank_radii_m", self.crank_radii_m, f"radii in m below k_m = {self.k_m} m")
        if self.k_m + radius >= reach:
            raise ConfigError(
                "p_m", self.p_m,
                f"m with c_m + p_m > k_m + crank_radii_m[0] = {self.k_m + radius:.6g} m "
                "(pitman too short: the linkage cannot close at every crank angle)",
            )
        if self.k_m - radius <= abs(self.c_m - self.p_m):
            longer = "p_m" if self.p_m > self.c_m else "c_m"
            raise ConfigError(
                longer, getattr(self, longer),
                f"m with |c_m - p_m| < k_m - crank_radii_m[0] = {self.k_m - radius:.6g} m "
                "(the linkage cannot close at every crank angle)",
            )

    @property
    def h_m(self) -> float:
        """Height of the saddle-bearing centre above the crank-shaft centre."""
        return math.sqrt(self.k_m**2 - self.i_m**2)

    @classmethod
    def from_height(cls, *, h_m: float, i_m: float, **fields: Any) -> BeamUnitGeometry:
        """Build from H (saddle bearing above crank shaft) instead of K: K = sqrt(I² + H²)."""
        _require_positive("h_m", h_m, "m")
        _require_positive("i_m", i_m, "m")
        return cls(i_m=i_m, k_m=math.hypot(i_m, h_m), **fields)

    def scaled_linkage(self, factor: float) -> BeamUnitGeometry:
        """Same crank radii, beam and frame lengths A, C, I, K, P multiplied by ``factor`` (A/C kept)."""
        _require_positive("factor", factor, "- (dimensionless)")
        return dataclasses.replace(self, **{name: getattr(self, name) * factor for name in _LINK_FIELDS})


def _cross(u: tuple[FloatArray, FloatArray], v: tuple[FloatArray, FloatArray]) -> FloatArray:
    return u[0] * v[1] - u[1] * v[0]


def _solve_columns(
    m1: tuple[FloatArray, FloatArray], m2: tuple[FloatArray, FloatArray], b: tuple[FloatArray, FloatArray]
) -> tuple[FloatArray, FloatArray]:
    """Cramer's rule for x1·m1 + x2·m2 = b, element-wise over arrays of 2-vectors."""
    det = _cross(m1, m2)
    return _cross(b, m2) / det, _cross(m1, b) / det


def _wrap_pi(angle: FloatArray) -> FloatArray:
    return (angle + np.pi) % (2.0 * np.pi) - np.pi


def _as_output(values: FloatArray) -> FloatOrArray:
    return float(values) if values.ndim == 0 else values


TF_CACHE_SIZE = 8            # setpoints whose strokes' torque factors a unit keeps
TF_CACHE_MIN_SAMPLES = 64    # below this an array is a query, not a stroke: computed each time


class ConventionalUnit:
    """Kinematics and torque of a beam unit with the pin in crank hole ``crank_hole`` (0 = longest); the name
    is historical: ``geometry.kind`` selects Class I (conventional) or Class III (Mark II, air-balanced).

    All angle inputs are the crank angle θ of the module doc (rad), vectorised; scalars in, floats out.
    """

    def __init__(self, geometry: BeamUnitGeometry, crank_hole: int = 0) -> None:
        holes = len(geometry.crank_radii_m)
        is_index = isinstance(crank_hole, (int, np.integer)) and not isinstance(crank_hole, bool)
        if not is_index or not 0 <= crank_hole < holes:
            raise ConfigError("crank_hole", crank_hole, f"an integer in [0, {holes - 1}], 0 = longest stroke")
        self.geometry = geometry
        self.crank_hole = int(crank_hole)
        self.crank_radius_m = geometry.crank_radii_m[self.crank_hole]
        self._sign = ROTATION_SIGNS[geometry.rotation]
        self._tf_cache: dict[bytes, FloatArray] = {}  # torque_factor_m of a stroke's crank angles (see there)
        self._lever = LEVER_SIGNS[geometry.kind]
        self._saddle = (self._lever * geometry.i_m, geometry.h_m)
        # Class I: pitman and crank in line (extended) is the bottom; Class III: the top (E is highest)
        class_one = self._lever > 0
        psi_bottom, self._delta_bottom = self._dead_centre(extended=class_one)
        psi_top, delta_top = self._dead_centre(extended=not class_one)
        self._theta_bottom = float((self._sign * psi_bottom) % (2.0 * np.pi))
        self._theta_top = float((self._sign * psi_top) % (2.0 * np.pi))
        self._stroke_m = geometry.a_m * float(_wrap_pi(np.asarray(delta_top - self._delta_bottom)))

    def __repr__(self) -> str:
        return (f"ConventionalUnit({self.geometry.designation!r}, crank_hole={self.crank_hole}, "
                f"stroke_m={self.stroke_m:.4f})")

    # ------------------------------------------------------------------ linkage
    def _dead_centre(self, extended: bool, radius_m: float | None = None) -> tuple[float, float]:
        """(ψ, beam angle δ) where pin, crank centre and pitman are collinear: the ends of the stroke.

        Extended (pitman and crank in line, E farthest from O) pushes E up: the bottom of the stroke on a
        Class I unit (E behind the saddle), the top on a Class III unit (E on the horsehead's side). Folded is
        the other end. Solved in closed form on the triangle O-G-E (on crank radius ``radius_m``, default own).
        """
        g = self.geometry
        r = self.crank_radius_m if radius_m is None else radius_m
        reach = g.p_m + r if extended else g.p_m - r
        cos_gamma = (g.c_m**2 + g.k_m**2 - reach**2) / (2.0 * g.c_m * g.k_m)
        # E above the line G-O: clockwise of G→O on a Class I unit, counterclockwise on a Class III one
        delta = math.atan2(-self._saddle[1], -self._saddle[0]) - self._lever * math.acos(cos_gamma)
        ex = self._saddle[0] + g.c_m * math.cos(delta)
        ey = self._saddle[1] + g.c_m * math.sin(delta)
        direction = 1.0 if extended else -1.0
        return math.atan2(direction * ex, direction * ey), delta

    def _angles(self, psi: FloatArray) -> tuple[FloatArray, FloatArray]:
        """Back-arm angle δ (direction G→E from +x) and pitman angle ε (direction pin→E)."""
        return self._linkage(psi)[:2]

    def _linkage(self, psi: FloatArray) -> tuple[FloatArray, ...]:
        """(δ, ε, sin ψ, cos ψ, cos δ, sin δ), each computed once: the rates reuse them (the same bits)."""
        g = self.geometry
        sin_psi, cos_psi = np.sin(psi), np.cos(psi)
        qx = self.crank_radius_m * sin_psi
        qy = self.crank_radius_m * cos_psi
        vx, vy = qx - self._saddle[0], qy - self._saddle[1]
        dist = np.hypot(vx, vy)
        cos_gamma = (g.c_m**2 + dist**2 - g.p_m**2) / (2.0 * g.c_m * dist)
        # the assembled branch: E above the pin (the pitman hangs down), i.e. clockwise from G→pin on a
        # Class I unit, counterclockwise on a Class III one
        delta = np.arctan2(vy, vx) - self._lever * np.arccos(np.clip(cos_gamma, -1.0, 1.0))
        cos_delta, sin_delta = np.cos(delta), np.sin(delta)
        ex = self._saddle[0] + g.c_m * cos_delta
        ey = self._saddle[1] + g.c_m * sin_delta
        return delta, np.arctan2(ey - qy, ex - qx), sin_psi, cos_psi, cos_delta, sin_delta

    def _beam_rates(self, psi: FloatArray, second: bool = True) -> tuple[FloatArray, FloatArray, FloatArray | None]:
        """δ(ψ), dδ/dψ, d²δ/dψ² (None if not ``second``) from the loop G + C·u(δ) = pin(ψ) + P·u(ε)."""
        g = self.geometry
        delta, eps, sin_psi, cos_psi, cos_delta, sin_delta = self._linkage(psi)
        cos_eps, sin_eps = np.cos(eps), np.sin(eps)
        m1 = (g.c_m * -sin_delta, g.c_m * cos_delta)   # C·n(δ), n = (-sin, cos)
        m2 = (-g.p_m * -sin_eps, -g.p_m * cos_eps)     # -P·n(ε)
        r = self.crank_radius_m
        d1, e1 = _solve_columns(m1, m2, (r * cos_psi, -r * sin_psi))
        if not second:
            return delta, d1, None
        ud, ue = (cos_delta, sin_delta), (cos_eps, sin_eps)
        rhs2 = tuple(
            -r * trig + g.c_m * d1**2 * ud[j] - g.p_m * e1**2 * ue[j]
            for j, trig in enumerate((sin_psi, cos_psi))
        )
        d2, _ = _solve_columns(m1, m2, rhs2)
        return delta, d1, d2

    def _psi(self, theta: npt.ArrayLike) -> FloatArray:
        return self._sign * np.asarray(theta, dtype=float)

    # ------------------------------------------------------------------ public kinematics
    @property
    def stroke_m(self) -> float:
        """Polished-rod stroke for this crank hole, from the linkage's dead-centre positions."""
        return self._stroke_m

    @property
    def theta_bottom(self) -> float:
        """Crank angle (rad, in [0, 2π)) of the bottom of the stroke."""
        return self._theta_bottom

    @property
    def theta_top(self) -> float:
        """Crank angle (rad, in [0, 2π)) of the top of the stroke."""
        return self._theta_top

    def position_m(self, theta: npt.ArrayLike) -> FloatOrArray:
        """Polished-rod position measured upward from the bottom of the stroke, in [0, stroke_m]."""
        delta, _ = self._angles(self._psi(theta))
        return _as_output(self.geometry.a_m * _wrap_pi(delta - self._delta_bottom))

    def torque_factor_m(self, theta: npt.ArrayLike) -> FloatOrArray:
        """API torque factor TF = d(position)/dθ (m/rad, exact); also the velocity factor v = TF·ω. A stroke's
        crank angles recur stroke after stroke at one setpoint: their factors are kept (bit-identical)."""
        arr = np.asarray(theta, dtype=float)
        key = arr.tobytes() if arr.ndim == 1 and arr.size >= TF_CACHE_MIN_SAMPLES else None
        tf = self._tf_cache.get(key) if key is not None else None
        if tf is None:
            tf = self.geometry.a_m * self._sign * self._beam_rates(self._psi(arr), second=False)[1]
            if key is None:
                return _as_output(tf)
            if len(self._tf_cache) >= TF_CACHE_SIZE:  # units are shared (lru-cached) across threads: no iterating
                self._tf_cache.clear()
            self._tf_cache[key] = tf
        return tf.copy()

    velocity_factor_m = torque_factor_m

    def kinematics(
        self, theta: npt.ArrayLike, omega_rad_s: float
    ) -> tuple[FloatOrArray, FloatOrArray, FloatOrArray]:
        """(position m, velocity m/s, acceleration m/s²) upward, at constant crank speed ω = dθ/dt."""
        delta, d1, d2 = self._beam_rates(self._psi(theta))
        a = self.geometry.a_m
        position = a * _wrap_pi(delta - self._delta_bottom)
        # dψ/dt = sign·ω, so the sign cancels in the second derivative
        velocity = a * d1 * self._sign * omega_rad_s
        acceleration = a * d2 * omega_rad_s**2
        return _as_output(position), _as_output(velocity), _as_output(acceleration)

    def crank_angle_rad(self, t_s: npt.ArrayLike, spm: float) -> FloatOrArray:
        """θ(t) for constant SPM, starting at the bottom of the stroke at t = 0 (not wrapped)."""
        return _as_output(self.theta_bottom + 2.0 * np.pi * spm / 60.0 * np.asarray(t_s, dtype=float))

    def upstroke_fraction(self) -> float:
        """Fraction of a crank revolution spent moving the polished rod up."""
        return float(((self._theta_top - self._theta_bottom) % (2.0 * np.pi)) / (2.0 * np.pi))

    # ------------------------------------------------------------------ loads and torque
    def net_torque_nm(
        self,
        theta: npt.ArrayLike,
        polished_rod_load_n: npt.ArrayLike,
        counterbalance_moment_nm: float,
        crank_offset_rad: float = 0.0,
        counterbalance_force_n: float = 0.0,
    ) -> FloatOrArray:
        """API net gearbox torque T = TF·(PRL - SU - B) - M·sin(θ + τ + φ) (N·m; sign convention in module doc).

        ``counterbalance_moment_nm`` M is the maximum moment of the crank counterweights (and crank arms)
        about the crank shaft; ``crank_offset_rad`` τ is the lead of the counterweight arm, in the direction of
        rotation, over its unphased position: the pin on a Class I unit, the side opposite the pin on a Class
        III unit (φ = 0 and π). ``counterbalance_force_n`` B is an air-balanced unit's cylinder force referred
        to the polished rod (it acts through the same lever as the rods' load).
        """
        theta_arr = np.asarray(theta, dtype=float)
        well = np.asarray(self.torque_factor_m(theta_arr)) * (
            np.asarray(polished_rod_load_n, dtype=float) - self.geometry.structural_unbalance_n
            - counterbalance_force_n)
        crank = counterbalance_moment_nm * self._crank_arm(theta_arr, crank_offset_rad)
        return _as_output(well - crank)

    @property
    def air_balanced(self) -> bool:
        """An air cylinder, not crank weights, balances this unit (its counterbalance is a force B)."""
        return self.geometry.kind == "air_balanced"

    def counterbalance_arm(self, theta: npt.ArrayLike, crank_offset_rad: float = 0.0) -> FloatArray:
        """dT/d(counterbalance) with the sign flipped: sin(θ + τ + φ) per N·m of crank moment, or TF(θ) per
        N of an air cylinder's force at the polished rod; T = (well's torque) - counterbalance · arm."""
        theta_arr = np.asarray(theta, dtype=float)
        if self.air_balanced:
            return np.asarray(self.torque_factor_m(theta_arr), dtype=float)
        return self._crank_arm(theta_arr, crank_offset_rad)

    def _crank_arm(self, theta: FloatArray, crank_offset_rad: float) -> FloatArray:
        # Class III counterweights sit opposite the pin: they fall while the pin rises (the upstroke)
        phase = 0.0 if self._lever > 0 else math.pi
        return np.sin(theta + crank_offset_rad + phase)

    def polished_rod_power_w(
        self, theta: npt.ArrayLike, omega_rad_s: float, polished_rod_load_n: npt.ArrayLike
    ) -> FloatOrArray:
        """Power delivered to the rod string at the polished rod, PRL·v (v upward), W."""
        _, velocity, _ = self.kinematics(theta, omega_rad_s)
        return _as_output(np.asarray(velocity) * np.asarray(polished_rod_load_n, dtype=float))

    # ------------------------------------------------------------------ harmonic reference
    def harmonic_position_m(self, theta: npt.ArrayLike) -> FloatOrArray:
        """The harmonic motion with the same stroke and bottom: (S/2)(1 - cos(θ - θ_bottom))."""
        phase = np.asarray(theta, dtype=float) - self.theta_bottom
        return _as_output(0.5 * self.stroke_m * (1.0 - np.cos(phase)))


def harmonic_deviation(unit: ConventionalUnit, n_angles: int = 720) -> float:
    """max |position - harmonic| / stroke over a crank turn: tends to 0 as P, K, C ≫ R (A/C fixed)."""
    theta = unit.theta_bottom + np.linspace(0.0, 2.0 * np.pi, n_angles, endpoint=False)
    gap = np.asarray(unit.position_m(theta)) - np.asarray(unit.harmonic_position_m(theta))
    return float(np.max(np.abs(gap)) / unit.stroke_m)
