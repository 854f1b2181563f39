"""Steered models: front-driven bicycle, rear-driven bicycle and Ackermann car (document 002).

Every model here has the inputs ``(speed, steering)`` [m/s, rad], in that order (the (v, δ)
commands of the controllers), and its reference point on the rear axle, where the body velocity
has no lateral component (v = 0 in ζ = (u, v, r)).

Steering limits. ``max_steering`` (0 < max_steering < π/2) is a mechanical stop: a steering
input beyond it, but still inside (−π/2, π/2), is clipped to ±max_steering by the model (in
``twist``, ``icc_radius`` and the Ackermann wheel angles), as a real steering rack would
stop there. A steering input with |steering| >= π/2 is not a steering angle at all (the wheel
would be across or behind its axle) and raises :class:`~wheelbase.errors.InputError`, as does
asking ``inverse`` for a turn that needs more steering than ``max_steering``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import ClassVar

import numpy as np
from numpy.typing import ArrayLike

from wheelbase._validate import as_float_array, finite, positive
from wheelbase.errors import ConfigError, InputError
from wheelbase.models.base import ModelBase

__all__ = ["Ackermann", "Bicycle", "RearWheelBicycle"]


def _check_max_steering(value: float) -> float:
    angle = finite("max_steering", value, "rad")
    if not 0.0 < angle < math.pi / 2:
        raise ConfigError(f"max_steering must be in (0, π/2) rad (got {angle:g})")
    return angle


def _check_steering_range(steering: np.ndarray) -> None:
    outside = np.abs(steering) >= math.pi / 2
    if np.any(outside):
        worst = float(steering[outside].flat[0])
        raise InputError(
            f"steering must be in (−π/2, π/2) rad (got {worst:g} rad = {math.degrees(worst):g}°)"
        )


class _Steered(ModelBase):
    """Shared plumbing of the steered models (fields ``wheel_base`` and ``max_steering``)."""

    wheel_base: float
    max_steering: float

    input_names: ClassVar[tuple[str, ...]] = ("speed", "steering")
    input_units: ClassVar[tuple[str, ...]] = ("m/s", "rad")

    def _check_common(self) -> None:
        object.__setattr__(self, "wheel_base", positive("wheel_base", self.wheel_base, "m"))
        object.__setattr__(self, "max_steering", _check_max_steering(self.max_steering))

    def validate_inputs(self, inputs: ArrayLike) -> np.ndarray:
        """Return inputs ``(..., 2)`` = (speed [m/s], steering [rad]) as a float array.

        Raises
        ------
        InputError
            On a wrong shape, NaN/inf, or |steering| >= π/2.
        """
        values = super().validate_inputs(inputs)
        _check_steering_range(values[..., 1])
        return values

    def clip_steering(self, steering: ArrayLike) -> np.ndarray:
        """Steering [rad] after the mechanical stop: clipped to ±``max_steering``.

        Raises
        ------
        InputError
            If |steering| >= π/2 or it is not finite.
        """
        steering = as_float_array("steering", steering)
        _check_steering_range(steering)
        return np.clip(steering, -self.max_steering, self.max_steering)

    def icc_radius(self, steering: ArrayLike) -> np.ndarray:
        """Signed radius [m] from the ICC to the rear-axle reference point.

        R = L / tan δ (document 002 eq. 11 with d = L), positive when turning left, ``inf`` for
        δ = 0 (no division warning). The steering is clipped to ±``max_steering`` first.
        """
        tan = np.tan(self.clip_steering(steering))
        with np.errstate(divide="ignore"):
            radius = self.wheel_base / tan
        return np.where(tan == 0.0, np.inf, radius)

    def _speed_steering(self, twist: ArrayLike, rate_name: str) -> tuple[np.ndarray, np.ndarray]:
        """Split twists into (u, r) and reject u = 0 with r ≠ 0, which no steering produces."""
        twist = as_float_array("twist", twist, 3)
        u, r = twist[..., 0], twist[..., 2]
        spin = (u == 0.0) & (r != 0.0)
        if np.any(spin):
            raise InputError(
                f"{type(self).__name__} cannot turn in place: a twist with u = 0 and "
                f"r ≠ 0 needs |{rate_name}| = 90° (got r = {float(r[spin].flat[0]):g} rad/s)"
            )
        return u, r

    def _check_reachable(self, steering: np.ndarray) -> None:
        beyond = np.abs(steering) > self.max_steering * (1.0 + 1e-12)
        if np.any(beyond):
            worst = float(np.max(np.abs(steering[beyond])))
            raise InputError(
                f"the twist needs a steering angle of {worst:g} rad, beyond "
                f"max_steering = {self.max_steering:g} rad"
            )


@dataclass(frozen=True)
class Bicycle(_Steered):
    """Bicycle with the front wheel steered AND driven (document 002 eqs. 11–16).

    Parameters
    ----------
    wheel_base : float
        Distance d between the rear and the front wheel [m], > 0.
    max_steering : float
        Steering stop [rad], in (0, π/2); default 1.2 rad (≈ 69°).

    Notes
    -----
    Inputs are ``(speed, steering)``: ``speed`` is the ground speed of the front wheel
    v_S = ω_S·r [m/s] (doc 002 eq. 13) and ``steering`` its angle α [rad]. The reference point
    is the rear axle: u = v_S cos α, v = 0, r = v_S sin α / d (doc 002 eqs. 14–16), and the
    ICC lies at R = d / tan α (eq. 11) to the left of it.

    Examples
    --------
    >>> bike = Bicycle(wheel_base=1.0)
    >>> np.round(bike.twist([2.0, np.pi / 6]), 6).tolist()
    [1.732051, 0.0, 1.0]
    """

    wheel_base: float
    max_steering: float = 1.2

    def __post_init__(self) -> None:
        self._check_common()

    def _twist(self, inputs: np.ndarray) -> np.ndarray:
        speed = inputs[..., 0]
        alpha = np.clip(inputs[..., 1], -self.max_steering, self.max_steering)
        return self._stack_twist(
            speed * np.cos(alpha), np.zeros_like(speed), speed * np.sin(alpha) / self.wheel_base
        )

    def inverse(self, twist: ArrayLike) -> np.ndarray:
        """Inputs ``(..., 2)`` = (v_S, α) that produce body twists ``(..., 3)``.

        α = atan(d·r/u), v_S = sign(u)·√(u² + (d·r)²), so that reversing (u < 0) gives v_S < 0
        with the same steering sense. The lateral component is ignored (the wheels cannot slide).

        Raises
        ------
        InputError
            If u = 0 and r ≠ 0 (it needs α = 90°), or the needed |α| exceeds ``max_steering``.
        """
        u, r = self._speed_steering(twist, "α")
        lateral = self.wheel_base * r
        safe_u = np.where(u == 0.0, 1.0, u)
        alpha = np.where(u == 0.0, 0.0, np.arctan(lateral / safe_u))
        self._check_reachable(alpha)
        speed = np.where(u < 0.0, -1.0, 1.0) * np.hypot(u, lateral)
        return np.stack([speed, alpha], -1)


class _RearDriven(_Steered):
    """Motion of a rear-driven bicycle: u = v, r = v·tan δ / L (shared by Ackermann)."""

    def _twist(self, inputs: np.ndarray) -> np.ndarray:
        speed = inputs[..., 0]
        delta = np.clip(inputs[..., 1], -self.max_steering, self.max_steering)
        return self._stack_twist(
            speed, np.zeros_like(speed), speed * np.tan(delta) / self.wheel_base
        )

    def inverse(self, twist: ArrayLike) -> np.ndarray:
        """Inputs ``(..., 2)`` = (v, δ) for body twists ``(..., 3)``: v = u, δ = atan(L·r/u).

        Reversing works: u < 0 gives v < 0, and δ keeps the sign that makes r right. The lateral
        component is ignored (the wheels cannot slide sideways).

        Raises
        ------
        InputError
            If u = 0 and r ≠ 0, or the needed |δ| exceeds ``max_steering``.
        """
        u, r = self._speed_steering(twist, "δ")
        safe_u = np.where(u == 0.0, 1.0, u)
        delta = np.where(u == 0.0, 0.0, np.arctan(self.wheel_base * r / safe_u))
        self._check_reachable(delta)
        return np.stack([u + 0.0, delta], -1)


@dataclass(frozen=True)
class RearWheelBicycle(_RearDriven):
    """Bicycle with the front wheel steered and the rear wheel driven.

    Parameters
    ----------
    wheel_base : float
        Distance L between the axles [m], > 0.
    max_steering : float
        Steering stop [rad], in (0, π/2); default 0.6 rad (≈ 34°).

    Notes
    -----
    Inputs are ``(speed, steering)``: the rear-axle speed v [m/s] and the front-wheel angle δ
    [rad]. u = v, v_lat = 0, r = v·tan δ / L; the path is a circle of radius L / tan δ.

    Examples
    --------
    >>> car = RearWheelBicycle(wheel_base=2.0)
    >>> np.round(car.twist([1.0, 0.5]), 6).tolist()
    [1.0, 0.0, 0.273151]
    """

    wheel_base: float
    max_steering: float = 0.6

    def __post_init__(self) -> None:
        self._check_common()


@dataclass(frozen=True)
class Ackermann(_RearDriven):
    """Car with Ackermann steering: a rear-wheel bicycle plus the real front-wheel angles.

    Parameters
    ----------
    wheel_base : float
        Distance L between the axles [m], > 0.
    track : float
        Distance w between the left and right front wheels [m], > 0.
    max_steering : float
        Stop of the virtual centre wheel [rad], in (0, π/2) and small enough that the ICC stays
        outside the inner wheel: tan(max_steering) < 2L/w. Default 0.6 rad.

    Notes
    -----
    The motion is that of :class:`RearWheelBicycle` for the virtual wheel at the centre of the
    front axle (inputs ``(speed, steering)`` = rear-axle-centre speed and virtual angle δ).
    :meth:`wheel_angles` gives the angles of the two real wheels whose axes meet at the same
    ICC, :meth:`rear_wheel_speeds` the ground speeds of the rear wheels.
    """

    wheel_base: float
    track: float
    max_steering: float = 0.6

    def __post_init__(self) -> None:
        self._check_common()
        object.__setattr__(self, "track", positive("track", self.track, "m"))
        limit = math.atan(2.0 * self.wheel_base / self.track)
        if self.max_steering >= limit:
            raise ConfigError(
                f"max_steering must be < atan(2·wheel_base/track) = {limit:g} rad so that the "
                f"turning centre stays outside the inner wheel (got {self.max_steering:g})"
            )

    def wheel_angles(self, steering: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
        """Angles (left, right) [rad] of the front wheels for the virtual angle δ [rad].

        tan δ_L = L tan δ / (L − (w/2) tan δ), tan δ_R = L tan δ / (L + (w/2) tan δ), computed
        as atan2(L sin δ, L cos δ ∓ (w/2) sin δ): smooth through δ = 0, no division. Turning
        left (δ > 0), the left wheel is the inner one and turns more. δ is clipped to
        ±``max_steering`` first.
        """
        delta = self.clip_steering(steering)
        s, c = np.sin(delta), np.cos(delta)
        big_l, half_w = self.wheel_base, 0.5 * self.track
        left = np.arctan2(big_l * s, big_l * c - half_w * s)
        right = np.arctan2(big_l * s, big_l * c + half_w * s)
        return left, right

    def rear_wheel_speeds(
        self, speed: ArrayLike, steering: ArrayLike
    ) -> tuple[np.ndarray, np.ndarray]:
        """Ground speeds (left, right) [m/s] of the rear wheels (an ideal differential).

        v_L = v (1 − (w/2) tan δ / L), v_R = v (1 + (w/2) tan δ / L): each wheel moves on its
        own circle about the ICC. Divide by the wheel radius for angular speeds.

        Parameters
        ----------
        speed : array_like
            Speed v of the rear-axle centre [m/s] (negative when reversing).
        steering : array_like
            Virtual centre-wheel angle δ [rad], |δ| < π/2, clipped to ±``max_steering``.
        """
        speed = as_float_array("speed", speed)
        tan = np.tan(self.clip_steering(steering))
        ratio = 0.5 * self.track * tan / self.wheel_base
        return speed * (1.0 - ratio), speed * (1.0 + ratio)
