"""``wheelbase.run``: a scenario in, a closed-loop result out (the main job of wheelbase).

The data flow of the design (one call on plain data per arrow):

    scenario → map + robot + limits → Hybrid A* plan → time-parametrised trajectory
             → controller(estimate) → plant → encoders → odometry → controller …
             → Log → metrics, CSV, figures, animation

Each step is a plain call on plain data; this module only wires them and resolves the scenario's
names (robot presets, control laws) to objects. Decisions made here, where the scenario is
silent:

- A differential drive (and the unicycle) plans with turning radius 0 (turns in place allowed);
  a car-like robot plans with R = wheel_base / tan(max_steering) × 1.2, leaving the controller
  20 % of steering authority to correct errors.
- Multiple goals are planned leg by leg (each from the previous goal) and tracked as one
  trajectory that stops at every goal.
- The run ends when the true pose is within the goal tolerance after the trajectory has ended
  and the robot has (nearly) stopped, at a collision, or at the time limit ``duration``
  (status ``timeout``), whichever comes first: a robot slower than its reference (a path
  follower, MPPI, one that waits for someone to pass) has until ``duration``. A scenario's
  ``settle_time`` ends the run that long after the trajectory's end instead, when that comes
  before ``duration``. ``arrival_delay_s`` says how much later than the reference's end the
  robot stopped.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np

from wheelbase._validate import nonnegative, positive
from wheelbase.errors import ConfigError, DataError, MapError, PlanningError, ScenarioError
from wheelbase.geometry import wrap_angle
from wheelbase.models import Bicycle, DiffDrive, RearWheelBicycle, Unicycle
from wheelbase.models.bicycle import Ackermann
from wheelbase.models.path import PoseTrajectory
from wheelbase.polyline import distance_to_polyline
from wheelbase.scenario import Scenario, load_scenario
from wheelbase.sim import STATUSES, Arrival, DynamicPlant, Engine, KinematicPlant, Log, WheelAxle
from wheelbase.timing import SpeedLimits, time_parametrize

__all__ = [
    "LAWS",
    "LOG_COPIES",
    "Prepared",
    "Robot",
    "RunResult",
    "build_robot",
    "prepare",
    "run",
    "run_metrics",
    "run_prepared",
    "run_seeds",
    "seeds_per_chunk",
]

FAN_PERIOD = 1.0  # s between the sampled-rollout fans kept for the animation
TURNING_MARGIN = 1.2


@dataclass(frozen=True)
class Robot:
    """A scenario's robot resolved to objects.

    Attributes
    ----------
    model : KinematicModel
        The kinematics the plant integrates.
    kind : str
        ``"diff"`` (commands (v, ω)) or ``"car"`` (commands (v, δ)).
    footprint : tuple of float
        (length, width) [m].
    center_offset : float
        Reference point to footprint centre [m].
    wheel_radius, half_track : float
        Geometry of the encoder axle [m].
    wheel_base : float
        Axle distance of a car [m] (0 for a differential drive).
    max_steering : float
        Steering stop [rad] (0 for a differential drive).
    max_wheel_speed : float
        Wheel angular speed limit [rad/s] (inf for none).
    dynamics : DiffDriveDynamics or None
        Rigid-body model of a preset (RM100), used by a dynamic plant.
    """

    model: Any
    kind: str
    footprint: tuple[float, float]
    center_offset: float
    wheel_radius: float
    half_track: float
    wheel_base: float = 0.0
    max_steering: float = 0.0
    max_wheel_speed: float = math.inf
    dynamics: Any = None

    @property
    def turning_radius(self) -> float:
        """Turning radius the planner uses [m] (0: turns in place)."""
        if self.kind == "diff":
            return 0.0
        return TURNING_MARGIN * self.wheel_base / math.tan(self.max_steering)


def build_robot(spec) -> Robot:
    """Resolve a :class:`~wheelbase.scenario.RobotSpec` (presets, defaults) to a :class:`Robot`.

    Parameters
    ----------
    spec : RobotSpec
        The scenario's ``robot`` section.
    """
    values = spec.model_dump()
    dynamics = None
    if spec.preset == "rm100":
        from wheelbase.dynamics import RM100

        dynamics = RM100
        preset = {
            "wheel_radius": RM100.wheel_radius,
            "half_track": RM100.half_track,
            "footprint": (0.66, 0.455),
        }
        values.update({k: v for k, v in preset.items() if values.get(k) is None})
        wheels = {"wheel_radius": values["wheel_radius"], "half_track": values["half_track"]}
        if tuple(wheels.values()) != (RM100.wheel_radius, RM100.half_track):
            dynamics = replace(RM100, **wheels)  # its own wheels on the RM100's body
    model_name = spec.model
    if model_name in ("diffdrive", "unicycle"):
        radius = values["wheel_radius"] or 0.05
        half = values["half_track"] or 0.2
        footprint = values["footprint"] or (2.4 * half, 2.4 * half)
        model = DiffDrive(radius, half) if model_name == "diffdrive" else Unicycle()
        return Robot(
            model=model,
            kind="diff",
            footprint=tuple(footprint),
            center_offset=values["center_offset"],
            wheel_radius=radius,
            half_track=half,
            max_wheel_speed=values["max_wheel_speed"] or math.inf,
            dynamics=dynamics,
        )
    wheel_base = values["wheel_base"] or 0.5
    max_steering = math.radians(values["max_steering_deg"] or 35.0)
    half = values["half_track"] or 0.35 * wheel_base
    footprint = values["footprint"] or (1.6 * wheel_base, 2.4 * half)
    if model_name == "ackermann":
        model = Ackermann(wheel_base, values["track"] or 2 * half, max_steering=max_steering)
    elif model_name == "bicycle":
        model = Bicycle(wheel_base, max_steering=max_steering)
    else:
        model = RearWheelBicycle(wheel_base, max_steering=max_steering)
    offset = values["center_offset"] if "center_offset" in spec.model_fields_set else wheel_base / 2
    return Robot(
        model=model,
        kind="car",
        footprint=tuple(footprint),
        center_offset=offset,
        wheel_radius=values["wheel_radius"] or 0.1,
        half_track=half,
        wheel_base=wheel_base,
        max_steering=max_steering,
    )


# --------------------------------------------------------------------------- control laws
def _tracker(name: str) -> Callable[..., Any]:
    def make(robot: Robot, gains: dict[str, float], limits: SpeedLimits, grid: Any = None):
        from wheelbase.control import tracking
        from wheelbase.control.base import VelocityLimits

        cls = getattr(tracking, name)
        velocity_limits = VelocityLimits(
            max_speed=1.5 * limits.max_speed,
            max_yaw_rate=1.5 * limits.max_yaw_rate,
            **(
                {
                    "max_wheel_speed": robot.max_wheel_speed,
                    "wheel_radius": robot.wheel_radius,
                    "half_track": robot.half_track,
                }
                if math.isfinite(robot.max_wheel_speed)
                else {}
            ),
        )
        return cls(**gains, limits=velocity_limits), "trajectory"

    return make


def _follower(name: str) -> Callable[..., Any]:
    def make(robot: Robot, gains: dict[str, float], limits: SpeedLimits, grid: Any = None):
        from wheelbase.control import path
        from wheelbase.control.base import SteeringLimits, VelocityLimits

        cls = getattr(path, name)
        arguments = {"speed": limits.max_speed, **gains}
        if cls is path.SegmentFollower and "length_scale" not in gains:
            # The offset decays at v·K_r/ℓ, which the heading loop K_φ must outpace: scale ℓ
            # with the speed (0.25 m up to 0.5 m/s with the default gains, 0.75 m at 1.5 m/s).
            k_r = arguments.get("k_r", path.SegmentFollower.k_r)
            k_heading = arguments.get("k_heading", path.SegmentFollower.k_heading)
            arguments["length_scale"] = max(0.25, 2.0 * arguments["speed"] * k_r / k_heading)
        if robot.kind == "car":
            arguments.update(output="steering", wheel_base=robot.wheel_base)
            command_limits = SteeringLimits(max_steering=robot.max_steering)
        else:
            command_limits = VelocityLimits(max_yaw_rate=limits.max_yaw_rate)
        return cls(**arguments, limits=command_limits), "path"

    return make


def _bound(name: str, value: Any, unit: str) -> float:
    """A positive limit, or ``math.inf`` for none (anything else is a ConfigError naming it)."""
    if isinstance(value, (int, float)) and value == math.inf:
        return math.inf
    return positive(name, value, unit)


class TorqueTracking:
    """Computed-torque PID (document 000 §5.3) on a time-parametrised trajectory.

    Adapts :class:`wheelbase.control.ComputedTorquePID` to the closed loop: it is called with
    the estimated state (x, y, θ, u, v, r) and a :class:`PoseTrajectory`, whose rows
    (x, y, ψ, u, 0, r, u̇, 0, ṙ) it reads (accelerations bounded, see below).

    Parameters
    ----------
    robot : Robot
        The resolved robot (its dynamics preset is the controller's model).
    bandwidth : float
        Pole-placement bandwidth ω of both loops [rad/s] (:meth:`TorqueGains.pole_placement`).
    speed : float
        Nominal speed of the lateral design [m/s].
    max_torque : float
        Wheel-torque saturation [N·m].
    derivative_filter : float
        Time constant of the error-rate filter [s].
    model_error : float
        Relative error of the controller's mass and inertia (0.2: the controller believes the
        robot is 20 % heavier), to study robustness.
    max_acceleration, max_yaw_acceleration : float
        Bounds on the feed-forward accelerations u̇_ref [m/s²] and ṙ_ref [rad/s²]. A planned
        path has curvature jumps (line to arc), so the time-parametrised ω steps and its
        derivative is an impulse the wheels cannot deliver; feeding it forward would only
        saturate the torques. The PID corrects the remaining error.
    law : callable, optional
        Builds the torque law from (model, gains, max_torque=, derivative_filter=) (default
        :class:`~wheelbase.control.ComputedTorquePID`; the adaptive law learns its model).
    """

    command_names = ("tau_left", "tau_right")

    def __init__(
        self,
        robot: Robot,
        bandwidth: float = 1.5,
        speed: float = 0.3,
        max_torque: float = 5.0,
        derivative_filter: float = 0.05,
        model_error: float = 0.0,
        max_acceleration: float = math.inf,
        max_yaw_acceleration: float = math.inf,
        law: Callable[..., Any] | None = None,
    ) -> None:
        from wheelbase.control.torque import ComputedTorquePID, TorqueGains

        model = robot.dynamics
        model_error = nonnegative("model_error", model_error)
        if model_error:
            factor = 1.0 + model_error
            model = model.with_body(model.body.scaled(factor, factor))
        self._pid = (law or ComputedTorquePID)(
            model,
            TorqueGains.pole_placement(bandwidth, speed=speed),
            max_torque=max_torque,
            derivative_filter=derivative_filter,
        )
        self._rows: tuple[Any, Any] | None = None
        self._accel_bounds = (
            _bound("max_acceleration", max_acceleration, "m/s²"),
            _bound("max_yaw_acceleration", max_yaw_acceleration, "rad/s²"),
        )

    def reset(self) -> None:
        """Forget the integrals of the PID."""
        self._pid.reset()

    @property
    def law(self) -> Any:
        """The torque law it runs (its estimates, for the adaptive one)."""
        return self._pid

    @property
    def model(self) -> Any:
        """The law's model of the robot (settable: a payload it knows it picked up)."""
        return self._pid.model

    @model.setter
    def model(self, model: Any) -> None:
        self._pid.model = model

    def __call__(self, t: float, state: np.ndarray, reference: PoseTrajectory) -> np.ndarray:
        """Wheel torques (left, right) [N·m] for the estimated state (6,) at time ``t`` [s].

        Parameters
        ----------
        t : float
            Time [s].
        state : numpy.ndarray, shape (6,)
            Estimated (x, y, θ, u, v, r).
        reference : PoseTrajectory or numpy.ndarray, shape (9,)
            The trajectory, or the row to track now.
        """
        if isinstance(reference, np.ndarray):  # a row (9,) already: traction's slowed clock
            return self._pid(t, state, reference)
        return self._pid(t, state, self.row(t, reference))

    def row(self, t: float, reference: PoseTrajectory) -> np.ndarray:
        """The reference row (x, y, ψ, u, v, r, u̇, v̇, ṙ) ``(9,)`` it tracks at time ``t``, its
        accelerations within the bounds.

        Parameters
        ----------
        t : float
            Time [s].
        reference : PoseTrajectory
            The trajectory.
        """
        if self._rows is None or self._rows[0] is not reference:
            from wheelbase.control.torque import TimedRows

            table = reference.reference()
            table[:, 6] = np.clip(table[:, 6], -self._accel_bounds[0], self._accel_bounds[0])
            table[:, 8] = np.clip(table[:, 8], -self._accel_bounds[1], self._accel_bounds[1])
            self._rows = (reference, TimedRows(reference.t, table))
        return self._rows[1].at(t)


