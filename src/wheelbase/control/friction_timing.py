"""A reference slowed to the friction: time scaling along its own path (traction control).

Traction control clips each wheel's torque to what the ground can take, but the lateral force a
turn needs and the longitudinal force of the reference's own accelerations are set by the
reference: where they exceed the friction, a clip only lets the tracking error grow (the robot
skids wide of a turn, or lags behind and cannot brake for a cusp). The remedy is to drive the
same path more slowly where the friction is short: keep the reference's geometry and change
only its timing.

**Time scaling.** The reference q(τ) (rows x, y, ψ, u, v, r, u̇, v̇, ṙ against its own time τ)
is run on a clock τ(t) of rate τ̇ = √z. Its twist becomes V = √z·V_ref and its acceleration
V̇ = z·V̇_ref + w·V_ref with w = ż/(2 τ̇) = dz/dτ / 2. The controller model's inverse
dynamics τ = M·V̇ + C(V)·V is then linear in (z, w), since C(V)·V is quadratic in V:

    F_x,k = α_k·z + β_k·w + γ_k,    F_y = λ_a·z + λ_b·w,

per drive wheel k (F_x,k its longitudinal force, τ_k / a; α from M·V̇_ref + C(V_ref)·V_ref,
β from M·V_ref, γ the modelled resistances at the reference's speed — an upper bound for
z ≤ 1), F_y the lateral force the ground must give, shared by the two drive wheels (the
casters take none). The friction circle of each wheel, at a share ``share`` of what it can
take,

    F_x,k² + (F_y/2)² ≤ (share·μ_k·N_k)²,   N_k = s·m·g/2,

is a convex quadratic in (z, w): at given z it leaves an interval of w. This is the change of
variables b = ṡ², a = s̈ of time-optimal path following (Verscheure, Demeulenaere, Swevers,
De Schutter and Diehl, "Time-optimal path tracking for robots: a convex optimization approach",
IEEE TAC 54(10), 2009), with friction circles for the torque limits (Lipp and Boyd,
"Minimum-time speed optimisation over a fixed path", IJC 87(6), 2014); the profile is found by
the integration passes of Bobrow, Dubowsky and Gibson (IJRR 4(3), 1985) on the reference's own
samples:

1. the maximum z at each sample with some w inside every wheel's circle (bisection, z ≤ 1:
   never faster than the reference);
2. backward from the end, the largest z from which the next sample's z can still be reached
   braking at the most negative w allowed (z_k + 2·Δτ·w_min(z_k) ≤ z_{k+1});
3. forward from the robot's present rate, the largest z reachable accelerating at the most
   positive w allowed, under the backward curve.

For a straight line (only u̇ and the speed) this is the trapezoid at the friction's acceleration
share·μ·s·g; on an arc of curvature κ at constant speed it is u² κ ≤ share·μ·s·g (the tests hold
both closed forms). A profile is built once per reference and friction: along the reference the
friction may change (a map of surfaces), and a new estimate builds it again from the robot's
present place on the clock.
"""

from __future__ import annotations

import math

import numba
import numpy as np
from numpy.typing import ArrayLike

from wheelbase._validate import as_float_array
from wheelbase.dynamics import GRAVITY, DiffDriveDynamics
from wheelbase.errors import ConfigError, InputError
from wheelbase.geometry import wrap_angle

__all__ = ["MIN_RATE", "FrictionTiming", "force_terms", "friction_profile"]

MIN_RATE = 0.01
"""Slowest clock rate τ̇ = √z the profile gives [-]: a robot the friction cannot move at all
(resistance beyond the grip) still advances its reference, and the stuck rule ends it."""


