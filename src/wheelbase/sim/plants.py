"""What the engine moves: the true robot, kinematic or dynamic, and its encoder axle.

A plant turns the controller's command into motion over one step for a batch of robots
``(N, …)``. It also says how fast the wheels of the encoder axle turn, which is what the
encoders measure.

The encoder axle
----------------
The encoders sit on the wheels of the axle through the reference point (the two drive wheels
of a differential drive, the rear wheels of a car). Whatever the model, the wheels of that axle
roll on the ground, so their true rates are ω_{L,R} = (u ∓ d_true·r)/a_{L,R,true}.
Odometry reads their ticks with the *nominal* radius and half track; the difference between the
true and the nominal geometry (``radius_scale``, ``track_scale``) is the systematic odometry
error (Borenstein's E_d, E_b), encoder noise the random one.

How the true geometry changes the motion depends on what drives the robot:

- a differential drive (and the unicycle, driven the same way) turns its two wheels at the
  rates the *nominal* geometry asks for; the true radii and track decide the motion
  (document 001 eqs. 18–20 with the true a_L, a_R, d);
- a steered or holonomic robot follows its own kinematics (v·tan δ/L for a car): its driven
  wheels' true radius scales the speed by the mean of ``radius_scale``, and the track does not
  change the path at all (it only misleads the odometry).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

from wheelbase._validate import check_choice, positive
from wheelbase.control.base import VELOCITY_COMMAND, command_to_inputs
from wheelbase.errors import ConfigError
from wheelbase.integrate import METHODS, integrate_step
from wheelbase.models.base import KinematicModel

__all__ = ["DynamicPlant", "KinematicPlant", "WheelAxle"]

_WHEEL_DRIVEN = (VELOCITY_COMMAND, ("omega_left", "omega_right"))


@dataclass(frozen=True)
class WheelAxle:
    """The encoder axle: nominal geometry, and the true geometry as scale factors.

    Parameters
    ----------
    wheel_radius : float
        Nominal wheel radius a [m], > 0.
    half_track : float
        Nominal half distance d between the encoder wheels [m], > 0.
    radius_scale : tuple of float
        True (left, right) wheel radius divided by the nominal one, > 0.
    track_scale : float
        True track divided by the nominal one, > 0.
    """

    wheel_radius: float
    half_track: float
    radius_scale: tuple[float, float] = (1.0, 1.0)
    track_scale: float = 1.0

    def __post_init__(self) -> None:
        object.__setattr__(self, "wheel_radius", positive("wheel_radius", self.wheel_radius, "m"))
        object.__setattr__(self, "half_track", positive("half_track", self.half_track, "m"))
        object.__setattr__(self, "track_scale", positive("track_scale", self.track_scale))
        scales = tuple(positive("radius_scale", value) for value in self.radius_scale)
        if len(scales) != 2:
            raise ConfigError(f"radius_scale must be (left, right) (got {self.radius_scale!r})")
        object.__setattr__(self, "radius_scale", scales)

    @property
    def has_error(self) -> bool:
        """Whether the true geometry differs from the nominal one."""
        return self.radius_scale != (1.0, 1.0) or self.track_scale != 1.0

    def wheel_rates(self, twist: np.ndarray, *, true: bool = True) -> np.ndarray:
        """Wheel angular rates (left, right) ``(..., 2)`` [rad/s] of a body twist (u, v, r).

        Parameters
        ----------
        twist : numpy.ndarray, shape (..., 3)
            Body twist [m/s, m/s, rad/s].
        true : bool
            With the true geometry (default) or the nominal one.
        """
        half = self.half_track * (self.track_scale if true else 1.0)
        left = self.wheel_radius * (self.radius_scale[0] if true else 1.0)
        right = self.wheel_radius * (self.radius_scale[1] if true else 1.0)
        u, r = twist[..., 0], twist[..., 2]
        out = np.empty((*u.shape, 2))
        out[..., 0] = (u - half * r) / left
        out[..., 1] = (u + half * r) / right
        return out

    def twist(self, wheel_rates: np.ndarray) -> np.ndarray:
        """Body twist ``(..., 3)`` that true wheel rates (left, right) produce.

        Parameters
        ----------
        wheel_rates : numpy.ndarray, shape (..., 2)
            Wheel angular rates [rad/s].
        """
        half = self.half_track * self.track_scale
        left = wheel_rates[..., 0] * self.wheel_radius * self.radius_scale[0]
        right = wheel_rates[..., 1] * self.wheel_radius * self.radius_scale[1]
        return np.stack(
            [0.5 * (left + right), np.zeros_like(left), 0.5 * (right - left) / half], -1
        )


class _PoseAndTwistOnly:
    """A plant that keeps nothing between steps besides pose and twist."""

    def start(self, n: int, seeds: np.ndarray) -> None:
        """Nothing to keep (the plant's state is the pose and the twist).

        Parameters
        ----------
        n : int
            Number of robots.
        seeds : numpy.ndarray
            Their seeds (unused).
        """
        return None


@dataclass(frozen=True)
class KinematicPlant(_PoseAndTwistOnly):
    """A kinematic robot: the command is held over the step and the model's twist integrated.

    Parameters
    ----------
    model : KinematicModel
        Any model of :mod:`wheelbase.models`.
    axle : WheelAxle or None
        The encoder axle (None: no wheel rates are measured, e.g. a holonomic base).
    integrator : str
        Method of :data:`wheelbase.integrate.METHODS` (``exact``: the closed-form arc, exact
        under a held command).
    """

    model: KinematicModel
    axle: WheelAxle | None = None
    integrator: str = "rk4"

    state_size: ClassVar[int] = 3
    dynamic: ClassVar[bool] = False

    def __post_init__(self) -> None:
        check_choice("integrator", self.integrator, METHODS)

    def command_names(self, controller_names: tuple[str, ...]) -> tuple[str, ...]:
        """The commands the plant takes from a controller that gives ``controller_names``.

        Parameters
        ----------
        controller_names : tuple of str
            The controller's command names.
        """
        command_to_inputs(np.zeros(len(controller_names)), controller_names, self.model)
        return tuple(controller_names)

    def motion(
        self, twist: np.ndarray, command: np.ndarray, names: tuple[str, ...], state: Any = None
    ):
        """The true twist ``(N, 3)`` and encoder wheel rates ``(N, 2)`` under a command.

        ``twist`` (the state's current twist) is unused: a kinematic robot moves at once.

        Parameters
        ----------
        twist : numpy.ndarray, shape (N, 3)
            The current body twist.
        command : numpy.ndarray, shape (N, k)
            The controller's commands.
        names : tuple of str
            Their meaning.
        state : None
            What the plant keeps (nothing).
        """
        inputs = command_to_inputs(command, names, self.model)
        moved = np.asarray(self.model.twist(inputs), dtype=np.float64).reshape(-1, 3)
        axle = self.axle
        if axle is None:
            return moved, np.zeros((moved.shape[0], 2))
        if not axle.has_error:
            return moved, axle.wheel_rates(moved)
        if tuple(self.model.input_names) in _WHEEL_DRIVEN:
            # The wheels turn at the rates the nominal geometry asks for; the true one moves.
            rates = axle.wheel_rates(moved, true=False)
            return axle.twist(rates), rates
        # A steered or holonomic robot keeps its own kinematics; only the speed scales.
        moved = moved * (0.5 * (axle.radius_scale[0] + axle.radius_scale[1]))
        return moved, axle.wheel_rates(moved)

    def step(self, pose, twist, command, moved, rates, dt, state=None, index=None):
        """Advance poses by ``dt`` under the twist ``moved`` of :meth:`motion`.

        Parameters
        ----------
        pose : numpy.ndarray, shape (M, 3)
            Poses at the start of the step (the robots still running).
        twist : numpy.ndarray, shape (M, 3)
            Twists at the start of the step (unused).
        command : numpy.ndarray, shape (M, k)
            The command (unused: already in ``moved``).
        moved : numpy.ndarray, shape (M, 3)
            The twist held over the step.
        rates : numpy.ndarray, shape (M, 2)
            The encoder wheel rates of :meth:`motion`, held over the step.
        dt : float
            Step [s].
        state, index : optional
            What the plant keeps, and which robots these rows are (unused).

        Returns
        -------
        pose, twist, wheel_turn, state
            The new poses and twists, the encoder wheels' rotation over the step [rad] and
            what the plant keeps.
        """
        new_pose = integrate_step(pose, moved, moved, moved, dt, self.integrator)
        return new_pose, moved, rates * dt, state


@dataclass(frozen=True)
class DynamicPlant(_PoseAndTwistOnly):
    """A dynamic differential drive: wheel torques in, Lagrange–Euler dynamics integrated.

    The state (x, y, ψ, u, v, r) is integrated by RK4 under the torques held over the step
    (:meth:`wheelbase.dynamics.DiffDriveDynamics.step`); the robots start at rest.

    Parameters
    ----------
    dynamics : DiffDriveDynamics
        The rigid-body model (document 000 §5), e.g. :data:`wheelbase.dynamics.RM100`.
    axle : WheelAxle or None
        The encoder axle (default: the model's wheels, no geometry error).
    """

    dynamics: Any
    axle: WheelAxle | None = None

    state_size: ClassVar[int] = 6
    dynamic: ClassVar[bool] = True

    def __post_init__(self) -> None:
        from wheelbase.dynamics import DiffDriveDynamics

        if not isinstance(self.dynamics, DiffDriveDynamics):
            raise ConfigError(
                f"a dynamic plant needs a DiffDriveDynamics (got {type(self.dynamics).__name__})"
            )
        if self.axle is None:
            axle = WheelAxle(self.dynamics.wheel_radius, self.dynamics.half_track)
            object.__setattr__(self, "axle", axle)
        params = np.array(self.dynamics._params)  # writable: Numba's fast dispatch path
        object.__setattr__(self, "_params", params)

    def command_names(self, controller_names: tuple[str, ...]) -> tuple[str, ...]:
        """The plant takes wheel torques: the controller must give (τ_L, τ_R).

        Parameters
        ----------
        controller_names : tuple of str
            The controller's command names.
        """
        if len(controller_names) != 2 or not all(
            name.startswith("tau") for name in controller_names
        ):
            raise ConfigError(
                f"a dynamic plant takes wheel torques (tau_left, tau_right); this controller "
                f"gives {tuple(controller_names)}: wrap it in control.TwistTorqueLoop"
            )
        return tuple(controller_names)

    def motion(
        self, twist: np.ndarray, command: np.ndarray, names: tuple[str, ...], state: Any = None
    ):
        """The current twist and its encoder wheel rates (torques act over the step).

        Parameters
        ----------
        twist : numpy.ndarray, shape (N, 3)
            The current body twist.
        command : numpy.ndarray, shape (N, 2)
            Wheel torques [N·m] (unused here).
        names : tuple of str
            Their names.
        state : None
            What the plant keeps (nothing).
        """
        return twist, self.axle.wheel_rates(twist)

    def step(self, pose, twist, command, moved, rates, dt, state=None, index=None):
        """Advance the states by ``dt`` under wheel torques ``command`` held over the step.

        Parameters
        ----------
        pose, twist : numpy.ndarray, shape (M, 3)
            The state at the start of the step (the robots still running).
        command : numpy.ndarray, shape (M, 2)
            Wheel torques (left, right) [N·m].
        moved : numpy.ndarray, shape (M, 3)
            The twist of :meth:`motion` (unused).
        rates : numpy.ndarray, shape (M, 2)
            The encoder wheel rates at the start of the step.
        dt : float
            Step [s].
        state, index : optional
            What the plant keeps, and which robots these rows are (unused).

        Returns
        -------
        pose, twist, wheel_turn, state
            The wheels turn by the integral of their rate: the trapezoid of the step's ends.
        """
        from wheelbase.dynamics import _step_many

        # the engine has checked the shapes and values: the compiled step directly
        full = np.concatenate([pose, twist], axis=-1)
        _step_many(full, np.ascontiguousarray(command, dtype=np.float64), self._params, dt)
        new_twist = full[:, 3:]
        turned = 0.5 * (rates + self.axle.wheel_rates(new_twist)) * dt
        return full[:, :3], new_twist, turned, state