def _computed_torque(robot: Robot, gains: dict[str, float], limits: SpeedLimits, grid: Any = None):
    if robot.dynamics is None:
        raise ConfigError("computed_torque needs a robot with dynamics (robot.preset: rm100)")
    defaults = {
        "speed": limits.max_speed,
        "max_acceleration": limits.max_acceleration,
        "max_yaw_acceleration": limits.max_yaw_acceleration,
    }
    return TorqueTracking(robot, **{**defaults, **gains}), "trajectory"


ADAPTIVE_GAINS = ("forgetting", "filter_time", "initial_spread", "force_drift")
"""Gains of ``adaptive_computed_torque`` that set its estimator (the others as computed_torque)."""


def _adaptive_computed_torque(
    robot: Robot, gains: dict[str, Any], limits: SpeedLimits, grid: Any = None
):
    """Computed torque on a model whose mass, inertia and CG moment are learnt online."""
    import functools

    from wheelbase.control.adaptive import AdaptiveComputedTorque

    options = {key: gains.pop(key) for key in ADAPTIVE_GAINS if key in gains}
    law = functools.partial(AdaptiveComputedTorque, **options)
    return _computed_torque(robot, {**gains, "law": law}, limits, grid)


def _mppi(robot: Robot, gains: dict[str, Any], limits: SpeedLimits, grid: Any = None):
    """MPPI (Williams et al.) on the map's distance field, following the planned path."""
    from wheelbase.control.mppi import MPPI

    defaults: dict[str, Any] = {"max_speed": limits.max_speed}
    if robot.kind == "diff":
        defaults["max_yaw_rate"] = limits.max_yaw_rate
    return MPPI.from_gains(
        robot.model, grid=grid, footprint=_footprint(robot), **{**defaults, **gains}
    ), "path"


