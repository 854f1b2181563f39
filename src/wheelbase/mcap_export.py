"""Runs as MCAP files that Foxglove opens: the map, the plan, the poses, the frame tree, markers
and every logged signal, stamped with simulated time.

What a file holds (one robot; with N robots each robot's topics and frames get a ``/robotI``
prefix and ``robotI/`` frame names):

========================  ============================  ===========================================
topic                     schema                        content
========================  ============================  ===========================================
``/map``                  ``foxglove.Grid``             the occupancy grid (uint8 ``occupancy``:
                                                        0 free, 100 occupied) in frame ``map``, t=0
``/map/obstacles``        ``foxglove.SceneUpdate``      a polygon world's polygons (holes too),
                                                        discs and bounds as line loops, t=0
``/plan``                 ``foxglove.PosesInFrame``     the planned path in ``map``, t=0
``/pose/true``            ``foxglove.PoseInFrame``      the true pose in ``map``, every row
``/pose/estimated``       ``foxglove.PoseInFrame``      the estimator's pose in ``map``, every row
``/tf``                   ``foxglove.FrameTransforms``  the estimator's tree (REP 105): ``map →
                                                        odom`` (its correction, estimate ∘
                                                        odometry⁻¹; the identity without a
                                                        filter) and ``odom → base_link`` (the
                                                        wheel odometry), every row
``/tf_true``              ``foxglove.FrameTransforms``  ``map → base_link_true``: the true pose,
                                                        every row
``/markers``              ``foxglove.SceneUpdate``      the footprint (frame ``base_link``) and the
                                                        goals (frame ``map``), t=0
``/scan``                 ``foxglove.LaserScan``        the lidar's scans (frame ``base_link``, the
                                                        scanner at its mount), at the rows where
                                                        they were taken, when the log kept them
``/particles``            ``foxglove.PosesInFrame``     a particle filter's particles in ``map``,
                                                        at the rows the log kept them (AMCL)
``/world/obstacles``      ``foxglove.SceneUpdate``      a world's obstacles off the map, t=0
``/world/agents``         ``foxglove.SceneUpdate``      its agents (discs and velocity arrows),
                                                        every 0.1 s
``/costmap``              ``foxglove.Grid``             what the robot believes (the map and the
                                                        cells its lidar marked: 100), once a second
``/tracks``               ``foxglove.SceneUpdate``      its confirmed tracks, once a second
``/command``              JSON                          the command columns (``command_names``)
``/twist``                JSON                          true body twist ``u``, ``v``, ``r``
``/wheel_rates``          JSON                          ``left``, ``right`` [rad/s]
``/torques``              JSON                          ``left``, ``right`` [N·m] (dynamic plant)
``/metrics``              JSON                          the run's metrics, at its last row
========================  ============================  ===========================================

So ``map → odom → base_link`` composes to the estimate, as REP 105 and Nav2 publish it: the odom
frame jumps against the map when a filter corrects the odometry; the truth is on its own topics
(``/pose/true``, ``/tf_true``), never in the robot's tree. Times are simulated time from t = 0
(``log_time`` and every message's ``timestamp``, in integer nanoseconds). Poses are written as
float64 positions and unit quaternions about z (θ = 2·atan2(q_z, q_w)).

The Foxglove protobuf schemas come from ``foxglove-schemas-protobuf`` and the file is written by
``mcap``; both are the optional extra ``wheelbase[foxglove]``.
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from wheelbase.errors import DependencyError, InputError
from wheelbase.geometry import compose, inverse_pose
from wheelbase.sim import STATUSES, Log

__all__ = [
    "MCAP_TOPICS",
    "require_foxglove",
    "write_log_mcap",
    "write_map_growth_mcap",
    "write_mcap",
]

MCAP_TOPICS = (
    "/map",
    "/map/obstacles",
    "/plan",
    "/pose/true",
    "/pose/estimated",
    "/tf",
    "/tf_true",
    "/markers",
    "/scan",
    "/particles",
    "/world/obstacles",
    "/world/agents",
    "/costmap",
    "/tracks",
    "/command",
    "/twist",
    "/wheel_rates",
    "/torques",
    "/metrics",
)
"""Topics an MCAP file of one robot can hold (``/torques`` on a dynamic plant only,
``/map/obstacles`` for a :class:`~wheelbase.planning.PolygonWorld`, ``/scan`` with a lidar,
``/particles`` with a particle filter, the ``/world`` topics, ``/costmap`` and ``/tracks``
for a run among obstacles the map does not show)."""

_EXTRA = "MCAP export needs the optional extra: pip install 'wheelbase[foxglove]'"


def require_foxglove() -> dict[str, Any]:
    """The Foxglove protobuf message classes and the MCAP writer, by name.

    Raises
    ------
    DependencyError
        The ``wheelbase[foxglove]`` extra (``mcap``, ``mcap-protobuf-support``,
        ``foxglove-schemas-protobuf``) is not installed.
    """
    try:
        from foxglove_schemas_protobuf import (
            Color_pb2,
            FrameTransform_pb2,
            FrameTransforms_pb2,
            Grid_pb2,
            LaserScan_pb2,
            LinePrimitive_pb2,
            PackedElementField_pb2,
            Point3_pb2,
            Pose_pb2,
            PoseInFrame_pb2,
            PosesInFrame_pb2,
            Quaternion_pb2,
            SceneEntity_pb2,
            SceneUpdate_pb2,
            Vector2_pb2,
            Vector3_pb2,
        )
        from mcap.writer import CompressionType, Writer
        from mcap_protobuf.schema import register_schema
    except ImportError as error:
        raise DependencyError(f"{_EXTRA} ({error})") from None
    return {
        "Color": Color_pb2.Color,
        "FrameTransform": FrameTransform_pb2.FrameTransform,
        "FrameTransforms": FrameTransforms_pb2.FrameTransforms,
        "Grid": Grid_pb2.Grid,
        "LaserScan": LaserScan_pb2.LaserScan,
        "LinePrimitive": LinePrimitive_pb2.LinePrimitive,
        "PackedElementField": PackedElementField_pb2.PackedElementField,
        "Point3": Point3_pb2.Point3,
        "Pose": Pose_pb2.Pose,
        "PoseInFrame": PoseInFrame_pb2.PoseInFrame,
        "PosesInFrame": PosesInFrame_pb2.PosesInFrame,
        "Quaternion": Quaternion_pb2.Quaternion,
        "SceneEntity": SceneEntity_pb2.SceneEntity,
        "SceneUpdate": SceneUpdate_pb2.SceneUpdate,
        "Vector2": Vector2_pb2.Vector2,
        "Vector3": Vector3_pb2.Vector3,
        "CompressionType": CompressionType,
        "Writer": Writer,
        "register_schema": register_schema,
    }


def _nanoseconds(t: float) -> int:
    return round(t * 1e9)


class _File:
    """One MCAP writer with channels registered on first use (private)."""

    def __init__(self, handle: Any, pb: dict[str, Any]) -> None:
        self.pb = pb
        self.writer = pb["Writer"](handle, compression=pb["CompressionType"].ZSTD)
        self.writer.start(profile="", library="wheelbase")
        self.channels: dict[str, int] = {}
        self.schemas: dict[str, int] = {}
        self.sequence: dict[str, int] = {}

    def _channel(self, topic: str, encoding: str, schema_id: int) -> int:
        if topic not in self.channels:
            self.channels[topic] = self.writer.register_channel(topic, encoding, schema_id)
            self.sequence[topic] = 0
        return self.channels[topic]

    def _write(self, channel: int, topic: str, t: float, data: bytes) -> None:
        stamp = _nanoseconds(t)
        self.writer.add_message(channel, stamp, data, stamp, sequence=self.sequence[topic])
        self.sequence[topic] += 1

    def protobuf(self, topic: str, t: float, message: Any) -> None:
        name = type(message).DESCRIPTOR.full_name
        if name not in self.schemas:
            self.schemas[name] = self.pb["register_schema"](self.writer, type(message))
        channel = self._channel(topic, "protobuf", self.schemas[name])
        self._write(channel, topic, t, message.SerializeToString())

    def json(self, topic: str, t: float, payload: dict[str, Any], properties: dict) -> None:
        if topic not in self.channels:
            schema = {"type": "object", "properties": properties}
            schema_id = self.writer.register_schema(
                topic.strip("/").replace("/", "."), "jsonschema", json.dumps(schema).encode()
            )
            self._channel(topic, "json", schema_id)
        self._write(self.channels[topic], topic, t, json.dumps(payload).encode())

    def finish(self) -> None:
        self.writer.finish()


def _stamp(message: Any, t: float) -> None:
    ns = _nanoseconds(t)
    message.timestamp.seconds, message.timestamp.nanos = divmod(ns, 1_000_000_000)


def _pose(pb: dict[str, Any], pose: np.ndarray) -> Any:
    half = 0.5 * float(pose[2])
    return pb["Pose"](
        position=pb["Vector3"](x=float(pose[0]), y=float(pose[1]), z=0.0),
        orientation=pb["Quaternion"](x=0.0, y=0.0, z=math.sin(half), w=math.cos(half)),
    )


def _transform(pb: dict[str, Any], t: float, parent: str, child: str, pose: np.ndarray) -> Any:
    pose_message = _pose(pb, pose)
    message = pb["FrameTransform"](
        parent_frame_id=parent,
        child_frame_id=child,
        translation=pose_message.position,
        rotation=pose_message.orientation,
    )
    _stamp(message, t)
    return message


def _grid(pb: dict[str, Any], grid: Any) -> Any:
    cols = grid.occupied.shape[1]
    message = pb["Grid"](
        frame_id="map",
        pose=_pose(pb, np.array([grid.origin[0], grid.origin[1], 0.0])),
        column_count=cols,
        cell_size=pb["Vector2"](x=float(grid.resolution), y=float(grid.resolution)),
        row_stride=cols,
        cell_stride=1,
        fields=[
            pb["PackedElementField"](
                name="occupancy", offset=0, type=pb["PackedElementField"].NumericType.UINT8
            )
        ],
        # Row 0 is the lowest y, as in the grid: Foxglove lays rows out along +y of the pose.
        data=(np.asarray(grid.occupied, dtype=np.uint8) * 100).tobytes(),
    )
    _stamp(message, 0.0)
    return message


def _loop(pb: dict[str, Any], points: np.ndarray, color: Any) -> Any:
    return pb["LinePrimitive"](
        type=pb["LinePrimitive"].Type.LINE_LOOP,
        pose=_pose(pb, np.zeros(3)),
        thickness=0.03,
        points=[pb["Point3"](x=float(x), y=float(y), z=0.0) for x, y in points],
        color=color,
    )


def _obstacles(pb: dict[str, Any], world: Any) -> Any:
    """A polygon world's rings, discs (64-gons) and bounds as line loops in ``map``."""
    entity = pb["SceneEntity"](frame_id="map", id="obstacles")
    dark = pb["Color"](r=0.2, g=0.2, b=0.2, a=1.0)
    for exterior, holes in world.polygons:
        for ring in (exterior, *holes):
            entity.lines.append(_loop(pb, np.asarray(ring), dark))
    angle = np.linspace(0.0, 2.0 * math.pi, 64, endpoint=False)
    for x, y, r in world.discs:
        circle = np.column_stack([x + r * np.cos(angle), y + r * np.sin(angle)])
        entity.lines.append(_loop(pb, circle, dark))
    x0, x1, y0, y1 = world.bounds
    box = np.array([[x0, y0], [x1, y0], [x1, y1], [x0, y1]])
    entity.lines.append(_loop(pb, box, pb["Color"](r=0.5, g=0.5, b=0.5, a=1.0)))
    _stamp(entity, 0.0)
    return pb["SceneUpdate"](entities=[entity])


