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

__all__ = ["DynamicPlant", "KinematicPlant", "TerrainPlant", "TerrainState", "WheelAxle"]

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


def _torque_names(controller_names: tuple[str, ...]) -> tuple[str, ...]:
    """The command names of a torque-driven plant, or ConfigError for another controller."""
    if len(controller_names) != 2 or not all(name.startswith("tau") for name in controller_names):
        raise ConfigError(
            f"a dynamic plant takes wheel torques (tau_left, tau_right); this controller "
            f"gives {tuple(controller_names)}: wrap it in control.TwistTorqueLoop"
        )
    return tuple(controller_names)


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
        return _torque_names(controller_names)

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


@dataclass(frozen=True)
class TerrainState:
    """What a :class:`TerrainPlant` keeps between steps, one row per robot.

    Attributes
    ----------
    aux : numpy.ndarray, shape (N, 13)
        Wheel rates and angles, energy integrals, the lagged ground force
        (:data:`wheelbase.terrain.dynamics.AUX_NAMES`).
    signals : numpy.ndarray, shape (N, 11)
        Slip, traction, loads, sinkage and surfaces after the last step
        (:data:`wheelbase.terrain.dynamics.SIGNAL_NAMES`).
    time : float
        Simulated time [s] of the next step (for the payload changes).
    """

    aux: np.ndarray
    signals: np.ndarray
    time: float = 0.0


@dataclass(frozen=True)
class TerrainPlant:
    """A dynamic differential drive on terrain: slip, traction limits, slopes, soil, payloads.

    Each step integrates :class:`wheelbase.terrain.TerrainDynamics` (rigid contact or wheel
    slip) under the wheel torques held over the step. With slip the encoders count the wheels'
    own rotation, so a spinning wheel drives the odometry off; with rigid contact they count it
    as :class:`DynamicPlant` does (the trapezoid of the rolling rates), so that on a surface
    without resistance, flat, the two plants give the same runs.

    Parameters
    ----------
    model : TerrainDynamics
        The robot on its ground from t = 0.
    axle : WheelAxle or None
        The encoder axle (default: the model's wheels, no geometry error).
    changes : tuple of (float, TerrainDynamics)
        Later models and the times [s] they take over, increasing (a payload picked up or
        dropped: the same ground under another body).
    """

    model: Any
    axle: WheelAxle | None = None
    changes: tuple = ()

    state_size: ClassVar[int] = 6
    dynamic: ClassVar[bool] = True

    def __post_init__(self) -> None:
        from wheelbase.terrain.dynamics import TerrainDynamics

        models = [self.model] + [model for _, model in self.changes]
        if not all(isinstance(model, TerrainDynamics) for model in models):
            raise ConfigError("a terrain plant needs TerrainDynamics models")
        times = [float(time) for time, _ in self.changes]
        if any(not np.isfinite(t) or t < 0 for t in times) or times != sorted(times):
            raise ConfigError(f"the model changes must come at increasing times >= 0 s ({times})")
        if len({(m.slip, m.dynamics.wheel_radius, m.dynamics.half_track) for m in models}) > 1:
            raise ConfigError("a payload change keeps the wheels and the contact model")
        object.__setattr__(self, "changes", tuple(zip(times, models[1:], strict=True)))
        if self.axle is None:
            dyn = self.model.dynamics
            object.__setattr__(self, "axle", WheelAxle(dyn.wheel_radius, dyn.half_track))

    def model_at(self, time: float) -> Any:
        """The model in force at ``time`` [s].

        Parameters
        ----------
        time : float
            Simulated time [s].
        """
        model = self.model
        for start, later in self.changes:
            if time >= start - 1e-9:
                model = later
        return model

    def command_names(self, controller_names: tuple[str, ...]) -> tuple[str, ...]:
        """The plant takes wheel torques, as :class:`DynamicPlant`.

        Parameters
        ----------
        controller_names : tuple of str
            The controller's command names.
        """
        return _torque_names(controller_names)

    def start(self, n: int, seeds: np.ndarray) -> TerrainState:
        """Wheels at rest (their rates are set from the first twist at the first step).

        Parameters
        ----------
        n : int
            Number of robots.
        seeds : numpy.ndarray
            Their seeds (unused: the plant is deterministic).
        """
        from wheelbase.terrain.dynamics import SIGNAL_NAMES

        return TerrainState(self.model.start(n), np.zeros((n, len(SIGNAL_NAMES))), 0.0)

    def signals(self, state: TerrainState) -> dict[str, np.ndarray]:
        """What the log keeps each row: slip, traction, normal load, sinkage and surface of
        each drive wheel, and the energy integrals [J] (``energy_*``).

        Parameters
        ----------
        state : TerrainState
            The plant's state.
        """
        from wheelbase.terrain.dynamics import AUX_NAMES, SIGNAL_NAMES

        out = {name: state.signals[:, k].copy() for k, name in enumerate(SIGNAL_NAMES[:10])}
        for k in range(4, 10):
            out[f"energy_{AUX_NAMES[k]}"] = state.aux[:, k].copy()
        return out

    def motion(
        self, twist: np.ndarray, command: np.ndarray, names: tuple[str, ...], state: Any = None
    ):
        """The current twist and the drive wheels' rates (their own with slip).

        Parameters
        ----------
        twist : numpy.ndarray, shape (N, 3)
            The current body twist.
        command : numpy.ndarray, shape (N, 2)
            Wheel torques [N·m] (unused here).
        names : tuple of str
            Their names.
        state : TerrainState
            The plant's state.
        """
        rolling = self.axle.wheel_rates(twist)
        if not self.model.slip or state is None:
            return twist, rolling
        started = state.aux[:, 12:13] > 0.5
        return twist, np.where(started, state.aux[:, 0:2], rolling)

    def step(self, pose, twist, command, moved, rates, dt, state, index):
        """Advance the robots ``index`` by ``dt`` under the wheel torques ``command``.

        Parameters
        ----------
        pose, twist : numpy.ndarray, shape (M, 3)
            The state at the start of the step (the robots still running).
        command : numpy.ndarray, shape (M, 2)
            Wheel torques (left, right) [N·m].
        moved : numpy.ndarray, shape (M, 3)
            The twist of :meth:`motion` (unused).
        rates : numpy.ndarray, shape (M, 2)
            The wheel rates at the start of the step.
        dt : float
            Step [s].
        state : TerrainState
            The plant's state (all robots).
        index : numpy.ndarray of int, shape (M,)
            Which robots the rows are.

        Returns
        -------
        pose, twist, wheel_turn, state
        """
        from wheelbase.terrain.dynamics import terrain_step

        model = self.model_at(state.time)
        full = np.concatenate([pose, twist], axis=-1)
        aux = state.aux[index].copy()
        before = aux[:, 2:4].copy()
        signals = np.zeros((len(index), state.signals.shape[1]))
        torques = np.ascontiguousarray(command, dtype=np.float64)
        terrain_step(full, aux, torques, dt, *model.kernel_args(), signals)
        new_twist = full[:, 3:]
        if model.slip:
            turned = aux[:, 2:4] - before
            if self.axle.has_error:  # the true wheels are scaled, their ground travel is not
                true = np.array(self.axle.radius_scale) * self.axle.wheel_radius
                turned = turned * model.dynamics.wheel_radius / true
        else:
            turned = 0.5 * (rates + self.axle.wheel_rates(new_twist)) * dt
        all_aux, all_signals = state.aux.copy(), state.signals.copy()
        all_aux[index], all_signals[index] = aux, signals
        return full[:, :3], new_twist, turned, TerrainState(all_aux, all_signals, state.time + dt)
