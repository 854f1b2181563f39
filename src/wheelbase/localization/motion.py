"""Motion models of the estimators: a velocity model for the Kalman filters, Nav2's odometry
model for the particle filter.

Velocity model (:class:`VelocityMotion`)
    A step of the unicycle moves the pose along the arc of length Δs = v·Δt and turn
    Δθ = ω·Δt (Thrun, Burgard and Fox, *Probabilistic Robotics*, 2005, §5.3, here in the
    closed form x' = x + Δs·sinc(Δθ/2)·cos(θ + Δθ/2), y' likewise with sin, θ' = θ + Δθ, which is
    smooth through Δθ = 0). The controls are noisy: Δs and Δθ carry independent zero-mean
    Gaussian errors with variances

        Var(Δs) = distance_per_m·|Δs| + distance_per_rad·|Δθ| + distance_per_s·Δt
        Var(Δθ) = heading_per_m·|Δs| + heading_per_rad·|Δθ| + heading_per_s·Δt.

    The book's α₁…α₄ multiply *squared velocities* and give the variance of one step whatever
    its length, so the same robot would be noisier at 10 Hz than at 100 Hz; variances linear in
    the increments (a random walk in distance and heading) add up to the same drift at any rate,
    which matters on logs such as MRCLAM's (odometry at 67 Hz, measurements at 2 Hz).

Odometry model (:class:`OdometryMotion`)
    The "diff" model of Nav2's AMCL and of the book's Table 5.6: the odometry's relative motion
    between two filter updates, as a rotation δ_rot1, a translation δ_trans and a rotation
    δ_rot2, is perturbed with zero-mean Gaussians of variances α₁δ_rot1² + α₂δ_trans²,
    α₃δ_trans² + α₄(δ_rot1² + δ_rot2²) and α₁δ_rot2² + α₂δ_trans². One departure: a motion
    whose direction points backwards is modelled as a reverse translation (δ_rot1 off by π,
    δ_trans negative), so a reversing robot is not given half-turn rotation noise.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from wheelbase._validate import as_float_array, nonnegative, positive
from wheelbase.geometry import compose, se2_exp, wrap_angle

__all__ = ["OdometryMotion", "VelocityMotion", "arc_move", "odometry_delta"]


def _sinc_half(phi: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """S(a) = sin(a)/a and S'(a) at a = φ/2, with series where the quotients lose precision."""
    a = 0.5 * phi
    small = np.abs(a) < 1e-4
    safe = np.where(small, 1.0, a)
    s = np.where(small, 1.0 - a * a / 6.0, np.sin(safe) / safe)
    ds = np.where(small, -a / 3.0 + a**3 / 30.0, (safe * np.cos(safe) - np.sin(safe)) / safe**2)
    return s, ds


def arc_move(poses: ArrayLike, increments: ArrayLike) -> np.ndarray:
    """Move poses along arcs of length Δs and turn Δθ (the exact unicycle step).

    Parameters
    ----------
    poses : array_like, shape (..., 3)
        Start poses (x [m], y [m], θ [rad]).
    increments : array_like, shape (..., 2)
        (Δs [m], Δθ [rad]); broadcast against ``poses``.

    Returns
    -------
    numpy.ndarray, shape (..., 3)
        End poses, θ wrapped to (−π, π].
    """
    inc = np.asarray(increments, dtype=np.float64)
    twist = np.stack([inc[..., 0], np.zeros_like(inc[..., 0]), inc[..., 1]], -1)
    return se2_exp(poses, twist, 1.0)  # the arc traversed in one unit of "time"


