"""The one closed-loop engine: N robots stepped in lockstep, one batched :class:`Log` out.

Constant parameters (the plant, the controller and its reference, the estimator, the arrival
rule, the collision check, ``dt``) live in an :class:`Engine`; what evolves lives in an
:class:`EngineState` with a leading batch axis ``(N, …)``. One robot is N = 1 through the same
code. Each :meth:`Engine.step`, for every robot still running:

1. *estimator*: the estimate the controller will see (odometry from the last step's encoder
   ticks and the sensors read at the end of the last step, or the true state);
2. *controller*: ``controller(t, estimate, reference)`` → command ``(N, k)`` (a learning agent
   may pass the command instead: the hook before the plant);
3. *command limits*: the plant turns the command into its inputs (steering stops); a
   non-finite command ends that robot ``diverged`` and the others run on;
4. *the rules* (on the state at time t): collision of the footprint → ``collision``; after
   the reference has ended, at rest and with the *estimate* within tolerance of the goal, the
   robot stops → ``arrived`` if the *true* pose is within tolerance too, else ``missed_goal``;
   with a ``stuck`` rule, commanded to move and not moving for its time → ``stuck``;
   the time limit → ``timeout``;
5. *plant*: the true state advances by ``dt`` (kinematic or dynamic);
6. *encoders and sensors*: the wheel angles' change becomes tick differences, and the sensors
   that are due (:class:`~wheelbase.sim.sensors.SensorSuite`: a lidar, landmarks) are read at
   the new true poses; both go to the estimator, whose estimate the controller sees next. An
   IMU (:class:`~wheelbase.sim.imu_sensing.ImuReadings`) is read from the step's true motion
   and goes to the controllers that read it (``reads_imu``: called with ``imu=`` its rows),
   and to an estimator with ``reads_imu`` with the step's ticks (gyrodometry).

Finished robots are frozen (masks, not branches); a controller's own per-step status (MPPI's
``ok``/``all_collide``/``arrived``) is recorded beside the engine's status. Nothing a robot does
raises: a collision or a NaN is a status (a non-finite estimate, from an estimator that failed
for that robot, ends it ``diverged`` too, and the controller keeps seeing its last estimate).
Bad *set-up* (shapes, a command of the wrong width for the plant) raises a
:class:`~wheelbase.errors.WheelbaseError` before the first step.

Controllers that keep per-robot memory and do not batch (MPPI: its warm-started control
sequence) declare ``per_robot = True``; the engine then runs one copy per robot.
"""

from __future__ import annotations

import copy
import math
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from wheelbase._validate import as_float_array, integer, nonnegative, positive
from wheelbase.errors import ConfigError, InputError
from wheelbase.geometry import wrap_angle
from wheelbase.limits import MAX_STEPS
from wheelbase.sim.imu_sensing import IMU_SIGNALS, ImuReadings
from wheelbase.sim.log import STATUSES, Log
from wheelbase.sim.sensing import EncoderReadings, PerfectState

__all__ = ["Arrival", "Engine", "EngineState", "closed_loop"]

RUNNING, ARRIVED, MISSED_GOAL, COLLISION, TIMEOUT, DIVERGED, BLOCKED, STUCK = range(len(STATUSES))


@dataclass(frozen=True)
class Arrival:
    """The one arrival rule: where the robots should stop and how closely.

    Parameters
    ----------
    goal : array_like, shape (3,) or (N, 3)
        Goal pose(s) [m, m, rad].
    tolerance : tuple of float
        (position [m], heading [rad]) tolerance, both > 0 (heading ``math.pi``: any heading).
    end_time : float
        When the reference ends [s]: arrival is judged from then on (0 for a goal pose).
    settle_time : float
        Time after ``end_time`` [s] the robot may still take; then ``timeout`` (default: the
        engine's duration only).
    rest_speed : float
        Planar speed [m/s] below which a robot is at rest.
    rest_yaw_rate : float
        Yaw rate [rad/s] below which a robot is at rest (turning on the spot is moving).
    judge_at_limit : bool
        At the time limit, a robot still running is judged instead of timing out: its true
        pose within tolerance of the goal → ``arrived``, else ``missed_goal``. For tracking a
        timed reference, whose end is the arrival (the robot need not have come to rest).
    """

    goal: Any
    tolerance: tuple[float, float] = (0.05, math.radians(5.0))
    end_time: float = 0.0
    settle_time: float = math.inf
    rest_speed: float = 0.01
    rest_yaw_rate: float = 0.1
    judge_at_limit: bool = False

    def __post_init__(self) -> None:
        goal = as_float_array("goal", self.goal, 3, min_ndim=1, max_ndim=2)
        object.__setattr__(self, "goal", goal)
        if len(self.tolerance) != 2:
            raise ConfigError(
                f"tolerance must be (position [m], heading [rad]) (got {self.tolerance!r})"
            )
        tolerance = (
            positive("position tolerance", self.tolerance[0], "m"),
            positive("heading tolerance", self.tolerance[1], "rad"),
        )
        object.__setattr__(self, "tolerance", tolerance)
        object.__setattr__(self, "end_time", nonnegative("end_time", self.end_time, "s"))
        if self.settle_time != math.inf:
            object.__setattr__(
                self, "settle_time", nonnegative("settle_time", self.settle_time, "s")
            )
        object.__setattr__(self, "rest_speed", positive("rest_speed", self.rest_speed, "m/s"))
        object.__setattr__(
            self, "rest_yaw_rate", positive("rest_yaw_rate", self.rest_yaw_rate, "rad/s")
        )

    def within(self, poses: np.ndarray, goal: np.ndarray) -> np.ndarray:
        """Which poses ``(N, 3)`` are within tolerance of their goals ``(N, 3)``.

        Parameters
        ----------
        poses, goal : numpy.ndarray, shape (N, 3)
            Poses and goals.
        """
        distance = np.hypot(poses[:, 0] - goal[:, 0], poses[:, 1] - goal[:, 1])
        heading = np.abs(wrap_angle(poses[:, 2] - goal[:, 2]))
        return (distance <= self.tolerance[0]) & (heading <= self.tolerance[1])

    def at_rest(self, twist: np.ndarray) -> np.ndarray:
        """Which robots are at rest, by their body twists ``(N, 3)``.

        Parameters
        ----------
        twist : numpy.ndarray, shape (N, 3)
            Body twists [m/s, m/s, rad/s].
        """
        speed = np.hypot(twist[:, 0], twist[:, 1])
        return (speed <= self.rest_speed) & (np.abs(twist[:, 2]) <= self.rest_yaw_rate)


