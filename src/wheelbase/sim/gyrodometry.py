"""Gyrodometry: the wheels' heading, and the gyro's while the two disagree (a wheel slips).

A wheel that spins (or a robot that skids) turns its encoder without moving the ground under
it: the odometry counts the difference as a rotation, and every metre after it carries that
heading error. On the ice demo with ``friction: estimate`` the traction control's start spin
(how the estimate learns the floor) turned the odometry's heading 0.5° within half a second,
and the turns' steady slip added more.

Borenstein and Feng's gyrodometry ("Gyrodometry: a new method for combining data from gyros and
odometry in mobile robots", IEEE ICRA 1996) takes the heading increment from the wheels, which
do not drift, except where the gyro and the wheels disagree by more than the wheels' own
error: there a wheel slips and the gyro is right. :class:`Gyrodometry` wraps an encoder
odometry (plain or :class:`~wheelbase.sim.slip_odometry.SlipCompensatedOdometry`) and compares
the two over a window of ``window`` seconds (W steps), not per step, since one tick is a large
rate over one step but a bounded angle over any number of steps:

    d_k = (ω_z,k − b̂)·Δt − φ_k  (gyro minus wheels, rad),   S = Σ d over the last W steps,

and the step is slipping where |S| exceeds the threshold

    S_max = 2·δ + 4·δ·σ_t·√(2W) + 4·(N_g·√(W·Δt) + N_g·W·Δt/√T_c),

δ = 2π·a/(P·b) the rotation of one tick (a the wheel radius, P the pulses per revolution, b the
track): each wheel's count over a window is within one tick of its angle, so the wheels' window
rotation is within 2δ (quantisation does not grow with W); σ_t the encoders' Gaussian tick
noise per step, a random walk over the window on both wheels; N_g the gyro's white-noise
density (its window angle has σ N_g·√(W·Δt)) and N_g/√T_c the σ of the bias that the start-up
calibration (:data:`~wheelbase.sim.imu_sensing.CALIBRATION_TIME` T_c at rest) leaves. Beyond
S_max the wheels are wrong by more than the gyro can be, so the step's rotation is the gyro's,
and the window's earlier steps that were counted on the wheels are put right at once (the
heading catches up by the sum of their d: a spin is seen only once it has lasted long enough
to pass S_max, and without the catch-up the wheels' share until then would stay). Missed or
extra ticks are not in S_max: they are wheel errors like a slip, which the gyro corrects.

The bias b̂ is the start-up calibration's: the engine hands the estimator with ``reads_imu``
the reading of the start (:meth:`Gyrodometry.calibrate`, the start's twist held steady for
T_c, at rest the reading is bias), as it hands it to a controller. Learning it later at rest
(no tick on either wheel) is not done: on ice a robot can slide with its wheels still. The
distance stays the wrapped odometry's (a longitudinal slip is the slip compensation's: a
z-gyro cannot see it), and so does the twist it reports: the friction estimate reads the
wheels' rim speeds from it, and a spin must show there.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

from wheelbase._validate import finite
from wheelbase.errors import ConfigError
from wheelbase.sim.imu_sensing import CALIBRATION_TIME
from wheelbase.sim.sensing import EncoderOdometry

__all__ = ["GYRO_WINDOW", "Gyrodometry"]

GYRO_WINDOW = 0.5
"""Default window [s] over which the gyro's and the wheels' rotations are compared: over
0.5 s the RM100's 2048-tick quantisation (2δ = 0.077°) lets a slip of 0.15 °/s show."""


