"""A small closed-loop runner for a batch of robots: controller → saturation → kinematic plant.

:func:`run_closed_loop` steps N robots at once — the controller is called on the ``(N, 3)``
batch of poses, the plant is any :mod:`wheelbase.models` model advanced with
:func:`wheelbase.integrate.integrate_step` — and records poses and commands. It is what the
control benchmarks and figures use; :func:`wheelbase.sim.run_loop` is the full single-robot
loop with encoders and odometry.

The command is a zero-order hold over each step, so the default ``exact`` integrator (the
closed-form arc) makes the plant exact: the only error is the controller's sampling.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from wheelbase._validate import as_float_array, check_choice, positive
from wheelbase.control.base import (
    HOLONOMIC_COMMAND,
    STEERING_COMMAND,
    VELOCITY_COMMAND,
    Controller,
    velocity_to_steering,
    velocity_to_wheel_speeds,
)
from wheelbase.errors import ConfigError
from wheelbase.integrate import METHODS, integrate_step, time_grid
from wheelbase.models.base import KinematicModel

__all__ = [
    "BENCHMARK_LIMITS",
    "POSE_LAWS",
    "ClosedLoopResult",
    "command_to_inputs",
    "dynamic_benchmark",
    "evaluate_pose_law",
    "figure_eight_reference",
    "make_pose_law",
    "pose_benchmark",
    "pose_benchmark_starts",
    "run_closed_loop",
    "run_dynamic_closed_loop",
    "three_point_turn_path",
    "tracking_benchmark",
    "velocity_torques",
]


@dataclass(frozen=True)
class ClosedLoopResult:
    """Trajectories of a closed-loop batch run.

    Attributes
    ----------
    t : numpy.ndarray, shape (T,)
        Times [s].
    poses : numpy.ndarray, shape (T, N, 3)
        Poses (x [m], y [m], θ [rad]).
    commands : numpy.ndarray, shape (T, N, 2)
        The (saturated) command in force from each time on; the last row repeats the one before.
        Zero after a robot has arrived when the run stops robots on arrival.
    command_names : tuple of str
        The meaning of the commands' last axis.
    arrival_time : numpy.ndarray, shape (N,)
        First time [s] each robot was within the goal tolerance; NaN if never (or no goal).
    """

    t: np.ndarray
    poses: np.ndarray
    commands: np.ndarray
    command_names: tuple[str, ...]
    arrival_time: np.ndarray

    @property
    def arrived(self) -> np.ndarray:
        """Whether each robot reached the goal tolerance, shape (N,)."""
        return ~np.isnan(self.arrival_time)

    @property
    def path_length(self) -> np.ndarray:
        """Length [m] of each robot's path (sum of the step chords), shape (N,)."""
        steps = np.diff(self.poses[..., :2], axis=0)
        return np.sum(np.hypot(steps[..., 0], steps[..., 1]), axis=0)

    @property
    def reversals(self) -> np.ndarray:
        """How often each robot changed its direction of travel (sign of v), shape (N,).

        Speeds below 1e-6 m/s (stops, turns in place) do not count as a direction.
        """
        v = self.commands[:-1, :, 0]
        sign = np.where(np.abs(v) > 1e-6, np.sign(v), 0.0)
        counts = np.zeros(v.shape[1], dtype=np.int64)
        last = np.zeros(v.shape[1])
        for row in sign:
            moving = row != 0.0
            counts += (moving & (last != 0.0) & (row != last)).astype(np.int64)
            last = np.where(moving, row, last)
        return counts

    def final_error(self, goal: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
        """Final position error [m] and absolute heading error [rad] against ``goal`` (3,)."""
        goal = as_float_array("goal", goal, 3)
        last = self.poses[-1]
        position = np.hypot(last[:, 0] - goal[..., 0], last[:, 1] - goal[..., 1])
        heading = np.abs(np.angle(np.exp(1j * (last[:, 2] - goal[..., 2]))))
        return position, heading


def _within(
    poses: np.ndarray, goal: np.ndarray, tol_position: float, tol_heading: float
) -> np.ndarray:
    """Which robots ``(N, 3)`` are within the position [m] and heading [rad] tolerance."""
    dx, dy = poses[:, 0] - goal[..., 0], poses[:, 1] - goal[..., 1]
    dth = np.abs(np.angle(np.exp(1j * (poses[:, 2] - goal[..., 2]))))
    return (np.hypot(dx, dy) <= tol_position) & (dth <= tol_heading)


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


def run_closed_loop(
    controller: Controller,
    model: KinematicModel,
    pose0: ArrayLike,
    reference: Any,
    t_end: float,
    dt: float,
    *,
    method: str = "exact",
    goal_tolerance: tuple[float, float] | None = None,
    stop_on_arrival: bool = True,
) -> ClosedLoopResult:
    """Run ``controller`` on ``model`` from ``pose0`` for ``t_end`` seconds.

    Parameters
    ----------
    controller : Controller
        Called once per step as ``controller(t, poses (N, 3), reference)``; it is
        :meth:`~Controller.reset` first.
    model : KinematicModel
        The plant (any :mod:`wheelbase.models` model).
    pose0 : array_like, shape (3,) or (N, 3)
        Initial poses (x [m], y [m], θ [rad]).
    reference : object
        Passed to the controller unchanged (a goal pose, a path, a trajectory).
    t_end : float
        Duration [s], > 0.
    dt : float
        Control period and integration step [s], 0 < dt <= t_end.
    method : str
        Integrator of :data:`wheelbase.integrate.METHODS` (default ``exact``).
    goal_tolerance : (float, float), optional
        (position [m], heading [rad]): a robot within both of the goal pose ``reference``
        has arrived; its arrival time is recorded.
    stop_on_arrival : bool
        Hold arrived robots still (zero command) and end the run once all have arrived.

    Returns
    -------
    ClosedLoopResult
    """
    check_choice("method", method, METHODS)
    times = time_grid(t_end, dt)
    pose = as_float_array("pose0", pose0, 3, min_ndim=1, max_ndim=2).reshape(-1, 3).copy()
    n = pose.shape[0]
    goal = None
    if goal_tolerance is not None:
        tol_position = positive("position tolerance", goal_tolerance[0], "m")
        tol_heading = positive("heading tolerance", goal_tolerance[1], "rad")
        goal = as_float_array("goal", reference, 3)
    names = tuple(getattr(controller, "command_names", VELOCITY_COMMAND))
    controller.reset()
    poses = np.empty((times.size, n, 3))
    commands = np.zeros((times.size, n, len(names)))
    arrival = np.full(n, np.nan)
    poses[0] = pose
    last = times.size - 1
    for k in range(times.size - 1):
        t = float(times[k])
        if goal is not None:
            inside = _within(pose, goal, tol_position, tol_heading)
            arrival = np.where(np.isnan(arrival) & inside, t, arrival)
            if stop_on_arrival and not np.any(np.isnan(arrival)):
                last = k
                break
        command = np.asarray(controller(t, pose, reference), dtype=np.float64)
        command = command.reshape(n, len(names))
        if goal is not None and stop_on_arrival:
            command = np.where(np.isnan(arrival)[:, None], command, 0.0)
        commands[k] = command
        twist = model.twist(command_to_inputs(command, names, model))
        pose = integrate_step(pose, twist, twist, twist, float(times[k + 1] - t), method)
        poses[k + 1] = pose
    else:
        if goal is not None:
            inside = _within(pose, goal, tol_position, tol_heading)
            arrival = np.where(np.isnan(arrival) & inside, times[-1], arrival)
    commands[last] = commands[last - 1] if last > 0 else commands[0]
    return ClosedLoopResult(
        t=times[: last + 1],
        poses=poses[: last + 1],
        commands=commands[: last + 1],
        command_names=names,
        arrival_time=arrival,
    )


def pose_benchmark_starts(radius: float = 2.0, bearings: int = 16, headings: int = 8) -> np.ndarray:
    """Start poses of the pose-control benchmark, shape ``(bearings·headings, 3)``.

    The goal is the origin facing +x; the starts lie on a circle of ``radius`` [m] at
    ``bearings`` equally spaced bearings (from 0), each with ``headings`` equally spaced
    headings (from 0) — 16 × 8 = 128 cases by default, bearing-major.

    Parameters
    ----------
    radius : float
        Radius of the circle of starts [m], > 0.
    bearings : int
        Number of bearings, >= 1.
    headings : int
        Number of headings per bearing, >= 1.
    """
    radius = positive("radius", radius, "m")
    for name, count in (("bearings", bearings), ("headings", headings)):
        if isinstance(count, bool) or not isinstance(count, (int, np.integer)) or count < 1:
            raise ConfigError(f"{name} must be an integer >= 1 (got {count!r})")
    bearing = 2.0 * np.pi * np.arange(bearings) / bearings
    heading = 2.0 * np.pi * np.arange(headings) / headings
    b, h = np.meshgrid(bearing, heading, indexing="ij")
    heading = np.arctan2(np.sin(h.ravel()), np.cos(h.ravel()))
    heading = np.where(heading <= -np.pi, np.pi, heading)
    return np.stack([radius * np.cos(b.ravel()), radius * np.sin(b.ravel()), heading], -1)


def evaluate_pose_law(
    controller: Controller,
    model: KinematicModel,
    starts: ArrayLike,
    goal: ArrayLike = (0.0, 0.0, 0.0),
    *,
    t_end: float = 60.0,
    dt: float = 0.01,
    tolerance: tuple[float, float] = (0.01, math.radians(1.0)),
) -> tuple[dict[str, float], ClosedLoopResult]:
    """Run a pose law from every start and summarise it (the 128-case pose benchmark).

    Parameters
    ----------
    controller : Controller
        A pose law (goal-pose reference).
    model : KinematicModel
        The plant.
    starts : array_like, shape (N, 3)
        Start poses.
    goal : array_like, shape (3,)
        The goal pose.
    t_end : float
        Time limit [s].
    dt : float
        Step [s].
    tolerance : (float, float)
        Position [m] and heading [rad] tolerance of success.

    Returns
    -------
    metrics : dict
        ``success_rate`` (fraction within ``tolerance`` of the goal before ``t_end``),
        ``mean_time_s`` and ``mean_path_length_m`` (over the successful runs; NaN if none),
        ``reversals`` (mean number of direction changes per run), ``position_success_rate``
        (within the position tolerance at the end, whatever the heading),
        ``max_final_position_error_m`` and ``max_final_heading_error_deg``.
    result : ClosedLoopResult
        The trajectories.
    """
    result = run_closed_loop(controller, model, starts, goal, t_end, dt, goal_tolerance=tolerance)
    position, heading = result.final_error(goal)
    ok = result.arrived
    metrics = {
        "success_rate": float(np.mean(ok)),
        "mean_time_s": float(np.mean(result.arrival_time[ok])) if ok.any() else math.nan,
        "mean_path_length_m": float(np.mean(result.path_length[ok])) if ok.any() else math.nan,
        "reversals": float(np.mean(result.reversals)),
        "position_success_rate": float(np.mean(position <= tolerance[0])),
        "max_final_position_error_m": float(np.max(position)),
        "max_final_heading_error_deg": float(np.degrees(np.max(heading))),
    }
    return metrics, result


# --------------------------------------------------------------------------- benchmarks
POSE_LAWS: tuple[str, ...] = (
    "point",
    "polar",
    "aicardi",
    "via_point",
    "via_direction",
    "line_arc",
)
"""Names of the pose laws (document 002 control list, laws 1–6), in order."""

BENCHMARK_LIMITS = (0.5, 1.5)
"""|v| [m/s] and |ω| [rad/s] limits of the benchmarks."""


def make_pose_law(name: str, limits: Any = None) -> Controller:
    """A pose law of :data:`POSE_LAWS` with its default gains and the given limits.

    Parameters
    ----------
    name : str
        One of :data:`POSE_LAWS`.
    limits : VelocityLimits, optional
        Command limits.
    """
    from wheelbase.control.point import GoToPoint
    from wheelbase.control.pose import Aicardi, LineArc, PolarPose, ViaDirection, ViaPoint

    check_choice("law", name, POSE_LAWS)
    classes = {
        "point": GoToPoint,
        "polar": PolarPose,
        "aicardi": Aicardi,
        "via_point": ViaPoint,
        "via_direction": ViaDirection,
        "line_arc": LineArc,
    }
    return classes[name](limits=limits)


def pose_benchmark(
    laws: tuple[str, ...] = POSE_LAWS,
    *,
    starts: ArrayLike | None = None,
    t_end: float = 60.0,
    dt: float = 0.01,
) -> tuple[dict[str, dict[str, float]], dict[str, ClosedLoopResult]]:
    """The pose benchmark: every law from the 128 starts to the origin, on a unicycle.

    |v| ≤ 0.5 m/s, |ω| ≤ 1.5 rad/s, dt = 0.01 s, 60 s limit, success within 1 cm and 1°.

    Parameters
    ----------
    laws : tuple of str
        Names of :data:`POSE_LAWS` to run.
    starts : array_like, shape (N, 3), optional
        Start poses (default :func:`pose_benchmark_starts`).
    t_end : float
        Time limit [s].
    dt : float
        Step [s].

    Returns
    -------
    table : dict
        Per law, the metrics of :func:`evaluate_pose_law` plus ``runtime_s`` (wall clock).
    results : dict
        Per law, the trajectories.
    """
    import time

    from wheelbase.control.base import VelocityLimits
    from wheelbase.models import Unicycle

    starts = pose_benchmark_starts() if starts is None else starts
    limits = VelocityLimits(*BENCHMARK_LIMITS)
    table, results = {}, {}
    for name in laws:
        begin = time.perf_counter()
        metrics, result = evaluate_pose_law(
            make_pose_law(name, limits), Unicycle(), starts, t_end=t_end, dt=dt
        )
        metrics["runtime_s"] = time.perf_counter() - begin
        table[name], results[name] = metrics, result
    return table, results


def figure_eight_reference(duration: float = 30.0, dt: float = 0.01) -> Any:
    """The figure-eight reference: x = 1.1 + 0.7 sin(2πt/T), y = 0.9 + 0.7 sin(4πt/T).

    Returns a :class:`wheelbase.models.PathReference` on the grid 0, dt, …, T, built from the
    analytic derivatives (document 002 eq. 10).

    Parameters
    ----------
    duration : float
        Period T [s].
    dt : float
        Sampling step [s].
    """
    from wheelbase.models import reference_from_derivatives

    duration = positive("duration", duration, "s")
    t = time_grid(duration, dt)
    w = 2.0 * np.pi / duration
    return reference_from_derivatives(
        1.1 + 0.7 * np.sin(w * t),
        0.9 + 0.7 * np.sin(2 * w * t),
        0.7 * w * np.cos(w * t),
        1.4 * w * np.cos(2 * w * t),
        -0.7 * w * w * np.sin(w * t),
        -2.8 * w * w * np.sin(2 * w * t),
        t=t,
    )


def three_point_turn_path(radius: float = 1.5, step: float = 0.05) -> Any:
    """A Hybrid-A*-style path with two cusps: forward, reverse, forward (a three-point turn).

    From (0, 0) heading +x: a left quarter circle of ``radius`` forward to (R, R); a quarter
    circle in reverse that swings the tail to +x, ending at (2R, 0) with heading π; then
    forward 2R·2/3 along −x. Points every ``step`` metres or less.

    Parameters
    ----------
    radius : float
        R [m], > 0.
    step : float
        Largest spacing of the points [m], > 0.
    """
    from wheelbase.control.path import Polyline

    r = positive("radius", radius, "m")
    n = max(4, math.ceil(0.5 * math.pi * r / positive("step", step, "m")) + 1)
    a = np.linspace(-0.5 * np.pi, 0.0, n)
    forward = np.stack([r * np.cos(a), r + r * np.sin(a)], -1)
    b = np.linspace(np.pi, 1.5 * np.pi, n)[1:]
    reverse = np.stack([2 * r + r * np.cos(b), r + r * np.sin(b)], -1)
    m = max(2, math.ceil(4.0 / 3.0 * r / step))
    last = np.stack([np.linspace(2 * r, 2 * r / 3, m + 1)[1:], np.zeros(m)], -1)
    directions = np.r_[np.ones(n - 1), -np.ones(n - 1), np.ones(m)]
    return Polyline(np.concatenate([forward, reverse, last]), directions)


def tracking_benchmark(dt: float = 0.01) -> tuple[list[dict[str, Any]], dict[str, Any]]:
    """The tracking benchmark: laws 7 and 8 on the figure-eight and the cusp path.

    Figure-eight (T = 30 s, start (1.1, 0.8, 0)): the trackers (law 8) follow the timed
    reference; the path followers (law 7) follow its polyline at the mean reference speed.
    Cusp path (:func:`three_point_turn_path`, start (0, 0.05, 0)): the path followers at
    0.3 m/s. Plants: the unicycle (|v| ≤ 0.5 m/s, |ω| ≤ 1.5 rad/s; Stanley's virtual front axle
    0.1 m ahead) and, for law 7, the rear-wheel bicycle with L = 0.5 m and |δ| ≤ 35° (on the
    figure-eight a bicycle with L = 0.05 m: the lobes' 8.8 cm radius of curvature is below the
    0.71 m turning radius of L = 0.5 m).

    Returns
    -------
    rows : list of dict
        ``reference``, ``law``, ``plant``, ``rms_lateral_error_m`` and
        ``max_lateral_error_m`` after 5 s (trackers: the error across the reference heading;
        path followers: the distance to the path), ``final_position_error_m``.
    traces : dict
        ``(reference, law, plant) -> (t, lateral error)`` for plots.
    """
    from wheelbase.control.base import SteeringLimits, VelocityLimits
    from wheelbase.control.path import (
        Polyline,
        PurePursuit,
        RearWheelFeedback,
        SegmentFollower,
        Stanley,
    )
    from wheelbase.control.tracking import Kanayama, LinearTracker
    from wheelbase.models import RearWheelBicycle, Unicycle

    limits = VelocityLimits(*BENCHMARK_LIMITS)
    rows: list[dict[str, Any]] = []
    traces: dict[Any, Any] = {}

    def record(reference, law, plant, t, lateral, final):
        late = t >= 5.0
        rows.append(
            {
                "reference": reference,
                "law": law,
                "plant": plant,
                "rms_lateral_error_m": float(np.sqrt(np.mean(lateral[late] ** 2))),
                "max_lateral_error_m": float(np.max(np.abs(lateral[late]))),
                "final_position_error_m": float(final),
            }
        )
        traces[(reference, law, plant)] = (t, lateral)

    eight = figure_eight_reference(30.0, dt)
    start8 = np.array([1.1, 0.8, 0.0])
    for name, law in (
        ("linear", LinearTracker(limits=limits)),
        ("kanayama", Kanayama(limits=limits)),
    ):
        result = run_closed_loop(law, _unicycle(), start8, eight, 30.0, dt)
        pose, ref = result.poses[:, 0], eight.poses[: result.t.size]
        lateral = -np.sin(ref[:, 2]) * (pose[:, 0] - ref[:, 0]) + np.cos(ref[:, 2]) * (
            pose[:, 1] - ref[:, 1]
        )
        final = np.hypot(*(pose[-1, :2] - ref[-1, :2]))
        record("figure_eight", name, "unicycle", result.t, lateral, final)

    eight_path = Polyline(eight.poses[::20, :2])
    cusp = three_point_turn_path()
    followers = {
        "segment": SegmentFollower,
        "pure_pursuit": PurePursuit,
        "stanley": Stanley,
        "rear_wheel": RearWheelFeedback,
    }
    cases = (
        ("figure_eight", eight_path, start8, eight_path.length / 30.0, 40.0, 0.05),
        ("cusp_path", cusp, np.array([0.0, 0.05, 0.0]), 0.3, 40.0, 0.5),
    )
    for reference, path, start, speed, horizon, bike_base in cases:
        for name, cls in followers.items():
            plants = (
                ("unicycle", Unicycle(), dict(output="velocity", wheel_base=0.1, limits=limits)),
                (
                    "bicycle",
                    RearWheelBicycle(wheel_base=bike_base, max_steering=math.radians(35.0)),
                    dict(
                        output="steering",
                        wheel_base=bike_base,
                        limits=SteeringLimits(math.radians(35.0), max_steering_rate=3.0),
                    ),
                ),
            )
            for plant_name, model, options in plants:
                law = cls(speed=speed, **options)
                result = run_closed_loop(law, model, start, path, horizon, dt)
                xy = result.poses[:, 0, :2]
                lateral = path.distance(xy)
                final = np.hypot(*(xy[-1] - path.points[-1]))
                record(reference, name, plant_name, result.t, lateral, final)
    return rows, traces


def _unicycle() -> Any:
    from wheelbase.models import Unicycle

    return Unicycle()


# --------------------------------------------------------------------------- dynamic plant
def velocity_torques(
    dynamics: Any,
    state: np.ndarray,
    command: np.ndarray,
    gains: tuple[float, float] = (30.0, 30.0),
    max_torque: float = math.inf,
) -> np.ndarray:
    """Wheel torques ``(..., 2)`` that make a dynamic robot follow ``(v, ω)`` commands.

    The torque layer between a kinematic controller and the dynamics: a computed-torque velocity
    loop. The desired body acceleration is a = (k_u·(v − u), 0, k_r·(ω − r)) and the torques are
    the inverse dynamics of :class:`wheelbase.dynamics.DiffDriveDynamics`, τ = M·a + C(V)·V
    mapped to the wheels by Wᵀ (document 000 §5.2), clipped to ``max_torque`` [N·m]. With an
    exact model each velocity error decays as e^(−k t).

    Parameters
    ----------
    dynamics : DiffDriveDynamics
        The robot's model.
    state : numpy.ndarray, shape (..., 6)
        (x, y, ψ, u, v, r).
    command : numpy.ndarray, shape (..., 2)
        (v [m/s], ω [rad/s]).
    gains : (float, float)
        k_u, k_r [1/s].
    max_torque : float
        Wheel torque limit [N·m].
    """
    velocity = state[..., 3:]
    accel = np.stack(
        [
            gains[0] * (command[..., 0] - velocity[..., 0]),
            np.zeros_like(command[..., 0]),
            gains[1] * (command[..., 1] - velocity[..., 2]),
        ],
        -1,
    )
    _force, torques = dynamics.inverse(velocity, accel)
    return np.clip(torques, -max_torque, max_torque)


def run_dynamic_closed_loop(
    controller: Controller,
    dynamics: Any,
    pose0: ArrayLike,
    reference: Any,
    t_end: float,
    dt: float,
    *,
    gains: tuple[float, float] = (30.0, 30.0),
    max_torque: float = math.inf,
    goal_tolerance: tuple[float, float] | None = None,
    rest_speed: float = 0.01,
) -> ClosedLoopResult:
    """:func:`run_closed_loop` with a dynamic plant: the RM100 of document 000 (or any
    :class:`~wheelbase.dynamics.DiffDriveDynamics`) through :func:`velocity_torques`.

    The robots start at rest; the plant is integrated with RK4 at ``dt`` (torques held over the
    step). ``commands`` records the kinematic commands. With ``goal_tolerance`` a robot has
    arrived when it is within the tolerance *and* nearly at rest (|u| ≤ ``rest_speed``,
    |r| ≤ 2·``rest_speed`` rad/s per m/s): a dynamic robot can cross the goal window at speed. An
    arrived robot is braked (command (0, 0) through the torque layer).

    Parameters
    ----------
    controller : Controller
        A (v, ω) controller.
    dynamics : DiffDriveDynamics
        The plant (e.g. :data:`wheelbase.dynamics.RM100`).
    pose0 : array_like, shape (3,) or (N, 3)
        Initial poses; the robots start at rest.
    reference : object
        Passed to the controller (a goal pose when ``goal_tolerance`` is given).
    t_end : float
        Duration [s].
    dt : float
        Control period and RK4 step [s].
    gains : (float, float)
        Velocity-loop gains k_u, k_r [1/s] of :func:`velocity_torques`.
    max_torque : float
        Wheel torque limit [N·m].
    goal_tolerance : (float, float), optional
        Position [m] and heading [rad] tolerance of arrival.
    rest_speed : float
        Speed [m/s] under which an arrived robot counts as at rest.
    """
    times = time_grid(t_end, dt)
    pose = as_float_array("pose0", pose0, 3, min_ndim=1, max_ndim=2).reshape(-1, 3)
    n = pose.shape[0]
    state = np.zeros((n, 6))
    state[:, :3] = pose
    goal = None
    if goal_tolerance is not None:
        goal = as_float_array("goal", reference, 3)
    controller.reset()
    poses = np.empty((times.size, n, 3))
    commands = np.zeros((times.size, n, 2))
    arrival = np.full(n, np.nan)
    poses[0] = pose
    last = times.size - 1
    for k in range(times.size - 1):
        t = float(times[k])
        if goal is not None:
            inside = _within(state[:, :3], goal, goal_tolerance[0], goal_tolerance[1])
            resting = (np.abs(state[:, 3]) <= rest_speed) & (np.abs(state[:, 5]) <= 2 * rest_speed)
            arrival = np.where(np.isnan(arrival) & inside & resting, t, arrival)
            if not np.any(np.isnan(arrival)):
                last = k
                break
        command = np.asarray(controller(t, state[:, :3], reference), float).reshape(n, 2)
        if goal is not None:
            command = np.where(np.isnan(arrival)[:, None], command, 0.0)
        torques = velocity_torques(dynamics, state, command, gains, max_torque)
        commands[k] = command
        h = float(times[k + 1] - t)
        k1 = dynamics.derivative(state, torques)
        k2 = dynamics.derivative(state + 0.5 * h * k1, torques)
        k3 = dynamics.derivative(state + 0.5 * h * k2, torques)
        k4 = dynamics.derivative(state + h * k3, torques)
        state = state + h / 6.0 * (k1 + 2 * k2 + 2 * k3 + k4)
        state[:, 2] = np.angle(np.exp(1j * state[:, 2]))
        poses[k + 1] = state[:, :3]
    commands[last] = commands[last - 1] if last > 0 else commands[0]
    return ClosedLoopResult(
        t=times[: last + 1],
        poses=poses[: last + 1],
        commands=commands[: last + 1],
        command_names=VELOCITY_COMMAND,
        arrival_time=arrival,
    )


def dynamic_benchmark(dt: float = 0.01) -> dict[str, Any]:
    """The pose benchmark (laws 1–6, 128 starts) and the figure-eight trackers on the RM100.

    Same limits and tolerances as :func:`pose_benchmark`; the torque layer is
    :func:`velocity_torques` with k_u = k_r = 30 1/s and no torque limit (with 10 1/s the
    velocity lag makes the polar law miss the final heading: 5 % success).

    Returns
    -------
    dict
        ``pose``: per law ``success_rate``, ``mean_time_s``, ``mean_path_length_m``,
        ``reversals``; ``tracking``: per tracker ``rms_lateral_error_m`` and
        ``max_lateral_error_m`` after 5 s on the figure-eight.
    """
    from wheelbase.control.base import VelocityLimits
    from wheelbase.control.tracking import Kanayama, LinearTracker
    from wheelbase.dynamics import RM100

    limits = VelocityLimits(*BENCHMARK_LIMITS)
    starts = pose_benchmark_starts()
    goal = np.zeros(3)
    tolerance = (0.01, math.radians(1.0))
    pose_table: dict[str, dict[str, float]] = {}
    for name in POSE_LAWS:
        result = run_dynamic_closed_loop(
            make_pose_law(name, limits), RM100, starts, goal, 60.0, dt, goal_tolerance=tolerance
        )
        ok = result.arrived
        pose_table[name] = {
            "success_rate": float(np.mean(ok)),
            "mean_time_s": float(np.mean(result.arrival_time[ok])) if ok.any() else math.nan,
            "mean_path_length_m": float(np.mean(result.path_length[ok])) if ok.any() else math.nan,
            "reversals": float(np.mean(result.reversals)),
        }
    eight = figure_eight_reference(30.0, dt)
    tracking: dict[str, dict[str, float]] = {}
    for name, law in (
        ("linear", LinearTracker(limits=limits)),
        ("kanayama", Kanayama(limits=limits)),
    ):
        result = run_dynamic_closed_loop(law, RM100, [1.1, 0.8, 0.0], eight, 30.0, dt)
        pose, ref = result.poses[:, 0], eight.poses[: result.t.size]
        lateral = -np.sin(ref[:, 2]) * (pose[:, 0] - ref[:, 0]) + np.cos(ref[:, 2]) * (
            pose[:, 1] - ref[:, 1]
        )
        late = result.t >= 5.0
        tracking[name] = {
            "rms_lateral_error_m": float(np.sqrt(np.mean(lateral[late] ** 2))),
            "max_lateral_error_m": float(np.max(np.abs(lateral[late]))),
        }
    return {"pose": pose_table, "tracking": tracking}
