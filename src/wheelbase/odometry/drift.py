"""Drift of the dead-reckoning updates against a known continuous motion.

:class:`CurvyDrive` is a smooth reference drive whose wheel angles and heading are known in
closed form and whose position is integrated to 1e-10 m by ``scipy.integrate.solve_ivp``
(DOP853). :func:`drift_table` samples its wheel angles at a given rate — exactly, or through an
:class:`~wheelbase.odometry.Encoder` — runs each odometry update over the samples and reports how
far the estimate drifts from the true pose.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike
from scipy.integrate import solve_ivp

from wheelbase._validate import as_float_array, check_choice, positive
from wheelbase.geometry import wrap_angle
from wheelbase.odometry.dead_reckoning import DEAD_RECKONING_METHODS, WheelOdometry
from wheelbase.odometry.encoder import Encoder, unwrap_ticks

__all__ = ["CurvyDrive", "drift_table"]


@dataclass(frozen=True)
class CurvyDrive:
    """A smooth S-curving drive of a differential drive, known in closed form.

    Forward speed v(t) = v0 + v1·sin(0.31 t) [m/s] and yaw rate
    ω(t) = w1·sin(0.23 t) + w2·cos(0.57 t) [rad/s], from the pose (0, 0, 0) at t = 0. The
    wheel angles φ_L,R = (∫v ∓ d∫ω)/r and the heading θ = ∫ω are exact; x and y are integrated
    numerically to rtol = atol = 1e-12.

    Parameters
    ----------
    wheel_radius : float
        Wheel radius r [m], > 0.
    half_track : float
        Half track d [m], > 0.
    v0, v1 : float
        Mean and amplitude of the forward speed [m/s].
    w1, w2 : float
        Amplitudes of the yaw rate [rad/s].
    """

    wheel_radius: float = 0.05
    half_track: float = 0.15
    v0: float = 0.4
    v1: float = 0.15
    w1: float = 0.8
    w2: float = 0.4

    def __post_init__(self) -> None:
        positive("wheel_radius", self.wheel_radius, "m")
        positive("half_track", self.half_track, "m")

    def _distance(self, t: np.ndarray) -> np.ndarray:
        return self.v0 * t + self.v1 * (1.0 - np.cos(0.31 * t)) / 0.31

    def heading(self, t: ArrayLike) -> np.ndarray:
        """Unwrapped heading θ(t) = ∫ω [rad] at times ``t`` [s]."""
        t = as_float_array("t", t)
        return self.w1 * (1.0 - np.cos(0.23 * t)) / 0.23 + self.w2 * np.sin(0.57 * t) / 0.57

    def wheel_angles(self, t: ArrayLike) -> np.ndarray:
        """Cumulative wheel angles ``(..., 2)`` (left, right) [rad] at times ``t`` [s]."""
        t = as_float_array("t", t)
        s, th = self._distance(t), self.heading(t)
        d, r = self.half_track, self.wheel_radius
        return np.stack([(s - d * th) / r, (s + d * th) / r], -1)

    def poses(self, t: ArrayLike) -> np.ndarray:
        """True poses ``(T, 3)`` at increasing times ``t`` [s] (first time >= 0)."""
        t = as_float_array("t", t, min_ndim=1, max_ndim=1)

        def rhs(time: float, xy: np.ndarray) -> list[float]:
            v = self.v0 + self.v1 * math.sin(0.31 * time)
            theta = float(self.heading(time))
            return [v * math.cos(theta), v * math.sin(theta)]

        span = (0.0, float(t[-1]))
        sol = solve_ivp(rhs, span, [0.0, 0.0], method="DOP853", t_eval=t, rtol=1e-12, atol=1e-12)
        return np.column_stack([sol.y[0], sol.y[1], wrap_angle(self.heading(t))])


def drift_table(
    rates_hz: Sequence[float] = (10.0, 50.0, 100.0),
    methods: Sequence[str] = DEAD_RECKONING_METHODS,
    duration: float = 300.0,
    pulses_per_revolution: int | None = None,
    drive: CurvyDrive | None = None,
) -> list[dict[str, float | str]]:
    """Drift of each odometry update on :class:`CurvyDrive` at each sampling rate.

    Parameters
    ----------
    rates_hz : sequence of float
        Odometry sampling rates [Hz], > 0.
    methods : sequence of str
        Updates to compare (``euler``, ``midpoint``, ``exact``).
    duration : float
        Length of the drive [s], > 0.
    pulses_per_revolution : int or None
        Encoder resolution [ticks/rev]; ``None`` reads the wheel angles exactly (isolates the
        discretisation error of the update from quantisation).
    drive : CurvyDrive, optional
        The reference drive (default: ``CurvyDrive()``).

    Returns
    -------
    list of dict
        One record per (rate, method): ``rate_hz``, ``method``, ``final_position_error_m``,
        ``max_position_error_m``, ``final_heading_error_rad``, ``distance_m`` (travelled) and
        ``drift_per_metre`` (final position error / distance).
    """
    duration = positive("duration", duration, "s")
    drive = drive if drive is not None else CurvyDrive()
    for method in methods:
        check_choice("method", method, DEAD_RECKONING_METHODS)
    records: list[dict[str, float | str]] = []
    for rate in rates_hz:
        rate = positive("rate_hz", rate, "Hz")
        n = round(duration * rate)
        t = np.arange(n + 1) / rate
        truth = drive.poses(t)
        angles = drive.wheel_angles(t)
        distance = float(drive._distance(t[-1]))
        for method in methods:
            if pulses_per_revolution is None:
                odo = WheelOdometry(drive.wheel_radius, drive.half_track, 1, method)
                ticks = np.diff(angles, axis=0) / (2.0 * math.pi)  # "1 tick per revolution"
            else:
                encoder = Encoder(pulses_per_revolution)
                odo = WheelOdometry(
                    drive.wheel_radius, drive.half_track, pulses_per_revolution, method
                )
                ticks = unwrap_ticks(encoder.measure(angles), None)
            est = odo.integrate([0.0, 0.0, 0.0], ticks)
            position = np.hypot(*(est[:, :2] - truth[:, :2]).T)
            records.append(
                {
                    "rate_hz": rate,
                    "method": method,
                    "final_position_error_m": float(position[-1]),
                    "max_position_error_m": float(position.max()),
                    "final_heading_error_rad": float(abs(wrap_angle(est[-1, 2] - truth[-1, 2]))),
                    "distance_m": distance,
                    "drift_per_metre": float(position[-1] / distance),
                }
            )
    return records