_CIRCLE = np.linspace(0.0, 2.0 * math.pi, 24, endpoint=False)
AGENT_PERIOD = 0.1
"""Seconds between two ``/world/agents`` updates."""


def _discs(pb: dict[str, Any], t: float, name: str, rows: np.ndarray, color: Any) -> Any:
    """Discs (x, y, v_x, v_y, radius) as line loops with velocity arrows, one entity each."""
    entities = []
    for j, (x, y, vx, vy, r) in enumerate(np.asarray(rows, dtype=np.float64)):
        entity = pb["SceneEntity"](frame_id="map", id=f"{name}{j}")
        circle = np.column_stack([x + r * np.cos(_CIRCLE), y + r * np.sin(_CIRCLE)])
        entity.lines.append(_loop(pb, circle, color))
        speed = math.hypot(vx, vy)
        if speed > 1e-6:
            arrow = entity.arrows.add()
            arrow.pose.CopyFrom(_pose(pb, np.array([x, y, math.atan2(vy, vx)])))
            arrow.shaft_length, arrow.shaft_diameter = speed, 0.03
            arrow.head_length, arrow.head_diameter = 0.1, 0.08
            arrow.color.CopyFrom(color)
        _stamp(entity, t)
        entities.append(entity)
    return pb["SceneUpdate"](entities=entities)


