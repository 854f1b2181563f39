"""Trapezoidal velocity profiles through waypoints, and pose trajectories for a differential drive.

:func:`trapezoidal` works like MATLAB's ``trapveltraj`` (document 000 §5.2 uses its Simulink
block): the trajectory stops at every waypoint and, on each segment, every coordinate follows a
trapezoidal velocity profile — accelerate, cruise, decelerate — with one common time law
s(t) ∈ [0, 1], so that the path between waypoints is the straight segment. The segment duration
is the shortest that keeps every coordinate within its peak velocity (and peak acceleration):

- with neither ``acceleration_time`` nor ``peak_acceleration``: each phase takes a third of
  the segment, T = 1.5·|Δq|/v_peak (``trapveltraj``'s default ratio);
- with ``acceleration_time`` t_a: T = |Δq|/v_peak + t_a (at least 2·t_a: triangular profile);
- with ``peak_acceleration`` a: t_a = v/a and T = |Δq|/v + v/a, or the triangular profile
  T = 2·√(|Δq|/a) when the peak velocity is not reached.

A differential drive must also point along its velocity. :func:`heading_from_velocity` takes
the heading ψ = atan2(ẏ, ẋ) of the velocity (document 000 fig. 5.7 differences positions,
ψ = atan(Δy/Δx): noisy, wrong by π when moving left, undefined at a stop); at a stop-over
waypoint where the direction changes, ψ jumps — a yaw rate no robot can follow. The feasible
variant :func:`feasible_trajectory` inserts a turn in place, with its own trapezoidal profile,
before every segment whose direction differs from the current heading.

Two types, on purpose: :class:`Trajectory` is a *position* profile (x(t), y(t) and their
derivatives through waypoints, no heading: what ``trapveltraj`` returns), and both
:func:`heading_from_velocity` and :func:`feasible_trajectory` turn it into the one timed pose
trajectory of wheelbase, :class:`wheelbase.models.PoseTrajectory`, which every tracker,
controller and the inverse dynamics take.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike

from wheelbase._validate import as_float_array, finite, positive
from wheelbase.errors import ConfigError, InputError
from wheelbase.geometry import wrap_angle
from wheelbase.models.path import PoseTrajectory

__all__ = [
    "Trajectory",
    "feasible_trajectory",
    "heading_from_velocity",
    "trapezoidal",
]


# --------------------------------------------------------------------------- phases
@dataclass(frozen=True)
class _Phases:
    """Piecewise trapezoidal motion: phase k moves from ``start[k]`` by ``delta[k]``."""

    t0: np.ndarray  # (K,) start times [s]
    duration: np.ndarray  # (K,)
    accel_time: np.ndarray  # (K,) ≤ duration / 2
    start: np.ndarray  # (K, D)
    delta: np.ndarray  # (K, D)

    @property
    def t_end(self) -> float:
        return float(self.t0[-1] + self.duration[-1])

    def evaluate(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Position, velocity, acceleration ``(T, D)`` at times ``t`` (clamped to the ends)."""
        t = np.clip(t, 0.0, self.t_end)
        k = np.clip(np.searchsorted(self.t0, t, side="right") - 1, 0, self.t0.size - 1)
        tau = t - self.t0[k]
        dur, acc_t = self.duration[k], self.accel_time[k]
        peak = 1.0 / (dur - acc_t)  # ṡ at cruise
        alpha = peak / acc_t  # s̈ while accelerating
        rise, fall = tau < acc_t, tau > dur - acc_t
        back = np.maximum(dur - tau, 0.0)
        s = np.where(rise, 0.5 * alpha * tau**2, 0.5 * alpha * acc_t**2 + peak * (tau - acc_t))
        s = np.where(fall, 1.0 - 0.5 * alpha * back**2, s)
        sd = np.where(rise, alpha * tau, np.where(fall, alpha * back, peak))
        sdd = np.where(rise, alpha, np.where(fall, -alpha, 0.0))
        s = np.clip(s, 0.0, 1.0)
        delta = self.delta[k]
        return (
            self.start[k] + delta * s[:, None],
            delta * sd[:, None],
            delta * sdd[:, None],
        )


