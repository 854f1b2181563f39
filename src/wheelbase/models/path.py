"""Inverse kinematics of a desired path x(t), y(t), and the two pure motions (document 002).

Document 002 eq. 10: a robot that follows x(t), y(t) with its heading tangent to the path needs

    v(t) = ±√(ẋ² + ẏ²)                 (+ forward, − reverse)
    Φ(t) = atan2(ẏ, ẋ) + l·π            (l = 0 forward, 1 reverse)
    ω(t) = (ẋÿ − ẏẍ) / (ẋ² + ẏ²) = v(t)·κ(t)

with κ the signed curvature of the path along the direction of travel (κ = ω / v). Where the
speed vanishes the heading is undefined and these functions raise an InputError naming the sample.

Document 002 eq. 9 gives the two pure motions of a differential drive: straight ahead
(v_R = v_L, ω = 0) and turning in place (v_R = −v_L, ω = 2 v_R / L).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from wheelbase._validate import as_float_array, nonnegative
from wheelbase.errors import ConfigError, InputError
from wheelbase.geometry import wrap_angle
from wheelbase.models.diffdrive import DiffDrive

__all__ = [
    "PathReference",
    "PureMotion",
    "pure_motions",
    "reference_from_derivatives",
    "reference_from_xy",
]


@dataclass(frozen=True)
class PathReference:
    """Reference states and unicycle inputs along a desired path (document 002 eq. 10).

    Attributes
    ----------
    t : numpy.ndarray, shape (T,) or None
        Times [s] (None when built from derivatives without times).
    poses : numpy.ndarray, shape (T, 3)
        Reference poses (x [m], y [m], Φ [rad] wrapped to (−π, π]).
    v : numpy.ndarray, shape (T,)
        Forward speed [m/s]; negative when reversing.
    omega : numpy.ndarray, shape (T,)
        Yaw rate Φ̇ [rad/s].
    curvature : numpy.ndarray, shape (T,)
        Signed curvature κ = ω / v [1/m] (positive turning left in the direction of travel of
        the robot's x axis).
    """

    t: np.ndarray | None
    poses: np.ndarray
    v: np.ndarray
    omega: np.ndarray
    curvature: np.ndarray

    @property
    def inputs(self) -> np.ndarray:
        """Unicycle inputs ``(T, 2)`` = (v [m/s], ω [rad/s]) for :func:`wheelbase.simulate`."""
        return np.stack([self.v, self.omega], -1)


def reference_from_derivatives(
    x: ArrayLike,
    y: ArrayLike,
    xd: ArrayLike,
    yd: ArrayLike,
    xdd: ArrayLike,
    ydd: ArrayLike,
    *,
    reverse: bool = False,
    t: ArrayLike | None = None,
    min_speed: float = 1e-9,
) -> PathReference:
    """Reference (pose, v, ω, κ) from a path and its analytic time derivatives.

    Parameters
    ----------
    x, y : array_like, shape (T,) or scalar
        Path points [m] (world frame).
    xd, yd : array_like
        First derivatives ẋ, ẏ [m/s].
    xdd, ydd : array_like
        Second derivatives ẍ, ÿ [m/s²].
    reverse : bool
        Drive the path backwards (v < 0, heading = atan2(ẏ, ẋ) + π), document 002 eq. 10.
    t : array_like, optional
        Times [s] to store in the result.
    min_speed : float
        Speeds √(ẋ² + ẏ²) at or below this [m/s] are treated as a stop, where the heading is
        undefined.

    Returns
    -------
    PathReference

    Raises
    ------
    InputError
        On non-finite values, shapes that do not broadcast to one axis, or a stop (the message
        names the first sample index where the speed is ~0).

    Examples
    --------
    >>> s = np.linspace(0.0, 1.0, 3)
    >>> ref = reference_from_derivatives(np.cos(s), np.sin(s), -np.sin(s), np.cos(s),
    ...                                  -np.cos(s), -np.sin(s))
    >>> np.allclose(ref.v, 1.0), np.allclose(ref.omega, 1.0), np.allclose(ref.curvature, 1.0)
    (True, True, True)
    """
    names = ("x", "y", "xd", "yd", "xdd", "ydd")
    values = (x, y, xd, yd, xdd, ydd)
    arrays = [as_float_array(n, a, max_ndim=1) for n, a in zip(names, values, strict=True)]
    try:
        arrays = [np.atleast_1d(a).astype(np.float64) for a in np.broadcast_arrays(*arrays)]
    except ValueError:
        shapes = ", ".join(f"{n}{np.shape(a)}" for n, a in zip(names, arrays, strict=True))
        raise InputError(f"path arrays must have matching shapes (got {shapes})") from None
    times = None
    if t is not None:
        times = np.atleast_1d(as_float_array("t", t, max_ndim=1)).astype(np.float64)
        if times.shape != arrays[0].shape:
            raise InputError(f"t must have shape {arrays[0].shape} (got {times.shape})")
    return _reference(*arrays, times, bool(reverse), nonnegative("min_speed", min_speed, "m/s"))


def reference_from_xy(
    t: ArrayLike,
    x: ArrayLike,
    y: ArrayLike,
    *,
    reverse: bool = False,
    min_speed: float = 1e-9,
) -> PathReference:
    """Reference (pose, v, ω, κ) from a path sampled at times ``t``.

    The derivatives are estimated with ``np.gradient`` (second order inside and at the edges,
    non-uniform ``t`` allowed), then document 002 eq. 10 is applied as in
    :func:`reference_from_derivatives`.

    Parameters
    ----------
    t : array_like, shape (T,)
        Strictly increasing times [s], T >= 3.
    x, y : array_like, shape (T,)
        Path points [m].
    reverse : bool
        Drive the path backwards (v < 0, heading flipped by π).
    min_speed : float
        Speeds at or below this [m/s] count as a stop (heading undefined).

    Raises
    ------
    InputError
        On mismatched shapes, fewer than 3 samples, times not strictly increasing, non-finite
        values, or a stop (the message names the sample index).
    """
    t = as_float_array("t", t, min_ndim=1, max_ndim=1)
    x = as_float_array("x", x, min_ndim=1, max_ndim=1)
    y = as_float_array("y", y, min_ndim=1, max_ndim=1)
    if not t.shape == x.shape == y.shape:
        raise InputError(
            f"t, x and y must have the same shape (got {t.shape}, {x.shape}, {y.shape})"
        )
    if t.size < 3:
        raise InputError(f"a sampled path needs at least 3 samples (got {t.size})")
    steps = np.diff(t)
    if np.any(steps <= 0.0):
        index = int(np.argmax(steps <= 0.0)) + 1
        raise InputError(f"t must be strictly increasing (sample {index}: t = {t[index]:g} s)")
    xd = np.gradient(x, t, edge_order=2)
    yd = np.gradient(y, t, edge_order=2)
    xdd = np.gradient(xd, t, edge_order=2)
    ydd = np.gradient(yd, t, edge_order=2)
    return _reference(
        x, y, xd, yd, xdd, ydd, t, bool(reverse), nonnegative("min_speed", min_speed, "m/s")
    )


def _reference(x, y, xd, yd, xdd, ydd, t, reverse, min_speed):
    speed_sq = xd * xd + yd * yd
    speed = np.sqrt(speed_sq)
    stopped = speed <= min_speed
    if np.any(stopped):
        index = int(np.argmax(stopped))
        raise InputError(
            f"the path speed is ~0 at sample {index} (√(ẋ² + ẏ²) = {speed[index]:g} m/s "
            f"<= min_speed = {min_speed:g}): the heading is undefined there"
        )
    heading = np.arctan2(yd, xd)
    if reverse:
        heading = heading + np.pi
    v = -speed if reverse else speed
    omega = (xd * ydd - yd * xdd) / speed_sq
    poses = np.stack([x, y, wrap_angle(heading)], -1)
    return PathReference(t=t, poses=poses, v=v, omega=omega, curvature=omega / v)


@dataclass(frozen=True)
class PureMotion:
    """One pure motion of a differential drive (document 002 eq. 9).

    Attributes
    ----------
    wheel_speeds : numpy.ndarray, shape (..., 2)
        Wheel angular speeds (left, right) [rad/s], the :class:`DiffDrive` inputs.
    wheel_linear_speeds : numpy.ndarray, shape (..., 2)
        Wheel ground speeds (v_L, v_R) [m/s].
    v : numpy.ndarray
        Forward speed [m/s].
    omega : numpy.ndarray
        Yaw rate [rad/s].
    """

    wheel_speeds: np.ndarray
    wheel_linear_speeds: np.ndarray
    v: np.ndarray
    omega: np.ndarray


def pure_motions(model: DiffDrive, wheel_linear_speed: ArrayLike) -> tuple[PureMotion, PureMotion]:
    """The two pure motions of document 002 eq. 9 for a right-wheel ground speed v_R.

    - straight: v_L = v_R, ω = 0, v = v_R;
    - rotation (turn in place): v_L = −v_R, ω = 2 v_R / L, v = 0 (counter-clockwise for v_R > 0).

    Parameters
    ----------
    model : DiffDrive
        The robot (wheel radius a and track L = 2·half_track).
    wheel_linear_speed : array_like
        Right-wheel ground speed v_R [m/s].

    Returns
    -------
    (straight, rotation) : tuple of PureMotion
    """
    if not isinstance(model, DiffDrive):
        raise ConfigError(f"model must be a DiffDrive (got {type(model).__name__})")
    v_r = as_float_array("wheel_linear_speed", wheel_linear_speed)
    a = model.wheel_radius
    zero = np.zeros_like(v_r)
    straight_linear = np.stack([v_r, v_r], -1)
    turn_linear = np.stack([-v_r, v_r], -1)
    straight = PureMotion(straight_linear / a, straight_linear, v_r.copy(), zero)
    rotation = PureMotion(
        turn_linear / a, turn_linear, zero.copy(), np.asarray(2.0 * v_r / model.track)
    )
    return straight, rotation
