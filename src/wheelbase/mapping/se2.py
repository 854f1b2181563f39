"""The Lie group SE(2) for estimation: logarithm, exponential, adjoint and right Jacobians.

A pose X = (x, y, θ) is the rigid motion with rotation R(θ) and translation t = (x, y); a
tangent vector ξ = (ρ₁, ρ₂, φ) (translation-like part first, as GTSAM's ``Pose2`` orders it)
maps to the group by Exp(ξ) = (V(φ)ρ, φ) with V(φ) = [[sin φ/φ, −(1 − cos φ)/φ], [(1 − cos φ)/φ,
sin φ/φ]] (Barfoot, *State Estimation for Robotics*, 2017, §7.1.9; Solà, Deray and Atchuthan,
"A micro Lie theory for state estimation in robotics", 2018, App. A). The estimators of
:mod:`wheelbase.mapping` perturb poses on the right, X ← X·Exp(δ), and linearise residuals
r = Log(·) through the right Jacobian J_r and its inverse. Every function takes one item or a
batch ``(..., 3)``.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from wheelbase.geometry import wrap_angle

__all__ = ["se2_adjoint", "se2_exp_map", "se2_log", "se2_right_jacobian", "se2_right_jacobian_inv"]

_SMALL = 1e-5  # |φ| below which the series are used (their error is O(φ⁴) ~ 1e-20)


def _a_b(phi: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """a = sin φ / φ and b = (1 − cos φ)/φ, smooth through 0."""
    a = np.sinc(phi / np.pi)
    half = phi / 2.0
    b = half * np.sinc(half / np.pi) ** 2
    return a, b


def se2_log(pose: ArrayLike) -> np.ndarray:
    """Log: the tangent vector ξ = (ρ₁, ρ₂, φ) with Exp(ξ) = pose, φ in (−π, π].

    Parameters
    ----------
    pose : array_like, shape (..., 3)
        Poses (x [m], y [m], θ [rad]).

    Returns
    -------
    numpy.ndarray, shape (..., 3)
        ρ = V(φ)⁻¹ t [m], φ [rad].
    """
    pose = np.asarray(pose, dtype=np.float64)
    phi = wrap_angle(pose[..., 2])
    a, b = _a_b(phi)
    det = a * a + b * b
    x, y = pose[..., 0], pose[..., 1]
    return np.stack([(a * x + b * y) / det, (-b * x + a * y) / det, phi], -1)


def se2_exp_map(xi: ArrayLike) -> np.ndarray:
    """Exp: the pose (V(φ)ρ, φ) of a tangent vector ξ = (ρ₁, ρ₂, φ).

    Parameters
    ----------
    xi : array_like, shape (..., 3)
        Tangent vectors [m, m, rad].

    Returns
    -------
    numpy.ndarray, shape (..., 3)
        Poses, θ wrapped to (−π, π].
    """
    xi = np.asarray(xi, dtype=np.float64)
    a, b = _a_b(xi[..., 2])
    r1, r2 = xi[..., 0], xi[..., 1]
    return np.stack([a * r1 - b * r2, b * r1 + a * r2, wrap_angle(xi[..., 2])], -1)


def se2_adjoint(pose: ArrayLike) -> np.ndarray:
    """Adjoint Ad(X) = [[R, (y, −x)ᵀ], [0, 1]]: X·Exp(ξ)·X⁻¹ = Exp(Ad(X) ξ).

    Parameters
    ----------
    pose : array_like, shape (..., 3)
        Poses X.

    Returns
    -------
    numpy.ndarray, shape (..., 3, 3)
    """
    pose = np.asarray(pose, dtype=np.float64)
    c, s = np.cos(pose[..., 2]), np.sin(pose[..., 2])
    out = np.zeros((*pose.shape[:-1], 3, 3))
    out[..., 0, 0], out[..., 0, 1], out[..., 0, 2] = c, -s, pose[..., 1]
    out[..., 1, 0], out[..., 1, 1], out[..., 1, 2] = s, c, -pose[..., 0]
    out[..., 2, 2] = 1.0
    return out


def _third_column(xi: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The (0, 2) and (1, 2) entries of J_r: ρ₁(φ − sin φ)/φ² − ρ₂(1 − cos φ)/φ² and
    ρ₁(1 − cos φ)/φ² + ρ₂(φ − sin φ)/φ², by their series below |φ| = 1e-5."""
    phi = xi[..., 2]
    small = np.abs(phi) < _SMALL
    safe = np.where(small, 1.0, phi)
    p = np.where(small, phi / 6.0, (safe - np.sin(safe)) / safe**2)  # (φ − sin φ)/φ²
    q = np.where(small, 0.5 - phi**2 / 24.0, (1.0 - np.cos(safe)) / safe**2)  # (1 − cos φ)/φ²
    r1, r2 = xi[..., 0], xi[..., 1]
    return r1 * p - r2 * q, r1 * q + r2 * p


def se2_right_jacobian(xi: ArrayLike) -> np.ndarray:
    """Right Jacobian J_r(ξ): Exp(ξ + δ) ≈ Exp(ξ)·Exp(J_r(ξ) δ).

    Parameters
    ----------
    xi : array_like, shape (..., 3)
        Tangent vectors.

    Returns
    -------
    numpy.ndarray, shape (..., 3, 3)
        ``[[a, b, u], [−b, a, v], [0, 0, 1]]`` with a = sin φ/φ, b = (1 − cos φ)/φ.
    """
    xi = np.asarray(xi, dtype=np.float64)
    a, b = _a_b(xi[..., 2])
    u, v = _third_column(xi)
    out = np.zeros((*xi.shape[:-1], 3, 3))
    out[..., 0, 0], out[..., 0, 1], out[..., 0, 2] = a, b, u
    out[..., 1, 0], out[..., 1, 1], out[..., 1, 2] = -b, a, v
    out[..., 2, 2] = 1.0
    return out


def se2_right_jacobian_inv(xi: ArrayLike) -> np.ndarray:
    """J_r(ξ)⁻¹: Log(Exp(ξ)·Exp(ε)) ≈ ξ + J_r(ξ)⁻¹ ε, in closed form.

    Parameters
    ----------
    xi : array_like, shape (..., 3)
        Tangent vectors.

    Returns
    -------
    numpy.ndarray, shape (..., 3, 3)
    """
    xi = np.asarray(xi, dtype=np.float64)
    a, b = _a_b(xi[..., 2])
    u, v = _third_column(xi)
    det = a * a + b * b
    ia, ib = a / det, b / det  # [[a, b], [−b, a]]⁻¹ = [[a, −b], [b, a]] / det
    out = np.zeros((*xi.shape[:-1], 3, 3))
    out[..., 0, 0], out[..., 0, 1] = ia, -ib
    out[..., 1, 0], out[..., 1, 1] = ib, ia
    out[..., 0, 2] = -(ia * u - ib * v)
    out[..., 1, 2] = -(ib * u + ia * v)
    out[..., 2, 2] = 1.0
    return out