@dataclass(frozen=True)
class VelocityMotion:
    """Unicycle steps with noise linear in the increments (module docstring).

    Parameters
    ----------
    distance_per_m : float
        Variance of Δs gained per metre driven [m²/m], >= 0.
    distance_per_rad : float
        Variance of Δs gained per radian turned [m²/rad], >= 0.
    heading_per_m : float
        Variance of Δθ gained per metre driven [rad²/m], >= 0.
    heading_per_rad : float
        Variance of Δθ gained per radian turned [rad²/rad], >= 0.
    distance_per_s : float
        Variance of Δs gained per second, moving or not [m²/s], >= 0.
    heading_per_s : float
        Variance of Δθ gained per second, moving or not [rad²/s], >= 0.

    Examples
    --------
    >>> model = VelocityMotion(distance_per_m=1e-3, heading_per_m=0.0, heading_per_rad=1e-3)
    >>> model.covariance([[1.0, 0.5]], 2.0).diagonal(axis1=-2, axis2=-1).tolist()
    [[0.002, 0.001]]
    """

    distance_per_m: float = 1e-3
    distance_per_rad: float = 0.0
    heading_per_m: float = 1e-4
    heading_per_rad: float = 1e-3
    distance_per_s: float = 0.0
    heading_per_s: float = 0.0

    def __post_init__(self) -> None:
        for name, unit in (
            ("distance_per_m", "m²/m"),
            ("distance_per_rad", "m²/rad"),
            ("heading_per_m", "rad²/m"),
            ("heading_per_rad", "rad²/rad"),
            ("distance_per_s", "m²/s"),
            ("heading_per_s", "rad²/s"),
        ):
            object.__setattr__(self, name, nonnegative(name, getattr(self, name), unit))

    def increments(self, control: ArrayLike, dt: float) -> np.ndarray:
        """(Δs, Δθ) = (v·Δt, ω·Δt).

        Parameters
        ----------
        control : array_like, shape (..., 2)
            (v [m/s], ω [rad/s]).
        dt : float
            Step [s], > 0.

        Returns
        -------
        numpy.ndarray, shape (..., 2)
        """
        control = as_float_array("control", control, 2)
        return control * positive("dt", dt, "s")

    def covariance(self, control: ArrayLike, dt: float) -> np.ndarray:
        """Covariance of the errors of (Δs, Δθ) over one step (diagonal).

        Parameters
        ----------
        control : array_like, shape (..., 2)
            (v [m/s], ω [rad/s]).
        dt : float
            Step [s], > 0.

        Returns
        -------
        numpy.ndarray, shape (..., 2, 2)
            [m², rad²] on the diagonal.
        """
        return self.increment_covariance(self.increments(control, dt), dt)

    def increment_covariance(self, increments: ArrayLike, dt: ArrayLike) -> np.ndarray:
        """Covariance of the errors of given increments (Δs, Δθ) over steps of ``dt``.

        Parameters
        ----------
        increments : array_like, shape (..., 2)
            (Δs [m], Δθ [rad]).
        dt : array_like
            Step lengths [s], broadcast against ``increments[..., 0]``.

        Returns
        -------
        numpy.ndarray, shape (..., 2, 2)
            Diagonal, [m²] and [rad²].
        """
        inc = np.abs(np.asarray(increments, dtype=np.float64))
        dt = np.asarray(dt, dtype=np.float64)
        d, phi = inc[..., 0], inc[..., 1]
        var_d = self.distance_per_m * d + self.distance_per_rad * phi + self.distance_per_s * dt
        var_phi = self.heading_per_m * d + self.heading_per_rad * phi + self.heading_per_s * dt
        out = np.zeros((*np.broadcast_shapes(d.shape, dt.shape), 2, 2))
        out[..., 0, 0] = var_d
        out[..., 1, 1] = var_phi
        return out

    def jacobians(self, poses: ArrayLike, increments: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
        """Jacobians of :func:`arc_move` with respect to the pose and to (Δs, Δθ).

        Parameters
        ----------
        poses : array_like, shape (..., 3)
            Poses before the step.
        increments : array_like, shape (..., 2)
            (Δs [m], Δθ [rad]).

        Returns
        -------
        G : numpy.ndarray, shape (..., 3, 3)
            ∂pose'/∂pose.
        V : numpy.ndarray, shape (..., 3, 2)
            ∂pose'/∂(Δs, Δθ).
        """
        poses = np.asarray(poses, dtype=np.float64)
        inc = np.asarray(increments, dtype=np.float64)
        shape = np.broadcast_shapes(poses.shape[:-1], inc.shape[:-1])
        d, phi = inc[..., 0], inc[..., 1]
        s, ds = _sinc_half(phi)
        mid = poses[..., 2] + 0.5 * phi
        c, sn = np.cos(mid), np.sin(mid)
        g = np.broadcast_to(np.eye(3), (*shape, 3, 3)).copy()
        g[..., 0, 2] = -d * s * sn
        g[..., 1, 2] = d * s * c
        v = np.zeros((*shape, 3, 2))
        v[..., 0, 0] = s * c
        v[..., 1, 0] = s * sn
        v[..., 0, 1] = 0.5 * d * (ds * c - s * sn)
        v[..., 1, 1] = 0.5 * d * (ds * sn + s * c)
        v[..., 2, 1] = 1.0
        return g, v

    def sample(
        self, poses: ArrayLike, control: ArrayLike, dt: float, rng: np.random.Generator
    ) -> np.ndarray:
        """One noisy step: the increments plus errors of :meth:`covariance`.

        Parameters
        ----------
        poses : array_like, shape (..., 3)
            Poses before the step.
        control : array_like, shape (..., 2)
            Commanded (v [m/s], ω [rad/s]).
        dt : float
            Step [s], > 0.
        rng : numpy.random.Generator
            Source of randomness.

        Returns
        -------
        numpy.ndarray, shape (..., 3)
        """
        return self.perturb(poses, self.increments(control, dt), dt, rng)

    def perturb(
        self, poses: ArrayLike, increments: ArrayLike, dt: float, rng: np.random.Generator
    ) -> np.ndarray:
        """Move poses by increments (Δs, Δθ) plus independent errors of
        :meth:`increment_covariance` (each pose its own draw).

        Parameters
        ----------
        poses : array_like, shape (..., 3)
            Poses before the step.
        increments : array_like, shape (..., 2)
            (Δs [m], Δθ [rad]).
        dt : float
            Duration of the step [s], >= 0 (for the per-second terms).
        rng : numpy.random.Generator
            Source of randomness.

        Returns
        -------
        numpy.ndarray, shape (..., 3)
        """
        poses = as_float_array("poses", poses, 3)
        inc = as_float_array("increments", increments, 2)
        cov = self.increment_covariance(inc, nonnegative("dt", dt, "s"))
        shape = np.broadcast_shapes(poses.shape[:-1], inc.shape[:-1])
        std = np.sqrt(np.stack([cov[..., 0, 0], cov[..., 1, 1]], -1))
        noisy = inc + np.broadcast_to(std, (*shape, 2)) * rng.standard_normal((*shape, 2))
        return arc_move(poses, noisy)

    def sample_relative(
        self, poses: ArrayLike, relative: ArrayLike, dt: float, rng: np.random.Generator
    ) -> np.ndarray:
        """Move poses by an odometry relative pose, with the noise of the arc it amounts to.

        Each pose is composed with ``relative`` (exact, whatever path the odometry took) and
        perturbed by V·ε, ε ~ N(0, :meth:`increment_covariance`) for the increments
        (Δs, Δθ) of the arc with the same chord and turn, V = ∂pose'/∂(Δs, Δθ) of that arc.

        Parameters
        ----------
        poses : array_like, shape (P, 3)
            Poses before the motion.
        relative : array_like, shape (3,)
            The motion in the frame of the old pose (x forward [m], y left [m], θ [rad]).
        dt : float
            Duration of the motion [s], >= 0 (for the per-second terms).
        rng : numpy.random.Generator
            Source of randomness.

        Returns
        -------
        numpy.ndarray, shape (P, 3)
        """
        poses = as_float_array("poses", poses, 3, min_ndim=2, max_ndim=2)
        rel = as_float_array("relative", relative, 3, max_ndim=1)
        turn = float(rel[2])
        chord = math.hypot(rel[0], rel[1])
        s, _ = _sinc_half(np.array(turn))
        forward = math.cos(math.atan2(rel[1], rel[0]) - 0.5 * turn) if chord > 0 else 1.0
        inc = np.array([math.copysign(chord / float(s), forward), turn])
        cov = self.increment_covariance(inc, nonnegative("dt", dt, "s"))
        eps = rng.standard_normal((poses.shape[0], 2)) * np.sqrt([cov[0, 0], cov[1, 1]])
        _, v = self.jacobians(poses, inc)
        moved = compose(poses, rel) + np.einsum("pij,pj->pi", v, eps)
        moved[:, 2] = wrap_angle(moved[:, 2])
        return moved


def odometry_delta(old: ArrayLike, new: ArrayLike) -> np.ndarray:
    """The odometry's motion between two poses as (δ_rot1, δ_trans, δ_rot2).

    A motion pointing backwards (|δ_rot1| > π/2) is a reverse translation: δ_trans < 0 and
    δ_rot1 is taken from the reversed direction. Below 1 mm of translation δ_rot1 is 0 and the
    whole turn is δ_rot2 (Nav2 does the same below 1 cm).

    Parameters
    ----------
    old, new : array_like, shape (..., 3)
        Odometry poses (x [m], y [m], θ [rad]) at the last filter update and now.

    Returns
    -------
    numpy.ndarray, shape (..., 3)
        (δ_rot1 [rad], δ_trans [m], δ_rot2 [rad]).
    """
    old = as_float_array("old", old, 3)
    new = as_float_array("new", new, 3)
    dx = new[..., 0] - old[..., 0]
    dy = new[..., 1] - old[..., 1]
    trans = np.hypot(dx, dy)
    rot1 = np.where(trans < 1e-3, 0.0, wrap_angle(np.arctan2(dy, dx) - old[..., 2]))
    backwards = np.abs(rot1) > 0.5 * math.pi
    rot1 = np.where(backwards, wrap_angle(rot1 + math.pi), rot1)
    trans = np.where(backwards, -trans, trans)
    rot2 = wrap_angle(new[..., 2] - old[..., 2] - rot1)
    return np.stack([rot1, trans, rot2], -1)


@dataclass(frozen=True)
class OdometryMotion:
    """Nav2's odometry ("diff") motion model (module docstring).

    Parameters
    ----------
    alpha1 : float
        Rotation noise from rotation [rad²/rad²], >= 0 (Nav2 ``alpha1``, default 0.2).
    alpha2 : float
        Rotation noise from translation [rad²/m²], >= 0 (Nav2 ``alpha2``).
    alpha3 : float
        Translation noise from translation [m²/m²], >= 0 (Nav2 ``alpha3``).
    alpha4 : float
        Translation noise from rotation [m²/rad²], >= 0 (Nav2 ``alpha4``).
    """

    alpha1: float = 0.2
    alpha2: float = 0.2
    alpha3: float = 0.2
    alpha4: float = 0.2

    def __post_init__(self) -> None:
        for name in ("alpha1", "alpha2", "alpha3", "alpha4"):
            object.__setattr__(self, name, nonnegative(name, getattr(self, name)))

    def sample(
        self, particles: np.ndarray, delta: ArrayLike, rng: np.random.Generator
    ) -> np.ndarray:
        """Move every particle by the odometry motion with independent noise.

        Parameters
        ----------
        particles : numpy.ndarray, shape (P, 3)
            Particle poses.
        delta : array_like, shape (3,)
            (δ_rot1 [rad], δ_trans [m], δ_rot2 [rad]) from :func:`odometry_delta`.
        rng : numpy.random.Generator
            Source of randomness.

        Returns
        -------
        numpy.ndarray, shape (P, 3)
        """
        rot1, trans, rot2 = (float(v) for v in np.asarray(delta, dtype=np.float64))
        a1, a2, a3, a4 = self.alpha1, self.alpha2, self.alpha3, self.alpha4
        std = np.sqrt(
            [
                a1 * rot1 * rot1 + a2 * trans * trans,
                a3 * trans * trans + a4 * (rot1 * rot1 + rot2 * rot2),
                a1 * rot2 * rot2 + a2 * trans * trans,
            ]
        )
        noise = rng.standard_normal((particles.shape[0], 3)) * std
        heading = particles[:, 2] + rot1 + noise[:, 0]
        t = trans + noise[:, 1]
        out = np.empty_like(particles)
        out[:, 0] = particles[:, 0] + t * np.cos(heading)
        out[:, 1] = particles[:, 1] + t * np.sin(heading)
        out[:, 2] = wrap_angle(heading + rot2 + noise[:, 2])
        return out
