"""Dead reckoning: wheel distances (or v, ω samples) → poses (document 003 §III, eqs. 1–7).

Over one sampling period the left and right wheels roll D_L and D_R metres. Document 003
(after E. Olson's primer, its ref. [12]) moves the robot by

- eq. 1: D_C = (D_L + D_R)/2, the distance rolled by the centre of the axle;
- eq. 2: φ = (D_R − D_L)/L, the heading change (L = track = 2·half_track);
- eqs. 3–5: θ' = θ + φ, x' = x + D_C·cos θ, y' = y + D_C·sin θ.

Eqs. 4–5 use the *unbarred* θ, i.e. the heading before the update: the robot is moved along its
old heading and turned afterwards. That is the forward-Euler step (``method="euler"``), first
order in the heading change, and it is what the document prints, so it is kept as printed. Two
better updates use the same D_C and φ:

``midpoint``  x' = x + D_C·cos(θ + φ/2): the chord of the arc is taken along the mean heading
              (second order; document 002 eq. 8's trapezoidal heading).
``exact``     the circular arc of length D_C and turn φ (the SE(2) exponential,
              :func:`wheelbase.geometry.se2_exp`): chord length D_C·sin(φ/2)/(φ/2) along
              θ + φ/2. Exact whenever the wheel-speed ratio is constant within the period.

All three give the same heading θ + φ. :func:`dead_reckon` does the same from logged forward
speed and yaw rate (v, ω) held over each sample interval (D_C = v·Δt, φ = ω·Δt); because the
heading is a cumulative sum, a whole stream is integrated with vectorised ``cumsum`` instead of
a Python loop.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from wheelbase._validate import as_float_array, check_choice, positive
from wheelbase.errors import InputError
from wheelbase.geometry import wrap_angle
from wheelbase.odometry.encoder import ticks_to_distance, ticks_to_rpm

__all__ = [
    "DEAD_RECKONING_METHODS",
    "WheelOdometry",
    "dead_reckon",
    "integrate_increments",
    "pose_increment",
]

DEAD_RECKONING_METHODS: tuple[str, ...] = ("euler", "midpoint", "exact")
"""Names of the dead-reckoning updates (see the module docstring)."""


def pose_increment(
    theta: ArrayLike, distance: ArrayLike, rotation: ArrayLike, method: str = "exact"
) -> np.ndarray:
    """World-frame displacement ``(..., 2)`` of one odometry step.

    Parameters
    ----------
    theta : array_like
        Heading before the step [rad].
    distance : array_like
        Distance rolled by the axle centre D_C [m] (document 003 eq. 1).
    rotation : array_like
        Heading change φ [rad] (document 003 eq. 2).
    method : {"euler", "midpoint", "exact"}
        The update (module docstring); ``euler`` is document 003 eqs. 4–5.

    Returns
    -------
    numpy.ndarray, shape (..., 2)
        (Δx, Δy) [m]; the heading change is ``rotation`` for every method.
    """
    check_choice("method", method, DEAD_RECKONING_METHODS)
    theta, distance, rotation = (
        np.asarray(v, dtype=np.float64) for v in (theta, distance, rotation)
    )
    if not theta.shape == distance.shape == rotation.shape:
        theta, distance, rotation = np.broadcast_arrays(theta, distance, rotation)
    if method == "euler":
        mid, chord = theta, distance
    elif method == "midpoint":
        mid, chord = theta + 0.5 * rotation, distance
    else:
        # The arc: chord D·sin(φ/2)/(φ/2) along the mid heading θ + φ/2 (exact for any φ).
        half = 0.5 * rotation
        mid = theta + half
        small = np.abs(half) < 1e-4
        safe = np.where(small, 1.0, half)
        chord = distance * np.where(small, 1.0 - half * half / 6.0, np.sin(safe) / safe)
    out = np.empty((*mid.shape, 2))
    out[..., 0] = chord * np.cos(mid)
    out[..., 1] = chord * np.sin(mid)
    return out


def integrate_increments(
    pose0: ArrayLike, distance: ArrayLike, rotation: ArrayLike, method: str = "exact"
) -> np.ndarray:
    """Chain odometry steps: poses after each of T steps of (D_C, φ), starting at ``pose0``.

    Parameters
    ----------
    pose0 : array_like, shape (..., 3)
        Starting pose(s) (x [m], y [m], θ [rad]).
    distance : array_like, shape (T, ...)
        Axle-centre distances D_C [m] of the T steps (time on the first axis; the other axes
        broadcast against ``pose0.shape[:-1]``).
    rotation : array_like, shape (T, ...)
        Heading changes φ [rad] of the T steps.
    method : {"euler", "midpoint", "exact"}
        The update (module docstring).

    Returns
    -------
    numpy.ndarray, shape (T + 1, ..., 3)
        ``pose0`` followed by the pose after each step; headings wrapped to (−π, π].
    """
    check_choice("method", method, DEAD_RECKONING_METHODS)
    pose0 = as_float_array("pose0", pose0, 3)
    distance = as_float_array("distance", distance, min_ndim=1)
    rotation = as_float_array("rotation", rotation, min_ndim=1)
    if distance.shape != rotation.shape:
        raise InputError(
            f"distance and rotation must have the same shape (got {distance.shape} and "
            f"{rotation.shape})"
        )
    # Heading before each step: θ0 + Σ_{j<k} φ_j (cumulative, unwrapped; wrapped at the end).
    theta_after = pose0[..., 2] + np.cumsum(rotation, axis=0)
    theta_before = np.concatenate(
        [np.broadcast_to(pose0[..., 2], theta_after.shape[1:])[None], theta_after[:-1]], axis=0
    )
    steps = pose_increment(theta_before, distance, rotation, method)
    xy = pose0[..., :2] + np.cumsum(steps, axis=0)
    poses = np.concatenate([xy, theta_after[..., None]], axis=-1)
    first = np.broadcast_to(pose0, poses.shape[1:])[None]
    out = np.concatenate([first, poses], axis=0)
    out[..., 2] = wrap_angle(out[..., 2])
    return out


def dead_reckon(
    t: ArrayLike,
    v: ArrayLike,
    omega: ArrayLike,
    pose0: ArrayLike,
    method: str = "exact",
) -> np.ndarray:
    """Poses from logged forward speed and yaw rate, each held until the next sample.

    Parameters
    ----------
    t : array_like, shape (T,)
        Sample times [s], strictly increasing.
    v : array_like, shape (T, ...)
        Forward speed [m/s] from time ``t[k]`` to ``t[k+1]`` (the last sample is not used).
    omega : array_like, shape (T, ...)
        Yaw rate [rad/s], held likewise.
    pose0 : array_like, shape (..., 3)
        Pose at ``t[0]`` (x [m], y [m], θ [rad]).
    method : {"euler", "midpoint", "exact"}
        ``euler`` is document 003 eqs. 1–5 with D_C = v·Δt and φ = ω·Δt; see the module
        docstring for the others.

    Returns
    -------
    numpy.ndarray, shape (T, ..., 3)
        Estimated poses at the times ``t``.

    Raises
    ------
    InputError
        Mismatched lengths, times that do not increase, non-finite values.

    Examples
    --------
    >>> t = np.linspace(0.0, np.pi, 101)          # half a turn of a 1 m radius circle
    >>> poses = dead_reckon(t, np.ones(101), np.ones(101), [0.0, 0.0, 0.0])
    >>> poses[-1].round(9).tolist() == [0.0, 2.0, 3.141592654]
    True
    """
    check_choice("method", method, DEAD_RECKONING_METHODS)
    t = as_float_array("t", t, min_ndim=1, max_ndim=1)
    v = as_float_array("v", v, min_ndim=1)
    omega = as_float_array("omega", omega, min_ndim=1)
    if t.size < 1 or v.shape[0] != t.size or omega.shape[0] != t.size:
        raise InputError(
            f"t, v and omega must have the same length >= 1 (got {t.size}, {v.shape[0]}, "
            f"{omega.shape[0]})"
        )
    dt = np.diff(t)
    if np.any(dt <= 0):
        raise InputError("t must be strictly increasing (sampling period of zero or negative)")
    dt = dt.reshape(dt.shape + (1,) * (v.ndim - 1))
    return integrate_increments(pose0, v[:-1] * dt, omega[:-1] * dt, method)


@dataclass(frozen=True)
class WheelOdometry:
    """Odometry of a differential drive from encoder tick differences (document 003 §III).

    Parameters
    ----------
    wheel_radius : float
        Nominal wheel radius r [m], > 0.
    half_track : float
        Half the (effective) wheel separation [m], > 0; document 003's L is ``2*half_track``.
    pulses_per_revolution : int
        Encoder resolution P [ticks per wheel revolution], > 0.
    method : {"euler", "midpoint", "exact"}
        The pose update (module docstring); ``euler`` is document 003 eqs. 3–5 as printed.
    scale_left, scale_right : float
        Calibration factors [–] > 0 on the left/right wheel distances (the c_L, c_R of
        UMBmark, :mod:`wheelbase.odometry.calibration`); 1 for an uncalibrated robot.

    Examples
    --------
    >>> odo = WheelOdometry(wheel_radius=0.05, half_track=0.2, pulses_per_revolution=1000)
    >>> odo.update([0.0, 0.0, 0.0], [1000, 1000]).round(6).tolist()  # one revolution each
    [0.314159, 0.0, 0.0]
    """

    wheel_radius: float
    half_track: float
    pulses_per_revolution: int
    method: str = "exact"
    scale_left: float = 1.0
    scale_right: float = 1.0

    def __post_init__(self) -> None:
        object.__setattr__(self, "wheel_radius", positive("wheel_radius", self.wheel_radius, "m"))
        object.__setattr__(self, "half_track", positive("half_track", self.half_track, "m"))
        ticks_to_distance(0, self.pulses_per_revolution, 1.0)  # validates P
        object.__setattr__(self, "pulses_per_revolution", int(self.pulses_per_revolution))
        check_choice("method", self.method, DEAD_RECKONING_METHODS)
        object.__setattr__(self, "scale_left", positive("scale_left", self.scale_left))
        object.__setattr__(self, "scale_right", positive("scale_right", self.scale_right))

    @property
    def track(self) -> float:
        """Wheel separation L = 2·half_track [m] (document 003 eq. 2)."""
        return 2.0 * self.half_track

    def wheel_distances(self, ticks: ArrayLike) -> np.ndarray:
        """Distances (D_L, D_R) [m] rolled for tick differences ``(..., 2)`` (doc 003 eq. 7)."""
        if not (
            isinstance(ticks, np.ndarray) and ticks.dtype == np.int64 and ticks.shape[-1:] == (2,)
        ):
            ticks = as_float_array("ticks", ticks, 2)  # integer counts need no finiteness check
        # eq. 7, 2π·r·Δn/P per wheel (P and r were checked when the odometry was made)
        scale = 2.0 * math.pi * self.wheel_radius / self.pulses_per_revolution
        return ticks * (scale * np.array([self.scale_left, self.scale_right]))

    def increments(self, ticks: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
        """Axle distance D_C [m] and heading change φ [rad] (document 003 eqs. 1–2).

        Parameters
        ----------
        ticks : array_like, shape (..., 2)
            Tick differences (left, right) over one or more periods.
        """
        distances = self.wheel_distances(ticks)
        left, right = distances[..., 0], distances[..., 1]
        return 0.5 * (left + right), (right - left) / self.track

    def wheel_rpm(self, ticks: ArrayLike, period: float) -> np.ndarray:
        """Wheel speeds (left, right) [RPM] from tick differences (eq. 6 for any period).

        Parameters
        ----------
        ticks : array_like, shape (..., 2)
            Tick differences (left, right).
        period : float
            Sampling period [s], > 0.
        """
        ticks = as_float_array("ticks", ticks, 2)
        return ticks_to_rpm(ticks, self.pulses_per_revolution, period)

    def velocity(self, ticks: ArrayLike, period: float) -> tuple[np.ndarray, np.ndarray]:
        """Mean forward speed v [m/s] and yaw rate ω [rad/s] over a period.

        Parameters
        ----------
        ticks : array_like, shape (..., 2)
            Tick differences (left, right).
        period : float
            Sampling period [s], > 0.
        """
        period = positive("period", period, "s")
        distance, rotation = self.increments(ticks)
        return distance / period, rotation / period

    def update(self, pose: ArrayLike, ticks: ArrayLike) -> np.ndarray:
        """Pose(s) after one period with tick differences ``ticks``.

        Parameters
        ----------
        pose : array_like, shape (..., 3)
            Pose(s) before the period (x [m], y [m], θ [rad]).
        ticks : array_like, shape (..., 2)
            Tick differences (left, right) counted during the period.

        Returns
        -------
        numpy.ndarray, shape (..., 3)
            The updated poses, heading wrapped to (−π, π].
        """
        pose = as_float_array("pose", pose, 3)
        distance, rotation = self.increments(ticks)
        step = pose_increment(pose[..., 2], distance, rotation, self.method)
        theta = wrap_angle(pose[..., 2] + rotation)
        xy = pose[..., :2] + step
        return np.concatenate([xy, np.asarray(theta)[..., None]], axis=-1)

    def integrate(self, pose0: ArrayLike, ticks: ArrayLike) -> np.ndarray:
        """Poses along a stream of tick differences (vectorised over time).

        Parameters
        ----------
        pose0 : array_like, shape (..., 3)
            Starting pose(s).
        ticks : array_like, shape (T, ..., 2)
            Tick differences (left, right) of T successive periods.

        Returns
        -------
        numpy.ndarray, shape (T + 1, ..., 3)
            ``pose0`` then the pose after each period.
        """
        ticks = as_float_array("ticks", ticks, 2, min_ndim=2)
        distance, rotation = self.increments(ticks)
        return integrate_increments(pose0, distance, rotation, self.method)