def _dwa(robot: Robot, gains: dict[str, Any], limits: SpeedLimits, grid: Any = None):
    """The dynamic window approach (Fox, Burgard and Thrun; Nav2's DWB critics) along the
    planned path, for (v, ω) robots."""
    from wheelbase.control.dwa import DWA

    if robot.kind != "diff":
        raise ConfigError("dwa drives (v, omega) robots: use mppi for a car-like robot")
    defaults: dict[str, Any] = {
        "max_speed": limits.max_speed,
        "max_yaw_rate": limits.max_yaw_rate,
        "max_acceleration": limits.max_acceleration,
        "max_yaw_acceleration": limits.max_yaw_acceleration,
    }
    return DWA.from_gains(
        robot.model, grid=grid, footprint=_footprint(robot), **{**defaults, **gains}
    ), "path"


LAWS: dict[str, Callable[..., Any]] = {
    "mppi": _mppi,
    "dwa": _dwa,
    "computed_torque": _computed_torque,
    "adaptive_computed_torque": _adaptive_computed_torque,
    "kanayama": _tracker("Kanayama"),
    "linear": _tracker("LinearTracker"),
    "pure_pursuit": _follower("PurePursuit"),
    "stanley": _follower("Stanley"),
    "rear_wheel_feedback": _follower("RearWheelFeedback"),
    "segment": _follower("SegmentFollower"),
}
"""Control laws a scenario can name (``controller.law``) and how each is built."""
TORQUE_LAWS = ("computed_torque", "adaptive_computed_torque")
"""The laws that give wheel torques themselves (a dynamic plant; the others are wrapped)."""


def _build_controller(
    law: str, robot: Robot, gains: dict[str, float], limits: SpeedLimits, grid: Any = None
):
    try:
        return LAWS[law](robot, dict(gains), limits, grid)
    except TypeError as error:
        # An unknown keyword: list the gains the law takes.
        import dataclasses

        built, _ = LAWS[law](robot, {}, limits, grid)
        if dataclasses.is_dataclass(built):
            names = [f.name for f in dataclasses.fields(built) if f.init and f.name != "limits"]
        else:
            import inspect

            names = list(inspect.signature(type(built).__init__).parameters)[2:]
        raise ConfigError(f"{error}; {law} takes: {', '.join(names)}") from None


# --------------------------------------------------------------------------- result
@dataclass(frozen=True)
class RunResult:
    """The outcome of :func:`run`.

    Attributes
    ----------
    scenario : Scenario
        The resolved scenario.
    robot : Robot
        The resolved robot.
    grid : OccupancyGrid
        The map.
    plan : Path or None
        The concatenated plan of all legs (None when planning failed).
    reference : PoseTrajectory or None
        The time-parametrised trajectory.
    log : Log or None
        The closed-loop record (None when planning failed).
    metrics : dict
        Planning and tracking figures (see ``metrics.json`` in the README).
    sensors : SensorSuite or None
        The sensors the robot read (a lidar, landmarks), for drawing.
    terrain : TerrainMap or None
        The ground it drove on (a scenario with terrain or a payload), for drawing.
    world : World or None
        The world beyond the map it drove in (the truth, for drawing and evaluation).
    """

    scenario: Scenario
    robot: Robot
    grid: Any
    plan: Any
    reference: PoseTrajectory | None
    log: Log | None
    metrics: dict[str, Any]
    sensors: Any = None
    terrain: Any = None
    world: Any = None

    @property
    def footprint_polygon(self) -> np.ndarray:
        """Footprint outline (M, 2) in the body frame of the reference point [m]."""
        length, width = self.robot.footprint
        c = self.robot.center_offset
        return np.array(
            [[c - length / 2, -width / 2], [c + length / 2, -width / 2],
             [c + length / 2, width / 2], [c - length / 2, width / 2]]
        )  # fmt: skip

    def plot(self):
        """Map, plan and driven path (a matplotlib figure)."""
        from wheelbase.report import figure_map

        if self.log is None:
            raise PlanningError(f"no run to plot: {self.metrics.get('message', 'no plan')}")
        plan = None if self.plan is None else self.plan.poses
        return figure_map(
            self.grid, plan, self.log, self.footprint_polygon, title=self.scenario.name,
            terrain=self.terrain,
        )  # fmt: skip


# --------------------------------------------------------------------------- run
@dataclass(frozen=True)
class Prepared:
    """A scenario resolved up to the engine: map, robot, plan, reference and the engine.

    Attributes
    ----------
    scenario : Scenario
        The validated scenario.
    robot : Robot
        The resolved robot.
    grid : OccupancyGrid
        The map.
    start : numpy.ndarray, shape (3,)
        Start pose [m, m, rad].
    goals : list of numpy.ndarray
        Goal poses [m, m, rad].
    plan : Path or None
        The concatenated plan (None when planning failed).
    reference : PoseTrajectory or None
        The time-parametrised plan.
    planning : dict
        Planning figures (time, nodes, length, cusps, success, message).
    engine : Engine or None
        The closed loop, ready to run (None when planning failed).
    footprint : Footprint or None
        The robot's outline (for collisions and clearance).
    starts : numpy.ndarray, shape (R, 3), or None
        Every robot's start (a fleet's R robots; R = 1 otherwise).
    plans, references : tuple
        Every robot's plan and its time-parametrised reference (``plan`` and ``reference``
        are robot 0's).
    follows_path : bool
        The controller follows the path (its tracking error is the distance to the path),
        not the timed trajectory.
    """

    scenario: Scenario
    robot: Robot
    grid: Any
    start: np.ndarray
    goals: list[np.ndarray]
    plan: Any
    reference: PoseTrajectory | None
    planning: dict[str, Any]
    engine: Engine | None
    footprint: Any = None
    starts: np.ndarray | None = None
    plans: tuple = ()
    references: tuple = ()
    follows_path: bool = False