@dataclass(frozen=True)
class Gyrodometry:
    """Encoder odometry whose heading follows the gyro where the wheels slip (module docstring).

    Parameters
    ----------
    inner : EncoderOdometry
        The encoder odometry whose distances and heading increments it reads.
    imu : Imu
        The IMU whose gyro it reads (its noise density sets the threshold).
    window : float
        Length [s] of the window over which gyro and wheels are compared, > 0.

    Examples
    --------
    >>> from wheelbase.odometry import Encoder, WheelOdometry
    >>> from wheelbase.sensors import Imu
    >>> inner = EncoderOdometry(Encoder(2048), WheelOdometry(0.1, 0.25, 2048))
    >>> odometry = Gyrodometry(inner, Imu())
    >>> round(math.degrees(odometry.threshold(0.01)), 3)
    0.094
    """

    inner: Any
    imu: Any
    window: float = GYRO_WINDOW
    reads_imu: ClassVar[bool] = True

    def __post_init__(self) -> None:
        from wheelbase.sensors.imu import Imu

        if not isinstance(self.inner, EncoderOdometry):
            raise ConfigError(
                f"gyrodometry wraps an encoder odometry (got {type(self.inner).__name__})"
            )
        if not isinstance(self.imu, Imu):
            raise ConfigError(f"imu must be an Imu (got {type(self.imu).__name__})")
        window = finite("window", self.window, "s")
        if not window > 0.0:
            raise ConfigError(f"window must be > 0 s (got {window:g})")
        object.__setattr__(self, "window", window)

    @property
    def encoder(self) -> Any:
        """The encoders the wrapped odometry reads."""
        return self.inner.encoder

    @property
    def reads_command(self) -> bool:
        """Whether the wrapped odometry reads its own torques (slip compensation)."""
        return bool(getattr(self.inner, "reads_command", False))

    def steps(self, dt: float) -> int:
        """Steps W in the window at step ``dt`` [s] (at least 1)."""
        return max(1, round(self.window / dt))

    def threshold(self, dt: float) -> float:
        """S_max [rad] at step ``dt`` [s] (module docstring).

        Parameters
        ----------
        dt : float
            Step [s], > 0.
        """
        w = self.steps(dt)
        odometry = self.inner.odometry
        tick = 2.0 * math.pi * odometry.wheel_radius / odometry.pulses_per_revolution
        delta = tick / odometry.track
        noise = self.imu.gyro_noise_density
        span = w * dt
        wheels = 2.0 * delta + 4.0 * delta * self.encoder.noise_std * math.sqrt(2.0 * w)
        gyro = 4.0 * (noise * math.sqrt(span) + noise * span / math.sqrt(CALIBRATION_TIME))
        return wheels + gyro

    def start(self, poses: np.ndarray, seeds: np.ndarray) -> dict[str, Any]:
        """Per robot: the wrapped odometry's state (``inner``), the gyro's bias [rad/s] (0
        until :meth:`calibrate`), and the window of disagreements d [rad] and whether each
        is in the heading (``taken``), sized at the first step (it needs Δt).

        Parameters
        ----------
        poses : numpy.ndarray, shape (N, 3)
            Start poses.
        seeds : numpy.ndarray
            The robots' seeds.
        """
        n = np.asarray(poses).reshape(-1, 3).shape[0]
        return {
            "inner": self.inner.start(poses, seeds),
            "bias": np.zeros(n),
            "window": np.zeros((n, 0)),
            "taken": np.zeros((n, 0), dtype=bool),
        }

    def calibrate(
        self, state: dict[str, Any], imu: np.ndarray, twist: np.ndarray
    ) -> dict[str, Any]:
        """The state with the gyro's bias from the start-up reading: the start's yaw rate
        held steady (at rest, the reading is all bias).

        Parameters
        ----------
        state : dict
            What :meth:`start` made.
        imu : numpy.ndarray, shape (N, 3)
            The start-up readings (ω_z [rad/s], a_x, a_y).
        twist : numpy.ndarray, shape (N, 3)
            The start twists (u, v, r) the robots are told.
        """
        gyro = np.asarray(imu, dtype=np.float64).reshape(-1, 3)[:, 0]
        rate = np.asarray(twist, dtype=np.float64).reshape(-1, 3)[:, 2]
        bias = gyro - rate
        return {**state, "bias": np.where(np.isfinite(bias), bias, 0.0)}

    def update(
        self, estimate, ticks, dt, pose, twist, *, state=None, index=None, readings=None,
        command=None, imu=None,
    ):  # fmt: skip
        """Dead-reckon one step on the wrapped odometry's distance and the heading increment
        of the wheels or, where they slip, of the gyro.

        Parameters
        ----------
        estimate : numpy.ndarray, shape (M, 3)
            The estimate at the start of the step.
        ticks : numpy.ndarray, shape (M, 2)
            Tick differences counted during the step.
        dt : float
            Step [s].
        pose, twist : numpy.ndarray, shape (M, 3)
            The truth (unused).
        state : dict, optional
            What :meth:`start` made (rows of all robots; None: a fresh one, uncalibrated).
        index : numpy.ndarray, optional
            Which robots these M rows are (default: all).
        readings : Readings, optional
            Sensor readings (unused).
        command : numpy.ndarray, shape (M, 2), optional
            The wheel torques, for a slip-compensated odometry.
        imu : numpy.ndarray, shape (M, 3), optional
            The IMU's readings (ω_z [rad/s], a_x, a_y) over the step; without them (or where
            not finite), the wheels' heading.

        Returns
        -------
        estimate, twist : numpy.ndarray, shape (M, 3)
            The new estimate, and the wrapped odometry's twist (the wheels').
        state : dict
        """
        estimate = np.asarray(estimate, dtype=np.float64).reshape(-1, 3)
        if state is None:
            state = self.start(estimate, np.zeros(len(estimate), dtype=np.int64))
        rows = np.arange(len(estimate)) if index is None else np.asarray(index)
        distance, rotation, inner_state = self.inner.travel(
            estimate, ticks, dt, state=state["inner"], index=index, command=command
        )
        wheel_twist = self.inner.twist(distance, rotation, dt)
        state = {**state, "inner": inner_state}
        start = estimate
        if imu is not None:
            w = self.steps(dt)
            window, taken = state["window"], state["taken"]
            if window.shape[1] != w:  # the first step: Δt is known now
                window = np.zeros((window.shape[0], w))
                taken = np.ones((window.shape[0], w), dtype=bool)
            gyro = np.asarray(imu, dtype=np.float64).reshape(-1, 3)[:, 0]
            ok = np.isfinite(gyro)
            gyro_rotation = np.where(ok, (gyro - state["bias"][rows]) * dt, rotation)
            d = gyro_rotation - rotation
            own = np.concatenate([window[rows, 1:], d[:, None]], axis=1)
            own_taken = np.concatenate([taken[rows, 1:], np.zeros((len(rows), 1), bool)], 1)
            slipping = ok & (np.abs(own.sum(axis=1)) > self.threshold(dt))
            # the window's earlier steps went in on the wheels: the heading catches up by
            # their disagreement before the step is dead-reckoned on the gyro's rotation
            earlier = np.where(own_taken[:, :-1], 0.0, own[:, :-1]).sum(axis=1)
            start = estimate.copy()
            start[:, 2] += np.where(slipping, earlier, 0.0)
            rotation = np.where(slipping, gyro_rotation, rotation)
            own_taken = own_taken | slipping[:, None]
            window, taken = window.copy(), taken.copy()
            window[rows], taken[rows] = own, own_taken
            state = {**state, "window": window, "taken": taken}
        new, _ = self.inner.dead_reckon(start, distance, rotation, dt)
        return new, wheel_twist, state
