"""Go-to-goal through motors, speed loop and encoders (document 003 Fig. 1), on the engine.

:class:`DriveTrainPlant` is the hardware under the go-to-goal law: every control period the
(v, ω) command becomes wheel set-points in RPM (corrected eqs. 9–16 with the *nominal*
geometry); the microcontroller's PI speed loop (:class:`wheelbase.motor.SpeedLoop`) runs
``control_period / speed_loop.period`` times, each time measuring the wheel speeds from the
encoder counts of its last period and holding a PWM duty; the DC motors
(:class:`wheelbase.motor.DCMotor`) are stepped exactly ``substeps`` times per loop period and the
true robot (with the :class:`~wheelbase.odometry.OdometryErrors` it may have, slip included)
moves by the exact arc of each wheel-angle increment. The encoders the engine reads for
odometry count the same wheel angles.

The speed loop measures ideal tick counts (quantisation only); the random encoder errors are
drawn once, by the engine's encoders, for the odometry — a simplification: on the robot both
read one counter.

:func:`run_go_to_goal` runs the loop for one or many goals at once.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Any, ClassVar

import numpy as np
from numpy.typing import ArrayLike

from wheelbase._validate import as_float_array, positive
from wheelbase.control.base import VELOCITY_COMMAND
from wheelbase.control.goal import DriveTrain, GoToGoal
from wheelbase.errors import ConfigError
from wheelbase.integrate import integrate_step
from wheelbase.sim.engine import Arrival, Engine
from wheelbase.sim.log import Log
from wheelbase.sim.plants import WheelAxle
from wheelbase.sim.sensing import EncoderOdometry
from wheelbase.sim.streams import counter_stream

__all__ = ["SLIP_STREAM", "DriveTrainPlant", "DriveTrainState", "run_go_to_goal"]

SLIP_STREAM = 4
"""Stream of a robot's wheel slip (:func:`~wheelbase.sim.streams.counter_stream`; counter: the
control period)."""

_RPM = 60.0 / (2.0 * math.pi)


@dataclass(frozen=True)
class DriveTrainState:
    """What the drive train keeps between control periods, one row per robot.

    Attributes
    ----------
    motors : numpy.ndarray, shape (N, 2, 3)
        (current [A], wheel speed [rad/s], wheel angle [rad]) of the (left, right) motors.
    integral : numpy.ndarray, shape (N, 2)
        The speed loops' error integrals [RPM·s].
    duty : numpy.ndarray, shape (N, 2)
        PWM duty in force [−1, 1].
    measured_rpm : numpy.ndarray, shape (N, 2)
        Wheel speeds the speed loop measured over its last period [RPM].
    setpoint_rpm : numpy.ndarray, shape (N, 2)
        Wheel-speed set-points in force [RPM].
    read_angle : numpy.ndarray, shape (N, 2)
        Wheel angles at the speed loop's last reading [rad].
    seeds : numpy.ndarray of int64, shape (N,)
        Each robot's seed of its wheel slip (stream :data:`SLIP_STREAM`).
    periods : numpy.ndarray of int64, shape (N,)
        Control periods each robot has driven (the counter of its slip's random stream).
    """

    motors: np.ndarray
    integral: np.ndarray
    duty: np.ndarray
    measured_rpm: np.ndarray
    setpoint_rpm: np.ndarray
    read_angle: np.ndarray
    seeds: np.ndarray
    periods: np.ndarray


@dataclass(frozen=True)
class DriveTrainPlant:
    """A differential drive moved by its motors under a PI speed loop (module docstring).

    Parameters
    ----------
    drive : DriveTrain
        Geometry, motors, encoders, speed loop and errors.
    substeps : int
        Motor steps per speed-loop period, >= 1.
    """

    drive: DriveTrain
    substeps: int = 5

    state_size: ClassVar[int] = 3
    dynamic: ClassVar[bool] = False

    def __post_init__(self) -> None:
        if not isinstance(self.drive, DriveTrain):
            raise ConfigError(f"drive must be a DriveTrain (got {type(self.drive).__name__})")
        if (
            isinstance(self.substeps, bool)
            or not isinstance(self.substeps, (int, np.integer))
            or self.substeps < 1
        ):
            raise ConfigError(f"substeps must be an integer >= 1 (got {self.substeps!r})")

    @property
    def axle(self) -> WheelAxle:
        """The nominal encoder axle (the true one differs by ``drive.errors``)."""
        model = self.drive.model
        return WheelAxle(model.wheel_radius, model.half_track)

    def loops_per_period(self, dt: float) -> int:
        """Speed-loop periods in one control period ``dt`` [s] (a whole number, or an error).

        Parameters
        ----------
        dt : float
            Control period [s].
        """
        period = self.drive.speed_loop.period
        ratio = dt / period
        if abs(ratio - round(ratio)) > 1e-9 or round(ratio) < 1:
            raise ConfigError(
                f"control_period must be a whole multiple of the speed-loop period {period:g} s "
                f"(got {dt:g} s)"
            )
        return round(ratio)

    def command_names(self, controller_names: tuple[str, ...]) -> tuple[str, ...]:
        """The drive train takes (v, ω).

        Parameters
        ----------
        controller_names : tuple of str
            The controller's command names.
        """
        if tuple(controller_names) != VELOCITY_COMMAND:
            raise ConfigError(f"a drive train takes (v, omega) (got {tuple(controller_names)})")
        return VELOCITY_COMMAND

    def start(self, n: int, seeds: np.ndarray) -> DriveTrainState:
        """Motors at rest, loops cleared.

        Parameters
        ----------
        n : int
            Number of robots.
        seeds : numpy.ndarray of int, shape (N,)
            Their seeds (wheel slip draws from a stream apart from the encoders').
        """
        zeros = np.zeros((n, 2))
        return DriveTrainState(
            motors=np.zeros((n, 2, 3)),
            integral=zeros.copy(),
            duty=zeros.copy(),
            measured_rpm=zeros.copy(),
            setpoint_rpm=zeros.copy(),
            read_angle=zeros.copy(),
            seeds=np.array(seeds, dtype=np.int64),
            periods=np.zeros(n, dtype=np.int64),
        )

    def signals(self, state: DriveTrainState) -> dict[str, np.ndarray]:
        """What the log keeps of the drive train at each row.

        Parameters
        ----------
        state : DriveTrainState
            The drive train's state.
        """
        return {
            "setpoint_rpm": state.setpoint_rpm.copy(),
            "measured_rpm": state.measured_rpm.copy(),
            "duty": state.duty.copy(),
        }

    def motion(
        self, twist: np.ndarray, command: np.ndarray, names: tuple[str, ...], state: Any = None
    ):
        """The current twist and wheel speeds (the motors, not the command, move the robot).

        Parameters
        ----------
        twist : numpy.ndarray, shape (N, 3)
            The body twist of the last motor step.
        command : numpy.ndarray, shape (N, 2)
            (v, ω) (unused here).
        names : tuple of str
            Their names.
        state : DriveTrainState
            The drive train's state.
        """
        return twist, state.motors[:, :, 1].copy()

    def step(self, pose, twist, command, moved, rates, dt, state, index):
        """One control period: set-points, speed loops, motors and ground motion.

        Parameters
        ----------
        pose, twist : numpy.ndarray, shape (M, 3)
            The robots still running.
        command : numpy.ndarray, shape (M, 2)
            (v [m/s], ω [rad/s]).
        moved, rates : numpy.ndarray
            Of :meth:`motion` (unused).
        dt : float
            Control period [s].
        state : DriveTrainState
            The drive train's state (all robots).
        index : numpy.ndarray of int, shape (M,)
            Which robots the rows are.

        Returns
        -------
        pose, twist, wheel_turn, state
        """
        drive = self.drive
        loop, motor, encoder, errors = drive.speed_loop, drive.motor, drive.encoder, drive.errors
        radius, half = drive.model.wheel_radius, drive.model.half_track
        loops = self.loops_per_period(dt)
        h = loop.period / self.substeps
        v, omega = command[:, 0], command[:, 1]
        setpoint = np.stack([v - half * omega, v + half * omega], -1) / radius * _RPM
        motors = state.motors[index].copy()
        integral, duty = state.integral[index].copy(), state.duty[index].copy()
        measured, read = state.measured_rpm[index].copy(), state.read_angle[index].copy()
        start_angle = motors[:, :, 2].copy()
        pose = pose.copy()
        slips = []  # one counter-based generator per robot for the period's substeps
        if errors.slip_std > 0:
            slips = [counter_stream(state.seeds[i], SLIP_STREAM, state.periods[i]) for i in index]
        for _ in range(loops):
            ticks = encoder.count(motors[:, :, 2]) - encoder.count(read)
            read = motors[:, :, 2].copy()
            measured = encoder.rpm(ticks, loop.period)
            duty, integral = loop.update(integral, setpoint, measured)
            for _ in range(self.substeps):
                before = motors[:, :, 2].copy()
                motors = motor.step(motors, duty, h)
                turned = motors[:, :, 2] - before
                if errors.slip_std > 0:
                    moves = [
                        errors.ground_increments(radius, half, turned[k], slips[k])
                        for k in range(len(index))
                    ]
                    distance = np.array([m[0] for m in moves])
                    rotation = np.array([m[1] for m in moves])
                else:
                    distance, rotation = errors.ground_increments(radius, half, turned)
                twist = np.stack([distance / h, np.zeros_like(distance), rotation / h], -1)
                pose = integrate_step(pose, twist, twist, twist, h, method="exact")
        new = replace(
            state,
            motors=state.motors.copy(),
            integral=state.integral.copy(),
            duty=state.duty.copy(),
            measured_rpm=state.measured_rpm.copy(),
            setpoint_rpm=state.setpoint_rpm.copy(),
            read_angle=state.read_angle.copy(),
            periods=state.periods.copy(),
        )
        new.periods[index] += 1
        new.motors[index], new.integral[index], new.duty[index] = motors, integral, duty
        new.measured_rpm[index], new.setpoint_rpm[index] = measured, setpoint
        new.read_angle[index] = read
        return pose, twist, motors[:, :, 2] - start_angle, new


def run_go_to_goal(
    goal: ArrayLike,
    controller: GoToGoal | None = None,
    drive: DriveTrain | None = None,
    *,
    pose0: ArrayLike = (0.0, 0.0, 0.0),
    control_period: float = 0.05,
    substeps: int = 5,
    t_max: float = 60.0,
    seed: int = 0,
) -> Log:
    """Drive to ``goal`` (or to N goals at once) through the loop of document 003.

    The engine's arrival rule ends each robot's run: its odometry says it is within the law's
    ``tolerance`` of the goal (any heading) and the motors have stopped; ``arrived`` if the
    true position is within the tolerance too, else ``missed_goal`` (odometry drift).

    Parameters
    ----------
    goal : array_like, shape (2,) or (N, 2)
        Goal position(s) (x, y) [m], finite: one robot per goal.
    controller : GoToGoal, optional
        The law (default: ``GoToGoal()`` with the drive's geometry and 80 % of the motor's
        no-load speed as wheel limit).
    drive : DriveTrain, optional
        Geometry, motors, encoders, speed loop and errors (default: ``DriveTrain()``).
    pose0 : array_like, shape (3,) or (N, 3)
        Start pose(s) (default: the origin facing +x, as in document 003 Fig. 8).
    control_period : float
        Period [s] of the law (the microprocessor); a whole multiple of the speed-loop period.
    substeps : int
        Motor steps per speed-loop period (the wheel speeds vary within a period).
    t_max : float
        Time limit [s], > 0.
    seed : int
        Seed of robot 0's random encoder errors and wheel slip (robot i: ``seed + i``).

    Returns
    -------
    Log
        One robot per goal, one row per control period; ``extras`` hold ``setpoint_rpm``,
        ``measured_rpm`` and ``duty`` (N, T, 2).

    Raises
    ------
    InputError
        A goal that is not finite numbers of the right shape.
    ConfigError
        Periods that are not positive or not commensurate.
    """
    goals = as_float_array("goal", goal, 2, min_ndim=1, max_ndim=2).reshape(-1, 2)
    starts = as_float_array("pose0", pose0, 3, min_ndim=1, max_ndim=2).reshape(-1, 3)
    drive = drive if drive is not None else DriveTrain()
    if controller is None:
        controller = GoToGoal(
            wheel_radius=drive.model.wheel_radius,
            half_track=drive.model.half_track,
            max_wheel_speed=0.8 * drive.motor.no_load_speed,
        )
    plant = DriveTrainPlant(drive, substeps)
    plant.loops_per_period(positive("control_period", control_period, "s"))
    n = max(goals.shape[0], starts.shape[0])
    goals = np.broadcast_to(goals, (n, 2))
    engine = Engine(
        plant,
        controller,
        goals,
        dt=control_period,
        duration=positive("t_max", t_max, "s"),
        estimator=EncoderOdometry(drive.encoder, drive.odometry()),
        arrival=Arrival(np.column_stack([goals, np.zeros(n)]), (controller.tolerance, math.pi)),
    )
    return engine.run(np.broadcast_to(starts, (n, 3)), seeds=seed)