def _durations(distance, peak_velocity, acceleration_time, peak_acceleration):
    """Per-segment (duration, accel time) from per-coordinate distances (S, D) and limits."""
    distance = np.abs(distance)
    with np.errstate(divide="ignore", invalid="ignore"):
        if acceleration_time is not None:
            each = distance / peak_velocity + acceleration_time
            duration = np.maximum(each.max(-1), 2.0 * acceleration_time)
            accel = np.full(duration.shape, acceleration_time)
        elif peak_acceleration is not None:
            reach = distance >= peak_velocity**2 / peak_acceleration
            each = np.where(
                reach,
                distance / peak_velocity + peak_velocity / peak_acceleration,
                2.0 * np.sqrt(distance / peak_acceleration),
            )
            lim = np.argmax(each, -1)
            rows = np.arange(each.shape[0])
            duration = each[rows, lim]
            acc = np.where(reach, peak_velocity / peak_acceleration, 0.5 * each)
            accel = acc[rows, lim]
        else:
            duration = (1.5 * distance / peak_velocity).max(-1)
            accel = duration / 3.0
    return duration, np.minimum(accel, 0.5 * duration)


def _limits(name, value, dims, segments):
    """A positive limit: scalar, per coordinate (D,) or per segment and coordinate (S, D)."""
    if value is None:
        return None
    arr = as_float_array(name, value, max_ndim=2)
    if np.any(arr <= 0.0):
        raise ConfigError(f"{name} must be > 0 (got {arr.min():g})")
    if arr.ndim == 0 or arr.shape in ((dims,), (segments, dims)):
        return np.broadcast_to(arr, (segments, dims))
    raise ConfigError(
        f"{name} must be a scalar, ({dims},) or ({segments}, {dims}) (got {arr.shape})"
    )


def _check_waypoints(waypoints: ArrayLike) -> np.ndarray:
    points = as_float_array("waypoints", waypoints, min_ndim=2, max_ndim=2)
    if points.shape[0] < 2:
        raise InputError(f"waypoints need at least two points (got {points.shape[0]})")
    if points.shape[1] < 1:
        raise InputError("waypoints need at least one coordinate")
    same = np.flatnonzero(np.all(np.diff(points, axis=0) == 0.0, axis=1))
    if same.size:
        raise InputError(
            f"repeated consecutive waypoints at index {same[0]} and {same[0] + 1}: "
            f"{points[same[0]].tolist()}"
        )
    return points


def _times(phases: _Phases, dt: float | None, times: ArrayLike | None) -> np.ndarray:
    if times is not None:
        t = as_float_array("times", times, min_ndim=1, max_ndim=1)
        if t.size == 0:
            raise InputError("times must not be empty")
        return t
    dt = positive("dt", 0.1 if dt is None else dt, "s")
    n = max(1, int(np.ceil(phases.t_end / dt - 1e-9)))
    t = dt * np.arange(n + 1)
    t[-1] = phases.t_end
    return t


# --------------------------------------------------------------------------- results
@dataclass(frozen=True)
class Trajectory:
    """Positions, velocities and accelerations through waypoints, sampled at times ``t``.

    Attributes
    ----------
    t : numpy.ndarray, shape (T,)
        Sample times [s].
    position, velocity, acceleration : numpy.ndarray, shape (T, D)
        Coordinates [m] (or any unit u), their rates [u/s] and second derivatives [u/s²].
    waypoints : numpy.ndarray, shape (P, D)
        The waypoints (one per row; document 000 and MATLAB write them as columns).
    waypoint_times : numpy.ndarray, shape (P,)
        When each waypoint is reached (the trajectory stops there) [s].
    """

    t: np.ndarray
    position: np.ndarray
    velocity: np.ndarray
    acceleration: np.ndarray
    waypoints: np.ndarray
    waypoint_times: np.ndarray
    _phases: _Phases = field(repr=False, compare=False)

    @property
    def duration(self) -> float:
        """Time to the last waypoint [s]."""
        return float(self.waypoint_times[-1])

    def at(self, times: ArrayLike) -> Trajectory:
        """The same trajectory sampled at other times [s] (clamped to [0, duration]).

        Parameters
        ----------
        times : array_like, shape (T,)
            Sample times [s].
        """
        t = as_float_array("times", times, min_ndim=1, max_ndim=1)
        pos, vel, acc = self._phases.evaluate(t)
        return Trajectory(t, pos, vel, acc, self.waypoints, self.waypoint_times, self._phases)


