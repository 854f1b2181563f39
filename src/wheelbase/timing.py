"""Time-parametrisation of a planned path: speed profiles under speed, acceleration and yaw-rate
limits, with stops at cusps and turns in place.

A planner returns geometry (poses, driving direction); a controller needs a trajectory (pose,
v, ω at each time). :func:`time_parametrize` splits the path into motions of one kind — driving
forwards, driving backwards, turning in place — and gives each a time-optimal profile under the
limits:

- |v| ≤ ``max_speed``, |ω| = |v·κ| ≤ ``max_yaw_rate`` (the curvature-aware slow-down) and
  optionally |v²·κ| ≤ ``max_lateral_acceleration``;
- |dv/dt| ≤ ``max_acceleration``; the robot stops at each cusp, at each turn in place, and at the
  end of the path;
- turns in place follow a trapezoidal yaw-rate profile with |ω| ≤ ``max_yaw_rate`` and
  |dω/dt| ≤ ``max_yaw_acceleration``.

Along a driving segment the profile is the classical forward–backward pass on the path samples
(speed limited by v_{i+1}² ≤ v_i² + 2·a·Δs in both directions), with constant acceleration
between samples, which makes Δt = 2Δs / (v_i + v_{i+1}) exact.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from wheelbase._validate import as_float_array, integer, positive
from wheelbase.errors import ConfigError, InputError
from wheelbase.geometry import wrap_angle
from wheelbase.limits import MAX_STEPS
from wheelbase.models.path import PoseTrajectory

__all__ = ["SpeedLimits", "time_parametrize"]

_SAME_POINT = 1e-9  # m: consecutive samples closer than this do not move the robot


@dataclass(frozen=True)
class SpeedLimits:
    """Limits used to time-parametrise a path.

    Parameters
    ----------
    max_speed : float
        Largest |v| [m/s], > 0.
    max_acceleration : float
        Largest |dv/dt| [m/s²], > 0.
    max_yaw_rate : float
        Largest |ω| [rad/s], > 0; on a curve of curvature κ the speed is limited to
        ``max_yaw_rate / |κ|``.
    max_yaw_acceleration : float
        Largest |dω/dt| in turns in place [rad/s²], > 0.
    max_lateral_acceleration : float
        Largest v²·|κ| [m/s²] (``inf`` for none).
    reverse_speed_factor : float
        Reversing speed limit as a fraction of ``max_speed``, in (0, 1].
    """

    max_speed: float = 0.5
    max_acceleration: float = 0.5
    max_yaw_rate: float = 1.0
    max_yaw_acceleration: float = 2.0
    max_lateral_acceleration: float = math.inf
    reverse_speed_factor: float = 1.0

    def __post_init__(self) -> None:
        for name in ("max_speed", "max_acceleration", "max_yaw_rate", "max_yaw_acceleration"):
            units = {"max_speed": "m/s", "max_acceleration": "m/s²"}.get(name, "rad/s or rad/s²")
            object.__setattr__(self, name, positive(name, getattr(self, name), units))
        lateral = float(self.max_lateral_acceleration)
        if not lateral > 0:
            raise ConfigError(f"max_lateral_acceleration must be > 0 m/s² (got {lateral:g})")
        factor = float(self.reverse_speed_factor)
        if not 0 < factor <= 1:
            raise ConfigError(f"reverse_speed_factor must be in (0, 1] (got {factor:g})")


def time_parametrize(
    poses: ArrayLike,
    directions: ArrayLike | None = None,
    limits: SpeedLimits | None = None,
    dt: float = 0.05,
    *,
    max_samples: int = MAX_STEPS,
) -> PoseTrajectory:
    """Time-parametrise a path of poses into a trajectory sampled every ``dt`` seconds.

    Parameters
    ----------
    poses : array_like, shape (N, 3)
        Path samples (x [m], y [m], θ [rad]) of the robot's reference point, N ≥ 2, e.g. a
        Hybrid A* ``Path.poses``. Consecutive samples at the same position with different
        headings are a turn in place.
    directions : array_like, shape (N,), optional
        Driving direction at each sample, +1 forwards and −1 backwards (default all +1). A sign
        change is a cusp: the robot stops there.
    limits : SpeedLimits, optional
        Speed, acceleration and yaw-rate limits (defaults of :class:`SpeedLimits`).
    dt : float
        Sampling period of the returned trajectory [s], > 0.
    max_samples : int
        Most samples the trajectory may have (default :data:`wheelbase.limits.MAX_STEPS`);
        a path that slow limits stretch beyond it is refused, not allocated.

    Returns
    -------
    PoseTrajectory
        ``t`` (T,), ``poses`` (T, 3), signed ``v`` (T,), ``omega`` (T,) and ``curvature`` (T,)
        (0 where the robot turns in place or stands). It starts and ends at rest, at the first
        and last pose of the path.

    Raises
    ------
    InputError
        Fewer than two samples, wrong shapes, non-finite values, directions other than ±1.
    ConfigError
        Non-positive ``dt``, invalid limits, or more than ``max_samples`` samples.
    """
    limits = SpeedLimits() if limits is None else limits
    dt = positive("dt", dt, "s")
    max_samples = integer("max_samples", max_samples, minimum=2)
    poses = as_float_array("poses", poses, 3, min_ndim=2, max_ndim=2)
    if poses.shape[0] < 2:
        raise InputError(f"poses must hold at least 2 samples (got {poses.shape[0]})")
    if directions is None:
        directions = np.ones(poses.shape[0])
    directions = as_float_array("directions", directions, min_ndim=1, max_ndim=1)
    if directions.shape[0] != poses.shape[0]:
        raise InputError(
            f"directions must have one entry per pose ({poses.shape[0]}, got {directions.shape[0]})"
        )
    if not np.all(np.isin(directions, (-1.0, 1.0))):
        raise InputError("directions must be +1 (forwards) or -1 (backwards)")

    headings = np.unwrap(poses[:, 2])
    pieces = []
    for kind, start, stop in _motions(poses, directions):
        if kind == 0:
            pieces.append(_turn_in_place(poses[start], headings[start], headings[stop], limits))
        else:
            pieces.append(_drive(poses[start : stop + 1], headings[start : stop + 1], kind, limits))

    return _sample(pieces, poses, dt, max_samples)


def _motions(poses: np.ndarray, directions: np.ndarray):
    """Split the path into (kind, start, stop) with kind +1/−1 (drive) or 0 (turn in place)."""
    step = np.hypot(*np.diff(poses[:, :2], axis=0).T)
    kinds = np.where(step > _SAME_POINT, directions[1:], 0.0)
    turn = np.abs(wrap_angle(np.diff(poses[:, 2]))) > 1e-9
    motions = []
    start = 0
    for i in range(1, len(kinds) + 1):
        if i == len(kinds) or kinds[i] != kinds[start]:
            kind = int(kinds[start])
            if kind != 0 or np.any(turn[start:i]):
                motions.append((kind, start, i))
            start = i
    if not motions:
        raise InputError("the path does not move: all poses are equal")
    return motions


@dataclass(frozen=True)
class _Piece:
    """One motion: per-interval start times, entry speeds and accelerations along a parameter."""

    times: np.ndarray  # (M,) start time of each sample, relative to the piece
    params: np.ndarray  # (M,) arc length (drive) or heading (turn) at each sample
    rates: np.ndarray  # (M,) |ds/dt| or |dθ/dt| at each sample
    poses: np.ndarray  # (M, 3) path samples (drive) or the two ends (turn)
    kind: int

    @property
    def duration(self) -> float:
        return float(self.times[-1])


def _densify(
    poses: np.ndarray, headings: np.ndarray, spacing: float
) -> tuple[np.ndarray, np.ndarray]:
    """The path with samples added (linearly) so that no interval is longer than ``spacing``."""
    ds = np.hypot(*np.diff(poses[:, :2], axis=0).T)
    parts = np.maximum(1, np.ceil(ds / spacing)).astype(np.int64)
    if parts.max() == 1:
        return poses, headings
    index = np.repeat(np.arange(ds.size), parts)
    first = np.repeat(np.cumsum(parts) - parts, parts)
    frac = (np.arange(parts.sum()) - first) / np.repeat(parts, parts)
    xy = poses[index, :2] + frac[:, None] * (poses[index + 1, :2] - poses[index, :2])
    heading = headings[index] + frac * (headings[index + 1] - headings[index])
    xy = np.vstack([xy, poses[-1:, :2]])
    heading = np.append(heading, headings[-1])
    return np.column_stack([xy, heading]), heading


def _drive(poses: np.ndarray, headings: np.ndarray, direction: int, limits: SpeedLimits) -> _Piece:
    # The speed profile lives on the path's samples (the robot is at rest at the first and the
    # last): a path given by few samples (two: one straight interval) is resampled so that the
    # ramps span several intervals and the robot can cruise between them; Hybrid A*'s paths,
    # sampled every few centimetres, are left as they are.
    top = limits.max_speed * (limits.reverse_speed_factor if direction < 0 else 1.0)
    length = float(np.hypot(*np.diff(poses[:, :2], axis=0).T).sum())
    ramp = top * top / (2.0 * limits.max_acceleration)
    if length > 0.0:
        spacing = min(ramp / 8.0, length / 2.0) if ramp > 0.0 else length / 2.0
        poses, headings = _densify(poses, headings, max(spacing, length / 100_000))
    ds = np.hypot(*np.diff(poses[:, :2], axis=0).T)
    s = np.concatenate([[0.0], np.cumsum(ds)])
    curvature = np.zeros_like(s)
    with np.errstate(divide="ignore", invalid="ignore"):
        # dθ/ds by differences; the sign of travel does not change |κ|, which is what limits v.
        k_mid = np.where(ds > 0, np.diff(headings) / ds, 0.0)
    curvature[:-1] = np.abs(k_mid)
    curvature[1:] = np.maximum(curvature[1:], np.abs(k_mid))
    # A straight (κ = 0) or all but straight (subnormal κ) stretch has no curvature limit:
    # the quotient is inf, and the minimum keeps the top speed.
    with np.errstate(divide="ignore", over="ignore"):
        cap = np.minimum(top, limits.max_yaw_rate / curvature)
        if math.isfinite(limits.max_lateral_acceleration):
            cap = np.minimum(cap, np.sqrt(limits.max_lateral_acceleration / curvature))
    speed = cap.copy()
    speed[0] = speed[-1] = 0.0
    accel = limits.max_acceleration
    for i in range(1, len(s)):  # forward pass
        speed[i] = min(speed[i], math.sqrt(speed[i - 1] ** 2 + 2 * accel * ds[i - 1]))
    for i in range(len(s) - 2, -1, -1):  # backward pass
        speed[i] = min(speed[i], math.sqrt(speed[i + 1] ** 2 + 2 * accel * ds[i]))
    dt = 2.0 * ds / (speed[:-1] + speed[1:])
    times = np.concatenate([[0.0], np.cumsum(dt)])
    return _Piece(times, s, speed, np.column_stack([poses[:, :2], headings]), direction)


def _turn_in_place(pose: np.ndarray, heading0: float, heading1: float, limits: SpeedLimits):
    angle = abs(heading1 - heading0)
    rate, accel = limits.max_yaw_rate, limits.max_yaw_acceleration
    # Trapezoid (or triangle when the turn is too short to reach the top rate).
    ramp = min(rate / accel, math.sqrt(angle / accel))
    peak = accel * ramp
    cruise = max(0.0, (angle - accel * ramp**2) / peak) if peak > 0 else 0.0
    times = np.array([0.0, ramp, ramp + cruise, 2 * ramp + cruise])
    swept = np.array([0.0, 0.5 * accel * ramp**2, 0.5 * accel * ramp**2 + peak * cruise, angle])
    rates = np.array([0.0, peak, peak, 0.0])
    ends = np.array([[pose[0], pose[1], heading0], [pose[0], pose[1], heading1]])
    return _Piece(times, swept, rates, ends, 0)


def _sample(pieces: list[_Piece], path: np.ndarray, dt: float, max_samples: int) -> PoseTrajectory:
    total = sum(piece.duration for piece in pieces)
    samples = total / dt + 1.0
    if not samples <= max_samples:  # also NaN; checked before ceil and the allocation
        raise ConfigError(
            f"the path takes {total:.3g} s at these limits: {samples:.3g} samples of dt = "
            f"{dt:g} s, more than max_samples = {max_samples} (scenario resources.max_steps); "
            "raise the speed limits or the limit"
        )
    n = max(2, math.ceil(total / dt - 1e-9) + 1)
    t = dt * np.arange(n)
    t[-1] = max(t[-1], total) if n > 1 else total
    t = np.minimum(t, total)
    out_pose = np.empty((n, 3))
    out_v = np.zeros(n)
    out_w = np.zeros(n)
    offset = 0.0
    for index, piece in enumerate(pieces):
        last = index == len(pieces) - 1
        mask = (t >= offset) & ((t < offset + piece.duration) | last)
        local = np.clip(t[mask] - offset, 0.0, piece.duration)
        param, rate = _profile(piece, local)
        if piece.kind == 0:
            sign = 1.0 if piece.poses[1, 2] >= piece.poses[0, 2] else -1.0
            out_pose[mask, :2] = piece.poses[0, :2]
            out_pose[mask, 2] = piece.poses[0, 2] + sign * param
            out_w[mask] = sign * rate
        else:
            s = piece.params
            out_pose[mask, 0] = np.interp(param, s, piece.poses[:, 0])
            out_pose[mask, 1] = np.interp(param, s, piece.poses[:, 1])
            out_pose[mask, 2] = np.interp(param, s, piece.poses[:, 2])
            # κ = dθ/ds on the interval the sample lies in, ω = ṡ·κ·(heading change sign).
            segment = np.clip(np.searchsorted(s, param, side="right") - 1, 0, len(s) - 2)
            ds = np.diff(s)
            kappa = np.diff(piece.poses[:, 2]) / np.where(ds > 0, ds, 1.0)
            out_v[mask] = piece.kind * rate
            out_w[mask] = rate * kappa[segment]
        offset += piece.duration
    out_pose[:, 2] = wrap_angle(out_pose[:, 2])
    out_pose[-1] = [path[-1, 0], path[-1, 1], wrap_angle(path[-1, 2])]
    return PoseTrajectory.from_speeds(t, out_pose, out_v, out_w)


def _profile(piece: _Piece, local: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Parameter and rate at local times, constant acceleration between samples."""
    index = np.clip(np.searchsorted(piece.times, local, side="right") - 1, 0, len(piece.times) - 2)
    tau = local - piece.times[index]
    span = piece.times[index + 1] - piece.times[index]
    rate0, rate1 = piece.rates[index], piece.rates[index + 1]
    with np.errstate(divide="ignore", invalid="ignore"):
        accel = np.where(span > 0, (rate1 - rate0) / span, 0.0)
    param = piece.params[index] + rate0 * tau + 0.5 * accel * tau**2
    rate = rate0 + accel * tau
    return np.minimum(param, piece.params[index + 1]), rate
