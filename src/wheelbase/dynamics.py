"""Rigid-body dynamics of a wheeled robot with a centre-of-gravity offset (document 000 §3.3).

Model
-----
Body frame B at the centroid (x forward, y left), moving with the body twist V = (u, v, r):
forward and lateral speed [m/s] and yaw rate [rad/s]. The centre of gravity C lies at
(x_bc, y_bc) in B; ``inertia`` is I_z about C. The Lagrange–Euler equations in the body frame
are (document 000 §3.3, re-derived here)::

    M·V̇ + C(V)·V = τ,   τ = (F_x, F_y, M_z)  (body-frame force at B [N] and moment about B [N·m])

        ⎡ m        0        −m·y_bc              ⎤
    M = ⎢ 0        m         m·x_bc              ⎥
        ⎣ −m·y_bc  m·x_bc    I_z + m(x_bc²+y_bc²) ⎦

           ⎡ 0                0               −m(v + x_bc·r) ⎤
    C(V) = ⎢ 0                0                m(u − y_bc·r) ⎥   (skew-symmetric)
           ⎣ m(v + x_bc·r)   −m(u − y_bc·r)    0             ⎦

    C(V)·V = ( −m·r(v + x_bc·r),  m·r(u − y_bc·r),  m·r(x_bc·u + y_bc·v) ).

Derivation. The velocity of C in B is (u − y_bc·r, v + x_bc·r), so the kinetic energy is
T = ½m[(u − y_bc r)² + (v + x_bc r)²] + ½I_z r² = ½Vᵀ M V. Body velocities are
quasi-velocities, so the plain Lagrange equation d/dt(∂T/∂V) = τ does not hold; the
Boltzmann–Hamel (Kirchhoff) form for a body rotating at r is, with p = ∂T/∂V = M·V,

    ṗ_u − r·p_v = F_x,   ṗ_v + r·p_u = F_y,   ṗ_r + u·p_v − v·p_u = M_z,

which gives the C(V)·V above. ``tests/test_dynamics.py`` checks it against a symbolic (sympy)
Euler–Lagrange derivation in world coordinates and checks energy conservation.

Typos of the printed derivation (document 000 §3.3), corrected here:

- "y_c = v + x_bc r" is ẏ_c (a velocity); the bracket of the Lagrangian wrongly encloses ½I_z r²
  inside ½m[…]; ``I_cx`` in the matrices is I_z.
- F_x = d/dt(∂L/∂u) etc. omit the rotating-frame terms (−r·p_v, +r·p_u, u·p_v − v·p_u), and
  the terms in ẋ_bc, ẏ_bc are zero (the CG is fixed in B); the printed M_z line
  (m v̇ ẏ_bc, 2mr[2x_bc ẋ_bc …]) is garbled.
- First row of the first vector form: −m·x_bc·r² − m·y_bc·r² should be −m·x_bc·r² alone (and
  the coupling −m·y_bc·ṙ of M is missing); second row: m·ur − m·y_bc r² + m·x_bc r² should be
  m·ur − m·y_bc r² (the coupling m·x_bc·ṙ is missing).
- Second vector form: the second row m·r(u + y_bc·r) should be m·r(u − y_bc·r).
- Matrix form r·[[0, −m, m x_bc], [m, 0, m y_bc], [m x_bc, m y_bc, 0]]·V: its first row gives
  −m·r·v + m·x_bc·r² (sign of the r² term wrong) and its second row +m·y_bc·r² (also wrong); the
  matrix is not skew-symmetric, so it would create or destroy kinetic energy with τ = 0. The
  correct C(V) above is skew-symmetric (Vᵀ C V = 0).

Differential drive
------------------
Two wheels of radius a on the axle through B at (0, ±d) (document 000 §3.1 puts the wheel
centres on the y axis of B: dx_i = 0). Wheel torques (τ_L, τ_R) push with τ/a at the contact
points, so F_x = (τ_L + τ_R)/a and M_z = d(τ_R − τ_L)/a, i.e. τ_body = (Wᵀ)⁺·τ_wheels with
document 000's W; conversely τ_wheels = Wᵀ·τ_body (document 000's τ* = J†ᵀ τ; the lateral
component F_y is carried by the ground and needs no torque). By default the no-lateral-slip
constraint v = 0 is enforced: the lateral ground force F_y acts on the axle line (no moment about
B) and the reduced dynamics in (u, r) are

    m·u̇ − m·y_bc·ṙ − m·x_bc·r² = F_x,    −m·y_bc·u̇ + I_B·ṙ + m·x_bc·r·u = M_z,
    F_y = m·x_bc·ṙ + m·r(u − y_bc·r)        (the constraint force, reported),

with I_B = I_z + m(x_bc² + y_bc²). ``constrained=False`` gives the unconstrained 3-DOF model of
document 000 with F_y = 0 (the robot skids sideways when it turns).

State vector of the simulations: (x, y, ψ, u, v, r) — world position [m], heading [rad], body
twist [m/s, m/s, rad/s].
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numba
import numpy as np
from numpy.typing import ArrayLike
from scipy.integrate import solve_ivp

from wheelbase._validate import as_float_array, check_choice, nonnegative, positive
from wheelbase.errors import ConfigError, InputError
from wheelbase.geometry import to_world_frame, wrap_angle
from wheelbase.geometry_numba import wrap_angle_scalar
from wheelbase.integrate import time_grid

__all__ = [
    "DYNAMICS_METHODS",
    "GRAVITY",
    "RM100",
    "RM100_HALF_TRACK",
    "DiffDriveDynamics",
    "DynamicsResult",
    "InverseDynamicsResult",
    "RigidBody",
    "inverse_dynamics",
    "simulate_dynamics",
]

GRAVITY = 9.80665
"""Standard gravity [m/s²] (for the rolling resistance)."""

DYNAMICS_METHODS: tuple[str, ...] = ("RK45", "DOP853", "Radau", "LSODA", "euler", "rk4")
"""Integrators of :func:`simulate_dynamics`: scipy's adaptive ``solve_ivp`` methods and the
fixed-step ``euler`` and ``rk4`` (compiled, batched)."""

_FIXED = ("euler", "rk4")
MAX_EVALUATIONS = 1_000_000
"""Most right-hand-side evaluations one adaptive ``solve_ivp`` run may take (about 15 s): with
huge torques the step size collapses, and 1e7 N·m for 2 s took 3 million evaluations."""


class _TooMuchWork(Exception):
    """Raised by a counted right-hand side past :data:`MAX_EVALUATIONS` (private)."""


def _counted(rhs):
    """``rhs`` that raises _TooMuchWork after MAX_EVALUATIONS calls."""
    calls = [0]

    def counted(t, y):
        calls[0] += 1
        if calls[0] > MAX_EVALUATIONS:
            raise _TooMuchWork
        return rhs(t, y)

    return counted


def _solve(rhs, span, state, method, **options):
    """solve_ivp with a bounded amount of work, or an InputError that says what to do."""
    try:
        return solve_ivp(_counted(rhs), span, state, method=method, **options)
    except _TooMuchWork:
        raise InputError(
            f"{method} took more than {MAX_EVALUATIONS} evaluations for t = {span[0]:g}.."
            f"{span[1]:g} s: the torques drive the robot so hard that the adaptive step "
            "collapses; use smaller torques or a fixed-step method (euler, rk4)"
        ) from None


RM100_HALF_TRACK = 0.455 / 2
"""Half track d of the RM100 preset [m]: half the breadth b = 0.455 m of document 000 ch. 4.

