"""A general PID controller: anti-windup, derivative on measurement with a first-order filter.

For an error e = setpoint − measurement the output is (parallel form, Åström & Hägglund)

    u = feedforward + k_p·e + I + k_d·D,
    I(t) = ∫ k_i·e dt                          (held as k_i∫e, so retuning k_i does not bump u)
    T_f·Ḋ + D = ṡ − ẏ                          (derivative on measurement: ṡ = 0 by default)

- Derivative on measurement: D filters −ẏ (the rate of the measurement, by backward
  differences unless given) plus the setpoint rate ṡ only if the caller passes it; a step of the
  setpoint therefore gives no derivative kick. The filter (time constant ``derivative_filter``
  T_f, often T_d/N with N = 5…20) is discretised by backward Euler,
  D_k = (T_f·D_{k−1} + dt·(ṡ − ẏ)_k)/(T_f + dt), stable for any dt.
- Output limits with anti-windup: ``"clamp"`` (conditional integration: the integrator stops
  while the output is saturated and the error would drive it further), ``"back-calculation"``
  (İ = k_i·e + (u_sat − u)/T_t, tracking time T_t default √(T_i·T_d) or T_i) or ``"none"``.

Gains, limits and signals may be scalars or arrays of one shape (independent channels).
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike

from wheelbase._validate import as_float_array, check_choice, finite, nonnegative, positive
from wheelbase.errors import ConfigError

__all__ = ["ANTI_WINDUP", "PID"]

ANTI_WINDUP: tuple[str, ...] = ("clamp", "back-calculation", "none")
"""Anti-windup methods of :class:`PID`."""


class PID:
    """Proportional–integral–derivative controller with anti-windup and a filtered derivative.

    Parameters
    ----------
    kp : float or array_like
        Proportional gain(s) [output unit / error unit], ≥ 0.
    ki : float or array_like
        Integral gain(s) [output unit / (error unit·s)], ≥ 0.
    kd : float or array_like
        Derivative gain(s) [output unit·s / error unit], ≥ 0.
    derivative_filter : float
        Time constant T_f of the first-order derivative filter [s], ≥ 0 (0: no filter).
    output_limits : tuple of float
        (low, high) saturation of the output; (−inf, inf) by default.
    anti_windup : {"clamp", "back-calculation", "none"}
        What the integrator does while the output saturates.
    tracking_time : float, optional
        T_t of back-calculation [s]; default √(T_i·T_d) with T_i = k_p/k_i, T_d = k_d/k_p, or
        T_i when k_d = 0.

    Examples
    --------
    >>> pid = PID(kp=2.0, ki=1.0, output_limits=(-1.0, 1.0))
    >>> float(pid.update(setpoint=1.0, measurement=0.0, dt=0.1))
    1.0
    """

    def __init__(
        self,
        kp: ArrayLike = 1.0,
        ki: ArrayLike = 0.0,
        kd: ArrayLike = 0.0,
        *,
        derivative_filter: float = 0.0,
        output_limits: tuple[float, float] = (-math.inf, math.inf),
        anti_windup: str = "clamp",
        tracking_time: float | None = None,
    ) -> None:
        gains = []
        for name, value in (("kp", kp), ("ki", ki), ("kd", kd)):
            arr = as_float_array(name, value)
            if np.any(arr < 0):
                raise ConfigError(f"{name} must be >= 0 (got {arr.min():g})")
            gains.append(arr)
        self.kp, self.ki, self.kd = np.broadcast_arrays(*gains)
        self.derivative_filter = nonnegative("derivative_filter", derivative_filter, "s")
        low, high = output_limits
        low = -math.inf if low == -math.inf else finite("output_limits[0]", low)
        high = math.inf if high == math.inf else finite("output_limits[1]", high)
        if not low < high:
            raise ConfigError(f"output_limits must have low < high (got ({low:g}, {high:g}))")
        self.output_limits = (low, high)
        self.anti_windup = check_choice("anti_windup", anti_windup, ANTI_WINDUP)
        if tracking_time is not None:
            self.tracking_time = np.asarray(positive("tracking_time", tracking_time, "s"))
        else:
            with np.errstate(divide="ignore", invalid="ignore"):
                ti = np.where(self.ki > 0, self.kp / self.ki, np.inf)
                td = np.where(self.kp > 0, self.kd / self.kp, 0.0)
                tt = np.where(td > 0, np.sqrt(ti * td), ti)
            self.tracking_time = np.where(np.isfinite(tt) & (tt > 0), tt, 1.0)
        self.reset()

    def reset(self) -> None:
        """Forget the integral, the filtered derivative and the last measurement."""
        self.integral = np.zeros(self.kp.shape)
        self.derivative = np.zeros(self.kp.shape)
        self._last: np.ndarray | None = None

    def update(
        self,
        setpoint: ArrayLike,
        measurement: ArrayLike,
        dt: float,
        *,
        setpoint_rate: ArrayLike = 0.0,
        measurement_rate: ArrayLike | None = None,
        feedforward: ArrayLike = 0.0,
    ) -> np.ndarray:
        """Advance by ``dt`` seconds and return the (saturated) output.

        Parameters
        ----------
        setpoint : float or array_like
            Desired value(s) s.
        measurement : float or array_like
            Measured value(s) y.
        dt : float
            Time since the last update [s], > 0.
        setpoint_rate : float or array_like
            ṡ, if known (0: pure derivative on measurement).
        measurement_rate : float or array_like, optional
            ẏ, if measured (e.g. a velocity); by default the backward difference of y (0 at the
            first update).
        feedforward : float or array_like
            Added to the output before saturation.
        """
        dt = positive("dt", dt, "s")
        sp = as_float_array("setpoint", setpoint)
        y = as_float_array("measurement", measurement)
        error = sp - y
        if measurement_rate is not None:
            rate = as_float_array("measurement_rate", measurement_rate)
        elif self._last is None:
            rate = np.zeros_like(y)
        else:
            rate = (y - self._last) / dt
        self._last = np.array(y, dtype=np.float64)
        raw = as_float_array("setpoint_rate", setpoint_rate) - rate
        tf = self.derivative_filter
        self.derivative = (tf * self.derivative + dt * raw) / (tf + dt)
        ff = as_float_array("feedforward", feedforward)
        unsat = ff + self.kp * error + self.integral + self.kd * self.derivative
        low, high = self.output_limits
        out = np.clip(unsat, low, high)
        if self.anti_windup == "clamp":
            push = self.ki * error
            blocked = ((unsat > high) & (push > 0)) | ((unsat < low) & (push < 0))
            self.integral = self.integral + np.where(blocked, 0.0, push * dt)
        elif self.anti_windup == "back-calculation":
            self.integral = self.integral + dt * (
                self.ki * error + (out - unsat) / self.tracking_time
            )
        else:
            self.integral = self.integral + dt * self.ki * error
        return out