def _world_obstacles(pb: dict[str, Any], world: Any) -> Any:
    """A world's static obstacles off the map as line loops in ``map``."""
    entity = pb["SceneEntity"](frame_id="map", id="world_obstacles")
    red = pb["Color"](r=0.55, g=0.0, b=0.0, a=1.0)
    for ring in world.obstacles.polygons:
        entity.lines.append(_loop(pb, np.asarray(ring), red))
    for x, y, r in world.obstacles.discs:
        circle = np.column_stack([x + r * np.cos(_CIRCLE), y + r * np.sin(_CIRCLE)])
        entity.lines.append(_loop(pb, circle, red))
    _stamp(entity, 0.0)
    return pb["SceneUpdate"](entities=[entity])


def _belief(pb: dict[str, Any], grid: Any, marks: np.ndarray, t: float) -> Any:
    """The map with the cells the lidar marked, as a ``foxglove.Grid``."""
    occupied = np.array(grid.occupied, dtype=bool)
    if len(marks):
        cells = grid.world_to_cell(np.asarray(marks, dtype=np.float64))
        rows, cols = occupied.shape
        ok = (cells[:, 0] >= 0) & (cells[:, 0] < rows) & (cells[:, 1] >= 0) & (cells[:, 1] < cols)
        occupied[cells[ok, 0], cells[ok, 1]] = True
    message = _grid(pb, type(grid)(occupied, grid.resolution, grid.origin))
    _stamp(message, t)
    return message