def force_terms(model: DiffDriveDynamics, rows: ArrayLike) -> np.ndarray:
    """The wheel-force coefficients of the time-scaled reference (module docstring).

    Parameters
    ----------
    model : DiffDriveDynamics
        The controller's model (mass, inertia, CG offset, wheel radius, half track,
        resistances).
    rows : array_like, shape (T, 9)
        Reference rows (x, y, ψ, u, v, r, u̇, v̇, ṙ) [m, m, rad, m/s, m/s, rad/s, m/s², m/s²,
        rad/s²].

    Returns
    -------
    numpy.ndarray, shape (T, 8)
        Per sample (α_L, α_R, β_L, β_R, γ_L, γ_R, λ_a, λ_b) [N]: F_x,k = α_k·z + β_k·w + γ_k and
        the lateral force F_y = λ_a·z + λ_b·w.
    """
    table = as_float_array("rows", rows, 9, min_ndim=2, max_ndim=2)
    if not isinstance(model, DiffDriveDynamics):
        raise ConfigError(f"model must be a DiffDriveDynamics (got {type(model).__name__})")
    velocity, acceleration = table[:, 3:6], table[:, 6:9]
    a = model.wheel_radius
    quadratic = model.body.inverse(velocity, acceleration)  # M·V̇_ref + C(V_ref)·V_ref
    linear = velocity @ model.body.mass_matrix().T  # M·V_ref
    total, _ = model.inverse(velocity, acceleration)
    resistance = total - quadratic  # the modelled resistances at the reference's speed
    out = np.empty((table.shape[0], 8))
    out[:, 0:2] = model.wheel_torques(quadratic) / a
    out[:, 2:4] = model.wheel_torques(linear) / a
    out[:, 4:6] = model.wheel_torques(resistance) / a
    out[:, 6] = quadratic[:, 1]
    out[:, 7] = linear[:, 1]
    return out


def friction_profile(
    times: ArrayLike, terms: ArrayLike, grip: ArrayLike, start: float = 1.0
) -> np.ndarray:
    """The squared clock rate z ``(T,)`` at each sample (module docstring, steps 1–3).

    Parameters
    ----------
    times : array_like, shape (T,)
        The reference's sample times τ_k [s], increasing.
    terms : array_like, shape (T, 8)
        :func:`force_terms` of its rows [N].
    grip : array_like, shape (T, 2)
        The force each drive wheel may take at each sample, share·μ_k·N_k [N], > 0.
    start : float
        The clock's squared rate at the first sample (the robot's present one), in [0, 1].

    Returns
    -------
    numpy.ndarray, shape (T,)
        z_k in [MIN_RATE², 1].
    """
    tau = as_float_array("times", times, min_ndim=1, max_ndim=1)
    coefficients = as_float_array("terms", terms, 8, min_ndim=2, max_ndim=2)
    limit = as_float_array("grip", grip, 2, min_ndim=2, max_ndim=2)
    if coefficients.shape[0] != tau.size or limit.shape[0] != tau.size or tau.size == 0:
        raise InputError(
            f"times, terms and grip need one row per sample (got {tau.size}, "
            f"{coefficients.shape[0]}, {limit.shape[0]})"
        )
    if np.any(np.diff(tau) <= 0):
        raise InputError("times must increase")
    if np.any(limit <= 0):
        raise InputError("grip must be > 0 N")
    start = float(start)
    if not 0.0 <= start <= 1.0:
        raise InputError(f"start must be in [0, 1] (got {start:g})")
    out = np.empty(tau.size)
    _profile(np.ascontiguousarray(tau), np.ascontiguousarray(coefficients),
             np.ascontiguousarray(limit), start, MIN_RATE**2, out)  # fmt: skip
    return out


# --------------------------------------------------------------------------- kernels
@numba.njit(cache=True)
def _wheel_interval(z, alpha, beta, gamma, lat_a, lat_b, grip):
    """The w-interval (lo, hi) in which one wheel's circle holds at z (lo > hi: none)."""
    fx = alpha * z + gamma
    fy = 0.5 * lat_a * z
    q2 = beta * beta + 0.25 * lat_b * lat_b
    q1 = 2.0 * (beta * fx + 0.5 * lat_b * fy)
    q0 = fx * fx + fy * fy - grip * grip
    if q2 < 1e-12:
        if q0 <= 0.0:
            return -np.inf, np.inf
        return np.inf, -np.inf
    disc = q1 * q1 - 4.0 * q2 * q0
    if disc < 0.0:
        return np.inf, -np.inf
    root = math.sqrt(disc)
    return (-q1 - root) / (2.0 * q2), (-q1 + root) / (2.0 * q2)