def _body_frame(psi, vel, acc, yaw_rate):
    """Twist and twist rate from heading ψ, world velocity/acceleration (T, 2) and r, ṙ."""
    c, s = np.cos(psi), np.sin(psi)
    r, rdot = yaw_rate
    u = c * vel[:, 0] + s * vel[:, 1]
    v = -s * vel[:, 0] + c * vel[:, 1]
    # d/dt(R(ψ)ᵀ ṗ) = R(ψ)ᵀ p̈ − r·S·R(ψ)ᵀ ṗ  with S = [[0, −1], [1, 0]]
    du = c * acc[:, 0] + s * acc[:, 1] + r * v
    dv = -s * acc[:, 0] + c * acc[:, 1] - r * u
    return np.column_stack([u, v, r]), np.column_stack([du, dv, rdot])


# --------------------------------------------------------------------------- public functions
def trapezoidal(
    waypoints: ArrayLike,
    peak_velocity: ArrayLike,
    *,
    acceleration_time: float | None = None,
    peak_acceleration: ArrayLike | None = None,
    dt: float | None = 0.1,
    times: ArrayLike | None = None,
) -> Trajectory:
    """Trapezoidal-velocity trajectory through waypoints, stopping at each (``trapveltraj``).

    Parameters
    ----------
    waypoints : array_like, shape (P, D)
        P ≥ 2 points, one per row, no two consecutive equal. Document 000 §5.2's
        [[0, 10, 20, 30], [0, 10, 0, 0]] (columns) is ``[[0, 0], [10, 10], [20, 0], [30, 0]]``.
    peak_velocity : float or array_like
        Peak velocity [u/s] > 0 of each coordinate: a scalar, ``(D,)`` or ``(P−1, D)`` (per
        segment). Document 000 uses (0.1, 0.1) m/s.
    acceleration_time : float, optional
        Duration of the acceleration (and deceleration) phase of every segment [s], > 0.
    peak_acceleration : float or array_like, optional
        Peak acceleration [u/s²] > 0 (scalar, ``(D,)`` or ``(P−1, D)``); exclusive with
        ``acceleration_time``. Without either, each phase lasts a third of the segment.
    dt : float, optional
        Sample step [s] (default 0.1 s); the last sample lands on the final waypoint.
    times : array_like, optional
        Explicit sample times [s], instead of ``dt``.

    Returns
    -------
    Trajectory

    Raises
    ------
    InputError
        Fewer than two waypoints, repeated consecutive waypoints, non-finite values.
    ConfigError
        A non-positive peak velocity, acceleration time or acceleration, or both of the last.

    Examples
    --------
    >>> traj = trapezoidal([[0, 0], [10, 10], [20, 0], [30, 0]], (0.1, 0.1))
    >>> traj.waypoint_times.tolist()
    [0.0, 150.0, 300.0, 450.0]
    >>> float(np.abs(traj.velocity).max())
    0.1
    """
    points = _check_waypoints(waypoints)
    segments, dims = points.shape[0] - 1, points.shape[1]
    vmax = _limits("peak_velocity", peak_velocity, dims, segments)
    amax = _limits("peak_acceleration", peak_acceleration, dims, segments)
    if acceleration_time is not None:
        acceleration_time = positive("acceleration_time", acceleration_time, "s")
        if amax is not None:
            raise ConfigError("give acceleration_time or peak_acceleration, not both")
    delta = np.diff(points, axis=0)
    duration, accel = _durations(delta, vmax, acceleration_time, amax)
    t0 = np.concatenate([[0.0], np.cumsum(duration)[:-1]])
    phases = _Phases(t0, duration, accel, points[:-1], delta)
    t = _times(phases, dt, times)
    pos, vel, acc = phases.evaluate(t)
    waypoint_times = np.concatenate([t0, [phases.t_end]])
    return Trajectory(t, pos, vel, acc, points, waypoint_times, phases)