def _markers(pb: dict[str, Any], footprint: np.ndarray | None, goals: np.ndarray, base: str) -> Any:
    entities = []
    if footprint is not None:
        entity = pb["SceneEntity"](frame_id=base, id="footprint", frame_locked=True)
        entity.lines.append(_loop(pb, footprint, pb["Color"](r=0.12, g=0.47, b=0.71, a=1.0)))
        entities.append(entity)
    for k, goal in enumerate(goals):
        entity = pb["SceneEntity"](frame_id="map", id=f"goal{k}")
        arrow = entity.arrows.add()
        arrow.pose.CopyFrom(_pose(pb, goal))
        arrow.shaft_length, arrow.shaft_diameter = 0.3, 0.05
        arrow.head_length, arrow.head_diameter = 0.12, 0.12
        arrow.color.CopyFrom(pb["Color"](r=0.84, g=0.15, b=0.16, a=1.0))
        entities.append(entity)
    for entity in entities:
        _stamp(entity, 0.0)
    return pb["SceneUpdate"](entities=entities)


def _numbers(names: tuple[str, ...]) -> dict[str, dict[str, str]]:
    return {name: {"type": "number"} for name in names}


def _metric_value(value: Any) -> Any:
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, float) and not math.isfinite(value):
        return None  # JSON has no inf or NaN
    if isinstance(value, dict):
        return {key: _metric_value(item) for key, item in value.items()}
    return value


