"""Benchmark harness of the controllers: the cases, not the library (``src/`` never imports it).

- the 128-case pose benchmark (:func:`pose_benchmark`): every pose law of document 002 from 128
  starts on a 2 m circle to the origin, on a unicycle;
- the tracking benchmark (:func:`tracking_benchmark`): the trackers (law 8) on a figure-eight and
  the path followers (law 7) on the figure-eight and a path with two cusps;
- the same on the dynamic RM100 of document 000 (:func:`dynamic_benchmark`);
- their reference generators (:func:`figure_eight_reference`, :func:`three_point_turn_path`).

Every run goes through the one engine (:func:`wheelbase.sim.closed_loop`): arrival is the
engine's rule (estimate within tolerance, at rest), the same as ``wheelbase run``. Used by
``benchmarks/control.py``, ``benchmarks/mppi.py``, the examples and the tests (which put this
folder on ``sys.path``).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from wheelbase._validate import positive
from wheelbase.control import POSE_LAWS, TwistTorqueLoop, make_pose_law
from wheelbase.errors import ConfigError
from wheelbase.integrate import time_grid
from wheelbase.sim import Log, closed_loop, status_code

__all__ = [
    "BENCHMARK_LIMITS",
    "dynamic_benchmark",
    "evaluate_pose_law",
    "figure_eight_reference",
    "pose_benchmark",
    "pose_benchmark_starts",
    "three_point_turn_path",
    "tracking_benchmark",
]

BENCHMARK_LIMITS = (0.5, 1.5)
"""|v| [m/s] and |ω| [rad/s] limits of the benchmarks."""


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
    controller: Any,
    plant: Any,
    starts: ArrayLike,
    goal: ArrayLike = (0.0, 0.0, 0.0),
    *,
    t_end: float = 60.0,
    dt: float = 0.01,
    tolerance: tuple[float, float] = (0.01, math.radians(1.0)),
) -> tuple[dict[str, float], Log]:
    """Run a pose law from every start to ``goal`` and summarise it.

    Parameters
    ----------
    controller : Controller
        A pose law (goal-pose reference), or a torque loop around one on a dynamic plant.
    plant : KinematicModel or DiffDriveDynamics
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
        Position [m] and heading [rad] tolerance of arrival.

    Returns
    -------
    metrics : dict
        ``success_rate`` (arrived by the engine's rule), ``mean_time_s`` and
        ``mean_path_length_m`` (over the arrived runs; NaN if none), ``reversals`` (mean
        direction changes per run), ``position_success_rate`` (within the position tolerance at
        the end, whatever the heading), ``max_final_position_error_m`` and
        ``max_final_heading_error_deg``.
    log : Log
        The runs.
    """
    log = closed_loop(controller, plant, starts, goal, t_end, dt, goal=goal, tolerance=tolerance)
    rows = log.metrics()
    ok = log.status == status_code("arrived")
    travelled = np.array([row["distance_travelled_m"] for row in rows])
    position = np.array([row["final_position_error_true_m"] for row in rows])
    heading = np.array([row["final_heading_error_true_deg"] for row in rows])
    metrics = {
        "success_rate": float(np.mean(ok)),
        "mean_time_s": float(np.mean(log.end_time[ok])) if ok.any() else math.nan,
        "mean_path_length_m": float(np.mean(travelled[ok])) if ok.any() else math.nan,
        "reversals": float(np.mean([row["reversals"] for row in rows])),
        "position_success_rate": float(np.mean(position <= tolerance[0])),
        "max_final_position_error_m": float(np.max(position)),
        "max_final_heading_error_deg": float(np.max(heading)),
    }
    return metrics, log


def pose_benchmark(
    laws: tuple[str, ...] = POSE_LAWS,
    *,
    starts: ArrayLike | None = None,
    t_end: float = 60.0,
    dt: float = 0.01,
) -> tuple[dict[str, dict[str, float]], dict[str, Log]]:
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

    Returns a :class:`wheelbase.models.PoseTrajectory` on the grid 0, dt, …, T, built from the
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
    from wheelbase.planning import PlannedPath

    r = positive("radius", radius, "m")
    n = max(4, math.ceil(0.5 * math.pi * r / positive("step", step, "m")) + 1)
    a = np.linspace(-0.5 * np.pi, 0.0, n)
    forward = np.stack([r * np.cos(a), r + r * np.sin(a)], -1)
    b = np.linspace(np.pi, 1.5 * np.pi, n)[1:]
    reverse = np.stack([2 * r + r * np.cos(b), r + r * np.sin(b)], -1)
    m = max(2, math.ceil(4.0 / 3.0 * r / step))
    last = np.stack([np.linspace(2 * r, 2 * r / 3, m + 1)[1:], np.zeros(m)], -1)
    directions = np.r_[np.ones(n - 1), -np.ones(n - 1), np.ones(m)]
    return PlannedPath.from_points(np.concatenate([forward, reverse, last]), directions)


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
        PurePursuit,
        RearWheelFeedback,
        SegmentFollower,
        Stanley,
    )
    from wheelbase.control.tracking import Kanayama, LinearTracker
    from wheelbase.models import RearWheelBicycle, Unicycle
    from wheelbase.planning import PlannedPath

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
        result = closed_loop(law, Unicycle(), start8, eight, 30.0, dt)
        pose, ref = result.true_pose[0], eight.poses[: result.t.size]
        lateral = -np.sin(ref[:, 2]) * (pose[:, 0] - ref[:, 0]) + np.cos(ref[:, 2]) * (
            pose[:, 1] - ref[:, 1]
        )
        final = np.hypot(*(pose[-1, :2] - ref[-1, :2]))
        record("figure_eight", name, "unicycle", result.t, lateral, final)

    eight_path = PlannedPath.from_points(eight.poses[::20, :2])
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
                result = closed_loop(law, model, start, path, horizon, dt)
                xy = result.true_pose[0, :, :2]
                lateral = path.distance(xy)
                final = np.hypot(*(xy[-1] - path.points[-1]))
                record(reference, name, plant_name, result.t, lateral, final)
    return rows, traces


def dynamic_benchmark(dt: float = 0.01) -> dict[str, Any]:
    """The pose benchmark (laws 1–6, 128 starts) and the figure-eight trackers on the RM100.

    Same limits and tolerances as :func:`pose_benchmark`; the torque layer is
    :class:`~wheelbase.control.TwistTorqueLoop` with k = 30 1/s and no torque limit (with 10 1/s the
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
        loop = TwistTorqueLoop(make_pose_law(name, limits), RM100, bandwidth=30.0)
        metrics, _ = evaluate_pose_law(loop, RM100, starts, goal, dt=dt, tolerance=tolerance)
        pose_table[name] = {
            key: metrics[key]
            for key in ("success_rate", "mean_time_s", "mean_path_length_m", "reversals")
        }
    eight = figure_eight_reference(30.0, dt)
    tracking: dict[str, dict[str, float]] = {}
    for name, law in (
        ("linear", LinearTracker(limits=limits)),
        ("kanayama", Kanayama(limits=limits)),
    ):
        loop = TwistTorqueLoop(law, RM100, bandwidth=30.0)
        result = closed_loop(loop, RM100, [1.1, 0.8, 0.0], eight, 30.0, dt)
        pose, ref = result.true_pose[0], eight.poses[: result.t.size]
        lateral = -np.sin(ref[:, 2]) * (pose[:, 0] - ref[:, 0]) + np.cos(ref[:, 2]) * (
            pose[:, 1] - ref[:, 1]
        )
        late = result.t >= 5.0
        tracking[name] = {
            "rms_lateral_error_m": float(np.sqrt(np.mean(lateral[late] ** 2))),
            "max_lateral_error_m": float(np.max(np.abs(lateral[late]))),
        }
    return {"pose": pose_table, "tracking": tracking}