def prepare(
    scenario: Scenario | str | Path | dict[str, Any],
    *,
    progress: Callable[[float, float], None] | None = None,
    seed: int | None = None,
) -> Prepared:
    """Resolve a scenario, plan it and build its closed-loop :class:`~wheelbase.sim.Engine`.

    Parameters
    ----------
    scenario : Scenario, str, Path or dict
        A validated scenario, a YAML path, a bundled scenario name, or a mapping.
    progress : callable, optional
        ``progress(simulated_time, expected_end_time)`` now and then during the run.
    seed : int, optional
        The seed of what the world draws for this run (``world.path_boxes``; default the
        scenario's ``seed``).

    Raises
    ------
    ScenarioError
        Invalid scenario or gains.
    MapError
        A map that cannot be read.
    PlanningError
        Start or goal in collision or outside the map.
    """
    if not isinstance(scenario, Scenario):
        scenario = load_scenario(scenario)
    robot = _field("robot", lambda: build_robot(scenario.robot))
    start = _pose(scenario.start)
    goals = [_pose(goal) for goal in scenario.goals]
    grid = _field(
        "map",
        lambda: _load_map(
            scenario.map,
            [_pose(p) for p in scenario.robot_poses()],
            scenario.resources.max_map_cells,
        ),
    )
    _check_free(grid, robot, start, "start")
    for index, goal in enumerate(goals):
        _check_free(grid, robot, goal, f"goals[{index}]")

    limits = _field("trajectory", lambda: SpeedLimits(**scenario.trajectory.model_dump()))
    if scenario.controller.law not in LAWS:
        allowed = ", ".join(sorted(LAWS))
        raise ScenarioError(
            f"controller.law: unknown law {scenario.controller.law!r}; allowed: {allowed}"
        )
    gains = dict(scenario.controller.gains)
    if scenario.controller.law == "adaptive_computed_torque":
        from wheelbase.scenario_ground import adaptive_defaults

        gains = {**adaptive_defaults(scenario), **gains}
    if scenario.controller.law in ("mppi", "dwa"):
        # MPPI stops itself at the goal: within half the scenario's tolerance, so that the
        # true pose, off by the odometry drift, still lands inside it.
        position, heading_deg = scenario.goal_tolerance
        gains.setdefault("goal_tolerance", (0.5 * position, 0.5 * math.radians(heading_deg)))
    dynamic = scenario.plant == "dynamic"
    believed = robot  # the controller's model: the robot with the payload it believes in
    if dynamic and robot.dynamics is not None:
        from wheelbase.scenario_ground import controller_model

        believed = replace(robot, dynamics=controller_model(scenario, robot))
    controller, reference_kind = _field(
        "controller.gains",
        lambda: _build_controller(scenario.controller.law, believed, gains, limits, grid),
    )

    if not dynamic and scenario.controller.law in TORQUE_LAWS:
        raise ScenarioError(
            f"controller.law: {scenario.controller.law} gives wheel torques: use it with "
            "plant: dynamic"
        )
    if dynamic and robot.dynamics is None:
        raise ScenarioError("plant: dynamic needs a robot with a dynamics preset (rm100)")
    if dynamic and scenario.controller.law not in TORQUE_LAWS:
        from wheelbase.control.torque import TwistTorqueLoop

        loop = scenario.controller.torque_loop
        controller = _field(
            "controller.torque_loop",
            lambda: TwistTorqueLoop(
                controller, believed.dynamics, bandwidth=loop.bandwidth,
                max_torque=loop.max_torque,
            ),
        )  # fmt: skip
    if (
        not dynamic
        and robot.kind == "diff"
        and tuple(controller.command_names)
        == (
            "speed",
            "steering",
        )
    ):
        raise ScenarioError("controller: a steering law cannot drive a differential drive")
    robots = _fleet(scenario, start, goals)
    if len(robots) > 1:
        _check_fleet_apart(robots, _footprint(robot))
    plans, planning = [], {}
    for index, (robot_start, robot_goals) in enumerate(robots):
        if index:
            _check_free(grid, robot, robot_start, f"fleet[{index}].start")
            for k, goal in enumerate(robot_goals):
                _check_free(grid, robot, goal, f"fleet[{index}].goals[{k}]")
        plan, stats = _plan(grid, robot, scenario, robot_start, robot_goals)
        planning = stats if not index else _sum_planning(planning, stats)
        if plan is None:
            if index:
                planning["message"] = f"fleet[{index}]: {stats.get('message')}"
            return Prepared(scenario, robot, grid, start, goals, None, None, planning, None)
        plans.append(plan)
    plan = plans[0]
    references = [
        _timed_reference(leg, limits, scenario.dt, scenario.resources.max_steps) for leg in plans
    ]
    reference = references[0]
    end_time = max(float(timed.t[-1]) for timed in references)
    from wheelbase.control.torque import interpolate_rows

    tables = [
        (timed.t, np.column_stack([timed.poses[:, :2], np.unwrap(timed.poses[:, 2])]))
        for timed in references
    ]

    def reference_pose(t: float) -> np.ndarray:
        rows = np.array([interpolate_rows(times, table, t) for times, table in tables])
        rows[:, 2] = wrap_angle(rows[:, 2])
        return rows[0] if len(rows) == 1 else rows

    footprint = _footprint(robot)
    axle = WheelAxle(
        robot.wheel_radius,
        robot.half_track,
        radius_scale=tuple(scenario.odometry.wheel_radius_scale),
        track_scale=scenario.odometry.track_scale,
    )
    plant = DynamicPlant(robot.dynamics, axle) if dynamic else KinematicPlant(robot.model, axle)
    if dynamic:  # the ground, the payloads and what the controller knows of them
        from wheelbase import scenario_ground as ground

        timeline = ground.payload_timeline(scenario, robot, reference, goals)
        terrain = ground.build_terrain(scenario, grid)
        if ground.ground_active(scenario):
            plant = ground.build_plant(scenario, robot, terrain, axle, timeline)
    from wheelbase.scenario_navigation import build_perception
    from wheelbase.scenario_sensors import build_estimator, build_imu, build_sensors

    sensors = _field("sensors", lambda: build_sensors(scenario, grid))
    imu = _field("sensors.imu", lambda: build_imu(scenario))
    estimator = _field("localization", lambda: build_estimator(scenario, robot, grid, sensors))
    if dynamic:
        estimator = ground.compensate_slip(scenario, estimator, robot, terrain)
        estimator = ground.gyrodometry(scenario, estimator, imu)
    surroundings = _field(
        "world", lambda: _surroundings(scenario, grid, robot, footprint, robots, plans, seed)
    )
    perception = _field("costmap", lambda: build_perception(scenario, grid, footprint, sensors))
    engine_reference: Any = reference if reference_kind == "trajectory" else plan
    fleet_references = None
    if perception is not None and reference_kind == "path":
        controller = _navigator(scenario, robot, controller, grid, footprint, dynamic)
        from wheelbase.navigation import Route

        routes = tuple(
            Route(leg, tuple(leg_goals), priority)
            for priority, (leg, (_, leg_goals)) in enumerate(zip(plans, robots, strict=True))
        )
        engine_reference = routes[0]
        fleet_references = routes if len(routes) > 1 else None
    elif len(robots) > 1:
        fleet_references = tuple(
            timed if reference_kind == "trajectory" else leg
            for timed, leg in zip(references, plans, strict=True)
        )
    if dynamic:  # the payload changes the controller knows of, traction control
        controller = ground.wrap_controller(scenario, controller, robot, timeline, terrain)
    control_every = 1
    if scenario.control_rate_hz is not None:
        control_every = max(1, round(1.0 / (scenario.control_rate_hz * scenario.dt)))
    engine = Engine(
        plant=plant,
        controller=controller,
        reference=engine_reference,
        dt=scenario.dt,
        duration=scenario.duration,
        estimator=estimator,
        sensors=sensors,
        arrival=Arrival(
            np.array([robot_goals[-1] for _, robot_goals in robots]),
            (scenario.goal_tolerance[0], math.radians(scenario.goal_tolerance[1])),
            end_time=end_time,
            settle_time=math.inf if scenario.settle_time is None else scenario.settle_time,
        ),
        collides=lambda poses: grid.in_collision(footprint, poses),
        reference_pose=reference_pose,
        progress=None if progress is None else lambda t: progress(t, end_time),
        fan_every=max(1, round(FAN_PERIOD / scenario.dt)),
        max_steps=scenario.resources.max_steps,
        control_every=control_every,
        surroundings=surroundings,
        perception=perception,
        references=fleet_references,
        stuck=_stuck(scenario),
        imu=imu,
    )
    return Prepared(
        scenario, robot, grid, start, goals, plan, reference, planning, engine, footprint,
        np.array([robot_start for robot_start, _ in robots]), tuple(plans), tuple(references),
        reference_kind == "path",
    )  # fmt: skip