def heading_from_velocity(
    trajectory: Trajectory, *, initial_heading: float | None = None, min_speed: float = 1e-9
) -> PoseTrajectory:
    """Add the heading ψ = atan2(ẏ, ẋ) to a planar trajectory (document 000 §5.2, corrected).

    Where the speed is below ``min_speed`` (at the stops) the heading is held; at a stop-over
    waypoint where the direction changes it therefore jumps — the yaw rate there is an
    impulse this sampled trajectory cannot carry (it reports r = (ẋÿ − ẏẍ)/(ẋ² + ẏ²), zero on
    straight segments). Use :func:`feasible_trajectory` for a trajectory a differential drive
    can follow.

    Parameters
    ----------
    trajectory : Trajectory
        A two-dimensional trajectory (x, y) [m].
    initial_heading : float, optional
        Heading before the first motion [rad]; by default the direction of the first motion.
    min_speed : float
        Speed [m/s] below which the robot is taken as stopped.

    Returns
    -------
    PoseTrajectory
    """
    if not isinstance(trajectory, Trajectory) or trajectory.position.shape[1] != 2:
        raise InputError("heading_from_velocity needs a two-dimensional (x, y) Trajectory")
    min_speed = positive("min_speed", min_speed, "m/s")
    if initial_heading is not None:
        initial_heading = finite("initial_heading", initial_heading, "rad")
    phases = trajectory._phases

    def evaluate(t: np.ndarray) -> PoseTrajectory:
        pos, vel, acc = phases.evaluate(t)
        speed2 = np.sum(vel**2, -1)
        moving = speed2 > min_speed**2
        psi = np.arctan2(vel[:, 1], vel[:, 0])
        # hold the heading through the stops: direction of the current segment (same as the
        # velocity's) when the sample lies inside it, else the last moving sample's heading
        seg = np.clip(np.searchsorted(phases.t0, np.clip(t, 0, None), side="right") - 1, 0, None)
        seg_heading = np.arctan2(phases.delta[:, 1], phases.delta[:, 0])
        first = seg_heading[0] if initial_heading is None else initial_heading
        held = np.where(t >= phases.t_end, seg_heading[-1], seg_heading[seg])
        held = np.where(t <= 0.0, first, held)
        psi = np.where(moving, psi, held)
        with np.errstate(divide="ignore", invalid="ignore"):
            r = np.where(moving, (vel[:, 0] * acc[:, 1] - vel[:, 1] * acc[:, 0]) / speed2, 0.0)
        twist, rate = _body_frame(psi, vel, acc, (r, np.zeros_like(r)))
        pose = np.column_stack([pos, wrap_angle(psi)])
        return PoseTrajectory(t, pose, twist, rate, trajectory.waypoints, evaluate)

    return evaluate(trajectory.t)


