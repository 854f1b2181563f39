"""Differential drive: two coaxial driven wheels (documents 000 §3.1, 001 §III, 002).

Symbols: wheel radius a (doc 000) = r (docs 001, 002); half track d (doc 000); track
L = 2·d (docs 001, 002). Wheel order is always (left, right); document 001 orders (right, left),
which is converted where its equations are quoted.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import numpy as np
from numpy.typing import ArrayLike

from wheelbase._validate import as_float_array, positive
from wheelbase.models.base import ModelBase

__all__ = ["DiffDrive"]


@dataclass(frozen=True)
class DiffDrive(ModelBase):
    """Differential-drive robot with wheel angular speeds (left, right) as inputs.

    Parameters
    ----------
    wheel_radius : float
        Wheel radius a (doc 000) or r (doc 001) [m], > 0.
    half_track : float
        Distance d from the robot centre to each wheel (doc 000) [m], > 0; the track (wheel
        separation) L of documents 001/002 is ``2 * half_track``.

    Notes
    -----
    Inputs are ``(omega_left, omega_right)`` in rad/s. The body twist is document 000's
    ζ = W·ω with W = [[a/2, a/2], [0, 0], [−a/(2d), a/(2d)]], i.e. v = a(ω_L + ω_R)/2 and
    ω = a(ω_R − ω_L)/(2d) (doc 001 eqs. 6, 8, 9).

    Examples
    --------
    >>> robot = DiffDrive(wheel_radius=0.05, half_track=0.2)
    >>> v, omega = robot.body_velocity(0.8, 0.6)
    >>> round(float(v), 3), round(float(omega), 3)
    (0.035, -0.025)
    """

    wheel_radius: float
    half_track: float

    input_names: ClassVar[tuple[str, ...]] = ("omega_left", "omega_right")
    input_units: ClassVar[tuple[str, ...]] = ("rad/s", "rad/s")

    def __post_init__(self) -> None:
        object.__setattr__(self, "wheel_radius", positive("wheel_radius", self.wheel_radius, "m"))
        object.__setattr__(self, "half_track", positive("half_track", self.half_track, "m"))

    @property
    def track(self) -> float:
        """Wheel separation L = 2·d [m] (documents 001 and 002)."""
        return 2.0 * self.half_track

    @property
    def wheel_matrix(self) -> np.ndarray:
        """Document 000's 3×2 W matrix: ζ = (u, v, r) = W·(ω_L, ω_R)."""
        a, d = self.wheel_radius, self.half_track
        return np.array([[a / 2, a / 2], [0.0, 0.0], [-a / (2 * d), a / (2 * d)]])

    def _twist(self, inputs: np.ndarray) -> np.ndarray:
        v, omega = self._unicycle(inputs[..., 0], inputs[..., 1])
        return self._stack_twist(v, np.zeros_like(v), omega)

    def _unicycle(self, left: np.ndarray, right: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        a, d = self.wheel_radius, self.half_track
        return 0.5 * a * (left + right), 0.5 * a * (right - left) / d

    def body_velocity(self, left: ArrayLike, right: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
        """Forward speed v [m/s] and yaw rate ω [rad/s] from wheel speeds [rad/s].

        v = a(ω_L + ω_R)/2, ω = a(ω_R − ω_L)/(2d) (doc 001 eqs. 6, 8 with eq. 9).

        Parameters
        ----------
        left, right : array_like
            Left and right wheel angular speeds [rad/s].
        """
        left = as_float_array("left", left)
        right = as_float_array("right", right)
        return self._unicycle(left, right)

    def wheel_speeds(self, v: ArrayLike, omega: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
        """Wheel angular speeds (left, right) [rad/s] for forward speed v [m/s], yaw rate ω.

        The inverse of :meth:`body_velocity`: ω_L = (v − dω)/a, ω_R = (v + dω)/a (doc 001
        eq. 20 with its rows swapped to (left, right)).

        Parameters
        ----------
        v : array_like
            Forward speed [m/s].
        omega : array_like
            Yaw rate [rad/s], counter-clockwise positive.
        """
        v = as_float_array("v", v)
        omega = as_float_array("omega", omega)
        a, d = self.wheel_radius, self.half_track
        return (v - d * omega) / a, (v + d * omega) / a

    def inverse(self, twist: ArrayLike) -> np.ndarray:
        """Wheel speeds ``(..., 2)`` that produce the body twist ``(..., 3)``.

        The lateral component must be zero (the wheels cannot slide sideways); a non-zero one
        is ignored, as in document 000's pseudo-inverse of W. Use :meth:`lateral_slip` to check.
        """
        twist = as_float_array("twist", twist, 3)
        left, right = self.wheel_speeds(twist[..., 0], twist[..., 2])
        return np.stack([left, right], -1)

    def icc_radius(self, left: ArrayLike, right: ArrayLike) -> np.ndarray:
        """Signed radius R [m] of the instantaneous centre of curvature (doc 001 eq. 7).

        R = d (v_R + v_L)/(v_R − v_L), positive when the ICC is on the left. It is ``inf``
        (signed by the direction of travel) when driving straight, 0 when spinning in place,
        and ``nan`` when the robot stands still; no division warning is raised.

        Parameters
        ----------
        left, right : array_like
            Left and right wheel angular speeds [rad/s].
        """
        left = as_float_array("left", left)
        right = as_float_array("right", right)
        total, diff = right + left, right - left
        with np.errstate(divide="ignore", invalid="ignore"):
            radius = self.half_track * total / diff
        straight = (diff == 0) & (total != 0)
        radius = np.where(straight, np.copysign(np.inf, total), radius)
        return np.where((diff == 0) & (total == 0), np.nan, radius)

    def pfaffian_matrix(self, pose: ArrayLike) -> np.ndarray:
        """Constraint matrix A(q) ``(..., 3, 5)`` with A(q)·q̇ = 0 (doc 001 eq. 16).

        The generalised coordinates are q = (x, y, θ, φ_L, φ_R) with φ the wheel rotation
        angles [rad]. Document 001 orders the wheel angles (φ_R, φ_L); here they are ordered
        (left, right) like everywhere in wheelbase, so the last two columns are swapped with
        respect to the printed matrix. Rows: no lateral slip (eq. 15.a), rolling without slip
        of the left wheel (eq. 15.d) and of the right wheel (eq. 15.c).
        """
        pose = as_float_array("pose", pose, 3)
        c, s = np.cos(pose[..., 2]), np.sin(pose[..., 2])
        zero, one = np.zeros_like(c), np.ones_like(c)
        d, a = self.half_track, self.wheel_radius
        rows = [
            [s, -c, zero, zero, zero],
            [c, s, -d * one, -a * one, zero],
            [c, s, d * one, zero, -a * one],
        ]
        return np.stack([np.stack(row, -1) for row in rows], -2)

    def nonholonomic_transform(self, pose: ArrayLike) -> np.ndarray:
        """T_NH(q) ``(..., 3, 2)`` with (ẋ, ẏ, θ̇) = T_NH(q)·(ω_L, ω_R) (doc 001 eq. 18).

        Document 001 multiplies (ω_R, ω_L); the columns here are in (left, right) order.
        """
        pose = as_float_array("pose", pose, 3)
        c, s = np.cos(pose[..., 2]), np.sin(pose[..., 2])
        a, big_l = self.wheel_radius, self.track
        one = np.ones_like(c)
        rows = [
            [a / 2 * c, a / 2 * c],
            [a / 2 * s, a / 2 * s],
            [-a / big_l * one, a / big_l * one],
        ]
        return np.stack([np.stack(row, -1) for row in rows], -2)