def _stuck(scenario: Scenario) -> Any:
    from wheelbase.scenario_ground import build_stuck

    return build_stuck(scenario)


def _fleet(scenario: Scenario, start: np.ndarray, goals: list[np.ndarray]) -> list:
    """(start, goals) of every robot: the fleet's, or the scenario's one robot."""
    if scenario.fleet is None:
        return [(start, goals)]
    return [(_pose(robot.start), [_pose(goal) for goal in robot.goals]) for robot in scenario.fleet]


def _check_fleet_apart(robots: list, footprint) -> None:
    """Two robots of a fleet may not start (or end) where their footprints overlap."""
    import shapely

    def outline(pose):
        c, s = math.cos(pose[2]), math.sin(pose[2])
        body = footprint.polygon
        return shapely.Polygon(
            np.column_stack([pose[0] + c * body[:, 0] - s * body[:, 1],
                             pose[1] + s * body[:, 0] + c * body[:, 1]])
        )  # fmt: skip

    for what, pick in (("start", lambda r: r[0]), ("goal", lambda r: r[1][-1])):
        shapes = [outline(pick(r)) for r in robots]
        for i in range(len(shapes)):
            for j in range(i):
                if shapes[i].intersects(shapes[j]):
                    raise ScenarioError(
                        f"fleet[{i}].{what} overlaps fleet[{j}].{what}: the robots' footprints "
                        "touch there; place them apart"
                    )


def _sum_planning(total: dict[str, Any], stats: dict[str, Any]) -> dict[str, Any]:
    """Planning figures of a fleet: times, nodes, lengths and cusps summed over its robots."""
    out = dict(total)
    for key in ("planning_time_s", "expanded_nodes", "compile_time_s", "path_length_m", "cusps"):
        if key in stats:
            out[key] = out.get(key, 0) + stats[key]
    out["planning_success"] = total.get("planning_success", True) and stats["planning_success"]
    return out


def _surroundings(scenario, grid, robot: Robot, footprint, robots, plans, seed):
    """The world beyond the map (None without a world or a fleet of several robots)."""
    if scenario.world is None and len(robots) == 1:
        return None
    from wheelbase.scenario_navigation import build_world, path_boxes
    from wheelbase.sim.surroundings import Surroundings

    boxes = None
    if scenario.world is not None and scenario.world.path_boxes is not None:
        from wheelbase.planning import PolygonWorld
        from wheelbase.scenario_sensors import world_grid

        def passable(polygons) -> bool:
            truth = PolygonWorld(polygons, grid=world_grid(grid))
            found, _ = _plan(truth, robot, scenario, robots[0][0], robots[0][1])
            return found is not None

        boxes = path_boxes(scenario, plans[0], passable, scenario.seed if seed is None else seed)
    world = build_world(scenario, grid, boxes)
    keep, labels = [], []
    radius = footprint.max_radius + 0.1  # nothing spawns where a robot stands or stops
    for index, (robot_start, robot_goals) in enumerate(robots):
        who = "" if len(robots) == 1 else f" of robot {index}"
        keep.append((*robot_start[:2], radius))
        labels.append(f"the start{who}")
        for k, goal in enumerate(robot_goals):
            keep.append((*goal[:2], radius))
            labels.append(f"goal {k}{who}" if len(robot_goals) > 1 else f"the goal{who}")
    return Surroundings(world, footprint, len(robots), np.array(keep), tuple(labels))


def _reach(law) -> float:
    """How far ahead a local controller looks [m]: MPPI's horizon, DWA's simulated time, at
    full speed (0 for a law without a horizon)."""
    limits = getattr(law, "limits", None)
    speed = float(getattr(limits, "max_speed", 0.0) or getattr(law, "max_speed", 0.0) or 0.0)
    if hasattr(law, "horizon_steps"):
        return law.horizon_steps * law.dt * speed
    return float(getattr(law, "sim_time", 0.0)) * speed