def write_log_mcap(
    log: Log,
    path: str | Path,
    *,
    grid: Any = None,
    plan: ArrayLike | None = None,
    footprint: ArrayLike | None = None,
    goals: ArrayLike | None = None,
    metrics: list[dict[str, Any]] | dict[str, Any] | None = None,
    overwrite: bool = False,
    lidar: Any = None,
    world: Any = None,
) -> Path:
    """Write a closed-loop :class:`~wheelbase.sim.Log` (one robot or N) to an MCAP file.

    Parameters
    ----------
    log : Log
        The record; each robot's own rows are written (``log.length``).
    path : str or Path
        Output file (``.mcap``).
    grid : OccupancyGrid or PolygonWorld, optional
        The map, written once: a grid to ``/map``; a polygon world's obstacles to
        ``/map/obstacles`` (and its grid, if it has one, to ``/map``).
    plan : array_like, shape (M, 3), optional
        Planned poses [m, m, rad], written once to ``/plan``.
    footprint : array_like, shape (K, 2), optional
        Footprint outline in the body frame [m], drawn in ``base_link``.
    goals : array_like, shape (3,) or (G, 3), optional
        Goal poses drawn as arrows (default: ``log.goal``).
    metrics : dict or list of dict, optional
        The metrics of the robot (a list: one per robot), written to ``/metrics`` at its last
        row (default: :meth:`Log.metrics`).
    overwrite : bool
        Replace an existing file (default: raise FileExistsError).
    lidar : Lidar, optional
        The lidar of ``log.scans``: its scans go to ``/scan`` (without it they are left out).
    world : World, optional
        The world beyond the map: its obstacles to ``/world/obstacles`` and, when the log kept
        them, its agents to ``/world/agents`` (the first world of the log).

    Returns
    -------
    Path
        The file written.

    Raises
    ------
    DependencyError
        ``mcap`` or ``foxglove-schemas-protobuf`` is missing (``pip install
        'wheelbase[foxglove]'``).
    """
    pb = require_foxglove()
    path = Path(path)
    if path.exists() and not overwrite:
        raise FileExistsError(f"{path} exists; pass overwrite=True to replace it")
    n = log.n_robots
    if metrics is None:
        metrics = log.metrics()
    elif isinstance(metrics, dict):
        metrics = [metrics]
    if len(metrics) != n:
        raise InputError(f"metrics must hold one dict per robot ({n}); got {len(metrics)}")
    if goals is None:
        goal_rows = [None if log.goal is None else log.goal[i : i + 1] for i in range(n)]
    else:
        shared = np.asarray(goals, dtype=np.float64).reshape(-1, 3)
        goal_rows = [shared] * n
    polygon = None if footprint is None else np.asarray(footprint, dtype=np.float64)
    if polygon is not None and (polygon.ndim != 2 or polygon.shape[1] != 2):
        raise InputError(f"footprint must have shape (K, 2) (got {polygon.shape})")
    plan_poses = None if plan is None else np.asarray(plan, dtype=np.float64).reshape(-1, 3)

    with path.open("wb") as handle:
        out = _File(handle, pb)
        if grid is not None and hasattr(grid, "polygons"):  # a PolygonWorld
            out.protobuf("/map/obstacles", 0.0, _obstacles(pb, grid))
            grid = grid.grid
        if grid is not None:
            out.protobuf("/map", 0.0, _grid(pb, grid))
        if world is not None:
            out.protobuf("/world/obstacles", 0.0, _world_obstacles(pb, world))
        if log.agents is not None and log.agents.shape[2]:
            radius = (np.full(log.agents.shape[2], 0.3) if world is None
                      else np.asarray(world.agent_radius, dtype=np.float64))  # fmt: skip
            brown = pb["Color"](r=0.55, g=0.34, b=0.29, a=1.0)
            last = -math.inf
            for k, t in enumerate(log.t):
                if t - last < AGENT_PERIOD - 1e-9:
                    continue
                last = float(t)
                rows = np.column_stack([log.agents[0, k], radius])
                out.protobuf("/world/agents", float(t), _discs(pb, float(t), "agent", rows, brown))
        if plan_poses is not None:
            message = pb["PosesInFrame"](
                frame_id="map", poses=[_pose(pb, pose) for pose in plan_poses]
            )
            _stamp(message, 0.0)
            out.protobuf("/plan", 0.0, message)
        for i in range(n):
            prefix = "" if n == 1 else f"/robot{i}"
            frames = ("odom", "base_link") if n == 1 else (f"robot{i}/odom", f"robot{i}/base_link")
            goal = goal_rows[i]
            out.protobuf(
                f"{prefix}/markers",
                0.0,
                _markers(pb, polygon, np.zeros((0, 3)) if goal is None else goal, frames[1]),
            )
            _write_robot(out, log, i, prefix, frames, lidar)
            belief_grid = grid if grid is not None and hasattr(grid, "occupied") else None
            cyan = pb["Color"](r=0.09, g=0.75, b=0.81, a=1.0)
            for (robot, k), seen in sorted(log.perceived.items()):
                if robot != i:
                    continue
                t = float(log.t[k])
                if belief_grid is not None:
                    out.protobuf(f"{prefix}/costmap", t, _belief(pb, belief_grid, seen["marks"], t))
                out.protobuf(f"{prefix}/tracks", t, _discs(pb, t, "track", seen["tracks"], cyan))
            end = float(log.t[int(log.length[i]) - 1])
            row = {key: _metric_value(value) for key, value in metrics[i].items()}
            row.setdefault("status", STATUSES[int(log.status[i])])
            out.json(f"{prefix}/metrics", end, row, {})
        out.finish()
    return path


