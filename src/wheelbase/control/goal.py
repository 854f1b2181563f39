"""Go-to-goal of document 003 §IV, and its full closed loop down to encoder ticks (§II–III).

The law (document 003 eqs. 8–16, with the printed unit slips corrected):

- heading error e = wrap(atan2(y_g − y, x_g − x) − θ) (atan2 and wrapped: document 002's
  warning about atan applies);
- eq. 8: W = K_p·e, the commanded yaw rate [rad/s];
- a forward speed v that slows near the goal, v = v_max·min(1, ρ/slow_radius), ρ the distance
  to the goal (the document's D_C in eqs. 9–10), and 0 within ``tolerance``;
- eqs. 9–10 print V_R,L = (2·D_C ± W·L)/(2·r). (2v ± W·L)/2 is already the wheel's linear
  speed [m/s]; dividing by the tyre radius r gives its angular speed, which eqs. 11–12 then
  compute *again* (W_R = V_R/r), and eqs. 13–14 divide by r a third time. Corrected:
  V_R,L = v ± W·L/2 [m/s], ω_R,L = V_R,L/r [rad/s] (eqs. 11–12), and
  RPM_R,L = ω_R,L·60/(2π) (eqs. 15–16 take D_R/r·60/(2π r); the document writes 3.14 for π);
- wheel-speed saturation that keeps the turning rate: when the faster wheel would exceed
  ``max_wheel_speed``, v is reduced until it does not (:func:`saturate_keep_turn_rate`); only if
  turning alone exceeds it is W reduced too. This differs on purpose from
  :func:`~wheelbase.control.saturate_velocity` (which keeps the curvature by scaling v and W
  together): go-to-goal must turn towards the goal first, and keeping W does that.

Stability: near the goal v = k_ρ·ρ with k_ρ = v_max/slow_radius, which is the go-to-point law
of :mod:`wheelbase.control.point`; the robot orbits the goal unless K_p > (2/π)·k_ρ and spirals
in unless K_p > k_ρ, so :class:`GoToGoal` refuses the first and warns on the second.

:func:`wheelbase.sim.run_go_to_goal` runs the loop of document 003 Fig. 1 on the engine: goal →
set-points in RPM (the microprocessor, every ``control_period``) → PI speed loop → PWM duty (the
microcontroller, every ``speed_loop.period``) → DC motor → wheel → encoder ticks → odometry →
estimated pose → law; :class:`DriveTrain` holds the hardware it runs on.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, field
from typing import ClassVar

import numpy as np
from numpy.typing import ArrayLike

from wheelbase._validate import as_float_array, positive
from wheelbase.control.base import VELOCITY_COMMAND
from wheelbase.errors import ConfigError, InputError
from wheelbase.geometry import wrap_angle
from wheelbase.models.diffdrive import DiffDrive
from wheelbase.motor import MOTOR_PRESETS, DCMotor, SpeedLoop
from wheelbase.odometry.dead_reckoning import DEAD_RECKONING_METHODS, WheelOdometry
from wheelbase.odometry.encoder import Encoder
from wheelbase.odometry.error_model import OdometryErrors

__all__ = [
    "FIGURE8_GOALS",
    "DriveTrain",
    "GoToGoal",
    "saturate_keep_turn_rate",
]

FIGURE8_GOALS: tuple[tuple[float, float], ...] = (
    (1.0, 1.0),
    (-1.0, 1.0),
    (-1.0, -1.0),
    (1.0, -1.0),
)
"""The four goals of document 003 Fig. 8 [m]: its (±100, ±100) read as centimetres (the
prototype is a table-top robot; :class:`DriveTrain`'s default is 7 cm wheels on a 15 cm track)."""


def saturate_keep_turn_rate(
    v: ArrayLike, omega: ArrayLike, wheel_radius: float, half_track: float, max_wheel_speed: float
) -> tuple[np.ndarray, np.ndarray]:
    """Limit the wheel speeds of a differential drive, giving up forward speed first.

    Parameters
    ----------
    v : array_like
        Forward speed [m/s].
    omega : array_like
        Yaw rate [rad/s].
    wheel_radius : float
        Wheel radius r [m], > 0.
    half_track : float
        Half track d [m], > 0.
    max_wheel_speed : float
        Largest wheel angular speed [rad/s], > 0.

    Returns
    -------
    tuple of numpy.ndarray
        (v', ω') with |v'| + d|ω'| <= r·ω_max: ω' = ω and |v'| = min(|v|, r·ω_max − d|ω|)
        when turning alone fits, else v' = 0 and |ω'| = r·ω_max/d. Signs are kept.

    Examples
    --------
    >>> v, w = saturate_keep_turn_rate(1.0, 2.0, wheel_radius=0.05, half_track=0.1,
    ...                                max_wheel_speed=10.0)
    >>> round(float(v), 6), float(w)
    (0.3, 2.0)
    """
    v = as_float_array("v", v)
    omega = as_float_array("omega", omega)
    r = positive("wheel_radius", wheel_radius, "m")
    d = positive("half_track", half_track, "m")
    limit = r * positive("max_wheel_speed", max_wheel_speed, "rad/s")  # rim speed [m/s]
    turn = np.minimum(np.abs(omega), limit / d)
    speed = np.minimum(np.abs(v), np.maximum(limit - d * turn, 0.0))
    return np.sign(v) * speed, np.sign(omega) * turn


@dataclass(frozen=True)
class GoToGoal:
    """Proportional heading controller to a goal position (document 003 §IV, eqs. 8–16).

    Called as ``controller(t, pose, goal) -> (v, ω)`` like every controller of
    :mod:`wheelbase.control`; :meth:`wheel_setpoints` and :meth:`rpm_setpoints` give the wheel
    set-points of eqs. 11–16.

    Parameters
    ----------
    kp : float
        Heading gain K_p [1/s] of eq. 8, > 0.
    max_speed : float
        Cruise forward speed v_max [m/s], > 0.
    slow_radius : float
        Distance [m] inside which the speed falls linearly to 0 at the goal, > 0.
    tolerance : float
        Stop distance [m], > 0: within it the command is (0, 0).
    wheel_radius, half_track : float
        Nominal geometry [m] used for the wheel set-points and the saturation.
    max_wheel_speed : float
        Wheel speed limit [rad/s], > 0 (``inf``: none).

    Examples
    --------
    >>> law = GoToGoal(kp=2.0, max_speed=0.2)
    >>> law(0.0, [0.0, 0.0, 0.0], [1.0, 1.0]).round(4).tolist()  # 45° to the left
    [0.2, 1.5708]
    """

    kp: float = 2.0
    max_speed: float = 0.2
    slow_radius: float = 0.3
    tolerance: float = 0.01
    wheel_radius: float = 0.035
    half_track: float = 0.075
    max_wheel_speed: float = math.inf

    command_names: ClassVar[tuple[str, ...]] = VELOCITY_COMMAND

    def __post_init__(self) -> None:
        for name, unit in (
            ("kp", "1/s"),
            ("max_speed", "m/s"),
            ("slow_radius", "m"),
            ("tolerance", "m"),
            ("wheel_radius", "m"),
            ("half_track", "m"),
        ):
            object.__setattr__(self, name, positive(name, getattr(self, name), unit))
        if self.max_wheel_speed != math.inf:
            limit = positive("max_wheel_speed", self.max_wheel_speed, "rad/s")
            object.__setattr__(self, "max_wheel_speed", limit)
        k_rho = self.max_speed / self.slow_radius
        if self.kp <= 2.0 / math.pi * k_rho:
            raise ConfigError(
                f"kp must be > (2/π)·max_speed/slow_radius = {2 / math.pi * k_rho:.3g} 1/s or "
                f"the robot orbits the goal (got kp={self.kp:g})"
            )
        if self.kp <= k_rho:
            warnings.warn(
                f"kp={self.kp:g} <= max_speed/slow_radius={k_rho:.3g}: the robot spirals in",
                stacklevel=2,
            )

    def reset(self) -> None:
        """Nothing to forget: the law keeps no state between calls."""

    def __call__(self, t: float, pose: ArrayLike, reference: ArrayLike) -> np.ndarray:
        """Command ``(..., 2)`` = (v [m/s], ω [rad/s]) towards the goal position(s).

        Parameters
        ----------
        t : float
            Time [s] (unused: the law is static).
        pose : array_like, shape (..., 3)
            Measured (estimated) poses (x [m], y [m], θ [rad]).
        reference : array_like, shape (..., 2) or (..., 3)
            Goal position(s) (x, y) [m]; a third column (a goal heading) is ignored.

        Raises
        ------
        InputError
            Non-finite or badly shaped poses or goals.
        """
        pose = as_float_array("pose", pose, 3)
        goal = as_float_array("goal", reference, min_ndim=1)
        if goal.shape[-1] not in (2, 3):
            raise InputError(f"goal must have shape (..., 2) or (..., 3) (got {goal.shape})")
        dx = goal[..., 0] - pose[..., 0]
        dy = goal[..., 1] - pose[..., 1]
        rho = np.hypot(dx, dy)
        error = wrap_angle(np.arctan2(dy, dx) - pose[..., 2])
        omega = self.kp * error  # eq. 8
        v = self.max_speed * np.minimum(1.0, rho / self.slow_radius)
        if self.max_wheel_speed != math.inf:
            v, omega = saturate_keep_turn_rate(
                v, omega, self.wheel_radius, self.half_track, self.max_wheel_speed
            )
        arrived = rho < self.tolerance
        v, omega = np.where(arrived, 0.0, v), np.where(arrived, 0.0, omega)
        return np.stack(np.broadcast_arrays(v, omega), -1)

    def wheel_setpoints(self, pose: ArrayLike, goal: ArrayLike) -> np.ndarray:
        """Wheel angular speeds ``(..., 2)`` (left, right) [rad/s] (corrected eqs. 9–12).

        Parameters
        ----------
        pose : array_like, shape (..., 3)
            Estimated poses.
        goal : array_like, shape (..., 2)
            Goal positions [m].
        """
        command = self(0.0, pose, goal)
        v, omega = command[..., 0], command[..., 1]
        half = self.half_track * omega  # W·L/2
        return np.stack([(v - half) / self.wheel_radius, (v + half) / self.wheel_radius], -1)

    def rpm_setpoints(self, pose: ArrayLike, goal: ArrayLike) -> np.ndarray:
        """Wheel-speed set-points ``(..., 2)`` (left, right) [RPM] (corrected eqs. 15–16).

        Parameters
        ----------
        pose : array_like, shape (..., 3)
            Estimated poses.
        goal : array_like, shape (..., 2)
            Goal positions [m].
        """
        return self.wheel_setpoints(pose, goal) * (60.0 / (2.0 * math.pi))

    def arrived(self, pose: ArrayLike, goal: ArrayLike) -> np.ndarray:
        """Whether each pose is within ``tolerance`` of its goal.

        Parameters
        ----------
        pose : array_like, shape (..., 3)
            Poses.
        goal : array_like, shape (..., 2)
            Goal positions [m].
        """
        pose = as_float_array("pose", pose, 3)
        goal = as_float_array("goal", goal, min_ndim=1)
        return np.hypot(goal[..., 0] - pose[..., 0], goal[..., 1] - pose[..., 1]) < self.tolerance


def _default_model() -> DiffDrive:
    return DiffDrive(wheel_radius=0.035, half_track=0.075)


def _default_encoder() -> Encoder:
    return Encoder(1440, counter_bits=16)  # 12 CPR × 4 (quadrature) × 30:1 gear, 16-bit counter


@dataclass(frozen=True)
class DriveTrain:
    """The hardware below the go-to-goal law: geometry, motors, encoders, speed loop, errors.

    Parameters
    ----------
    model : DiffDrive
        Nominal geometry (default: 35 mm wheel radius, 75 mm half track — a table-top robot).
    motor : DCMotor
        Both wheels' motor (default: the ``gearmotor_12v`` preset of :mod:`wheelbase.motor`).
    encoder : Encoder
        Both wheels' encoder (default: 1440 ticks per wheel revolution, 16-bit counter).
    speed_loop : SpeedLoop or None
        The microcontroller's loop (default: :meth:`SpeedLoop.for_motor` at 100 Hz).
    errors : OdometryErrors
        How the real robot differs from ``model`` (default: not at all).
    odometry_method : {"euler", "midpoint", "exact"}
        Dead-reckoning update of the estimator.
    """

    model: DiffDrive = field(default_factory=_default_model)
    motor: DCMotor = field(default_factory=lambda: MOTOR_PRESETS["gearmotor_12v"])
    encoder: Encoder = field(default_factory=_default_encoder)
    speed_loop: SpeedLoop | None = None
    errors: OdometryErrors = field(default_factory=OdometryErrors)
    odometry_method: str = "exact"

    def __post_init__(self) -> None:
        if self.speed_loop is None:
            object.__setattr__(self, "speed_loop", SpeedLoop.for_motor(self.motor, 0.01))
        if self.odometry_method not in DEAD_RECKONING_METHODS:
            raise ConfigError(
                f"unknown odometry_method {self.odometry_method!r}; allowed: "
                + ", ".join(map(repr, DEAD_RECKONING_METHODS))
            )

    def odometry(self) -> WheelOdometry:
        """The estimator: nominal geometry, the encoder's resolution."""
        return WheelOdometry(
            self.model.wheel_radius,
            self.model.half_track,
            self.encoder.pulses_per_revolution,
            self.odometry_method,
        )
