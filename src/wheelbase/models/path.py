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

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike

from wheelbase._validate import as_float_array, nonnegative
from wheelbase.errors import ConfigError, InputError
from wheelbase.geometry import wrap_angle
from wheelbase.models.diffdrive import DiffDrive

__all__ = [
    "PoseTrajectory",
    "PureMotion",
    "pure_motions",
    "reference_from_derivatives",
    "reference_from_xy",
]


@dataclass(frozen=True)
class PoseTrajectory:
    """A timed pose trajectory: the one type wherever wheelbase means "where to be, when".

    Built from a path's derivatives (document 002 eq. 10, :func:`reference_from_derivatives`),
    by time-parametrising a planned path (:func:`wheelbase.timing.time_parametrize`) or from
    trapezoidal profiles through waypoints (:func:`wheelbase.trajectory.feasible_trajectory`);
    followed by the trackers, the computed-torque PID and the inverse dynamics.

    Attributes
    ----------
    t : numpy.ndarray, shape (T,) or None
        Sample times [s] (None when built from derivatives without times).
    poses : numpy.ndarray, shape (T, 3)
        (x [m], y [m], ψ [rad] in (−π, π]).
    twist : numpy.ndarray, shape (T, 3)
        Body twist (u [m/s], v [m/s], r [rad/s]) = J(ψ)ᵀ·η̇ (document 000 §5.2); u < 0 when
        reversing.
    twist_rate : numpy.ndarray, shape (T, 3)
        Its time derivative (u̇ [m/s²], v̇ [m/s²], ṙ [rad/s²]): exact where the builder knows
        it, else second-order differences in time (zeros without times).
    waypoints : numpy.ndarray, shape (P, 2) or None
        The waypoints (x, y) [m] it was built through, if any.
    """

    t: np.ndarray | None
    poses: np.ndarray
    twist: np.ndarray
    twist_rate: np.ndarray
    waypoints: np.ndarray | None = None
    _evaluate: Callable[[np.ndarray], PoseTrajectory] | None = field(
        default=None, repr=False, compare=False
    )

    @classmethod
    def from_speeds(
        cls, t: np.ndarray | None, poses: np.ndarray, v: np.ndarray, omega: np.ndarray
    ) -> PoseTrajectory:
        """A trajectory of a robot that cannot slide sideways: twist (v, 0, ω).

        Parameters
        ----------
        t : numpy.ndarray, shape (T,) or None
            Times [s].
        poses : numpy.ndarray, shape (T, 3)
            Poses [m, m, rad].
        v, omega : numpy.ndarray, shape (T,)
            Forward speed [m/s] and yaw rate [rad/s].
        """
        twist = np.stack([v, np.zeros_like(v), omega], -1)
        if t is not None and len(t) >= 2:
            rate = np.gradient(twist, t, axis=0)
        else:
            rate = np.zeros_like(twist)
        return cls(t, poses, twist, rate)

    @property
    def v(self) -> np.ndarray:
        """Forward speed u [m/s], shape (T,); negative when reversing."""
        return self.twist[:, 0]

    @property
    def omega(self) -> np.ndarray:
        """Yaw rate r [rad/s], shape (T,)."""
        return self.twist[:, 2]

    @property
    def curvature(self) -> np.ndarray:
        """Signed curvature κ = ω / v [1/m] along the robot's x axis (0 where v = 0)."""
        v = self.v
        with np.errstate(divide="ignore", invalid="ignore"):
            return np.where(np.abs(v) > 1e-12, self.omega / v, 0.0)

    @property
    def inputs(self) -> np.ndarray:
        """Unicycle inputs ``(T, 2)`` = (v [m/s], ω [rad/s]) for :func:`wheelbase.simulate`."""
        return np.stack([self.v, self.omega], -1)

    @property
    def duration(self) -> float:
        """Time span of the trajectory [s]."""
        if self.t is None:
            raise InputError("a trajectory built without times has no duration")
        return float(self.t[-1])

    @property
    def world_velocity(self) -> np.ndarray:
        """(ẋ, ẏ, ψ̇) ``(T, 3)`` = J(ψ)·twist."""
        c, s = np.cos(self.poses[:, 2]), np.sin(self.poses[:, 2])
        u, v, r = self.twist.T
        return np.column_stack([c * u - s * v, s * u + c * v, r])

    def at(self, times: ArrayLike) -> PoseTrajectory:
        """The same trajectory at other times [s] (clamped to its span): exact where it was
        built from a closed form, else interpolated linearly (heading unwrapped).

        Parameters
        ----------
        times : array_like, shape (T,)
            Sample times [s].
        """
        times = as_float_array("times", times, min_ndim=1, max_ndim=1)
        if self._evaluate is not None:
            return self._evaluate(times)
        if self.t is None:
            raise InputError("a trajectory built without times cannot be sampled in time")
        clamped = np.clip(times, self.t[0], self.t[-1])

        def column(values: np.ndarray) -> np.ndarray:
            return np.interp(clamped, self.t, values)

        heading = np.unwrap(self.poses[:, 2])
        poses = np.column_stack(
            [column(self.poses[:, 0]), column(self.poses[:, 1]), wrap_angle(column(heading))]
        )
        twist = np.column_stack([column(self.twist[:, k]) for k in range(3)])
        rate = np.column_stack([column(self.twist_rate[:, k]) for k in range(3)])
        return PoseTrajectory(times, poses, twist, rate, self.waypoints)

    def reference(self) -> np.ndarray:
        """Rows (x, y, ψ, u, v, r, u̇, v̇, ṙ) ``(T, 9)``: the controller's reference format."""
        return np.column_stack([self.poses, self.twist, self.twist_rate])


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
) -> PoseTrajectory:
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
    PoseTrajectory
        Its ``twist_rate`` comes from differences in time (zeros without ``t``).

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
) -> PoseTrajectory:
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
    return PoseTrajectory.from_speeds(t, poses, v, omega)


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