def _navigator(scenario, robot: Robot, law, grid, footprint, dynamic: bool):
    """The path law wrapped in a :class:`~wheelbase.navigation.Navigator` (replanning and
    recovery on the robot's costmap); on a dynamic plant inside the torque loop."""
    from wheelbase.control.torque import TwistTorqueLoop
    from wheelbase.navigation import Navigator
    from wheelbase.scenario_navigation import navigator_options

    inner = law.law if isinstance(law, TwistTorqueLoop) else law
    spec = scenario.planner
    radius = robot.turning_radius if spec.turning_radius is None else spec.turning_radius
    margin = spec.margin
    options = {**spec.options, "max_iterations": scenario.replanning.max_expansions}
    options.setdefault("time_limit", 60.0)

    def plan_route(believed, start, goals):
        from wheelbase.planning import HybridAStar

        planner = HybridAStar(
            believed,
            footprint=(robot.footprint[0] + 2 * margin, robot.footprint[1] + 2 * margin),
            turning_radius=radius,
            reverse=spec.reverse,
            rear_axle_to_center=robot.center_offset,
            **options,
        )
        legs, leg_start = [], start
        for goal in goals:
            try:
                leg = planner.plan(leg_start, goal)
            except PlanningError:  # the start or a goal inside what the robot now sees
                return None
            if not leg.success:
                return None
            legs.append(leg)
            leg_start = goal
        from wheelbase.planning.path import PlannedPath

        return legs[0] if len(legs) == 1 else _concatenate(legs, PlannedPath)

    navigator = Navigator(
        inner, plan_route, footprint, navigator_options(scenario, _reach(inner)), kind=robot.kind,
        plan_margin=margin,
    )  # fmt: skip
    if isinstance(law, TwistTorqueLoop):
        return TwistTorqueLoop(
            navigator, law.model, bandwidth=law.bandwidth, max_torque=law.max_torque
        )
    return navigator


def run(
    scenario: Scenario | str | Path | dict[str, Any],
    *,
    progress: Callable[[float, float], None] | None = None,
) -> RunResult:
    """Run a closed-loop scenario: plan, time-parametrise, track with odometry in the loop.

    The run ends as the engine's one arrival rule says (:class:`wheelbase.sim.Arrival`): the
    robot stops when its *estimate* is within the goal tolerance, at rest, after the
    trajectory has ended; the *true* pose then decides ``arrived`` or ``missed_goal``. A
    collision or ``duration`` (or the scenario's ``settle_time`` after the trajectory's end,
    when given and earlier) end it earlier (``collision``, ``timeout``).

    Parameters
    ----------
    scenario : Scenario, str, Path or dict
        A validated scenario, a YAML path, a bundled scenario name, or a mapping.
    progress : callable, optional
        ``progress(simulated_time, expected_end_time)`` now and then during the run.

    Returns
    -------
    RunResult
        With the plan, the trajectory, the log (one robot) and the metrics; a plan that
        cannot be found gives a result with ``metrics["status"] == "planning_failed"`` and no
        log.

    Raises
    ------
    ScenarioError
        Invalid scenario or gains.
    MapError
        A map that cannot be read.
    PlanningError
        Start or goal in collision or outside the map.
    """
    prepared = prepare(scenario, progress=progress)
    if prepared.engine is None:
        metrics = {**_base_metrics(prepared, prepared.scenario.seed), "status": "planning_failed"}
        return RunResult(
            prepared.scenario, prepared.robot, prepared.grid, None, None, None, metrics
        )
    starts = prepared.starts if prepared.starts is not None else prepared.start[None]
    log = prepared.engine.run(starts, seeds=np.full(len(starts), prepared.scenario.seed))
    metrics = _world_metrics(prepared, log, 0)
    return RunResult(
        prepared.scenario,
        prepared.robot,
        prepared.grid,
        prepared.plan,
        prepared.reference,
        log,
        metrics,
        prepared.engine.sensors,
        getattr(getattr(prepared.engine.plant, "model", None), "terrain", None),
        None if prepared.engine.surroundings is None else prepared.engine.surroundings.world,
    )


LOG_COPIES = 3
"""A run's record is held about three times while it is made: the rows of every step, the
stacked arrays of the log, and the per-robot copies its metrics are taken from."""


def run_seeds(
    scenario: Scenario | str | Path | dict[str, Any],
    seeds: Any,
    *,
    memory_budget: float | None = None,
) -> list[dict[str, Any]]:
    """Run one scenario over many noise seeds in vectorised chunks; metrics per seed.

    The plan is made once (it does not depend on the seed); the engine then steps one robot
    per seed in lockstep, as many seeds at a time as :func:`seeds_per_chunk` lets into
    ``memory_budget``, and keeps only each finished chunk's metrics: memory stays flat however
    many seeds there are. Robot ``i`` equals :func:`run` with ``seed = seeds[i]``.

    Parameters
    ----------
    scenario : Scenario, str, Path or dict
        The scenario (its own ``seed`` is ignored).
    seeds : sequence of int
        Noise seeds, one run each.
    memory_budget : float, optional
        Bytes the logs of one chunk may take (default
        :data:`wheelbase.limits.BATCH_MEMORY`, 512 MiB), > 0.

    Returns
    -------
    list of dict
        The metrics of each run (as :func:`run` gives them), in the order of ``seeds``.
    """
    if memory_budget is not None:
        positive("memory_budget", memory_budget, "bytes")
    if not isinstance(scenario, Scenario):
        scenario = load_scenario(scenario)
    seeds = [int(seed) for seed in seeds]
    if scenario.world is not None and scenario.world.path_boxes is not None:
        # each seed drops its own boxes: its own world, run alone
        rows = []
        for seed in seeds:
            rows += run_prepared(prepare(scenario, seed=seed), [seed], memory_budget=memory_budget)
        return rows
    return run_prepared(prepare(scenario), seeds, memory_budget=memory_budget)


def run_prepared(
    prepared: Prepared, seeds: Any, *, memory_budget: float | None = None
) -> list[dict[str, Any]]:
    """Engine runs of a prepared scenario for ``seeds`` (a world of R robots per seed), as many
    worlds at a time as fit ``memory_budget`` bytes (:func:`seeds_per_chunk`): what
    :func:`run_seeds` does after :func:`prepare`, for a caller that changed the prepared
    scenario first (another engine, map or sensors: ``dataclasses.replace``).

    Parameters
    ----------
    prepared : Prepared
        From :func:`prepare`, changed or not.
    seeds : sequence of int
        Noise seeds, one world each.
    memory_budget : float, optional
        Bytes the logs of one chunk may take (default
        :data:`wheelbase.limits.BATCH_MEMORY`), > 0.

    Returns
    -------
    list of dict
        The metrics of each world, in the order of ``seeds``.
    """
    from wheelbase.limits import BATCH_MEMORY

    budget = BATCH_MEMORY if memory_budget is None else memory_budget
    budget = positive("memory_budget", budget, "bytes")
    seeds = [int(seed) for seed in seeds]
    if prepared.engine is None:
        return [{**_base_metrics(prepared, seed), "status": "planning_failed"} for seed in seeds]
    fleet = len(prepared.starts)
    engine = replace(prepared.engine, record_sensors=False)  # metrics only: no scans kept
    size = seeds_per_chunk(engine, prepared.starts, budget) if seeds else 1
    rows: list[dict[str, Any]] = []
    for first in range(0, len(seeds), size):
        chunk = seeds[first : first + size]
        starts = np.tile(prepared.starts, (len(chunk), 1))
        log = engine.run(starts, seeds=np.repeat(np.array(chunk, dtype=np.int64), fleet))
        rows.extend(_world_metrics(prepared, log, k) for k in range(len(chunk)))
        del log  # only the rows outlive the chunk
    return rows