@numba.njit(cache=True)
def _interval(z, c, g):
    """The w-interval both wheels allow at z, for one sample's terms c (8,) and grips g (2,)."""
    lo_l, hi_l = _wheel_interval(z, c[0], c[2], c[4], c[6], c[7], g[0])
    lo_r, hi_r = _wheel_interval(z, c[1], c[3], c[5], c[6], c[7], g[1])
    return max(lo_l, lo_r), min(hi_l, hi_r)


@numba.njit(cache=True)
def _largest(c, g, cap, floor, dtau, target, braking):
    """Largest z in [floor, cap] feasible at this sample and, braking, from which the next
    sample is reached within [floor, target]: z + 2·Δτ·w_min(z) ≤ target and
    z + 2·Δτ·w_max(z) ≥ floor (near standstill the reference's acceleration leaves w a wide
    interval far from 0, which would drive z below 0); floor when none is."""

    def ok(z):
        lo, hi = _interval(z, c, g)
        if lo > hi:
            return False
        if not braking:
            return True
        return z + 2.0 * dtau * lo <= target and z + 2.0 * dtau * hi >= floor

    if ok(cap):
        return cap
    lo_z, hi_z = floor, cap
    if not ok(lo_z):
        return floor
    for _ in range(50):
        mid = 0.5 * (lo_z + hi_z)
        if ok(mid):
            lo_z = mid
        else:
            hi_z = mid
    return lo_z


@numba.njit(cache=True)
def _profile(tau, terms, grip, start, floor, out):
    n = tau.size
    for k in range(n):  # 1. the maximum z of each sample
        out[k] = _largest(terms[k], grip[k], 1.0, floor, 0.0, 0.0, False)
    for k in range(n - 2, -1, -1):  # 2. backward: braking in time for what comes
        out[k] = _largest(terms[k], grip[k], out[k], floor, tau[k + 1] - tau[k], out[k + 1],
                          True)  # fmt: skip
    z = max(min(start, out[0]), floor)  # 3. forward from the present rate
    out[0] = z
    for k in range(n - 1):
        lo, hi = _interval(z, terms[k], grip[k])
        step = 2.0 * (tau[k + 1] - tau[k]) * hi if lo <= hi else 0.0
        z = max(min(out[k + 1], z + step), floor)
        out[k + 1] = z


