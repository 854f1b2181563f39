"""Inertial parameters: a payload added to a rigid body, and the dynamics' regressor in them.

A payload of mass m_p with its CG at p (body frame at the centroid B) and yaw inertia I_p about
its own CG, carried by a body (m, c, I_z about c), makes the body

    m' = m + m_p,    c' = (m·c + m_p·p)/m',
    I' = I_z + m·|c − c'|² + I_p + m_p·|p − c'|²   (about c', parallel-axis theorem).

Document 000's dynamics are linear in the inertial parameters θ = (m, m·x_c, m·y_c, I_B) —
mass, first moments of mass about B (the CG moment), yaw inertia about B,
I_B = I_z + m(x_c² + y_c²). Writing out M·V̇ + C(V)·V = τ (:mod:`wheelbase.dynamics`):

    F_x = m(u̇ − r·v) − (m x_c)·r² − (m y_c)·ṙ
    F_y = m(v̇ + r·u) + (m x_c)·ṙ − (m y_c)·r²
    M_z = (m x_c)(v̇ + r·u) + (m y_c)(r·v − u̇) + I_B·ṙ

so τ = Y(V, V̇)·θ with the 3×4 regressor Y of :func:`regressor` (v = v̇ = 0 gives the no-slip
model; its F_y is the ground's constraint force). θ is additive: the θ of a body with a
payload is the sum of both θs (:func:`inertial_parameters`), which is why an unknown payload is
an unknown θ that a linear estimator can learn (:mod:`wheelbase.control.adaptive`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from wheelbase._validate import as_float_array, finite
from wheelbase.dynamics import RigidBody
from wheelbase.errors import ConfigError

__all__ = [
    "PARAMETER_NAMES",
    "Payload",
    "body_from_parameters",
    "inertial_parameters",
    "regressor",
    "with_payload",
]

PARAMETER_NAMES: tuple[str, ...] = ("mass", "moment_x", "moment_y", "inertia_b")
"""θ = (m [kg], m·x_c [kg·m], m·y_c [kg·m], I_B [kg·m²])."""


@dataclass(frozen=True)
class Payload:
    """A load carried by the robot.

    Parameters
    ----------
    mass : float
        Mass m_p [kg], ≥ 0.
    position : tuple of float
        Its CG (x [m], y [m]) in the body frame at the centroid B.
    inertia : float
        Yaw inertia about its own CG [kg·m²], ≥ 0 (0: a point mass).
    height : float or None
        Height of its CG above the ground [m], ≥ 0 (None: the robot's CG height).

    Examples
    --------
    >>> from wheelbase.dynamics import RM100
    >>> body = with_payload(RM100.body, Payload(26.2, (0.01, 0.0)))
    >>> body.mass, body.cg_offset, round(body.inertia, 3)
    (52.4, (0.01, 0.0), 1.14)
    """

    mass: float
    position: tuple[float, float] = (0.0, 0.0)
    inertia: float = 0.0
    height: float | None = None

    def __post_init__(self) -> None:
        mass = finite("payload mass", self.mass, "kg")
        if mass < 0:
            raise ConfigError(f"payload mass must be >= 0 kg (got {mass:g})")
        inertia = finite("payload inertia", self.inertia, "kg·m²")
        if inertia < 0:
            raise ConfigError(f"payload inertia must be >= 0 kg·m² (got {inertia:g})")
        position = as_float_array("payload position", self.position, 2, max_ndim=1)
        object.__setattr__(self, "mass", mass)
        object.__setattr__(self, "inertia", inertia)
        object.__setattr__(self, "position", (float(position[0]), float(position[1])))
        if self.height is not None:
            height = finite("payload height", self.height, "m")
            if height < 0:
                raise ConfigError(f"payload height must be >= 0 m (got {height:g})")
            object.__setattr__(self, "height", height)

    def check_footprint(self, length: float, width: float, center_offset: float = 0.0) -> None:
        """Raise ConfigError unless the payload's CG lies on the robot's rectangular footprint.

        Parameters
        ----------
        length, width : float
            Footprint (length, width) [m].
        center_offset : float
            Footprint centre ahead of B [m].
        """
        x, y = self.position
        if abs(x - center_offset) > length / 2 + 1e-12 or abs(y) > width / 2 + 1e-12:
            raise ConfigError(
                f"payload position ({x:g}, {y:g}) m lies outside the robot's footprint: x must "
                f"be in [{center_offset - length / 2:g}, {center_offset + length / 2:g}] m and "
                f"y in [{-width / 2:g}, {width / 2:g}] m"
            )


def with_payload(body: RigidBody, payload: Payload | None) -> RigidBody:
    """The rigid body carrying ``payload`` (module docstring); the body itself without one.

    Parameters
    ----------
    body : RigidBody
        The robot.
    payload : Payload or None
        What it carries.
    """
    if payload is None or payload.mass == 0.0:
        return body
    m, (xc, yc) = body.mass, body.cg_offset
    mp, (xp, yp) = payload.mass, payload.position
    total = m + mp
    cx, cy = (m * xc + mp * xp) / total, (m * yc + mp * yp) / total
    inertia = (
        body.inertia
        + m * ((xc - cx) ** 2 + (yc - cy) ** 2)
        + payload.inertia
        + mp * ((xp - cx) ** 2 + (yp - cy) ** 2)
    )
    return RigidBody(total, inertia, (cx, cy))


def inertial_parameters(body: RigidBody) -> np.ndarray:
    """θ = (m, m·x_c, m·y_c, I_B) of a body (module docstring).

    Parameters
    ----------
    body : RigidBody
        The body.
    """
    m, (xc, yc) = body.mass, body.cg_offset
    return np.array([m, m * xc, m * yc, body.inertia_centroid])


def body_from_parameters(theta: ArrayLike) -> RigidBody:
    """The rigid body of θ = (m, m·x_c, m·y_c, I_B) (the inverse of
    :func:`inertial_parameters`); ConfigError unless m > 0 and I_B > m·|c|².

    Parameters
    ----------
    theta : array_like, shape (4,)
        Inertial parameters.
    """
    m, mx, my, ib = (float(v) for v in as_float_array("theta", theta, 4, max_ndim=1))
    if m <= 0:
        raise ConfigError(f"mass must be > 0 kg (got {m:g})")
    return RigidBody(m, ib, (mx / m, my / m), inertia_about="centroid")


def regressor(velocity: ArrayLike, acceleration: ArrayLike) -> np.ndarray:
    """Y(V, V̇) ``(..., 3, 4)`` with (F_x, F_y, M_z) = Y·θ (module docstring).

    Parameters
    ----------
    velocity : array_like, shape (..., 3)
        Body twist V = (u [m/s], v [m/s], r [rad/s]).
    acceleration : array_like, shape (..., 3)
        V̇ = (u̇ [m/s²], v̇ [m/s²], ṙ [rad/s²]).

    Examples
    --------
    >>> from wheelbase.dynamics import RM100
    >>> V, dV = np.array([0.3, 0.0, 0.5]), np.array([0.2, 0.0, 0.1])
    >>> np.allclose(regressor(V, dV) @ inertial_parameters(RM100.body),
    ...             RM100.body.inverse(V, dV))
    True
    """
    vel = as_float_array("velocity", velocity, 3)
    acc = as_float_array("acceleration", acceleration, 3)
    vel, acc = np.broadcast_arrays(vel, acc)
    u, v, r = vel[..., 0], vel[..., 1], vel[..., 2]
    du, dv, dr = acc[..., 0], acc[..., 1], acc[..., 2]
    out = np.zeros((*u.shape, 3, 4))
    out[..., 0, 0], out[..., 0, 1], out[..., 0, 2] = du - r * v, -r * r, -dr
    out[..., 1, 0], out[..., 1, 1], out[..., 1, 2] = dv + r * u, dr, -r * r
    out[..., 2, 1], out[..., 2, 2], out[..., 2, 3] = dv + r * u, r * v - du, dr
    return out
