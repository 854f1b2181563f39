"""What every controller shares: the protocol, command limits and the saturation step.

A controller holds its gains and limits and is called as ``controller(t, pose, reference)``:

- ``t`` is the time [s] (a float);
- ``pose`` is the measured pose ``(x, y, θ)``, shape ``(3,)`` for one robot or ``(N, 3)`` for a
  batch (every controller of :mod:`wheelbase.control` is vectorised over the leading axes);
- ``reference`` is what the law follows: a goal pose, a path or a trajectory (see each law).

It returns the command as an array of shape ``(..., 2)``:

- ``(v, ω)`` — forward speed [m/s] and yaw rate [rad/s] — for the unicycle and differential
  drive (:class:`~wheelbase.models.Unicycle` inputs; for :class:`~wheelbase.models.DiffDrive`
  convert with :func:`velocity_to_wheel_speeds`);
- ``(v, δ)`` — speed [m/s] and steering angle [rad] — for the bicycle, rear-wheel bicycle and
  Ackermann models.

``reset()`` forgets whatever the controller remembered (switching phases, the last steering
angle for the rate limit) so that one object can run several episodes.

The saturation step
-------------------
A law computes the command it wants; the robot can give less. Clipping v and ω separately would
change the curvature κ = ω/v and so the path the robot drives (a robot told to turn tightly
and drive fast would drive a wide arc instead). :func:`saturate_velocity` scales v and ω by
one common factor s ∈ (0, 1] — the largest that satisfies every limit — so that κ is kept and
only the speed along the path is lost. The limits are on |v|, |ω| and on the wheel angular
speeds |ω_L|, |ω_R| of a differential drive (ω_{L,R} = (v ∓ dω)/a, document 001 eq. 20).

For a steered vehicle the curvature is κ = tan(δ)/L, fixed by the steering angle alone, so the
speed limit scales v and keeps δ (and κ); the steering angle and steering rate limits clip δ —
the vehicle cannot turn tighter than its mechanism allows — and leave v as it is
(:func:`saturate_steering`). Reversing keeps the sign of v and of δ: the law negates both.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, ClassVar, Protocol, runtime_checkable

import numpy as np
from numpy.typing import ArrayLike

from wheelbase._validate import as_float_array, finite, positive
from wheelbase.errors import ConfigError, InputError
from wheelbase.geometry import wrap_angle
from wheelbase.models.base import KinematicModel

__all__ = [
    "HOLONOMIC_COMMAND",
    "STEERING_COMMAND",
    "VELOCITY_COMMAND",
    "Controller",
    "GoalController",
    "SteeringLimits",
    "VelocityLimits",
    "WrappedLaw",
    "command_to_inputs",
    "saturate_steering",
    "saturate_velocity",
    "steering_to_velocity",
    "velocity_to_steering",
    "velocity_to_wheel_speeds",
]

VELOCITY_COMMAND: tuple[str, str] = ("v", "omega")
"""Names of a unicycle / differential-drive command ``(v [m/s], ω [rad/s])``."""

STEERING_COMMAND: tuple[str, str] = ("speed", "steering")
"""Names of a steered-vehicle command ``(v [m/s], δ [rad])``."""

HOLONOMIC_COMMAND: tuple[str, str, str] = ("vx", "vy", "omega")
"""Names of a holonomic-base command, the body twist ``(v_x [m/s], v_y [m/s], ω [rad/s])``."""


class WrappedLaw:
    """A controller that wraps another one, ``law`` (slope feed-forward, traction control, a model
    schedule, the twist-to-torque loop): the wrapped law's ``reset``, ``per_robot`` (the engine
    runs one copy per robot) and ``status`` pass through. A subclass sets ``self.law``."""

    law: Any

    def reset(self) -> None:
        """Reset the wrapped law (if it has a reset)."""
        reset = getattr(self.law, "reset", None)
        if reset is not None:
            reset()

    @property
    def per_robot(self) -> bool:
        """Whether the wrapped law needs one copy per robot (MPPI), as the engine asks."""
        return bool(getattr(self.law, "per_robot", False))

    @property
    def status(self) -> str | None:
        """The wrapped law's status (MPPI's ``ok`` / ``all_collide`` / ...), if it has one."""
        return getattr(self.law, "status", None)


@runtime_checkable
class Controller(Protocol):
    """The call signature every controller of :mod:`wheelbase.control` follows.

    Attributes
    ----------
    command_names : tuple of str
        :data:`VELOCITY_COMMAND` or :data:`STEERING_COMMAND`: the meaning of the last axis of
        the command.
    """

    command_names: ClassVar[tuple[str, ...]]

    def __call__(self, t: float, pose: ArrayLike, reference: Any) -> np.ndarray:
        """Command ``(..., 2)`` for the measured pose ``(..., 3)`` at time ``t`` [s]."""
        ...

    def reset(self) -> None:
        """Forget the state kept between calls (phase, last command)."""
        ...


# --------------------------------------------------------------------------- (v, ω) limits
@dataclass(frozen=True)
class VelocityLimits:
    """Limits of a ``(v, ω)`` command; every limit defaults to none (``inf``).

    Parameters
    ----------
    max_speed : float
        Largest |v| [m/s], > 0.
    max_yaw_rate : float
        Largest |ω| [rad/s], > 0.
    max_wheel_speed : float
        Largest wheel angular speed |ω_L|, |ω_R| [rad/s] of a differential drive, > 0; needs
        ``wheel_radius`` and ``half_track``.
    wheel_radius : float, optional
        Wheel radius a [m] for the wheel-speed limit.
    half_track : float, optional
        Half the wheel separation d [m] for the wheel-speed limit.

    Examples
    --------
    >>> limits = VelocityLimits(max_speed=0.5, max_yaw_rate=1.5)
    >>> saturate_velocity([1.0, 1.0], limits).tolist()
    [0.5, 0.5]
    """

    max_speed: float = math.inf
    max_yaw_rate: float = math.inf
    max_wheel_speed: float = math.inf
    wheel_radius: float | None = None
    half_track: float | None = None

    def __post_init__(self) -> None:
        for name, unit in (
            ("max_speed", "m/s"),
            ("max_yaw_rate", "rad/s"),
            ("max_wheel_speed", "rad/s"),
        ):
            object.__setattr__(self, name, _positive_or_inf(name, getattr(self, name), unit))
        for name in ("wheel_radius", "half_track"):
            value = getattr(self, name)
            if value is not None:
                object.__setattr__(self, name, positive(name, value, "m"))
        if math.isfinite(self.max_wheel_speed) and (
            self.wheel_radius is None or self.half_track is None
        ):
            raise ConfigError(
                "max_wheel_speed needs wheel_radius and half_track "
                f"(got wheel_radius={self.wheel_radius}, half_track={self.half_track})"
            )

    @classmethod
    def for_diffdrive(
        cls, model: Any, max_wheel_speed: float, *, max_speed: float = math.inf
    ) -> VelocityLimits:
        """Limits from a :class:`~wheelbase.models.DiffDrive` and its top wheel speed [rad/s]."""
        return cls(
            max_speed=max_speed,
            max_wheel_speed=max_wheel_speed,
            wheel_radius=model.wheel_radius,
            half_track=model.half_track,
        )

    @property
    def bounded(self) -> bool:
        """Whether any limit is finite."""
        return bool(
            math.isfinite(self.max_speed)
            or math.isfinite(self.max_yaw_rate)
            or math.isfinite(self.max_wheel_speed)
        )


def saturate_velocity(command: ArrayLike, limits: VelocityLimits | None) -> np.ndarray:
    """Scale ``(v, ω)`` commands into ``limits`` while keeping their curvature κ = ω/v.

    Parameters
    ----------
    command : array_like, shape (..., 2)
        Commands (v [m/s], ω [rad/s]).
    limits : VelocityLimits or None
        The limits; ``None`` returns the commands unchanged (as a float array).

    Returns
    -------
    numpy.ndarray, shape (..., 2)
        ``s · command`` with s = min(1, v_max/|v|, ω_max/|ω|, ω_w,max/|ω_L|, ω_w,max/|ω_R|),
        one factor per command, so that the signs of v and ω and the ratio ω/v are kept.

    Examples
    --------
    >>> saturate_velocity([[0.2, 3.0], [-1.0, 0.1]], VelocityLimits(0.5, 1.5)).round(3).tolist()
    [[0.1, 1.5], [-0.5, 0.05]]
    """
    command = as_float_array("command", command, 2)
    if limits is None or not limits.bounded:
        return command.copy()
    v, omega = command[..., 0], command[..., 1]
    scale = np.ones_like(v)
    with np.errstate(divide="ignore", over="ignore"):
        scale = np.minimum(scale, limits.max_speed / np.abs(v))
        scale = np.minimum(scale, limits.max_yaw_rate / np.abs(omega))
        if math.isfinite(limits.max_wheel_speed):
            a, d = limits.wheel_radius, limits.half_track
            wheel = (np.abs(v) + d * np.abs(omega)) / a  # the faster wheel, |v| + d|ω| over a
            scale = np.minimum(scale, limits.max_wheel_speed / wheel)
    return command * scale[..., None]


def velocity_to_wheel_speeds(command: ArrayLike, model: Any) -> np.ndarray:
    """Wheel angular speeds ``(..., 2)`` = (ω_L, ω_R) [rad/s] of a differential drive.

    ω_L = (v − dω)/a, ω_R = (v + dω)/a (document 001 eq. 20, rows in (left, right) order); these
    are the inputs of :class:`~wheelbase.models.DiffDrive`.

    Parameters
    ----------
    command : array_like, shape (..., 2)
        Commands (v [m/s], ω [rad/s]).
    model : DiffDrive
        Anything with ``wheel_radius`` a [m] and ``half_track`` d [m].
    """
    command = as_float_array("command", command, 2)
    a, d = model.wheel_radius, model.half_track
    v, omega = command[..., 0], command[..., 1]
    return np.stack([(v - d * omega) / a, (v + d * omega) / a], -1)


# --------------------------------------------------------------------------- (v, δ) limits
@dataclass(frozen=True)
class SteeringLimits:
    """Limits of a ``(v, δ)`` command of a steered vehicle.

    Parameters
    ----------
    max_steering : float
        Largest |δ| [rad], in (0, π/2).
    max_speed : float
        Largest |v| [m/s], > 0 (default: none).
    max_steering_rate : float
        Largest |δ̇| [rad/s], > 0 (default: none); applied by :func:`saturate_steering` when
        it is given the previous steering angle and the step.
    """

    max_steering: float
    max_speed: float = math.inf
    max_steering_rate: float = math.inf

    def __post_init__(self) -> None:
        steering = positive("max_steering", self.max_steering, "rad")
        if steering >= 0.5 * math.pi:
            raise ConfigError(f"max_steering must be < π/2 rad (got {steering:g})")
        object.__setattr__(self, "max_steering", steering)
        object.__setattr__(self, "max_speed", _positive_or_inf("max_speed", self.max_speed, "m/s"))
        object.__setattr__(
            self,
            "max_steering_rate",
            _positive_or_inf("max_steering_rate", self.max_steering_rate, "rad/s"),
        )


def saturate_steering(
    command: ArrayLike,
    limits: SteeringLimits | None,
    previous: ArrayLike | None = None,
    dt: float | None = None,
) -> np.ndarray:
    """Limit ``(v, δ)`` commands: |v| ≤ v_max, |δ| ≤ δ_max and |δ − δ_prev| ≤ δ̇_max·dt.

    Parameters
    ----------
    command : array_like, shape (..., 2)
        Commands (v [m/s], δ [rad]).
    limits : SteeringLimits or None
        The limits; ``None`` returns the commands unchanged.
    previous : array_like, shape (...), optional
        The steering angles [rad] commanded one step before, for the rate limit.
    dt : float, optional
        The step [s] since ``previous`` was commanded, > 0.

    Returns
    -------
    numpy.ndarray, shape (..., 2)
        The limited commands. The speed clip keeps δ and hence the curvature tan(δ)/L; the
        steering clips change the curvature, which the mechanism imposes.
    """
    command = as_float_array("command", command, 2)
    if limits is None:
        return command.copy()
    v = np.clip(command[..., 0], -limits.max_speed, limits.max_speed)
    delta = command[..., 1]
    if previous is not None and math.isfinite(limits.max_steering_rate):
        if dt is None:
            raise ConfigError("the steering-rate limit needs dt (got None)")
        step = limits.max_steering_rate * positive("dt", dt, "s")
        previous = as_float_array("previous", previous)
        delta = np.clip(delta, previous - step, previous + step)
    delta = np.clip(delta, -limits.max_steering, limits.max_steering)
    return np.stack([v, delta], -1)


def velocity_to_steering(command: ArrayLike, wheel_base: float) -> np.ndarray:
    """Convert ``(v, ω)`` commands to ``(v, δ)`` for a rear-axle-referenced bicycle.

    The bicycle with wheel base L turns at ω = v·tan(δ)/L about its rear axle (document 002
    eqs. 11–12 with the speed of the rear wheel), so δ = atan(L·ω/v), which has the sign of
    ω/v: a reversing command (v < 0) gets the steering that gives its curvature. At v = 0 the
    curvature is undefined; δ is then ±π/2 in the direction of ω (0 when ω = 0 too), which the
    steering limit clips.

    Parameters
    ----------
    command : array_like, shape (..., 2)
        Commands (v [m/s], ω [rad/s]).
    wheel_base : float
        L [m], > 0.
    """
    command = as_float_array("command", command, 2)
    length = positive("wheel_base", wheel_base, "m")
    v, omega = command[..., 0], command[..., 1]
    delta = np.arctan2(length * omega * np.sign(v), np.abs(v))
    delta = np.where(v == 0.0, 0.5 * np.pi * np.sign(omega), delta)
    return np.stack([v, delta], -1)


def steering_to_velocity(command: ArrayLike, wheel_base: float) -> np.ndarray:
    """Convert ``(v, δ)`` commands to ``(v, ω)`` with ω = v·tan(δ)/L (inverse of the above).

    Parameters
    ----------
    command : array_like, shape (..., 2)
        Commands (v [m/s], δ [rad]).
    wheel_base : float
        L [m], > 0.
    """
    command = as_float_array("command", command, 2)
    length = positive("wheel_base", wheel_base, "m")
    v, delta = command[..., 0], command[..., 1]
    return np.stack([v, v * np.tan(delta) / length], -1)


# --------------------------------------------------------------------------- pose-goal base
@dataclass(frozen=True)
class GoalController:
    """Shared plumbing of the controllers that drive a unicycle to a goal pose.

    Subclasses implement ``_law(t, x, y, theta)`` on the robot pose expressed in the goal frame
    (goal at the origin facing +x; arrays of the batch shape) and return ``(v, ω)``; this class
    validates the inputs, transforms them, applies :func:`saturate_velocity` and keeps the
    per-episode state (a dict of arrays of the batch shape) that :meth:`reset` clears. A call
    with a different batch shape than the previous one starts a new episode.

    Parameters
    ----------
    limits : VelocityLimits, optional
        Limits applied to every command (keyword only); ``None`` for none.
    """

    command_names: ClassVar[tuple[str, ...]] = VELOCITY_COMMAND
    limits: VelocityLimits | None = field(default=None, kw_only=True)
    _state: dict = field(default_factory=dict, init=False, repr=False, compare=False)

    def reset(self) -> None:
        """Forget the episode state (phases, plans) kept between calls."""
        self._state.clear()

    def __call__(self, t: float, pose: ArrayLike, reference: ArrayLike) -> np.ndarray:
        """Command ``(v [m/s], ω [rad/s])`` of shape ``(..., 2)``.

        Parameters
        ----------
        t : float
            Time [s].
        pose : array_like, shape (..., 3)
            Measured poses (x [m], y [m], θ [rad]).
        reference : array_like, shape (3,) or (..., 3)
            The goal pose(s), broadcast against ``pose``.

        Raises
        ------
        InputError
            On bad shapes or non-finite values, or when the first call of an episode finds a
            robot already at the goal position (nothing to steer to; turn in place instead).
        """
        pose = as_float_array("pose", pose, 3)
        goal = as_float_array("goal", reference, 3)
        pose, goal = np.broadcast_arrays(pose, goal)
        dx, dy = pose[..., 0] - goal[..., 0], pose[..., 1] - goal[..., 1]
        c, s = np.cos(goal[..., 2]), np.sin(goal[..., 2])
        x, y = c * dx + s * dy, -s * dx + c * dy
        theta = wrap_angle(pose[..., 2] - goal[..., 2])
        if self._state.get("shape") != x.shape:
            self._state.clear()
            self._state["shape"] = x.shape
            if np.any(np.hypot(x, y) < 1e-9):
                raise InputError(
                    "goal equals the start position; a pose controller needs a distance "
                    "to travel (turn in place instead)"
                )
            self._start(x, y, theta)
        v, omega = self._law(float(t), x, y, theta)
        return saturate_velocity(np.stack(np.broadcast_arrays(v, omega), -1), self.limits)

    def _start(self, x: np.ndarray, y: np.ndarray, theta: np.ndarray) -> None:
        """Hook: initialise the episode state from the first poses (goal frame)."""

    def _law(
        self, t: float, x: np.ndarray, y: np.ndarray, theta: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray]:  # pragma: no cover - abstract
        raise NotImplementedError


def _positive_or_inf(name: str, value: float, unit: str) -> float:
    number = finite(name, value, unit) if not _is_inf(value) else math.inf
    if number <= 0.0:
        raise ConfigError(f"{name} must be > 0 {unit} (got {number:g})")
    return number


def _is_inf(value: object) -> bool:
    try:
        return float(value) == math.inf  # type: ignore[arg-type]
    except (TypeError, ValueError):
        return False


def command_to_inputs(
    command: np.ndarray, command_names: tuple[str, ...], model: KinematicModel
) -> np.ndarray:
    """Model inputs ``(..., k)`` for controller commands ``(..., 2)`` (or ``(..., 3)``).

    ``(v, ω)`` drives a :class:`~wheelbase.models.Unicycle` directly, a
    :class:`~wheelbase.models.DiffDrive` through its wheel speeds and a steered model
    (inputs ``(speed, steering)``) through δ = atan(L·ω/v) clipped to its steering stop;
    ``(v, δ)`` drives a steered model directly; ``(v_x, v_y, ω)`` drives
    :class:`~wheelbase.models.BodyTwist` directly and a holonomic wheeled base through its
    inverse kinematics. Any other model gets ``model.inverse`` of the twist (v, 0, ω).

    Parameters
    ----------
    command : numpy.ndarray, shape (..., 2)
        Controller commands.
    command_names : tuple of str
        Their meaning (``VELOCITY_COMMAND`` or ``STEERING_COMMAND``).
    model : KinematicModel
        The plant.
    """
    names = tuple(model.input_names)
    if tuple(command_names) == HOLONOMIC_COMMAND:
        if names == ("u", "v", "r"):
            return command
        if not getattr(model, "is_holonomic", False):
            raise ConfigError(
                f"a (vx, vy, omega) controller needs a holonomic base (got {type(model).__name__})"
            )
        return model.inverse(command)  # type: ignore[attr-defined]
    if tuple(command_names) == STEERING_COMMAND:
        if names != STEERING_COMMAND:
            raise ConfigError(
                f"a (speed, steering) controller needs a steered model (got {type(model).__name__})"
            )
        return command
    if names == VELOCITY_COMMAND:
        return command
    if names == ("omega_left", "omega_right"):
        return velocity_to_wheel_speeds(command, model)
    if names == STEERING_COMMAND:
        steering = velocity_to_steering(command, model.wheel_base)  # type: ignore[attr-defined]
        limit = model.max_steering  # type: ignore[attr-defined]
        steering[..., 1] = np.clip(steering[..., 1], -limit, limit)
        return steering
    twist = np.stack([command[..., 0], np.zeros_like(command[..., 0]), command[..., 1]], -1)
    return model.inverse(twist)  # type: ignore[attr-defined]
