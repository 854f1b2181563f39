"""Planar geometry on poses ``(x, y, θ)``: angle wrapping, rotations, SE(2) operations.

Conventions (REP 103): world frame x east, y north, θ counter-clockwise from +x in radians.
Body frame x forward, y left. Every function works on one pose of shape ``(3,)`` or a batch of
shape ``(..., 3)`` and returns float64 arrays of the matching shape.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from wheelbase._validate import as_float_array

__all__ = [
    "compose",
    "inverse_pose",
    "relative_pose",
    "rotation_2d",
    "rotation_jacobian",
    "se2_exp",
    "to_body_frame",
    "to_world_frame",
    "transform_points",
    "wrap_angle",
]


def wrap_angle(angle: ArrayLike) -> np.ndarray:
    """Wrap angles to the interval (−π, π] [rad].

    Uses ``atan2(sin, cos)`` (document 002: never ``atan``) and maps −π to +π so that the
    interval is half-open on the left.

    Examples
    --------
    >>> float(wrap_angle(3 * np.pi / 2))
    -1.5707963267948966
    """
    angle = np.asarray(angle, dtype=np.float64)
    wrapped = np.arctan2(np.sin(angle), np.cos(angle))
    return np.where(wrapped <= -np.pi, np.pi, wrapped)


def rotation_2d(theta: ArrayLike) -> np.ndarray:
    """2×2 rotation matrices R(θ) of shape ``(..., 2, 2)`` (θ in rad)."""
    theta = np.asarray(theta, dtype=np.float64)
    c, s = np.cos(theta), np.sin(theta)
    return np.stack([np.stack([c, -s], -1), np.stack([s, c], -1)], -2)


def rotation_jacobian(theta: ArrayLike) -> np.ndarray:
    """The 3×3 matrix J(ψ) of document 000 §3.1 that maps body twist to pose rate.

    η̇ = J(ψ)·ζ with η = (x, y, ψ) and ζ = (u, v, r): forward [m/s], lateral [m/s] and yaw
    rate [rad/s] in the body frame. Shape ``(..., 3, 3)``.
    """
    theta = np.asarray(theta, dtype=np.float64)
    out = np.zeros((*theta.shape, 3, 3))
    out[..., :2, :2] = rotation_2d(theta)
    out[..., 2, 2] = 1.0
    return out


def to_world_frame(theta: ArrayLike, twist: ArrayLike) -> np.ndarray:
    """Rotate body-frame twists ``(u, v, r)`` into world-frame pose rates ``(ẋ, ẏ, θ̇)``.

    This is η̇ = J(ψ)·ζ (document 000 §3.1) without building the matrix.

    Parameters
    ----------
    theta : array_like, shape (...)
        Headings ψ [rad].
    twist : array_like, shape (..., 3)
        Body twists (u [m/s], v [m/s], r [rad/s]).
    """
    theta = np.asarray(theta, dtype=np.float64)
    twist = np.asarray(twist, dtype=np.float64)
    c, s = np.cos(theta), np.sin(theta)
    u, v, r = twist[..., 0], twist[..., 1], twist[..., 2]
    return np.stack(np.broadcast_arrays(c * u - s * v, s * u + c * v, r), -1)


def to_body_frame(theta: ArrayLike, pose_rate: ArrayLike) -> np.ndarray:
    """Inverse of :func:`to_world_frame`: ζ = J(ψ)⁻¹ η̇ = J(ψ)ᵀ η̇.

    Parameters
    ----------
    theta : array_like, shape (...)
        Headings ψ [rad].
    pose_rate : array_like, shape (..., 3)
        World-frame rates (ẋ [m/s], ẏ [m/s], θ̇ [rad/s]).
    """
    theta = np.asarray(theta, dtype=np.float64)
    pose_rate = np.asarray(pose_rate, dtype=np.float64)
    c, s = np.cos(theta), np.sin(theta)
    xd, yd, td = pose_rate[..., 0], pose_rate[..., 1], pose_rate[..., 2]
    return np.stack(np.broadcast_arrays(c * xd + s * yd, -s * xd + c * yd, td), -1)


def compose(a: ArrayLike, b: ArrayLike) -> np.ndarray:
    """SE(2) composition a ⊕ b: pose ``b`` given in the frame of ``a``, expressed in the world.

    Parameters
    ----------
    a : array_like, shape (..., 3)
        Poses of frame A in the world [m, m, rad].
    b : array_like, shape (..., 3)
        Poses given in frame A.
    """
    a = as_float_array("a", a, 3)
    b = as_float_array("b", b, 3)
    c, s = np.cos(a[..., 2]), np.sin(a[..., 2])
    x = a[..., 0] + c * b[..., 0] - s * b[..., 1]
    y = a[..., 1] + s * b[..., 0] + c * b[..., 1]
    return np.stack(np.broadcast_arrays(x, y, wrap_angle(a[..., 2] + b[..., 2])), -1)


def inverse_pose(a: ArrayLike) -> np.ndarray:
    """SE(2) inverse ⊖a, such that ``compose(a, inverse_pose(a))`` is the identity."""
    a = as_float_array("a", a, 3)
    c, s = np.cos(a[..., 2]), np.sin(a[..., 2])
    x = -c * a[..., 0] - s * a[..., 1]
    y = s * a[..., 0] - c * a[..., 1]
    return np.stack([x, y, wrap_angle(-a[..., 2])], -1)


def relative_pose(a: ArrayLike, b: ArrayLike) -> np.ndarray:
    """Pose of ``b`` in the frame of ``a`` (⊖a ⊕ b): e.g. a goal seen from the robot.

    Parameters
    ----------
    a : array_like, shape (..., 3)
        Reference poses (the robot) in the world [m, m, rad].
    b : array_like, shape (..., 3)
        Poses (the goal) in the world.
    """
    return compose(inverse_pose(a), b)


def transform_points(pose: ArrayLike, points: ArrayLike) -> np.ndarray:
    """Map body-frame points to the world frame.

    Parameters
    ----------
    pose : array_like, shape (..., 3)
        Body poses in the world [m, m, rad].
    points : array_like, shape (..., M, 2)
        Points in the body frame [m] (x forward, y left).
    """
    pose = as_float_array("pose", pose, 3)
    points = as_float_array("points", points, 2)
    rot = rotation_2d(pose[..., 2])
    return np.einsum("...ij,...mj->...mi", rot, points) + pose[..., None, :2]


def se2_exp(pose: ArrayLike, twist: ArrayLike, duration: ArrayLike) -> np.ndarray:
    """Move ``pose`` along a body twist ``(u, v, r)`` held constant for ``duration`` seconds.

    This is the closed-form arc (the exponential map of SE(2)): exact for any yaw rate, smooth
    as r → 0 (no 0/0: it uses ``sin(φ)/φ`` and ``(1 − cos φ)/φ`` through ``np.sinc``).

    Parameters
    ----------
    pose : array_like, shape (..., 3)
        Start poses [m, m, rad].
    twist : array_like, shape (..., 3)
        Body twists (u [m/s], v [m/s], r [rad/s]).
    duration : array_like
        How long the twist is held [s].
    """
    pose = np.asarray(pose, dtype=np.float64)
    twist = np.asarray(twist, dtype=np.float64)
    h = np.asarray(duration, dtype=np.float64)
    u, v, r = twist[..., 0], twist[..., 1], twist[..., 2]
    phi = r * h
    # np.sinc(x) = sin(πx)/(πx); a = ∫₀ʰ cos(rτ)dτ, b = ∫₀ʰ sin(rτ)dτ.
    a = h * np.sinc(phi / np.pi)
    b = h * np.sin(phi / 2.0) * np.sinc(phi / (2.0 * np.pi))
    dx_body = u * a - v * b
    dy_body = u * b + v * a
    theta = pose[..., 2]
    c, s = np.cos(theta), np.sin(theta)
    x = pose[..., 0] + c * dx_body - s * dy_body
    y = pose[..., 1] + s * dx_body + c * dy_body
    return np.stack(np.broadcast_arrays(x, y, wrap_angle(theta + phi)), -1)