@dataclass
class EngineState:
    """What evolves during a run, batch axis first.

    Attributes
    ----------
    step : int
        Index of the step about to run (time ``step·dt``).
    pose, twist : numpy.ndarray, shape (N, 3)
        True pose [m, m, rad] and body twist [m/s, m/s, rad/s].
    estimate, estimated_twist : numpy.ndarray, shape (N, 3)
        What the controller sees.
    wheel_angle : numpy.ndarray, shape (N, 2)
        Cumulative wheel angles (left, right) of the encoder axle [rad].
    ticks : numpy.ndarray of int64, shape (N, 2)
        Cumulative encoder counts.
    status : numpy.ndarray of int8, shape (N,)
        Codes of :data:`~wheelbase.sim.STATUSES` (0: running).
    goal : numpy.ndarray, shape (N, 3) or None
        Each robot's goal.
    seeds : numpy.ndarray of int64, shape (N,)
        Each robot's seed.
    controllers : list
        One controller copy per robot for a ``per_robot`` controller, else one shared.
    encoders : EncoderReadings or None
        The encoders and their robots' seeds (counter-based random errors).
    plant : object or None
        What a plant keeps between steps besides pose and twist (a drive train's motor
        currents and speed-loop integrals), from ``plant.start``.
    estimator : object or None
        What an estimator keeps besides the estimate (a covariance, particles), from
        ``estimator.start``.
    sensors : SensorStreams or None
        The robots' seeds of the sensors' counter-based random streams.
    held : numpy.ndarray, shape (N, k), or None
        The last controller commands, held between controller calls (``control_every``).
    held_status : list or None
        The controllers' statuses of that call.
    world : object or None
        The world's evolving truth (agents), from ``surroundings.start``.
    perception : object or None
        What each robot has made of its sensors (costmap, tracks), from ``perception.start``.
    still : numpy.ndarray, shape (N,), or None
        Seconds each robot has stood still while commanded to move (the ``stuck`` rule).
    track_scores : numpy.ndarray, shape (N, 3), or None
        For the metrics only (nothing that decides reads it): each robot's running sums of
        squared track position and velocity errors against the true agents, and of matches.
    imu : ImuReadings or None
        The IMUs and their robots' biases (counter-based noise).
    imu_reading : numpy.ndarray, shape (N, 3), or None
        The last IMU readings (ω_z, f_x, f_y) (the start-up calibration before the first step).
    """

    step: int
    pose: np.ndarray
    twist: np.ndarray
    estimate: np.ndarray
    estimated_twist: np.ndarray
    wheel_angle: np.ndarray
    ticks: np.ndarray
    status: np.ndarray
    goal: np.ndarray | None
    seeds: np.ndarray
    controllers: list = field(default_factory=list)
    encoders: EncoderReadings | None = None
    plant: Any = None
    estimator: Any = None
    sensors: Any = None
    held: np.ndarray | None = None
    held_status: list | None = None
    world: Any = None
    perception: Any = None
    still: np.ndarray | None = None
    track_scores: np.ndarray | None = None
    imu: Any = None
    imu_reading: np.ndarray | None = None

    @property
    def running(self) -> np.ndarray:
        """Which robots are still running, shape (N,)."""
        return self.status == RUNNING


@dataclass(frozen=True)
class _Row:
    """What one step records (before the plant moves)."""

    t: float
    pose: np.ndarray
    estimate: np.ndarray
    reference: np.ndarray
    twist: np.ndarray
    command: np.ndarray
    rates: np.ndarray
    ticks: np.ndarray
    controller_status: list[str | None]
    signals: dict[str, np.ndarray]
    scan: np.ndarray | None = None  # read after the step, at the next row's true poses
    scan_index: np.ndarray | None = None
    agents: np.ndarray | None = None  # (B, A, 4) every world's agents at the row