def _write_robot(
    out: _File, log: Log, i: int, prefix: str, frames: tuple[str, str], lidar: Any
) -> None:
    pb = out.pb
    scans = {} if lidar is None else {row: r for (robot, row), r in log.scans.items() if robot == i}
    if scans:
        angles = lidar.beam_angles
        mount = np.asarray(lidar.mount, dtype=np.float64)
    clouds = {row: cloud for (robot, row), cloud in log.particles.items() if robot == i}
    rows = int(log.length[i])
    true, estimate = log.true_pose[i, :rows], log.estimated_pose[i, :rows]
    # REP 105: odom → base_link is the wheel odometry, map → odom the estimator's correction
    # (estimate ∘ odometry⁻¹); without a filter the odometry is the estimate (identity).
    odom = log.extras["odom_pose"][i, :rows] if "odom_pose" in log.extras else estimate
    correction = compose(estimate, inverse_pose(odom))
    command_names = tuple(log.command_names)
    twist_names, wheel_names = ("u", "v", "r"), ("left", "right")
    for k in range(rows):
        t = float(log.t[k])
        for topic, pose in (("/pose/true", true[k]), ("/pose/estimated", estimate[k])):
            message = pb["PoseInFrame"](frame_id="map", pose=_pose(pb, pose))
            _stamp(message, t)
            out.protobuf(prefix + topic, t, message)
        tf = pb["FrameTransforms"](
            transforms=[
                _transform(pb, t, "map", frames[0], correction[k]),
                _transform(pb, t, frames[0], frames[1], odom[k]),
            ]
        )
        out.protobuf(prefix + "/tf", t, tf)
        truth = pb["FrameTransforms"](
            transforms=[_transform(pb, t, "map", frames[1] + "_true", true[k])]
        )
        out.protobuf(prefix + "/tf_true", t, truth)
        if k in scans:
            scan = pb["LaserScan"](
                frame_id=frames[1], pose=_pose(pb, mount), start_angle=float(angles[0]),
                end_angle=float(angles[-1]), ranges=[float(r) for r in scans[k]],
            )  # fmt: skip
            _stamp(scan, t)
            out.protobuf(prefix + "/scan", t, scan)
        if k in clouds:
            cloud = pb["PosesInFrame"](
                frame_id="map", poses=[_pose(pb, pose) for pose in np.asarray(clouds[k])[:, :3]]
            )
            _stamp(cloud, t)
            out.protobuf(prefix + "/particles", t, cloud)
        signals = [
            ("/command", command_names, log.command[i, k]),
            ("/twist", twist_names, log.twist[i, k]),
            ("/wheel_rates", wheel_names, log.wheel_rates[i, k]),
        ]
        if log.torques is not None:
            signals.append(("/torques", wheel_names, log.torques[i, k]))
        for topic, names, values in signals:
            payload = {"t": t, **{name: float(v) for name, v in zip(names, values, strict=True)}}
            out.json(prefix + topic, t, payload, _numbers(("t", *names)))