def _world_metrics(prepared: Prepared, log: Log, world: int) -> dict[str, Any]:
    """The metrics of world ``world`` of a run: its robot's, or a fleet's first robot's with
    ``robots`` (each robot's) and the fleet's status (the first that is not ``arrived``)."""
    fleet = len(prepared.starts) if prepared.starts is not None else 1
    metrics = run_metrics(prepared, log, world * fleet)
    if fleet > 1:
        robots = [run_metrics(prepared, log, world * fleet + i) for i in range(fleet)]
        worst = next((m["status"] for m in robots if m["status"] != "arrived"), "arrived")
        metrics = {**metrics, "status": worst, "robots": robots}
    return metrics


def seeds_per_chunk(engine: Engine, starts: np.ndarray, budget: float) -> int:
    """How many worlds (seeds) of ``engine`` one vectorised run can hold within ``budget``
    bytes, a world being the robots of ``starts`` (one, or a fleet).

    One step of one world is recorded (its rows' arrays: poses, command, wheel rates, ticks,
    the estimator's and plant's signals) and counted :data:`LOG_COPIES` times for each of the
    engine's ``steps`` (the longest a run can last).

    Parameters
    ----------
    engine : Engine
        The closed loop.
    starts : numpy.ndarray, shape (3,) or (R, 3)
        The start pose(s) of one world.
    budget : float
        Bytes.

    Returns
    -------
    int
        At least 1.
    """
    starts = np.asarray(starts, dtype=np.float64).reshape(-1, 3)
    seeds = np.zeros(len(starts), dtype=np.int64)
    _, row = engine.step(engine.reset(starts, seeds=seeds))
    per_step = _nbytes(row) + 64  # and the row's own bookkeeping
    return max(1, int(budget // (per_step * engine.steps * LOG_COPIES)))


def _nbytes(value: Any) -> int:
    """Bytes of the arrays in a value (a dataclass, dict, list or array), recursively."""
    import dataclasses

    if isinstance(value, np.ndarray):
        return int(value.nbytes)
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        return sum(_nbytes(getattr(value, f.name)) for f in dataclasses.fields(value))
    if isinstance(value, dict):
        return sum(_nbytes(v) for v in value.values())
    if isinstance(value, (list, tuple)):
        return sum(_nbytes(v) for v in value) + 8 * len(value)
    return 0


def _base_metrics(prepared: Prepared, seed: int) -> dict[str, Any]:
    return {"name": prepared.scenario.name, "seed": seed, **prepared.planning}


def run_metrics(prepared: Prepared, log: Log, index: int) -> dict[str, Any]:
    """The metrics of robot ``index`` of a run of a prepared scenario (``metrics.json``).

    Parameters
    ----------
    prepared : Prepared
        The scenario as :func:`prepare` resolved it.
    log : Log
        The engine's record.
    index : int
        Which robot.
    """
    seed = int(log.seeds[index])
    one = log.robot(index)
    plan, reference = prepared.plan, prepared.reference
    if len(prepared.plans) > 1:  # robot i of a batch of fleets is robot i % R of its world
        plan = prepared.plans[index % len(prepared.plans)]
        reference = prepared.references[index % len(prepared.plans)]
    metrics = {**_base_metrics(prepared, seed), **one.metrics()[0]}
    metrics.pop("controller_statuses", None)
    metrics["trajectory_duration_s"] = float(reference.t[-1])
    if metrics["status"] in ("arrived", "missed_goal"):  # it stopped: how late
        metrics["arrival_delay_s"] = metrics["duration_s"] - metrics["trajectory_duration_s"]
    counts = one.controller_status_counts(0)
    if counts:
        metrics["controller_statuses"] = counts
    true_pose = one.true_pose[0]
    deviation = distance_to_polyline(true_pose[:, :2], plan.poses[:, :2])
    metrics["path_deviation_rms_m"] = float(np.sqrt(np.mean(deviation**2)))
    metrics["path_deviation_max_m"] = float(np.max(deviation))
    if prepared.follows_path:
        # a path law is scored by its distance to the path; the error against the timed
        # reference (where the trajectory would be at that time) keeps its own name
        for name in ("rms_position_error_m", "max_position_error_m", "rms_heading_error_deg"):
            metrics[f"timed_{name}"] = metrics.pop(f"tracking_{name}")
        metrics["tracking_rms_position_error_m"] = metrics["path_deviation_rms_m"]
        metrics["tracking_max_position_error_m"] = metrics["path_deviation_max_m"]
    metrics["tracking_error_of"] = "path" if prepared.follows_path else "trajectory"
    if one.torques is not None:
        # Mechanical energy the wheels deliver: ∫ τ·ω dt, positive (motoring) parts only.
        power = np.sum(one.torques[0] * one.wheel_rates[0], axis=1)
        metrics["wheel_energy_j"] = float(np.sum(np.clip(power[:-1], 0, None) * np.diff(one.t)))
    from wheelbase.scenario_ground import terrain_metrics

    metrics.update(terrain_metrics(one))  # slip, sinkage and the energy budget on terrain
    clearance = _min_clearance(prepared.grid, prepared.footprint, true_pose)  # every pose
    metrics["min_clearance_m"] = clearance if math.isfinite(clearance) else None  # no obstacle
    metrics["localization"] = prepared.scenario.localization.method
    for key, value in one.extras.items():  # a filter's cumulative counts, at the end
        if key == "loc_converged":  # a global localisation's belief is one cluster at the end
            metrics["localization_converged"] = bool(value[0, -1])
        elif key.startswith("loc_") and key != "loc_particles":
            metrics[f"localization_{key[4:]}"] = int(value[0, -1])
    summary = log.summaries[index] if log.summaries else {}
    if summary or (prepared.engine is not None and prepared.engine.surroundings is not None):
        metrics.update(_navigation_metrics(one, plan, summary))
    return metrics


def _navigation_metrics(one: Log, plan, summary: dict[str, Any]) -> dict[str, Any]:
    """Figures of a run among obstacles: contacts, least distances, replans and stops."""
    from wheelbase.sim.surroundings import world_metrics

    out: dict[str, Any] = {}
    extras = {key: value[0] for key, value in one.extras.items() if key.startswith("world_")}
    if extras:
        speed = float(np.hypot(*one.twist[0, -1, :2]))
        dt = np.append(np.diff(one.t), 0.0)
        out.update(world_metrics(extras, STATUSES[int(one.status[0])], speed, dt))
    if "track_matches" in one.extras:
        matches = float(one.extras["track_matches"][0, -1])
        for name, key in (("position", "track_position_rmse_m"),
                          ("velocity", "track_velocity_rmse_m_s")):  # fmt: skip
            total = float(one.extras[f"track_{name}_sq_sum"][0, -1])
            out[key] = math.sqrt(total / matches) if matches else None
        out["track_matches"] = int(matches)
    out["replans"] = int(summary.get("replans", 0))
    out["yields"] = int(summary.get("yields", 0))
    out["recoveries"] = int(summary.get("recoveries", 0))
    speed = np.hypot(one.twist[0, :-1, 0], one.twist[0, :-1, 1])
    out["time_stopped_s"] = float(np.sum(np.diff(one.t)[speed < 0.01]))
    driven = float(np.sum(np.hypot(*np.diff(one.true_pose[0, :, :2], axis=0).T)))
    out["path_length_ratio"] = driven / plan.length if plan.length > 0 else None
    return out


def _min_clearance(grid, footprint, poses: np.ndarray) -> float:
    """The least footprint clearance [m] over ``poses``, exact, evaluating few poses.

    Small disks tile the footprint's bounding box (cells of at most a quarter of its shorter
    side, each covered by the disk through its corners), so the map's clearance at a disk's
    centre minus its radius, the least over the disks, bounds a pose's clearance from below:
    poses are evaluated exactly in the order of that bound until it passes the best found.
    """
    (xmin, ymin), (xmax, ymax) = footprint.polygon.min(0), footprint.polygon.max(0)
    cell = 0.25 * min(xmax - xmin, ymax - ymin)
    nx, ny = max(1, math.ceil((xmax - xmin) / cell)), max(1, math.ceil((ymax - ymin) / cell))
    gx = xmin + (np.arange(nx) + 0.5) * (xmax - xmin) / nx
    gy = ymin + (np.arange(ny) + 0.5) * (ymax - ymin) / ny
    centres = np.stack(np.meshgrid(gx, gy), -1).reshape(-1, 2)  # body frame
    radius = 0.5 * math.hypot((xmax - xmin) / nx, (ymax - ymin) / ny)
    c, s = np.cos(poses[:, 2])[:, None], np.sin(poses[:, 2])[:, None]
    world = np.stack(
        [poses[:, :1] + c * centres[:, 0] - s * centres[:, 1],
         poses[:, 1:2] + s * centres[:, 0] + c * centres[:, 1]],
        axis=-1,
    )  # fmt: skip
    bound = np.min(grid.clearance(world), axis=1) - radius
    best = math.inf
    order = np.argsort(bound)
    start, size = 0, 1  # the lowest bound first: it is usually the least clearance
    while start < len(poses) and bound[order[start]] < best:
        batch = order[start : start + size]
        batch = batch[bound[batch] < best]
        best = min(best, float(np.min(grid.footprint_clearance(footprint, poses[batch]))))
        start, size = start + size, 4
    return best


def _field(name: str, build: Callable[[], Any]) -> Any:
    try:
        return build()
    except ScenarioError:
        raise
    except ConfigError as error:
        raise ScenarioError(f"{name}: {error}") from None
    except (MapError, DataError) as error:
        raise type(error)(f"{name}: {error}") from None


def _pose(values) -> np.ndarray:
    return np.array([values[0], values[1], math.radians(values[2])], dtype=np.float64)


def _load_map(name: str, points: list[np.ndarray], max_cells: int):
    """A bundled map or a map file; ``empty`` is an obstacle-free field around the points,
    walled by the map edge (sized as the scenario's validation sized it)."""
    from wheelbase.planning.maps import load_map
    from wheelbase.scenario import empty_map

    if name != "empty":
        return load_map(name, max_cells=max_cells)
    return empty_map(points, max_cells)


def _footprint(robot: Robot):
    from wheelbase.planning import Footprint

    return Footprint.rectangle(*robot.footprint, rear_axle_to_center=robot.center_offset)


def _check_free(grid, robot: Robot, pose: np.ndarray, name: str) -> None:
    if not grid.contains(pose[:2]):
        raise PlanningError(f"{name} ({pose[0]:g}, {pose[1]:g}) is outside the map")
    if grid.in_collision(_footprint(robot), pose):
        raise PlanningError(
            f"{name} ({pose[0]:g}, {pose[1]:g}, {math.degrees(pose[2]):g} deg): the robot's "
            "footprint there overlaps an obstacle or leaves the map"
        )


def _plan(grid, robot: Robot, scenario: Scenario, start, goals):
    from wheelbase.planning import HybridAStar
    from wheelbase.planning.path import PlannedPath

    spec = scenario.planner
    radius = robot.turning_radius if spec.turning_radius is None else spec.turning_radius
    margin = spec.margin
    planner = _field(
        "planner",
        lambda: HybridAStar(
            grid,
            footprint=(robot.footprint[0] + 2 * margin, robot.footprint[1] + 2 * margin),
            turning_radius=radius,
            reverse=spec.reverse,
            rear_axle_to_center=robot.center_offset,
            **spec.options,
        ),
    )
    legs = []
    stats = {"planning_time_s": 0.0, "expanded_nodes": 0, "compile_time_s": 0.0}
    leg_start = start
    for goal in goals:
        leg = planner.plan(leg_start, goal)
        stats["planning_time_s"] += leg.stats.planning_time_s
        stats["expanded_nodes"] += leg.stats.expanded_nodes
        stats["compile_time_s"] += leg.stats.compile_time_s
        if not leg.success:
            stats.update(planning_success=False, message=leg.stats.message or "no path found")
            return None, stats
        legs.append(leg)
        leg_start = goal
    plan = legs[0] if len(legs) == 1 else _concatenate(legs, PlannedPath)
    stats.update(
        planning_success=True,
        path_length_m=float(sum(leg.length for leg in legs)),
        cusps=int(sum(leg.cusps for leg in legs)),
        turning_radius_m=radius,
    )
    return plan, stats


def _concatenate(legs, path_type):
    poses = np.vstack([legs[0].poses] + [leg.poses[1:] for leg in legs[1:]])
    directions = np.concatenate([legs[0].directions] + [leg.directions[1:] for leg in legs[1:]])
    curvatures = np.concatenate([legs[0].curvatures] + [leg.curvatures[1:] for leg in legs[1:]])
    arc = [legs[0].arc_length]
    for leg in legs[1:]:
        arc.append(arc[-1][-1] + leg.arc_length[1:])
    return path_type(poses, directions, curvatures, np.concatenate(arc), True, legs[0].stats)


def _timed_reference(plan, limits: SpeedLimits, dt: float, max_steps: int) -> PoseTrajectory:
    """Time-parametrise each forward/backward run of the plan; stops at every goal."""
    directions = np.where(plan.directions < 0, -1.0, 1.0)
    return time_parametrize(plan.poses, directions, limits, dt=dt, max_samples=max_steps)