@dataclass(frozen=True)
class Engine:
    """Parameters of a closed loop; :meth:`run` steps N robots from their start poses.

    Parameters
    ----------
    plant : KinematicPlant or DynamicPlant
        The true robot.
    controller : callable
        ``controller(t, measured (N, 3) or (N, 6), reference) -> (N, k)`` with
        ``command_names`` and ``reset()`` (every law of :mod:`wheelbase.control`). On a dynamic
        plant it is called with the estimated state (x, y, θ, u, v, r) and returns wheel
        torques. ``per_robot = True`` on the controller: robot 0 runs it, every other robot a
        copy, each called with its own (3,) pose.
    reference : object
        Passed to the controller unchanged (a goal pose, a path, a trajectory).
    dt : float
        Control and integration step [s], > 0.
    duration : float
        Time limit [s], > 0.
    estimator : object
        How the controller learns the state (default: perfectly): :class:`PerfectState`,
        :class:`EncoderOdometry`, or a filter of :mod:`wheelbase.sim.localizers` that also
        reads the sensors.
    arrival : Arrival or None
        The arrival rule (None: run to the time limit; the status is then ``timeout``).
    collides : callable, optional
        ``collides(poses (M, 3)) -> (M,) bool``: the footprint touches an obstacle.
    reference_pose : callable, optional
        ``reference_pose(t) -> (3,) or (N, 3)``: where the robot should be (for the log;
        default: the goal, or NaN).
    progress : callable, optional
        Called with the simulated time now and then.
    fan_every : int
        Every this many steps (0: never) keep ``fan_size`` sampled rollouts of a controller
        that has them (``last_plan.samples`` and ``predict``, as MPPI).
    fan_size : int
        Rollouts kept per fan.
    sensors : SensorSuite, optional
        A lidar and/or a landmark sensor read at the true poses at their rates; the readings
        go to ``estimator.update(..., readings=...)``.
    record_sensors : bool
        Keep the lidar scans and, every ``fan_every`` steps, the particles of a particle
        filter in the log (for drawing); off for batches that only want metrics.
    control_every : int
        The controller is called every this many steps (its rate 1 / (control_every·dt));
        the command is held in between.
    surroundings : Surroundings, optional
        The world beyond the map (:class:`~wheelbase.sim.Surroundings`: obstacles, agents, the
        other robots of a fleet): it steps with the plant, the lidar sees it and touching it is
        a collision. Nothing that decides (controller, estimator) reads it.
    perception : PerceptionSuite, optional
        Turns each robot's scans into a costmap and tracks
        (:class:`~wheelbase.sim.PerceptionSuite`); a controller with ``uses_perception`` is
        called with ``perception=`` its robot's view.
    references : tuple, optional
        One reference per robot of a world (a fleet's plans): robot i follows
        ``references[i % len(references)]`` (per-robot controllers only).
    stuck : Stuck, optional
        The ``stuck`` rule (:class:`~wheelbase.sim.stuck.Stuck`): a robot commanded to move
        that does not move for its time ends ``stuck``.
    imu : Imu, optional
        An IMU on each robot (:class:`~wheelbase.sensors.Imu`, a dynamic plant), read after
        every step; a controller with ``reads_imu`` is called with ``imu=`` the last readings
        ``(N, 3)`` (its robot's ``(3,)`` for a per-robot one; before the first step its
        start-up calibration, :meth:`~wheelbase.sim.imu_sensing.ImuReadings.calibration`).
        An estimator with ``reads_imu`` gets that calibration at the start
        (``estimator.calibrate(state, reading, start_twists)``) and each step's readings with
        its ticks (``update(..., imu=)``, :class:`~wheelbase.sim.gyrodometry.Gyrodometry`).
    """

    plant: Any
    controller: Any
    reference: Any
    dt: float
    duration: float
    estimator: Any = field(default_factory=PerfectState)
    arrival: Arrival | None = None
    collides: Callable[[np.ndarray], np.ndarray] | None = None
    reference_pose: Callable[[float], np.ndarray] | None = None
    progress: Callable[[float], None] | None = None
    fan_every: int = 0
    fan_size: int = 20
    max_steps: int = MAX_STEPS
    sensors: Any = None
    record_sensors: bool = True
    control_every: int = 1
    surroundings: Any = None
    perception: Any = None
    references: tuple | None = None
    stuck: Any = None
    imu: Any = None

    def __post_init__(self) -> None:
        object.__setattr__(self, "dt", positive("dt", self.dt, "s"))
        object.__setattr__(self, "duration", positive("duration", self.duration, "s"))
        limit = integer("max_steps", self.max_steps, minimum=1)
        steps = self.duration / self.dt
        if steps - 1e-9 > limit:
            raise ConfigError(
                f"duration / dt = {steps:.4g} steps: more than max_steps = {limit}; use a "
                "larger dt or a shorter duration, or raise max_steps"
            )
        if not callable(self.controller):
            raise ConfigError(f"controller must be callable (got {type(self.controller).__name__})")
        integer("control_every", self.control_every, minimum=1)
        if self.references is not None and not getattr(self.controller, "per_robot", False):
            raise ConfigError("references (one per robot) need a per-robot controller")
        names = tuple(getattr(self.controller, "command_names", ("v", "omega")))
        object.__setattr__(self, "_names", self.plant.command_names(names))
        if self.estimator.encoder is not None and getattr(self.plant, "axle", None) is None:
            raise ConfigError(
                "wheel-encoder odometry needs the plant's encoder axle (WheelAxle); "
                "run this plant with perfect state"
            )
        if self.imu is not None:
            from wheelbase.sensors.imu import Imu

            if not isinstance(self.imu, Imu):
                raise ConfigError(f"imu must be an Imu (got {type(self.imu).__name__})")
            if not self.plant.dynamic:
                raise ConfigError("an IMU reads a dynamic plant's accelerations: use one")
        if self.sensors is not None:
            from wheelbase.sim.sensors import SensorSuite

            if not isinstance(self.sensors, SensorSuite):
                raise ConfigError(
                    f"sensors must be a SensorSuite (got {type(self.sensors).__name__})"
                )

    # ------------------------------------------------------------------ public
    @property
    def command_names(self) -> tuple[str, ...]:
        """Names of the command columns."""
        return self._names  # type: ignore[attr-defined]

    @property
    def steps(self) -> int:
        """Largest number of steps of a run."""
        return math.ceil(self.duration / self.dt - 1e-9)

    def reset(
        self,
        poses: ArrayLike,
        seeds: ArrayLike | int | None = None,
        twists: ArrayLike | None = None,
    ) -> EngineState:
        """The state at t = 0: robots at ``poses``, at rest (or moving), estimates exact
        (or, for an estimator with ``first_estimate(state)``, such as a global localisation,
        what it estimates without the start).

        Parameters
        ----------
        poses : array_like, shape (3,) or (N, 3)
            Start poses [m, m, rad].
        seeds : int or array_like of int, shape (N,), optional
            Seeds of each robot's random encoder errors (default 0, 1, …, N − 1; an int s
            gives s, s + 1, …).
        twists : array_like, shape (3,) or (N, 3), optional
            Start body twists (u, v, r) of a dynamic plant [m/s, m/s, rad/s] (default: rest).
        """
        start = as_float_array("poses", poses, 3, min_ndim=1, max_ndim=2).reshape(-1, 3)
        n = start.shape[0]
        if n == 0:
            raise InputError("give at least one robot (poses has shape (0, 3))")
        twist = np.zeros((n, 3))
        if twists is not None:
            given = as_float_array("twists", twists, 3, min_ndim=1, max_ndim=2).reshape(-1, 3)
            if given.shape[0] not in (1, n):
                raise InputError(f"twists has {given.shape[0]} rows for {n} robots")
            if not self.plant.dynamic and np.any(given != 0):
                raise ConfigError("a kinematic plant starts at rest: give twists to a dynamic one")
            twist = np.broadcast_to(given, (n, 3)).copy()
        seeds = _seeds(seeds, n)
        start = start.copy()
        start[:, 2] = wrap_angle(start[:, 2])
        goal = None
        if self.arrival is not None:
            goal = self.arrival.goal.reshape(-1, 3)
            if n % goal.shape[0]:
                raise InputError(
                    f"arrival.goal has {goal.shape[0]} rows for {n} robots; give (3,), ({n}, 3) "
                    "or one row per robot of a world whose robots make up the batch"
                )
            goal = np.tile(goal, (n // goal.shape[0], 1))  # a fleet's goals in every world
        reset = getattr(self.controller, "reset", None)
        if reset is not None:
            reset()
        if getattr(self.controller, "per_robot", False):
            # robot 0 runs the given object (its status and plan stay visible to the caller)
            controllers = [self.controller] + [copy.deepcopy(self.controller) for _ in range(n - 1)]
        else:
            controllers = [self.controller]
        imu = None if self.imu is None else ImuReadings(self.imu, seeds)
        calibration = None if imu is None else imu.calibration(twist)
        encoder = self.estimator.encoder
        estimator_state = self.estimator.start(start, seeds)
        if calibration is not None and getattr(self.estimator, "reads_imu", False):
            # the start-up reading the controller sees is the estimator's too (gyro bias)
            estimator_state = self.estimator.calibrate(estimator_state, calibration, twist)
        first = getattr(self.estimator, "first_estimate", None)  # one that ignores the start
        estimate = start.copy() if first is None else np.array(first(estimator_state), float)
        return EngineState(
            step=0,
            pose=start,
            twist=twist,
            estimate=estimate,
            estimated_twist=twist.copy(),
            wheel_angle=np.zeros((n, 2)),
            ticks=np.zeros((n, 2), dtype=np.int64),
            status=np.zeros(n, dtype=np.int8),
            goal=goal,
            seeds=seeds,
            controllers=controllers,
            encoders=None if encoder is None else EncoderReadings(encoder, seeds),
            plant=self.plant.start(n, seeds),
            estimator=estimator_state,
            sensors=None if self.sensors is None else self.sensors.start(seeds),
            world=None if self.surroundings is None else self.surroundings.start(seeds, start),
            perception=None if self.perception is None else self.perception.start(start),
            still=None if self.stuck is None else np.zeros(n),
            track_scores=np.zeros((n, 3)) if self._scores_tracks else None,
            imu=imu,
            imu_reading=calibration,
        )

    @property
    def _scores_tracks(self) -> bool:
        """Whether the log scores the robots' tracks against the world's agents."""
        return (
            self.surroundings is not None
            and self.perception is not None
            and getattr(self.perception, "tracker", None) is not None
            and getattr(self.surroundings, "has_agents", False)
        )

    def command(self, state: EngineState) -> tuple[np.ndarray, list[str | None]]:
        """The controllers' commands ``(N, k)`` for the current estimates, and their own
        per-robot statuses (None where a controller reports none).

        Parameters
        ----------
        state : EngineState
            The current state.
        """
        t = state.step * self.dt
        measured = state.estimate
        if self.plant.dynamic:
            measured = np.concatenate([state.estimate, state.estimated_twist], axis=-1)
        n, width = measured.shape[0], len(self.command_names)
        controllers = state.controllers
        imu = state.imu_reading
        if len(controllers) == 1 and not getattr(controllers[0], "per_robot", False):
            extra = {}
            if imu is not None and getattr(controllers[0], "reads_imu", False):
                extra["imu"] = imu.copy()
            raw = np.asarray(
                controllers[0](t, measured.copy(), self.reference, **extra), dtype=np.float64
            )
            command = _shaped(raw, n, width, self.command_names)
            reported = getattr(controllers[0], "status", None)
            return command, [reported if isinstance(reported, str) else None] * n
        command = np.zeros((n, width))
        statuses: list[str | None] = [None] * n
        references = self.references
        for i in np.flatnonzero(state.running):
            law = controllers[i]
            reference = self.reference if references is None else references[i % len(references)]
            extra = {}
            if self.perception is not None and getattr(law, "uses_perception", False):
                extra["perception"] = self.perception.view(state.perception, int(i), t)
            if imu is not None and getattr(law, "reads_imu", False):
                extra["imu"] = imu[i].copy()
            raw = np.asarray(law(t, measured[i].copy(), reference, **extra), dtype=np.float64)
            command[i] = _shaped(raw, 1, width, self.command_names)[0]
            reported = getattr(law, "status", None)
            statuses[i] = reported if isinstance(reported, str) else None
        return command, statuses

    def step(
        self, state: EngineState, command: ArrayLike | None = None
    ) -> tuple[EngineState, _Row]:
        """One control step of every running robot (module docstring).

        Parameters
        ----------
        state : EngineState
            The state at time ``state.step·dt``; it is not changed, and the result is a
            function of it: the random streams are counter-based
            (:mod:`wheelbase.sim.streams`), so stepping one state twice gives equal states.
            (A controller that keeps memory between calls, such as a path follower's progress
            or MPPI's warm start, is an object in ``state.controllers`` that the call
            advances: :func:`copy.deepcopy` the state to branch with one.)
        command : array_like, shape (N, k), optional
            Commands to apply instead of asking the controller (a learning agent's action).

        Returns
        -------
        state : EngineState
            The state one step later (finished robots frozen).
        row : object
            What the step recorded (time, poses, command, …) before the plant moved.
        """
        t = state.step * self.dt
        running = state.running
        n = running.size
        held = state.held_status
        if command is None and state.held is not None and state.step % self.control_every:
            command, controller_status = state.held, held
        elif command is None:
            command, controller_status = self.command(state)
            held = controller_status
        else:
            command = _shaped(
                np.asarray(command, dtype=np.float64), n, len(self.command_names),
                self.command_names,
            )  # fmt: skip
            controller_status = [None] * n
        status = state.status.copy()
        finite = _finite_rows(command)
        status[running & ~finite] = DIVERGED
        command = np.where(finite[:, None], command, 0.0)
        command[~running] = 0.0
        held_command = command
        gave_up = np.array([name == "blocked" for name in controller_status], dtype=bool)
        if gave_up.any():  # the controller found no way on and stopped the robot
            status[running & finite & gave_up] = BLOCKED
            command = np.where(gave_up[:, None], 0.0, command)
        moved, rates = self.plant.motion(state.twist, command, self.command_names, state.plant)
        reference = self._reference_pose(t, n, state.goal)
        signals = self.plant.signals(state.plant) if state.plant is not None else {}
        estimator_signals = getattr(self.estimator, "signals", None)
        if estimator_signals is not None and state.estimator is not None:
            signals = {**signals, **estimator_signals(state.estimator)}
        agents = None
        if state.track_scores is not None:
            signals = {**signals, "track_position_sq_sum": state.track_scores[:, 0],
                       "track_velocity_sq_sum": state.track_scores[:, 1],
                       "track_matches": state.track_scores[:, 2]}  # fmt: skip
        if state.imu_reading is not None:  # read after the last step: what the controller saw
            signals = {**signals, **{name: state.imu_reading[:, k]
                                     for k, name in enumerate(IMU_SIGNALS)}}  # fmt: skip
        if self.surroundings is not None:
            signals = {**signals, **self.surroundings.signals(state.world, state.pose, state.twist)}
            if self.record_sensors:
                agents = self.surroundings.agents(state.world)
        scan = scan_index = None

        active = status == RUNNING
        if self.collides is not None and active.any():
            hit = np.zeros(n, dtype=bool)
            hit[active] = np.asarray(self.collides(state.pose[active]), dtype=bool)
            status[hit] = COLLISION
            active &= ~hit
        if self.surroundings is not None and active.any():
            hit = np.zeros(n, dtype=bool)
            index = np.flatnonzero(active)
            hit[index] = self.surroundings.collides(state.world, state.pose, index)
            status[hit] = COLLISION
            active &= ~hit
        limit = self.duration
        if self.arrival is not None:
            arrival = self.arrival
            if arrival.settle_time != math.inf:
                limit = min(limit, arrival.end_time + arrival.settle_time)
            if t >= arrival.end_time - 1e-12:
                stopped = (
                    active & arrival.at_rest(moved) & arrival.within(state.estimate, state.goal)
                )
                if stopped.any():
                    truly = arrival.within(state.pose, state.goal)
                    status[stopped & truly] = ARRIVED
                    status[stopped & ~truly] = MISSED_GOAL
                    active &= ~stopped
        still = state.still
        if self.stuck is not None and still is not None:
            still, stuck = self.stuck.update(still, state.pose, moved, reference, self.dt)
            status[active & stuck] = STUCK
            active &= ~stuck
        if state.step >= self.steps or t >= limit - 1e-12:
            if self.arrival is not None and self.arrival.judge_at_limit:
                truly = self.arrival.within(state.pose, state.goal)
                status[active & truly] = ARRIVED
                status[active & ~truly] = MISSED_GOAL
            else:
                status[active] = TIMEOUT
            active[:] = False

        pose, twist = state.pose.copy(), state.twist.copy()
        wheel_angle, ticks = state.wheel_angle.copy(), state.ticks.copy()
        estimate, estimated_twist = state.estimate.copy(), state.estimated_twist.copy()
        plant_state = state.plant
        world_state = state.world
        perception_state = state.perception
        track_scores = state.track_scores
        imu_reading = state.imu_reading
        if active.any():
            index = np.flatnonzero(active)
            new_pose, new_twist, turned, plant_state = self.plant.step(
                state.pose[index], state.twist[index], command[index], moved[index],
                rates[index], self.dt, plant_state, index,
            )  # fmt: skip
            ok = _finite_rows(new_pose) & _finite_rows(new_twist)
            status[index[~ok]] = DIVERGED
            moving, new_pose, new_twist = index[ok], new_pose[ok], new_twist[ok]
            new_angle = state.wheel_angle[moving] + turned[ok]
            if state.encoders is not None:
                before = state.wheel_angle.copy()
                after = before.copy()
                after[moving] = new_angle
                delta = state.encoders.tick_deltas(before, after, state.step)[moving]
                ticks[moving] = state.ticks[moving] + delta
            else:
                delta = None
            pose[moving], twist[moving], wheel_angle[moving] = new_pose, new_twist, new_angle
            if state.imu is not None:
                imu_reading = imu_reading.copy()
                imu_reading[moving] = state.imu.read(
                    state.step, self.dt, state.twist[moving], new_twist, moving
                )
            extra = {}
            cast = None
            if self.surroundings is not None:  # the agents move with the robots, from time t
                world_state = self.surroundings.step(state.world, self.dt, state.pose, state.twist)
                cast = self.surroundings.caster(world_state, pose)
            if self.sensors is not None:
                readings = self.sensors.read(
                    state.step, self.dt, new_pose, state.sensors, moving, cast=cast
                )
                extra["readings"] = readings
                if readings.scan is not None and self.record_sensors:
                    scan, scan_index = readings.scan, moving
            if getattr(self.estimator, "reads_command", False):  # its own torques (slip)
                extra["command"] = command[moving]
            if imu_reading is not None and getattr(self.estimator, "reads_imu", False):
                extra["imu"] = imu_reading[moving]  # this step's, as the ticks (gyrodometry)
            est, est_twist, estimator_state = self.estimator.update(
                state.estimate[moving], delta, self.dt, new_pose, new_twist,
                state=state.estimator, index=moving, **extra,
            )  # fmt: skip
            est = np.asarray(est, dtype=np.float64)
            est_twist = np.asarray(est_twist, dtype=np.float64)
            lost = ~(_finite_rows(est) & _finite_rows(est_twist))
            if lost.any():  # the estimator failed for these robots: never a NaN to a controller
                status[moving[lost]] = DIVERGED
                est[lost] = state.estimate[moving[lost]]
                est_twist[lost] = state.estimated_twist[moving[lost]]
            estimate[moving], estimated_twist[moving] = est, est_twist
            if self.perception is not None and extra and extra["readings"].scan is not None:
                perception_state = self.perception.update(
                    state.perception, t + self.dt, extra["readings"], estimate[moving], moving
                )
                if track_scores is not None:  # evaluation against the truth, for the log
                    tracks = [self.perception.tracks(perception_state, int(i)) for i in moving]
                    track_scores = track_scores.copy()
                    track_scores[moving] += self.surroundings.track_scores(
                        world_state, tracks, moving
                    )
        else:
            estimator_state = state.estimator
            if self.surroundings is not None:  # the world goes on around robots that stopped
                world_state = self.surroundings.step(state.world, self.dt, state.pose, state.twist)
        row = _Row(t, state.pose, state.estimate, reference, moved, command, rates,
                   state.ticks, controller_status, signals, scan, scan_index, agents)  # fmt: skip
        new_state = EngineState(
            step=state.step + 1,
            pose=pose,
            twist=twist,
            estimate=estimate,
            estimated_twist=estimated_twist,
            wheel_angle=wheel_angle,
            ticks=ticks,
            status=status,
            goal=state.goal,
            seeds=state.seeds,
            controllers=state.controllers,
            encoders=state.encoders,
            plant=plant_state,
            estimator=estimator_state,
            sensors=state.sensors,
            held=held_command,
            held_status=held,
            world=world_state,
            perception=perception_state,
            still=still,
            track_scores=track_scores,
            imu=state.imu,
            imu_reading=imu_reading,
        )
        return new_state, row

    def run(
        self,
        poses: ArrayLike,
        seeds: ArrayLike | int | None = None,
        twists: ArrayLike | None = None,
    ) -> Log:
        """Run every robot from its start pose until it finishes; record everything.

        Parameters
        ----------
        poses : array_like, shape (3,) or (N, 3)
            Start poses [m, m, rad].
        seeds : int or array_like of int, optional
            Seeds of each robot's random encoder errors (see :meth:`reset`).
        twists : array_like, shape (3,) or (N, 3), optional
            Start twists of a dynamic plant (see :meth:`reset`).

        Returns
        -------
        Log
            The batch's record, one row per step until the last robot finished.
        """
        state = self.reset(poses, seeds, twists)
        n = state.pose.shape[0]
        rows: list[_Row] = []
        last_row = np.zeros(n, dtype=np.int64)
        fans: dict[tuple[int, int], np.ndarray] = {}
        particles: dict[tuple[int, int], np.ndarray] = {}
        particles_of = getattr(self.estimator, "particles_of", None)
        perceived: dict[tuple[int, int], dict] = {}
        status_names: list[str] = []
        while True:
            was_running = state.running
            fan_now = self.fan_every > 0 and state.step % self.fan_every == 0
            if fan_now and particles_of is not None and self.record_sensors:
                for i in np.flatnonzero(was_running):  # the belief of this row's estimate
                    cloud = particles_of(state.estimator, int(i))
                    particles[(int(i), len(rows))] = np.asarray(cloud, dtype=np.float32)
            if fan_now and self.perception is not None and self.record_sensors:
                for i in np.flatnonzero(was_running):  # what this row's controller saw
                    perceived[(int(i), len(rows))] = self.perception.snapshot(
                        state.perception, int(i)
                    )
            state, row = self.step(state)
            rows.append(row)
            if fan_now:  # the plans the controllers just made for this row's poses
                self._keep_fans(state.controllers, was_running, len(rows) - 1, fans)
            last_row[was_running] = len(rows) - 1
            if self.progress is not None and state.step % 200 == 0:
                self.progress(row.t)
            for name in row.controller_status:
                if name is not None and name not in status_names:
                    status_names.append(name)
            if not state.running.any():
                break
        if self.progress is not None:
            self.progress(rows[-1].t)
        log = self._log(rows, last_row, state, fans, tuple(status_names), particles)
        if perceived:
            log = replace(log, perceived=perceived)
        summaries = [getattr(law, "summary", None) for law in state.controllers]
        if len(state.controllers) == n and any(callable(s) for s in summaries):
            log = replace(log, summaries=tuple(s() if callable(s) else {} for s in summaries))
        return log

    # ------------------------------------------------------------------ helpers
    def _reference_pose(self, t: float, n: int, goal: np.ndarray | None) -> np.ndarray:
        if self.reference_pose is not None:
            value = np.asarray(self.reference_pose(t), dtype=np.float64).reshape(-1, 3)
            if len(value) > 1 and n % len(value) == 0:  # one per robot of each world
                return np.tile(value, (n // len(value), 1))
            return np.broadcast_to(value, (n, 3))
        if goal is not None:
            return goal
        return np.full((n, 3), np.nan)

    def _keep_fans(self, controllers: list, running: np.ndarray, row: int, fans: dict) -> None:
        for i, law in enumerate(controllers):
            if len(controllers) > 1 and not running[i]:
                continue
            plan = getattr(law, "last_plan", None)
            if plan is None or getattr(plan, "samples", None) is None:
                continue
            rollouts = law.predict(plan, plan.samples[: self.fan_size])
            fans[(i, row)] = np.asarray(rollouts)[..., :2]

    def _log(self, rows, last_row, state, fans, status_names, particles) -> Log:
        n = state.pose.shape[0]
        t = np.array([row.t for row in rows])
        early = np.flatnonzero(last_row < len(rows) - 1)  # robots that finished before the end

        def frozen(arrays: list[np.ndarray]) -> np.ndarray:
            values = np.stack(arrays, axis=1)  # (N, T, …), each robot's rows held after its end
            for i in early:
                values[i, last_row[i] + 1 :] = values[i, last_row[i]]
            return values

        def stack(name: str) -> np.ndarray:
            return frozen([getattr(row, name) for row in rows])

        command = stack("command")
        controller_status = None
        if status_names:  # only controllers that report one (MPPI) pay for this table
            codes = {name: k for k, name in enumerate(status_names)}
            controller_status = np.array(
                [[codes.get(name, -1) if name is not None else -1
                  for name in row.controller_status] for row in rows],
                dtype=np.int16,
            ).T.reshape(n, len(rows))  # fmt: skip
            controller_status = np.where(np.arange(len(rows))[None, :] <= last_row[:, None],
                                         controller_status, -1)  # fmt: skip
        scans: dict[tuple[int, int], np.ndarray] = {}
        for k, row in enumerate(rows):
            if row.scan is None:
                continue
            for ranges, i in zip(row.scan, row.scan_index, strict=True):
                if k + 1 <= last_row[i]:  # taken at the true pose of the next row
                    scans[(int(i), k + 1)] = ranges
        return Log(
            t=t,
            true_pose=stack("pose"),
            estimated_pose=stack("estimate"),
            reference_pose=stack("reference"),
            twist=stack("twist"),
            command=command,
            wheel_rates=stack("rates"),
            ticks=stack("ticks"),
            torques=command if self.plant.dynamic else None,
            status=state.status.copy(),
            length=last_row + 1,
            goal=state.goal,
            seeds=state.seeds,
            command_names=self.command_names,
            controller_status=controller_status,
            controller_status_names=status_names,
            extras={name: frozen([row.signals[name] for row in rows]) for name in rows[0].signals},
            rollout_fans=fans,
            scans=scans,
            particles=particles,
            agents=None if rows[0].agents is None else np.stack([r.agents for r in rows], axis=1),
        )


def _finite_rows(values: np.ndarray) -> np.ndarray:
    """Which rows ``(N, k)`` hold only finite numbers."""
    return np.isfinite(values).all(axis=-1)


def _seeds(seeds: ArrayLike | int | None, n: int) -> np.ndarray:
    if seeds is None:
        return np.arange(n, dtype=np.int64)
    largest = np.iinfo(np.int64).max
    if isinstance(seeds, (int, np.integer)) and not isinstance(seeds, bool):
        if not 0 <= int(seeds) <= largest - n:
            raise InputError(f"seeds must be in [0, 2**63 - {n}] for {n} robots (got {seeds})")
        return int(seeds) + np.arange(n, dtype=np.int64)
    try:
        array = np.asarray(seeds)
    except (TypeError, ValueError, OverflowError):
        array = np.asarray(None)
    if array.ndim != 1 or array.shape[0] != n or not np.issubdtype(array.dtype, np.integer):
        raise InputError(f"seeds must be an int or {n} integers, one per robot (got {seeds!r})")
    if np.any(array < 0) or np.any(array > largest):
        raise InputError(f"seeds must be in [0, 2**63 - 1] (got {seeds!r})")
    return array.astype(np.int64)


def _shaped(raw: np.ndarray, n: int, width: int, names: tuple[str, ...]) -> np.ndarray:
    """Commands as (n, width), or a clear error naming the expected shape."""
    if raw.size == n * width and raw.shape[-1:] == (width,):
        return raw.reshape(n, width)
    raise ConfigError(
        f"the controller returned commands of shape {raw.shape}; the plant expects ({n}, {width}) "
        f"= {names} per robot"
    )


def closed_loop(
    controller: Any,
    plant: Any,
    poses: ArrayLike,
    reference: Any,
    duration: float,
    dt: float,
    *,
    goal: ArrayLike | None = None,
    tolerance: tuple[float, float] | None = None,
    integrator: str = "exact",
    estimator: Any = None,
    collides: Callable[[np.ndarray], np.ndarray] | None = None,
    seeds: ArrayLike | int | None = None,
) -> Log:
    """Run a controller on a plant from one or N start poses: the engine in one call.

    Parameters
    ----------
    controller : callable
        Any law of :mod:`wheelbase.control` (``controller(t, poses, reference)``).
    plant : KinematicModel, DiffDriveDynamics, KinematicPlant or DynamicPlant
        A model of :mod:`wheelbase.models` (integrated by ``integrator`` under a held
        command), a dynamic model (the controller then gives wheel torques: wrap a (v, ω)
        law in :class:`~wheelbase.control.TwistTorqueLoop`), or a plant.
    poses : array_like, shape (3,) or (N, 3)
        Start poses [m, m, rad].
    reference : object
        Passed to the controller (a goal pose, a path, a trajectory).
    duration : float
        Time limit [s].
    dt : float
        Control period and step [s].
    goal : array_like, shape (3,) or (N, 3), optional
        Where the robots should stop: the run of a robot ends ``arrived`` by the arrival rule
        (:class:`Arrival`); without it every robot runs to the time limit.
    tolerance : (float, float), optional
        (position [m], heading [rad]) of arrival (default 0.05 m, 5°).
    integrator : str
        Integration method of a kinematic model (default ``exact``: the closed-form arc, exact
        under the held command, so the only error is the controller's sampling).
    estimator : PerfectState or EncoderOdometry, optional
        What the controller sees (default: the true state).
    collides : callable, optional
        ``collides(poses (M, 3)) -> (M,) bool``.
    seeds : int or array_like of int, optional
        Seeds of the robots' random encoder errors.

    Returns
    -------
    Log

    Examples
    --------
    >>> from wheelbase.control import PolarPose
    >>> from wheelbase.models import Unicycle
    >>> log = closed_loop(PolarPose(), Unicycle(), [-1.0, 0.5, 0.0], [0, 0, 0], 30.0, 0.01,
    ...                   goal=[0, 0, 0], tolerance=(0.01, 0.02))
    >>> log.statuses
    ['arrived']
    """
    from wheelbase.dynamics import DiffDriveDynamics
    from wheelbase.sim.plants import DynamicPlant, KinematicPlant

    if isinstance(plant, DiffDriveDynamics):
        plant = DynamicPlant(plant)
    elif not isinstance(plant, (KinematicPlant, DynamicPlant)):
        plant = KinematicPlant(plant, integrator=integrator)
    arrival = None
    if goal is not None:
        arrival = Arrival(goal) if tolerance is None else Arrival(goal, tolerance)
    engine = Engine(
        plant,
        controller,
        reference,
        dt=dt,
        duration=duration,
        estimator=PerfectState() if estimator is None else estimator,
        arrival=arrival,
        collides=collides,
    )
    return engine.run(poses, seeds)