def write_mcap(result: Any, path: str | Path, *, overwrite: bool = False) -> Path:
    """Write a scenario run (:func:`wheelbase.run`'s result) to an MCAP file for Foxglove.

    The map, the plan, the footprint, every goal of the scenario, the log and the run's
    metrics (module docstring for the topics).

    Parameters
    ----------
    result : RunResult
        The run.
    path : str or Path
        Output file, conventionally ``run.mcap``.
    overwrite : bool
        Replace an existing file (default: raise FileExistsError).

    Returns
    -------
    Path
        The file written.

    Raises
    ------
    InputError
        The run has no log (its planning failed).
    DependencyError
        The ``wheelbase[foxglove]`` extra is missing.
    """
    if result.log is None:
        raise InputError(
            f"no run to export: {result.metrics.get('message', 'planning failed')} "
            "(the result has no log)"
        )
    goals = np.array(
        [[x, y, math.radians(heading)] for x, y, heading in result.scenario.goals],
        dtype=np.float64,
    )
    return write_log_mcap(
        result.log,
        path,
        grid=result.grid,
        plan=None if result.plan is None else result.plan.poses,
        footprint=result.footprint_polygon,
        goals=goals,
        metrics=result.metrics,
        overwrite=overwrite,
        lidar=None if result.sensors is None else result.sensors.lidar,
        world=getattr(result, "world", None),
    )


def write_map_growth_mcap(
    frames: list[tuple[float, Any, np.ndarray]],
    path: str | Path,
    *,
    overwrite: bool = False,
) -> Path:
    """Write a map as it grows (SLAM) to an MCAP file: ``/map`` (``foxglove.Grid``, 0 free,
    100 occupied; unknown cells 50 when the grid has an unknown mask) and ``/path``
    (``foxglove.PosesInFrame``, the trajectory estimated so far) at each frame's time, and
    ``/pose/estimated`` at its last pose.

    Parameters
    ----------
    frames : list of tuple
        ``(t [s], OccupancyGrid, poses (T, 3))`` in time order.
    path : str or Path
        Output file.
    overwrite : bool
        Replace an existing file (default: raise FileExistsError).

    Returns
    -------
    Path
    """
    pb = require_foxglove()
    path = Path(path)
    if path.exists() and not overwrite:
        raise FileExistsError(f"{path} exists; pass overwrite=True to replace it")
    with path.open("wb") as handle:
        out = _File(handle, pb)
        for t, grid, poses in frames:
            message = _grid(pb, grid)
            if grid.unknown is not None:
                cells = np.where(grid.occupied & ~grid.unknown, 100, 0).astype(np.uint8)
                cells[grid.unknown] = 50
                message.data = cells.tobytes()
            _stamp(message, t)
            out.protobuf("/map", t, message)
            trail = pb["PosesInFrame"](frame_id="map", poses=[_pose(pb, q) for q in poses])
            _stamp(trail, t)
            out.protobuf("/path", t, trail)
            if len(poses):
                pose = pb["PoseInFrame"](frame_id="map", pose=_pose(pb, poses[-1]))
                _stamp(pose, t)
                out.protobuf("/pose/estimated", t, pose)
        out.finish()
    return path