# --------------------------------------------------------------------------- the clock
class FrictionTiming:
    """A reference on a clock slowed to the friction (module docstring).

    Parameters
    ----------
    model : DiffDriveDynamics
        The controller's model.
    times : array_like, shape (T,)
        The reference's sample times [s].
    rows : array_like, shape (T, 9)
        Its rows at those times (the accelerations the tracking law feeds forward).
    share : float
        Share of each wheel's friction force the slowed reference may use, in (0, 1].
    drive_load_share : float
        Share s of the weight on the drive wheels, in (0, 1].
    """

    def __init__(
        self,
        model: DiffDriveDynamics,
        times: ArrayLike,
        rows: ArrayLike,
        *,
        share: float,
        drive_load_share: float,
    ) -> None:
        self.times = as_float_array("times", times, min_ndim=1, max_ndim=1)
        self.rows = as_float_array("rows", rows, 9, min_ndim=2, max_ndim=2).copy()
        if self.rows.shape[0] != self.times.size:
            raise InputError("rows must have one row per time")
        self.rows[:, 2] = np.unwrap(self.rows[:, 2])
        self.terms = force_terms(model, self.rows)
        self.load = share * drive_load_share * model.body.mass * GRAVITY / 2.0
        self.z: np.ndarray | None = None
        self.friction: np.ndarray | None = None
        self.clock = float(self.times[0])
        self.last_t: float | None = None

    def plan(
        self,
        friction: ArrayLike,
        start: float | None = None,
        resistance: ArrayLike = 0.0,
        forces: ArrayLike = 0.0,
    ) -> None:
        """Build the profile from the present clock on, for the friction μ under each wheel.

        Parameters
        ----------
        friction : array_like, shape (T, 2) or (2,)
            μ of each wheel at each sample (or the same everywhere).
        start : float, optional
            The present squared rate (default: the present profile's, 1 before any).
        resistance : array_like, shape (T, 2) or (2,)
            A resistance the ground adds that the model lacks, as a force each drive wheel
            must give against the travel [N], ≥ 0 (the floor's rolling resistance); at the
            reference's speed, like the model's own (γ).
        forces : array_like, shape (T, 2) or (2,)
            Forces each drive wheel must give the ground besides the model's, signed along the
            wheel's travel [N], finite (the casters' rolling resistance, which also turns with
            a turn): added to γ as they are.
        """
        mu = np.broadcast_to(np.asarray(friction, dtype=np.float64), (self.times.size, 2))
        extra = np.broadcast_to(np.asarray(resistance, dtype=np.float64), (self.times.size, 2))
        if np.any(extra < 0) or not np.all(np.isfinite(extra)):
            raise InputError("resistance must be finite and >= 0 N")
        signed = np.broadcast_to(np.asarray(forces, dtype=np.float64), (self.times.size, 2))
        if not np.all(np.isfinite(signed)):
            raise InputError("forces must be finite (N)")
        terms = self.terms.copy()
        terms[:, 4:6] += extra * np.tanh(self.rows[:, 3] / 1e-3)[:, None] + signed
        if start is None:
            start = 1.0 if self.z is None else self._z_at(self.clock)
        k = max(int(np.searchsorted(self.times, self.clock, side="right")) - 1, 0)
        z = np.ones(self.times.size) if self.z is None else self.z.copy()
        grip = np.maximum(mu[k:] * self.load, 1e-9)
        times = self.times[k:].copy()
        times[0] = min(self.clock, times[1] - 1e-9) if times.size > 1 else times[0]
        z[k:] = friction_profile(times, terms[k:], grip, min(max(start, 0.0), 1.0))
        self.z = z
        self.friction = np.array(mu)

    def _z_at(self, tau: float) -> float:
        return float(np.interp(tau, self.times, self.z))

    def advance(self, t: float) -> np.ndarray:
        """Move the clock to time ``t`` [s] and give the slowed row ``(9,)`` there.

        Parameters
        ----------
        t : float
            Time [s]; the first call, or one before the last, starts the clock at ``t`` (within
            the reference's span).
        """
        if self.z is None:
            raise InputError("plan the profile before advancing the clock")
        if self.last_t is None or t < self.last_t:
            self.clock = min(max(float(t), float(self.times[0])), float(self.times[-1]))
            self.last_t = t
        step = t - self.last_t
        if step > 0.0:  # midpoint rate over the step
            half = self.clock + 0.5 * step * math.sqrt(self._z_at(self.clock))
            self.clock = min(self.clock + step * math.sqrt(self._z_at(half)),
                             float(self.times[-1]))  # fmt: skip
        self.last_t = t
        return self.row()

    def row(self) -> np.ndarray:
        """The slowed row ``(9,)`` at the present clock: pose, √z·V_ref, z·V̇_ref + w·V_ref."""
        tau = min(self.clock, float(self.times[-1]))
        k = min(max(int(np.searchsorted(self.times, tau, side="right")) - 1, 0),
                self.times.size - 2)  # fmt: skip
        if self.times.size == 1:
            return self.rows[0].copy()
        span = self.times[k + 1] - self.times[k]
        f = min(max((tau - self.times[k]) / span, 0.0), 1.0)
        ref = (1 - f) * self.rows[k] + f * self.rows[k + 1]
        z = (1 - f) * self.z[k] + f * self.z[k + 1]
        w = (self.z[k + 1] - self.z[k]) / (2.0 * span)
        if self.clock >= self.times[-1]:
            z, w = 1.0, 0.0  # the reference has ended: its own final row
        out = ref.copy()
        out[2] = float(wrap_angle(ref[2]))
        out[3:6] = math.sqrt(z) * ref[3:6]
        out[6:9] = z * ref[6:9] + w * ref[3:6]
        return out