Document 000 gives no track width. The RM100's drive wheels sit at the sides of its body
(figures 4.1–4.4, the casters at the corners), so the wheel centres are put at the body's
half-width: d = b/2. This is an upper bound — the true track is a few centimetres less (wheel
width, clearance) — and only scales the yaw moment M_z = d(τ_R − τ_L)/a and the wheel torques of
a turn (τ ∝ 1/d)."""


# --------------------------------------------------------------------------- rigid body
@dataclass(frozen=True)
class RigidBody:
    """A planar rigid body: mass, inertia about its CG, and the CG offset from the centroid.

    Parameters
    ----------
    mass : float
        Mass m [kg], > 0.
    inertia : float
        Yaw moment of inertia [kg·m²] about the CG (document 000's I_z), > 0; or about the
        centroid B when ``inertia_about="centroid"``.
    cg_offset : tuple of float
        (x_bc, y_bc): position of the CG in the body frame at B [m].
    inertia_about : {"cg", "centroid"}
        Where ``inertia`` is taken. About the centroid it must exceed m(x_bc² + y_bc²)
        (parallel-axis theorem), else ConfigError.

    Examples
    --------
    >>> body = RigidBody(mass=26.2, inertia=1.14, cg_offset=(0.01, 0.0))
    >>> body.mass_matrix().round(3)[2]
    array([-0.   ,  0.262,  1.143])
    """

    mass: float
    inertia: float
    cg_offset: tuple[float, float] = (0.0, 0.0)
    inertia_about: str = "cg"

    def __post_init__(self) -> None:
        mass = positive("mass", self.mass, "kg")
        inertia = positive("inertia", self.inertia, "kg·m²")
        check_choice("inertia_about", self.inertia_about, ("cg", "centroid"))
        offset = as_float_array("cg_offset", self.cg_offset, 2, max_ndim=1)
        xb, yb = float(offset[0]), float(offset[1])
        if self.inertia_about == "centroid":
            shift = mass * (xb * xb + yb * yb)
            if inertia <= shift:
                raise ConfigError(
                    f"inertia about the centroid ({inertia:g} kg·m²) is too small for the CG "
                    f"offset: it must be > m·(x_bc² + y_bc²) = {shift:g} kg·m²"
                )
            inertia -= shift
        object.__setattr__(self, "mass", mass)
        object.__setattr__(self, "inertia", inertia)
        object.__setattr__(self, "cg_offset", (xb, yb))
        object.__setattr__(self, "inertia_about", "cg")

    @property
    def inertia_centroid(self) -> float:
        """Yaw inertia about the centroid B, I_z + m(x_bc² + y_bc²) [kg·m²]."""
        xb, yb = self.cg_offset
        return self.inertia + self.mass * (xb * xb + yb * yb)

    def mass_matrix(self) -> np.ndarray:
        """The 3×3 inertia matrix M of M·V̇ + C(V)·V = τ (document 000 §3.3)."""
        m, (xb, yb) = self.mass, self.cg_offset
        return np.array(
            [[m, 0.0, -m * yb], [0.0, m, m * xb], [-m * yb, m * xb, self.inertia_centroid]]
        )

    def coriolis(self, velocity: ArrayLike) -> np.ndarray:
        """The skew-symmetric Coriolis/centripetal matrix C(V), shape ``(..., 3, 3)``.

        Parameters
        ----------
        velocity : array_like, shape (..., 3)
            Body twist V = (u [m/s], v [m/s], r [rad/s]).
        """
        vel = as_float_array("velocity", velocity, 3)
        m, (xb, yb) = self.mass, self.cg_offset
        u, v, r = vel[..., 0], vel[..., 1], vel[..., 2]
        p = m * (v + xb * r)  # m × lateral velocity of the CG
        q = m * (u - yb * r)  # m × forward velocity of the CG
        out = np.zeros((*vel.shape[:-1], 3, 3))
        out[..., 0, 2], out[..., 2, 0] = -p, p
        out[..., 1, 2], out[..., 2, 1] = q, -q
        return out

    def kinetic_energy(self, velocity: ArrayLike) -> np.ndarray:
        """Kinetic energy T = ½·Vᵀ·M·V [J] of body twists ``(..., 3)``.

        Parameters
        ----------
        velocity : array_like, shape (..., 3)
            Body twist (u [m/s], v [m/s], r [rad/s]).
        """
        vel = as_float_array("velocity", velocity, 3)
        return 0.5 * np.einsum("...i,ij,...j->...", vel, self.mass_matrix(), vel)

    def forward(self, velocity: ArrayLike, force: ArrayLike) -> np.ndarray:
        """Body acceleration V̇ = M⁻¹(τ − C(V)·V) of the unconstrained model, shape ``(..., 3)``.

        Parameters
        ----------
        velocity : array_like, shape (..., 3)
            Body twist (u [m/s], v [m/s], r [rad/s]).
        force : array_like, shape (..., 3)
            Body-frame force at B and moment about B, (F_x [N], F_y [N], M_z [N·m]).
        """
        vel = as_float_array("velocity", velocity, 3)
        tau = as_float_array("force", force, 3)
        cv = np.einsum("...ij,...j->...i", self.coriolis(vel), vel)
        return np.linalg.solve(self.mass_matrix(), (tau - cv)[..., None])[..., 0]

    def inverse(self, velocity: ArrayLike, acceleration: ArrayLike) -> np.ndarray:
        """Body force τ = M·V̇ + C(V)·V ``(..., 3)`` = (F_x [N], F_y [N], M_z [N·m]).

        Parameters
        ----------
        velocity : array_like, shape (..., 3)
            Body twist (u [m/s], v [m/s], r [rad/s]).
        acceleration : array_like, shape (..., 3)
            Its time derivative V̇ (u̇ [m/s²], v̇ [m/s²], ṙ [rad/s²]).
        """
        vel = as_float_array("velocity", velocity, 3)
        acc = as_float_array("acceleration", acceleration, 3)
        cv = np.einsum("...ij,...j->...i", self.coriolis(vel), vel)
        return acc @ self.mass_matrix().T + cv

    def scaled(self, mass_factor: float = 1.0, inertia_factor: float = 1.0) -> RigidBody:
        """The same body with mass and inertia multiplied (for model-error studies).

        Parameters
        ----------
        mass_factor : float
            Factor on the mass, > 0.
        inertia_factor : float
            Factor on the inertia about the CG, > 0.
        """
        return RigidBody(
            self.mass * positive("mass_factor", mass_factor),
            self.inertia * positive("inertia_factor", inertia_factor),
            self.cg_offset,
        )


# --------------------------------------------------------------------------- compiled core
@numba.njit(cache=True)
def _accel(u, v, r, tau_l, tau_r, p):
    """(u̇, v̇, ṙ, F_y) for one robot; ``p`` is the parameter vector of ``_params``."""
    m, xb, yb, ib, a, d = p[0], p[1], p[2], p[3], p[4], p[5]
    bu, br, frr, constrained = p[6], p[7], p[8], p[9]
    fx = (tau_l + tau_r) / a - bu * u - frr * math.tanh(u / 1e-3)
    mz = d * (tau_r - tau_l) / a - br * r
    if constrained > 0.5:
        # reduced dynamics in (u, r), v = 0:  [[m, -m yb], [-m yb, ib]] (u̇, ṙ) = rhs
        b1 = fx + m * xb * r * r
        b2 = mz - m * xb * r * u
        det = m * ib - m * m * yb * yb
        du = (ib * b1 + m * yb * b2) / det
        dr = (m * yb * b1 + m * b2) / det
        fy = m * xb * dr + m * r * (u - yb * r)
        return du, 0.0, dr, fy
    # unconstrained 3-DOF: M V̇ = τ − C(V)V with F_y = 0 (lateral damping bu as well)
    b1 = fx + m * r * (v + xb * r)
    b2 = -bu * v - m * r * (u - yb * r)
    b3 = mz - m * r * (xb * u + yb * v)
    # solve M x = b with M symmetric [[m,0,-m yb],[0,m,m xb],[-m yb, m xb, ib]] (Schur on r)
    s = ib - m * (xb * xb + yb * yb)  # = I_z > 0
    dr = (b3 + yb * b1 - xb * b2) / s
    du = (b1 + m * yb * dr) / m
    dv = (b2 - m * xb * dr) / m
    return du, dv, dr, 0.0


@numba.njit(cache=True)
def _deriv(s, tau_l, tau_r, p, out):
    c, sn = math.cos(s[2]), math.sin(s[2])
    du, dv, dr, fy = _accel(s[3], s[4], s[5], tau_l, tau_r, p)
    out[0] = c * s[3] - sn * s[4]
    out[1] = sn * s[3] + c * s[4]
    out[2] = s[5]
    out[3], out[4], out[5] = du, dv, dr
    return fy


@numba.njit(cache=True)
def _step(s, tau_l, tau_r, p, h, method, k1, k2, k3, k4, tmp):
    """Advance one state ``s`` (6,) in place by h; returns F_y at the start of the step."""
    fy = _deriv(s, tau_l, tau_r, p, k1)
    if method == 0:  # euler
        for j in range(6):
            s[j] += h * k1[j]
        return fy
    for j in range(6):
        tmp[j] = s[j] + 0.5 * h * k1[j]
    _deriv(tmp, tau_l, tau_r, p, k2)
    for j in range(6):
        tmp[j] = s[j] + 0.5 * h * k2[j]
    _deriv(tmp, tau_l, tau_r, p, k3)
    for j in range(6):
        tmp[j] = s[j] + h * k3[j]
    _deriv(tmp, tau_l, tau_r, p, k4)
    for j in range(6):
        s[j] += h / 6.0 * (k1[j] + 2.0 * k2[j] + 2.0 * k3[j] + k4[j])
    return fy


@numba.njit(cache=True)
def _step_many(states, torques, p, h):
    """RK4-advance every state row (N, 6) in place by h under its torques (N, 2); wrap ψ."""
    k1, k2, k3, k4, tmp = np.empty(6), np.empty(6), np.empty(6), np.empty(6), np.empty(6)
    for i in range(states.shape[0]):
        s = states[i]
        _step(s, torques[i, 0], torques[i, 1], p, h, 1, k1, k2, k3, k4, tmp)
        s[2] = wrap_angle_scalar(s[2])


@numba.njit(cache=True, parallel=True)
def _roll(states, torques, times, p, method, out, fy_out):
    """Integrate N robots (N, 6) under torques (S, N, 2) (zero-order hold), recording all steps."""
    n = states.shape[0]
    n_steps = times.shape[0] - 1
    for i in numba.prange(n):
        s = states[i].copy()
        k1, k2, k3, k4, tmp = np.empty(6), np.empty(6), np.empty(6), np.empty(6), np.empty(6)
        for j in range(6):
            out[0, i, j] = s[j]
        for k in range(n_steps):
            row = k if torques.shape[0] > 1 else 0
            fy = _step(
                s, torques[row, i, 0], torques[row, i, 1], p, times[k + 1] - times[k],
                method, k1, k2, k3, k4, tmp,
            )  # fmt: skip
            fy_out[k, i] = fy
            s[2] = wrap_angle_scalar(s[2])
            for j in range(6):
                out[k + 1, i, j] = s[j]
        last = n_steps - 1 if torques.shape[0] > 1 else 0
        tl, tr = torques[last, i, 0], torques[last, i, 1]
        fy_out[n_steps, i] = _accel(s[3], s[4], s[5], tl, tr, p)[3]


@numba.njit(cache=True, parallel=True)
def _roll_final(states, tau, h, n_steps, p, method):
    """Benchmark kernel: N robots under constant torques (N, 2), final states only, in place."""
    for i in numba.prange(states.shape[0]):
        s = states[i]
        k1, k2, k3, k4, tmp = np.empty(6), np.empty(6), np.empty(6), np.empty(6), np.empty(6)
        for _ in range(n_steps):
            _step(s, tau[i, 0], tau[i, 1], p, h, method, k1, k2, k3, k4, tmp)


# --------------------------------------------------------------------------- differential drive
@dataclass(frozen=True)
class DiffDriveDynamics:
    """Dynamics of a differential-drive robot driven by wheel torques (left, right).

    Parameters
    ----------
    body : RigidBody
        Mass, inertia about the CG and CG offset.
    wheel_radius : float
        Wheel radius a [m], > 0.
    half_track : float
        Distance d from B to each wheel along the axle [m], > 0.
    constrained : bool
        Enforce no lateral slip (v = 0, reduced dynamics in (u, r), constraint force F_y
        reported); ``False`` gives document 000's unconstrained 3-DOF model with F_y = 0.
    linear_damping : float
        Viscous resistance b_u on the forward (and, unconstrained, lateral) speed [N·s/m], ≥ 0.
    angular_damping : float
        Viscous resistance b_r on the yaw rate [N·m·s/rad], ≥ 0.
    rolling_resistance : float
        Rolling-resistance coefficient c_rr (dimensionless, ≥ 0): a force c_rr·m·g opposing the
        forward motion (smoothed as tanh(u/1 mm/s)). All resistances default to 0, as in
        document 000.

    Examples
    --------
    >>> RM100.body_force([0.01, 0.01]).round(4)
    array([0.3077, 0.    , 0.    ])
    """

    body: RigidBody
    wheel_radius: float
    half_track: float
    constrained: bool = True
    linear_damping: float = 0.0
    angular_damping: float = 0.0
    rolling_resistance: float = 0.0
    _params: np.ndarray = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        if not isinstance(self.body, RigidBody):
            raise ConfigError(f"body must be a RigidBody (got {type(self.body).__name__})")
        object.__setattr__(self, "wheel_radius", positive("wheel_radius", self.wheel_radius, "m"))
        object.__setattr__(self, "half_track", positive("half_track", self.half_track, "m"))
        for name, unit in (
            ("linear_damping", "N·s/m"),
            ("angular_damping", "N·m·s/rad"),
            ("rolling_resistance", ""),
        ):
            object.__setattr__(self, name, nonnegative(name, getattr(self, name), unit))
        object.__setattr__(self, "constrained", bool(self.constrained))
        b = self.body
        params = np.array(
            [
                b.mass,
                b.cg_offset[0],
                b.cg_offset[1],
                b.inertia_centroid,
                self.wheel_radius,
                self.half_track,
                self.linear_damping,
                self.angular_damping,
                self.rolling_resistance * b.mass * GRAVITY,
                1.0 if self.constrained else 0.0,
            ]
        )
        object.__setattr__(self, "_params", params)

    @property
    def params(self) -> np.ndarray:
        """Parameter vector of the compiled kernels (a copy)."""
        return self._params.copy()

    @property
    def wheel_matrix(self) -> np.ndarray:
        """Document 000's W (3×2): body twist (u, v, r) = W·(ω_L, ω_R)."""
        a, d = self.wheel_radius, self.half_track
        return np.array([[a / 2, a / 2], [0.0, 0.0], [-a / (2 * d), a / (2 * d)]])

    def with_body(self, body: RigidBody) -> DiffDriveDynamics:
        """The same robot with another rigid body (e.g. a model with mass errors).

        Parameters
        ----------
        body : RigidBody
            The new body.
        """
        return DiffDriveDynamics(
            body,
            self.wheel_radius,
            self.half_track,
            self.constrained,
            self.linear_damping,
            self.angular_damping,
            self.rolling_resistance,
        )

    def body_force(self, torques: ArrayLike) -> np.ndarray:
        """Body force (F_x [N], 0, M_z [N·m]) ``(..., 3)`` of wheel torques (τ_L, τ_R) [N·m].

        F_x = (τ_L + τ_R)/a and M_z = d(τ_R − τ_L)/a, i.e. (Wᵀ)⁺·τ.

        Parameters
        ----------
        torques : array_like, shape (..., 2)
            Wheel torques (left, right) [N·m].
        """
        tau = as_float_array("torques", torques, 2)
        a, d = self.wheel_radius, self.half_track
        fx = (tau[..., 0] + tau[..., 1]) / a
        mz = d * (tau[..., 1] - tau[..., 0]) / a
        return np.stack([fx, np.zeros_like(fx), mz], -1)

    def wheel_torques(self, force: ArrayLike) -> np.ndarray:
        """Wheel torques (τ_L, τ_R) [N·m] = Wᵀ·τ that produce F_x and M_z (F_y is dropped).

        This is document 000's τ* = J†ᵀ·τ: the lateral force needs no torque (the ground
        carries it), so it is projected out.

        Parameters
        ----------
        force : array_like, shape (..., 3)
            Body force (F_x [N], F_y [N], M_z [N·m]).
        """
        tau = as_float_array("force", force, 3)
        return tau @ self.wheel_matrix

    def acceleration(self, velocity: ArrayLike, torques: ArrayLike) -> tuple[np.ndarray, Any]:
        """Body acceleration V̇ ``(..., 3)`` and lateral constraint force F_y ``(...)`` [N].

        Parameters
        ----------
        velocity : array_like, shape (..., 3)
            Body twist (u [m/s], v [m/s], r [rad/s]); with ``constrained`` v must be 0.
        torques : array_like, shape (..., 2)
            Wheel torques (left, right) [N·m].
        """
        vel = as_float_array("velocity", velocity, 3)
        tau = as_float_array("torques", torques, 2)
        shape = np.broadcast_shapes(vel.shape[:-1], tau.shape[:-1])
        vel = np.broadcast_to(vel, (*shape, 3))
        tau = np.broadcast_to(tau, (*shape, 2))
        return _accel_numpy(vel, tau, self._params)

    def derivative(self, state: ArrayLike, torques: ArrayLike) -> np.ndarray:
        """State rate ``(..., 6)`` of states (x, y, ψ, u, v, r) under wheel torques.

        Parameters
        ----------
        state : array_like, shape (..., 6)
            (x [m], y [m], ψ [rad], u [m/s], v [m/s], r [rad/s]).
        torques : array_like, shape (..., 2)
            Wheel torques (left, right) [N·m].
        """
        s = as_float_array("state", state, 6)
        acc, _ = self.acceleration(s[..., 3:], torques)
        rate = to_world_frame(s[..., 2], s[..., 3:])
        rate, acc = np.broadcast_arrays(rate, acc)
        return np.concatenate([rate, acc], -1)

    def step(self, state: ArrayLike, torques: ArrayLike, h: float) -> np.ndarray:
        """One RK4 step of length ``h`` [s] from states ``(..., 6)`` under torques held constant.

        The compiled step of :func:`simulate_dynamics`, for closed loops that step the plant
        themselves (:class:`wheelbase.sim.DynamicPlant`); the heading is wrapped to (−π, π].

        Parameters
        ----------
        state : array_like, shape (..., 6)
            (x [m], y [m], ψ [rad], u [m/s], v [m/s], r [rad/s]), one robot or a batch.
        torques : array_like, shape (..., 2)
            Wheel torques (left, right) [N·m], one row per robot.
        h : float
            Step [s], > 0.
        """
        s = np.array(as_float_array("state", state, 6), dtype=np.float64)
        tau = np.broadcast_to(as_float_array("torques", torques, 2), (*s.shape[:-1], 2))
        flat = np.ascontiguousarray(s.reshape(-1, 6))
        _step_many(flat, np.ascontiguousarray(tau.reshape(-1, 2)), self._params,
                   positive("h", h, "s"))  # fmt: skip
        return flat.reshape(s.shape)

    def inverse(self, velocity: ArrayLike, acceleration: ArrayLike) -> tuple[np.ndarray, Any]:
        """Inverse dynamics: body force (F_x, F_y, M_z) and wheel torques (τ_L, τ_R).

        τ = M·V̇ + C(V)·V plus the resistances; the wheel torques are Wᵀ·τ (document 000 §5.2
        and τ* = J†ᵀ τ). With no lateral slip, F_y is the lateral force the ground must supply.

        Parameters
        ----------
        velocity : array_like, shape (..., 3)
            Body twist (u [m/s], v [m/s], r [rad/s]).
        acceleration : array_like, shape (..., 3)
            Its derivative (u̇ [m/s²], v̇ [m/s²], ṙ [rad/s²]).

        Returns
        -------
        force : numpy.ndarray, shape (..., 3)
            (F_x [N], F_y [N], M_z [N·m]).
        torques : numpy.ndarray, shape (..., 2)
            (τ_L, τ_R) [N·m].
        """
        vel = as_float_array("velocity", velocity, 3)
        force = self.body.inverse(vel, acceleration)
        p = self._params
        resist = np.zeros_like(force)
        resist[..., 0] = p[6] * vel[..., 0] + p[8] * np.tanh(vel[..., 0] / 1e-3)
        resist[..., 1] = p[6] * vel[..., 1]
        resist[..., 2] = p[7] * vel[..., 2]
        force = force + resist
        return force, self.wheel_torques(force)


def _accel_numpy(vel: np.ndarray, tau: np.ndarray, p: np.ndarray) -> tuple[np.ndarray, Any]:
    """NumPy twin of the compiled ``_accel`` (vectorised over leading axes)."""
    m, xb, yb, ib, a, d, bu, br, frr, constrained = p
    u, v, r = vel[..., 0], vel[..., 1], vel[..., 2]
    fx = (tau[..., 0] + tau[..., 1]) / a - bu * u - frr * np.tanh(u / 1e-3)
    mz = d * (tau[..., 1] - tau[..., 0]) / a - br * r
    if constrained > 0.5:
        b1 = fx + m * xb * r * r
        b2 = mz - m * xb * r * u
        det = m * ib - m * m * yb * yb
        du = (ib * b1 + m * yb * b2) / det
        dr = (m * yb * b1 + m * b2) / det
        fy = m * xb * dr + m * r * (u - yb * r)
        return np.stack([du, np.zeros_like(du), dr], -1), fy
    b1 = fx + m * r * (v + xb * r)
    b2 = -bu * v - m * r * (u - yb * r)
    b3 = mz - m * r * (xb * u + yb * v)
    s = ib - m * (xb * xb + yb * yb)
    dr = (b3 + yb * b1 - xb * b2) / s
    du = (b1 + m * yb * dr) / m
    dv = (b2 - m * xb * dr) / m
    return np.stack([du, dv, dr], -1), np.zeros_like(du)


RM100 = DiffDriveDynamics(
    body=RigidBody(mass=26.2, inertia=1.14, cg_offset=(0.01, 0.0)),
    wheel_radius=0.065,
    half_track=RM100_HALF_TRACK,
)
"""Peer Robotics RM100 (document 000 ch. 4): m = 26.2 kg, I_z = 1.14 kg·m² about the CG,
x_bc = 0.01 m, y_bc = 0, wheel radius 0.065 m; body 0.66 × 0.455 × 0.20 m. The half track
d = 0.2275 m is chosen (see :data:`RM100_HALF_TRACK`)."""


# --------------------------------------------------------------------------- simulation
@dataclass(frozen=True)
class DynamicsResult:
    """The outcome of :func:`simulate_dynamics`.

    Attributes
    ----------
    t : numpy.ndarray, shape (T,)
        Times [s].
    states : numpy.ndarray, shape (T, 6) or (T, N, 6)
        (x [m], y [m], ψ [rad] wrapped to (−π, π], u [m/s], v [m/s], r [rad/s]).
    torques : numpy.ndarray, shape (T, 2) or (T, N, 2)
        Wheel torques (left, right) [N·m] applied from each time on.
    lateral_force : numpy.ndarray, shape (T,) or (T, N)
        Lateral constraint force F_y [N] the ground supplies (0 when unconstrained).
    method : str
        The integrator.
    """

    t: np.ndarray
    states: np.ndarray
    torques: np.ndarray
    lateral_force: np.ndarray
    method: str

    @property
    def poses(self) -> np.ndarray:
        """Poses (x, y, ψ) ``(T, [N,] 3)``."""
        return self.states[..., :3]

    @property
    def twists(self) -> np.ndarray:
        """Body twists (u, v, r) ``(T, [N,] 3)``."""
        return self.states[..., 3:]

    def columns(self) -> dict[str, np.ndarray]:
        """Named columns of one robot, for CSV export (t, state, torques, F_y)."""
        if self.states.ndim != 2:
            raise InputError("columns() needs a single-robot result")
        names = ("x", "y", "psi", "u", "v", "r")
        out = {"t": self.t}
        out.update({name: self.states[:, i] for i, name in enumerate(names)})
        out["tau_left"], out["tau_right"] = self.torques[:, 0], self.torques[:, 1]
        out["lateral_force"] = self.lateral_force
        return out


TorquesLike = ArrayLike | Callable[[float, np.ndarray], ArrayLike]


def simulate_dynamics(
    dynamics: DiffDriveDynamics,
    torques: TorquesLike,
    t_end: float,
    dt: float,
    *,
    state0: ArrayLike | None = None,
    method: str = "RK45",
    rtol: float = 1e-9,
    atol: float = 1e-11,
) -> DynamicsResult:
    """Forward dynamics from wheel torques (document 000 §5.1): integrate V̇ then η̇ = J(ψ)V.

    Parameters
    ----------
    dynamics : DiffDriveDynamics
        The robot (e.g. :data:`RM100`).
    torques : array_like or callable
        Wheel torques (left, right) [N·m]: constant ``(2,)`` (or ``(N, 2)``, one row per robot
        of a batch, fixed-step methods only); sampled per step ``(S, 2)`` with S = number of
        steps (a zero-order hold); or a callable ``f(t, state) -> (2,)`` (held over each step by
        the fixed-step methods, evaluated continuously by ``solve_ivp``).
    t_end : float
        Duration [s], > 0.
    dt : float
        Output step (and step of ``euler``/``rk4``) [s], 0 < dt ≤ t_end.
    state0 : array_like, shape (6,) or (N, 6), optional
        Initial state (x, y, ψ, u, v, r); zeros by default. With ``constrained`` dynamics v
        must be 0.
    method : str
        One of :data:`DYNAMICS_METHODS`.
    rtol : float
        Relative tolerance of ``solve_ivp``.
    atol : float
        Absolute tolerance of ``solve_ivp``.

    Returns
    -------
    DynamicsResult

    Raises
    ------
    ConfigError
        Bad ``t_end``, ``dt``, ``method`` or tolerances.
    InputError
        Bad shapes, non-finite values, a non-zero lateral speed with ``constrained`` dynamics.

    Examples
    --------
    >>> out = simulate_dynamics(RM100, (0.01, 0.01), t_end=10.0, dt=0.1)
    >>> round(float(out.states[-1, 3]), 5)   # u = F_x·t/m = (0.02/0.065)·10/26.2
    0.11744
    """
    if not isinstance(dynamics, DiffDriveDynamics):
        raise ConfigError(f"dynamics must be a DiffDriveDynamics (got {type(dynamics).__name__})")
    check_choice("method", method, DYNAMICS_METHODS)
    rtol = positive("rtol", rtol)
    atol = positive("atol", atol)
    times = time_grid(t_end, dt)
    n_steps = times.size - 1
    if state0 is None:
        state0 = np.zeros(6)
    s0 = as_float_array("state0", state0, 6, min_ndim=1, max_ndim=2)
    batch = s0.ndim == 2
    s0 = np.ascontiguousarray(s0.reshape(-1, 6)).copy()
    if dynamics.constrained and np.any(s0[:, 4] != 0.0):
        raise InputError("state0 lateral speed v must be 0 with constrained (no-slip) dynamics")
    s0[:, 2] = wrap_angle(s0[:, 2])
    n = s0.shape[0]

    if callable(torques):
        if batch:
            raise InputError("a torque callable drives one robot; give state0 of shape (6,)")
        return _simulate_callable(dynamics, torques, times, s0[0], method, rtol, atol)

    tau = as_float_array("torques", torques, 2, min_ndim=1, max_ndim=3)
    if tau.ndim == 1 or (tau.ndim == 2 and batch):
        tau = np.broadcast_to(tau.reshape(-1, 2), (n, 2))[None]
        if tau.shape[1] != n:
            raise InputError(f"torques must have shape (2,) or ({n}, 2) (got {tau.shape[1:]})")
    else:
        if tau.ndim == 2:
            tau = tau[:, None, :]
        if tau.shape[0] not in (n_steps, n_steps + 1) or tau.shape[1] not in (1, n):
            raise InputError(
                f"sampled torques need {n_steps} rows (one per step) of shape (2,) or ({n}, 2) "
                f"(got shape {tau.shape})"
            )
        tau = np.broadcast_to(tau[:n_steps], (n_steps, n, 2))
    tau = np.ascontiguousarray(tau)

    if method in _FIXED:
        out = np.empty((n_steps + 1, n, 6))
        fy = np.empty((n_steps + 1, n))
        _roll(s0, tau, times, dynamics._params, _FIXED.index(method), out, fy)
    else:
        if batch:
            raise InputError(f"method {method!r} integrates one robot; use 'rk4' for a batch")
        out, fy = _solve_ivp_sampled(dynamics, tau[:, 0, :], times, s0[0], method, rtol, atol)
        out, fy = out[:, None, :], fy[:, None]
    used = np.broadcast_to(tau, (max(tau.shape[0], 1), n, 2))
    used = np.concatenate([used, used[-1:]], 0) if used.shape[0] == n_steps else used
    used = np.broadcast_to(used, (n_steps + 1, n, 2)).copy()
    if not np.all(np.isfinite(out)):
        raise InputError("the simulation produced non-finite states; torques are too large")
    if not batch:
        out, used, fy = out[:, 0], used[:, 0], fy[:, 0]
    return DynamicsResult(times, out, used, fy, method)


def _solve_ivp_sampled(dynamics, tau, times, s0, method, rtol, atol):
    """solve_ivp over each piece where the torques are constant (one piece if constant)."""
    p = dynamics._params
    out = np.empty((times.size, 6))
    out[0] = s0
    constant = tau.shape[0] == 1
    pieces = [(0, times.size - 1)] if constant else [(k, k + 1) for k in range(times.size - 1)]
    state = s0.copy()
    buf = np.empty(6)
    for start, stop in pieces:
        tl, tr = tau[0 if constant else start]

        def rhs(_t, y, tl=tl, tr=tr):
            _deriv(y, tl, tr, p, buf)
            return buf.copy()

        sol = _solve(
            rhs, (times[start], times[stop]), state, method,
            t_eval=times[start : stop + 1], rtol=rtol, atol=atol,
        )  # fmt: skip
        if not sol.success:  # pragma: no cover - scipy failure
            raise InputError(f"solve_ivp failed: {sol.message}")
        out[start : stop + 1] = sol.y.T
        state = sol.y[:, -1].copy()
    out[:, 2] = wrap_angle(out[:, 2])
    rows = np.broadcast_to(tau, (times.size - 1, 2)) if constant else tau
    rows = np.concatenate([rows, rows[-1:]], 0)
    _, fy = _accel_numpy(out[:, 3:], rows, p)
    return out, fy


def _simulate_callable(dynamics, function, times, s0, method, rtol, atol):
    p = dynamics._params

    def torque_at(t: float, state: np.ndarray) -> np.ndarray:
        try:
            raw = function(float(t), state.copy())
        except Exception as error:  # a user callable: say where it failed
            raise InputError(f"torques({t:g}) raised {type(error).__name__}: {error}") from error
        return as_float_array(f"torques({t:g})", raw, 2, min_ndim=1, max_ndim=1)

    n_steps = times.size - 1
    out = np.empty((times.size, 6))
    used = np.empty((times.size, 2))
    out[0] = s0
    if method in _FIXED:
        state = s0.copy()
        k = [np.empty(6) for _ in range(5)]
        for step in range(n_steps):
            used[step] = torque_at(times[step], state)
            _step(state, used[step, 0], used[step, 1], p, times[step + 1] - times[step],
                  _FIXED.index(method), *k)  # fmt: skip
            state[2] = wrap_angle_scalar(state[2])
            out[step + 1] = state
    else:
        buf = np.empty(6)

        def rhs(t, y):
            tau = torque_at(t, y)
            _deriv(y, tau[0], tau[1], p, buf)
            return buf.copy()

        sol = _solve(rhs, (times[0], times[-1]), s0, method, t_eval=times, rtol=rtol,
                     atol=atol)  # fmt: skip
        if not sol.success:  # pragma: no cover
            raise InputError(f"solve_ivp failed: {sol.message}")
        out = sol.y.T.copy()
        out[:, 2] = wrap_angle(out[:, 2])
        for step in range(n_steps):
            used[step] = torque_at(times[step], out[step])
    used[-1] = torque_at(times[-1], out[-1])
    _, fy = _accel_numpy(out[:, 3:], used, p)
    if not np.all(np.isfinite(out)):
        raise InputError("the simulation produced non-finite states; torques are too large")
    return DynamicsResult(times, out, used, fy, method)


# --------------------------------------------------------------------------- inverse dynamics
@dataclass(frozen=True)
class InverseDynamicsResult:
    """Forces and wheel torques along a trajectory (document 000 §5.2, figures 5.10–5.11).

    Attributes
    ----------
    t : numpy.ndarray, shape (T,)
        Times [s].
    force : numpy.ndarray, shape (T, 3)
        Body force (F_x [N], F_y [N], M_z [N·m]); F_y is the lateral ground force.
    torques : numpy.ndarray, shape (T, 2)
        Wheel torques (τ_L, τ_R) [N·m].
    """

    t: np.ndarray
    force: np.ndarray
    torques: np.ndarray


def inverse_dynamics(dynamics: DiffDriveDynamics, reference: Any) -> InverseDynamicsResult:
    """Forces and wheel torques that make ``dynamics`` follow ``reference`` (document 000 §5.2).

    τ = M·V̇ + C(V)·V with V and V̇ the reference twist and twist rate, then τ* = Wᵀτ.

    Parameters
    ----------
    dynamics : DiffDriveDynamics
        The robot.
    reference : PoseTrajectory
        Anything with ``t`` (T,), ``twist`` (T, 3) and ``twist_rate`` (T, 3), e.g. from
        :func:`wheelbase.trajectory.feasible_trajectory`.

    Returns
    -------
    InverseDynamicsResult
    """
    try:
        t, twist, rate = reference.t, reference.twist, reference.twist_rate
    except AttributeError:
        raise InputError("reference needs t, twist and twist_rate (a PoseTrajectory)") from None
    force, torques = dynamics.inverse(twist, rate)
    return InverseDynamicsResult(np.asarray(t, dtype=np.float64), force, torques)
