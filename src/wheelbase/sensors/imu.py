"""A planar MEMS inertial sensor: a z-gyro and the body's horizontal linear acceleration.

A robot on the floor turns about its body z axis and accelerates in its plane, so the IMU that
matters here reads three channels in the body frame at its mount (x_m, y_m) [m]:

    ω_z = r + b_g + n_g,
    a_x = u̇ − v·r − ṙ·y_m − r²·x_m + b_x + n_x,
    a_y = v̇ + u·r + ṙ·x_m − r²·y_m + b_y + n_y,

(u, v, r) the body twist at the reference point, b a constant bias of each channel (drawn once
per run from its σ) and n white noise of density N: a sample averaged over Δt has σ = N/√Δt
(the discrete form of a white-noise density, as in the Allan-variance convention of IEEE Std
952). The accelerometers feel the specific force, acceleration minus gravity; on a slope that
is the acceleration plus g·sin α uphill, which a wheel-versus-IMU comparison cannot tell from a
spin. A 6-axis IMU's attitude filter (its x/y gyros and the vertical accelerometer, which a
planar plant does not model) removes gravity and reports the linear acceleration, as modelled
here; its tilt error is part of the accelerometers' bias.

Default noise: the InvenSense MPU-6050 product specification (PS-MPU-6000A-00, rev. 3.4,
§6.1–6.2): rate noise spectral density 0.005 °/s/√Hz, accelerometer noise power spectral
density 400 µg/√Hz (3.9e-3 m/s²/√Hz). Its initial zero-rate output tolerance ±20 °/s and
zero-g offset ±50 mg are factory tolerances that a start-up calibration at rest removes;
what is left defaults to σ_b = 0.1 °/s for the gyro and 0.1 m/s² for the accelerometer (10 mg,
or 0.6° of the attitude filter's tilt error), chosen, not from the datasheet (the datasheet
gives no in-run figure).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from wheelbase._validate import as_float_array, finite, nonnegative
from wheelbase.errors import ConfigError

__all__ = [
    "MPU6050_ACCEL_NOISE_DENSITY",
    "MPU6050_GYRO_NOISE_DENSITY",
    "Imu",
    "specific_force",
]

MPU6050_GYRO_NOISE_DENSITY = math.radians(0.005)
"""Rate noise spectral density of the MPU-6050 [rad/s/√Hz] (0.005 °/s/√Hz)."""
MPU6050_ACCEL_NOISE_DENSITY = 400e-6 * 9.80665
"""Accelerometer noise power spectral density of the MPU-6050 [m/s²/√Hz] (400 µg/√Hz)."""

MAX_MOUNT = 10.0
"""Largest distance of the mount from the reference point on either axis [m]."""


@dataclass(frozen=True)
class Imu:
    """The noise and mount of a planar IMU (module docstring).

    Parameters
    ----------
    gyro_noise_density : float
        White-noise density N_g of the z-gyro [rad/s/√Hz], ≥ 0.
    gyro_bias_std : float
        σ of the gyro's constant bias [rad/s], ≥ 0.
    accel_noise_density : float
        White-noise density N_a of each accelerometer axis [m/s²/√Hz], ≥ 0.
    accel_bias_std : float
        σ of each accelerometer axis' constant bias [m/s²], ≥ 0.
    mount : tuple of float
        (x_m, y_m) of the sensor in the body frame [m], each within ±10 m.

    Examples
    --------
    >>> imu = Imu(gyro_noise_density=0.0, gyro_bias_std=0.0, accel_noise_density=0.0,
    ...           accel_bias_std=0.0)
    >>> imu.read(np.array([[0.5, 0.0, 0.2]]), np.zeros((1, 3)), 0.01,
    ...          [np.random.default_rng(0)]).round(3).tolist()
    [[0.2, 0.0, 0.1]]
    """

    gyro_noise_density: float = MPU6050_GYRO_NOISE_DENSITY
    gyro_bias_std: float = math.radians(0.1)
    accel_noise_density: float = MPU6050_ACCEL_NOISE_DENSITY
    accel_bias_std: float = 0.1
    mount: tuple[float, float] = (0.0, 0.0)

    def __post_init__(self) -> None:
        for name, unit in (
            ("gyro_noise_density", "rad/s/√Hz"),
            ("gyro_bias_std", "rad/s"),
            ("accel_noise_density", "m/s²/√Hz"),
            ("accel_bias_std", "m/s²"),
        ):
            object.__setattr__(self, name, nonnegative(name, getattr(self, name), unit))
        try:
            x, y = self.mount
        except (TypeError, ValueError):
            raise ConfigError(f"mount must be (x, y) in m (got {self.mount!r})") from None
        x, y = finite("mount x", x, "m"), finite("mount y", y, "m")
        if max(abs(x), abs(y)) > MAX_MOUNT:
            raise ConfigError(f"mount must be within ±{MAX_MOUNT:g} m (got ({x:g}, {y:g}))")
        object.__setattr__(self, "mount", (x, y))

    @property
    def bias_std(self) -> np.ndarray:
        """σ of the biases of (ω_z, f_x, f_y) [rad/s, m/s², m/s²]."""
        return np.array([self.gyro_bias_std, self.accel_bias_std, self.accel_bias_std])

    def noise_std(self, dt: float) -> np.ndarray:
        """σ of one sample averaged over ``dt`` [s]: N/√dt of (ω_z, f_x, f_y).

        Parameters
        ----------
        dt : float
            Averaging time of a sample [s], > 0.
        """
        densities = np.array(
            [self.gyro_noise_density, self.accel_noise_density, self.accel_noise_density]
        )
        return densities / math.sqrt(dt)

    def biases(self, generators: list[np.random.Generator]) -> np.ndarray:
        """One run's constant biases ``(M, 3)`` of (ω_z, f_x, f_y), robot i's from
        ``generators[i]``.

        Parameters
        ----------
        generators : list of numpy.random.Generator
            One per robot.
        """
        std = self.bias_std
        return np.array([g.normal(0.0, 1.0, 3) * std for g in generators]).reshape(-1, 3)

    def read(
        self,
        twist_mean: ArrayLike,
        twist_rate: ArrayLike,
        dt: float,
        generators: list[np.random.Generator],
        bias: ArrayLike | None = None,
    ) -> np.ndarray:
        """Readings ``(M, 3)``: (ω_z [rad/s], a_x [m/s²], a_y [m/s²]) averaged over a step.

        Parameters
        ----------
        twist_mean : array_like, shape (M, 3)
            The body twist (u, v, r) over the step (the mean of its ends).
        twist_rate : array_like, shape (M, 3)
            Its rate (u̇, v̇, ṙ) over the step.
        dt : float
            The step [s], > 0 (the noise's averaging time).
        generators : list of numpy.random.Generator
            One per robot: its white noise of this step.
        bias : array_like, shape (M, 3), optional
            The run's biases (:meth:`biases`; default none).
        """
        twist = as_float_array("twist_mean", twist_mean, 3).reshape(-1, 3)
        rate = as_float_array("twist_rate", twist_rate, 3).reshape(-1, 3)
        dt = finite("dt", dt, "s")
        if dt <= 0:
            raise ConfigError(f"dt must be > 0 s (got {dt:g})")
        out = np.column_stack([twist[:, 2], specific_force(twist, rate, self.mount)])
        if bias is not None:
            out = out + np.asarray(bias, dtype=np.float64).reshape(-1, 3)
        std = self.noise_std(dt)
        if np.any(std > 0):
            out = out + np.array([g.normal(0.0, 1.0, 3) for g in generators]).reshape(-1, 3) * std
        return out


def specific_force(twist: ArrayLike, rate: ArrayLike, mount: tuple[float, float] = (0.0, 0.0)):
    """The acceleration ``(M, 2)`` [m/s²] in the body frame of the point ``mount`` of a body
    moving in the plane (module docstring, without bias or noise).

    Parameters
    ----------
    twist : array_like, shape (M, 3)
        Body twist (u [m/s], v [m/s], r [rad/s]) at the reference point.
    rate : array_like, shape (M, 3)
        Its rate (u̇, v̇, ṙ).
    mount : tuple of float
        The point (x_m, y_m) in the body frame [m].

    Examples
    --------
    >>> specific_force([[1.0, 0.0, 0.5]], [[0.0, 0.0, 0.0]]).tolist()  # a steady turn: u·r
    [[0.0, 0.5]]
    """
    t = np.asarray(twist, dtype=np.float64).reshape(-1, 3)
    d = np.asarray(rate, dtype=np.float64).reshape(-1, 3)
    x, y = mount
    u, v, r = t[:, 0], t[:, 1], t[:, 2]
    ax = d[:, 0] - v * r - d[:, 2] * y - r * r * x
    ay = d[:, 1] + u * r + d[:, 2] * x - r * r * y
    return np.column_stack([ax, ay])
