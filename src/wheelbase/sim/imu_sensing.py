"""The IMU in the closed loop: read after each plant step from the step's true motion.

The engine reads the :class:`~wheelbase.sensors.Imu` after each plant step, as it reads the
encoders: the twist went from ``before`` to ``after`` over ``dt``, so the sample is the IMU's
average over the step, (u, v, r) the mean of the ends and (u̇, v̇, ṙ) their difference over dt
(the sensor's own low-pass; an IMU read at the control rate). The reading goes to
the controllers that read the IMU (``reads_imu``) at the next step, as the estimate does — a
proprioceptive sensor of the controller, not of the pose estimator.

Before the first step the controller sees the robot's start-up calibration: the reading of the
start's motion held steady (at rest by default) averaged over :data:`CALIBRATION_TIME`, so the
estimator may take its biases from it, as a robot standing still before it drives does.

Randomness is counter-based (:mod:`wheelbase.sim.streams`): robot i's white noise after step k
comes from (seed_i, :data:`IMU_STREAM`, k), its run's constant biases from (seed_i,
:data:`IMU_BIAS_STREAM`, 0) and its calibration's noise from (seed_i, :data:`IMU_BIAS_STREAM`,
1), so robot i of a batch reads what the single run with seed i reads.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from wheelbase.errors import ConfigError
from wheelbase.sim.streams import counter_stream

__all__ = ["CALIBRATION_TIME", "IMU_BIAS_STREAM", "IMU_SIGNALS", "IMU_STREAM", "ImuReadings"]

CALIBRATION_TIME = 1.0
"""Averaging time [s] of the start-up reading (module docstring)."""

IMU_SIGNALS: tuple[str, ...] = ("imu_yaw_rate", "imu_accel_x", "imu_accel_y")
"""Names of the log's columns of the readings a step's controller saw (rad/s, m/s², m/s²)."""

IMU_STREAM = 8
"""Stream of a robot's IMU white noise (counter: the step)."""
IMU_BIAS_STREAM = 9
"""Stream of a robot's IMU biases (counter 0: one draw per run)."""


class ImuReadings:
    """The IMUs of N robots: their run's biases and their noise (module docstring).

    Parameters
    ----------
    imu : Imu
        The sensor model.
    seeds : numpy.ndarray of int, shape (N,)
        One seed per robot.
    """

    def __init__(self, imu: Any, seeds: np.ndarray) -> None:
        from wheelbase.sensors.imu import Imu

        if not isinstance(imu, Imu):
            raise ConfigError(f"imu must be an Imu (got {type(imu).__name__})")
        self.imu = imu
        self.seeds = np.array(seeds, dtype=np.int64)
        self.seeds.setflags(write=False)
        bias = imu.biases([counter_stream(s, IMU_BIAS_STREAM, 0) for s in self.seeds])
        bias.setflags(write=False)
        self.bias = bias

    def read(
        self,
        step: int,
        dt: float,
        before: np.ndarray,
        after: np.ndarray,
        index: np.ndarray,
    ) -> np.ndarray:
        """Readings ``(M, 3)`` (ω_z, f_x, f_y) of the robots ``index`` over step ``step``.

        Parameters
        ----------
        step : int
            Index of the step just taken.
        dt : float
            Step [s].
        before, after : numpy.ndarray, shape (M, 3)
            Body twists of those robots at the step's start and end.
        index : numpy.ndarray of int, shape (M,)
            Which robots.
        """
        generators = [counter_stream(self.seeds[i], IMU_STREAM, step) for i in index]
        return self.imu.read(
            0.5 * (before + after), (after - before) / dt, dt, generators,
            bias=self.bias[index],
        )  # fmt: skip

    def calibration(self, twist: np.ndarray) -> np.ndarray:
        """The start-up readings ``(N, 3)``: the start twists held steady, averaged over
        :data:`CALIBRATION_TIME` (module docstring).

        Parameters
        ----------
        twist : numpy.ndarray, shape (N, 3)
            The start twists (zeros: at rest).
        """
        generators = [counter_stream(seed, IMU_BIAS_STREAM, 1) for seed in self.seeds]
        return self.imu.read(
            twist, np.zeros_like(twist), CALIBRATION_TIME, generators, bias=self.bias
        )