def feasible_trajectory(
    waypoints: ArrayLike,
    peak_velocity: ArrayLike,
    *,
    peak_yaw_rate: float = 0.2,
    acceleration_time: float | None = None,
    peak_acceleration: ArrayLike | None = None,
    yaw_acceleration_time: float | None = None,
    peak_yaw_acceleration: float | None = None,
    initial_heading: float | None = None,
    dt: float | None = 0.1,
    times: ArrayLike | None = None,
) -> PoseTrajectory:
    """A trajectory a differential drive can follow: straight segments and turns in place.

    The translation along each segment is the one of :func:`trapezoidal` (same limits, same
    durations); before a segment whose direction differs from the current heading, the robot
    stops and turns in place by the shortest angle with a trapezoidal yaw-rate profile.

    Parameters
    ----------
    waypoints : array_like, shape (P, 2)
        P ≥ 2 points (x, y) [m], no two consecutive equal.
    peak_velocity : float or array_like
        Peak velocity of x and y [m/s] (see :func:`trapezoidal`).
    peak_yaw_rate : float
        Peak yaw rate of the turns [rad/s], > 0.
    acceleration_time : float, optional
        Acceleration time of the translations [s] (see :func:`trapezoidal`).
    peak_acceleration : float or array_like, optional
        Peak acceleration of the translations [m/s²] (see :func:`trapezoidal`).
    yaw_acceleration_time : float, optional
        Acceleration time of the turns [s].
    peak_yaw_acceleration : float, optional
        Peak yaw acceleration of the turns [rad/s²]; without this or the previous, each phase of
        a turn lasts a third of it.
    initial_heading : float, optional
        Heading at the start [rad]; by default the direction of the first segment (no turn).
    dt : float, optional
        Sample step [s].
    times : array_like, optional
        Explicit sample times [s], instead of ``dt``.

    Returns
    -------
    PoseTrajectory

    Examples
    --------
    >>> ref = feasible_trajectory([[0, 0], [10, 10], [20, 0]], 0.1, peak_yaw_rate=0.2)
    >>> round(ref.duration, 3)   # 2 × 150 s of translation + a 90° turn of 1.5·(π/2)/0.2 s
    311.781
    """
    points = _check_waypoints(waypoints)
    if points.shape[1] != 2:
        raise InputError(f"waypoints must have shape (P, 2) (got {points.shape})")
    plain = trapezoidal(
        points,
        peak_velocity,
        acceleration_time=acceleration_time,
        peak_acceleration=peak_acceleration,
        times=[0.0],
    )._phases
    yaw_rate = positive("peak_yaw_rate", peak_yaw_rate, "rad/s")
    yaw_acc = None if peak_yaw_acceleration is None else [[peak_yaw_acceleration]]
    if yaw_acc is not None:
        positive("peak_yaw_acceleration", peak_yaw_acceleration, "rad/s²")
    if yaw_acceleration_time is not None:
        yaw_acceleration_time = positive("yaw_acceleration_time", yaw_acceleration_time, "s")
        if yaw_acc is not None:
            raise ConfigError("give yaw_acceleration_time or peak_yaw_acceleration, not both")
    directions = np.arctan2(plain.delta[:, 1], plain.delta[:, 0])
    if initial_heading is None:
        heading = float(directions[0])
    else:
        heading = float(wrap_angle(finite("initial_heading", initial_heading, "rad")))
    t0, dur, acc, start, delta = [], [], [], [], []
    clock = 0.0
    for k, direction in enumerate(directions):
        turn = float(wrap_angle(direction - heading))
        if abs(turn) > 1e-12:
            d, a = _durations(
                np.array([[turn]]), np.array([[yaw_rate]]), yaw_acceleration_time,
                None if yaw_acc is None else np.array(yaw_acc),
            )  # fmt: skip
            t0.append(clock), dur.append(d[0]), acc.append(a[0])
            start.append([*plain.start[k], heading]), delta.append([0.0, 0.0, turn])
            clock += d[0]
        heading = float(direction)
        t0.append(clock), dur.append(plain.duration[k]), acc.append(plain.accel_time[k])
        start.append([*plain.start[k], heading]), delta.append([*plain.delta[k], 0.0])
        clock += plain.duration[k]
    phases = _Phases(np.array(t0), np.array(dur), np.array(acc), np.array(start), np.array(delta))

    def evaluate(t: np.ndarray) -> PoseTrajectory:
        pose, vel, accel = phases.evaluate(t)
        twist, rate = _body_frame(pose[:, 2], vel[:, :2], accel[:, :2], (vel[:, 2], accel[:, 2]))
        pose[:, 2] = wrap_angle(pose[:, 2])
        return PoseTrajectory(t, pose, twist, rate, points, evaluate)

    return evaluate(_times(phases, dt, times))
