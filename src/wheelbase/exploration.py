"""Frontier-based exploration (Yamauchi 1997; Nav2's explore_lite): the robot maps a world it
has no map of, with lidar SLAM, and saves the map.

An exploration scenario is a scenario (:mod:`wheelbase.scenario`) with ``map: unknown``, the
true world in ``world: {map: NAME}`` (a bundled map or a map file, seen only through the
lidar), no goal, and an optional ``exploration`` section (:class:`ExplorationSpec`). It needs
``sensors.lidar``; it drives a kinematic plant with wheel-encoder odometry (or perfect state),
and ``localization`` is left out: SLAM localises the robot.

The loop (:func:`explore`):

1. **Map.** The scans so far, with the encoder odometry chained over the legs, go through
   :class:`~wheelbase.mapping.LidarSlam` (scan-to-submap matching, keyframes, loop closures),
   incrementally (:meth:`~wheelbase.mapping.LidarSlam.session`: each leg adds its own scans
   to the pose graph of the legs before, with the result the batch run would give);
   the map is rendered from its poses (``exploration.slam: false``: from the odometry poses).
   The first ``initial_scans`` scans are taken at rest at the start.
2. **Frontiers** (:mod:`wheelbase.mapping.frontiers`) of the map, at least
   ``min_frontier_size`` long, not counting unknown cells within ``wall_fringe`` of a wall
   (its blurred surface: a strip along a wall that no visit turns free), ranked by
   explore_lite's cost over a path-distance field from the robot's SLAM pose through the
   cells whose clearance exceeds half the planning footprint's width.
3. **Plan** with Hybrid A* (the scenario's ``planner``) on the map, **unknown cells treated as
   obstacles**: the robot only ever plans through space it has seen free, which is why it
   cannot hit a wall it has not seen; the goal is the frontier's approach cell, facing the
   frontier (other headings tried in quarter turns when that one collides), from the SLAM
   pose, or, where the planning footprint does not fit there (the robot stopped closer to a
   wall than the margin), from the nearest pose where it does (``_free_start``; the
   path-distance field of step 2 starts there too). A frontier Hybrid A* cannot reach is
   blacklisted and the next one tried; so is every frontier once driven to (what is left of
   it after the visit cannot be seen from there: ragged edges where beams graze a wall).
4. **Drive** the plan with the one closed-loop engine (:class:`~wheelbase.sim.Engine`: the
   scenario's controller, plant, encoders and lidar; collisions against the true world). The
   plan is made in the map frame and handed to the controller in its odometry frame through
   map→odom = SLAM pose ⊖ odometry pose, as a ROS robot does; each leg's odometry frame starts
   where the engine starts it (the leg's true start pose: only the origin of that frame; the
   odometry chained for SLAM keeps only the encoders' relative motion). A leg that does not
   arrive (``missed_goal``, ``timeout``) blacklists its frontier. A plan longer than
   ``replan_distance`` is driven only to the point that far along it (the robot stops there),
   and the loop goes back to 1: the map→odom transform is held fixed through a leg and the plan
   is made on what the robot saw from the leg's start, so a long leg drives far on a map that
   the scans on the way would have corrected (measured on the maze, seed 0: whole legs of up
   to 30 m drove into a wall on the 68th leg; with legs cut at 3 m it is explored without a
   collision; the encoders drift < 1 mm a leg there, the SLAM pose is off by up to 0.65 m).
5. **Stop** when no reachable frontier is left (status ``explored``), at a collision
   (``collision``), when the simulated time reaches ``duration`` (``timeout``) or after
   ``max_legs`` frontier legs (``max_legs``; legs cut at ``replan_distance`` do not count),
   or when the planning footprint fits nowhere near the robot's pose on its map (``stuck``:
   no plan can start, which says nothing of the frontiers).

The map's array is sized once SLAM renders it (the beams' reach plus 1 m); the true world is
read only by the simulation (lidar, collisions) and by the evaluation
(:func:`exploration_metrics`).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np
import yaml
from pydantic import BaseModel, ConfigDict, Field, ValidationError, field_validator

from wheelbase._validate import read_text
from wheelbase.errors import PlanningError, ScenarioError
from wheelbase.geometry import compose, relative_pose, wrap_angle
from wheelbase.scenario import Scenario, format_validation_error

__all__ = [
    "ExplorationResult",
    "ExplorationSpec",
    "bundled_explorations",
    "exploration_metrics",
    "explore",
    "load_exploration",
]


MIN_REPLAN_DISTANCE = 0.5
"""Shortest cut [m] of a leg's plan (``replan_distance``), other than 0 (whole plans)."""


class ExplorationSpec(BaseModel):
    """The ``exploration`` section of an exploration scenario."""

    model_config = ConfigDict(extra="forbid", frozen=True)

    min_frontier_size: float = Field(
        0.5, gt=0, le=100, description="Shortest frontier worth visiting [m] (explore_lite 0.5)."
    )
    distance_weight: float = Field(
        3.0, ge=0, le=1e6, description="Weight of the path distance in the cost (potential_scale)."
    )
    gain_weight: float = Field(
        1.0, ge=0, le=1e6, description="Weight of the frontier's length in the cost (gain_scale)."
    )
    approach: float = Field(
        1.0, gt=0, le=100, description="Farthest the goal may lie from the frontier [m]."
    )
    wall_fringe: float = Field(
        0.1, ge=0, le=10, description="Unknown cells this near a wall's cells are its blurred "
        "surface, not unexplored space, and make no frontier [m] (about two cells)."
    )  # fmt: skip
    blacklist_radius: float = Field(
        0.5, ge=0, le=100, description="A given-up goal blacklists frontiers this near [m]."
    )
    max_legs: int = Field(100, ge=1, le=10_000, description="Most frontiers driven to.")
    replan_distance: float = Field(
        3.0, ge=0, le=1e4, description="A leg drives at most this far along its plan before "
        "the robot re-maps and re-plans [m] (0: whole plans; else at least "
        f"{MIN_REPLAN_DISTANCE} m)."
    )  # fmt: skip
    leg_slack: float = Field(
        20.0, gt=0, le=3600, description="Time a leg may take beyond its reference [s]."
    )
    slam: bool = Field(True, description="Map from SLAM poses (false: odometry poses).")
    resolution: float = Field(0.05, gt=0, le=1, description="Cell side of the map [m].")

    @field_validator("replan_distance")
    @classmethod
    def _cut_that_moves(cls, value: float) -> float:
        # cut legs do not count towards max_legs: a cut of almost nothing would re-map and
        # re-plan without end (the fuzzer's 6e-280 m hung)
        if 0.0 < value < MIN_REPLAN_DISTANCE:
            raise ValueError(f"must be 0 (whole plans) or at least {MIN_REPLAN_DISTANCE} m")
        return value

    initial_scans: int = Field(
        5, ge=1, le=100, description="Scans taken at rest at the start, one lidar period apart "
        "(a cell needs four misses of the default sensor model to be called free)."
    )  # fmt: skip


@dataclass(frozen=True)
class ExplorationResult:
    """The outcome of :func:`explore`.

    Attributes
    ----------
    scenario : Scenario
        The scenario driven (its ``map`` is the true world).
    spec : ExplorationSpec
        The exploration options.
    grid : OccupancyGrid
        The map made (unknown cells marked).
    truth : OccupancyGrid
        The true world (for evaluation only).
    true_path, estimated_path : numpy.ndarray, shape (M, 3)
        True and SLAM poses at the scans [m, m, rad].
    goals : numpy.ndarray, shape (G, 3)
        The goals driven to (map frame) [m, m, rad].
    frontiers : numpy.ndarray, shape (G, 2)
        Each goal's frontier centroid [m].
    legs : list of dict
        Per leg: status, duration, planning time, the length driven, whether the plan was
        cut at ``replan_distance``, the SLAM pose's error at the start (``start_error_m``,
        against the truth) and the encoders' drift over the leg (``odometry_drift_m``).
    status : str
        explored, collision, timeout, max_legs or stuck.
    frames : list of tuple
        (simulated time [s], map, SLAM trajectory) after each leg (the map growing).
    metrics : dict
        :func:`exploration_metrics`.
    """

    scenario: Scenario
    spec: ExplorationSpec
    grid: Any
    truth: Any
    true_path: np.ndarray
    estimated_path: np.ndarray
    goals: np.ndarray
    frontiers: np.ndarray
    legs: list[dict[str, Any]]
    status: str
    frames: list = field(default_factory=list, repr=False)
    metrics: dict[str, Any] = field(default_factory=dict)


_NOT_HERE = {
    "localization": "SLAM localises the robot: leave localization out",
    "fleet": "exploration drives one robot",
    "costmap": "the planner plans on the SLAM map; there is no costmap",
    "tracker": "there are no moving obstacles to track",
    "terrain": "exploration drives a kinematic plant",
    "goal_payloads": "there are no goals",
    "goal": "the frontiers are the goals: give none",
    "goals": "the frontiers are the goals: give none",
}


def bundled_explorations() -> dict[str, Path]:
    """Names and paths of the exploration scenarios in ``wheelbase/data/explorations/``."""
    folder = Path(__file__).parent / "data" / "explorations"
    return {path.stem: path for path in sorted(folder.glob("*.yaml"))}


def load_exploration(source: str | Path | dict[str, Any]) -> tuple[Scenario, ExplorationSpec]:
    """Read an exploration scenario (module docstring).

    Parameters
    ----------
    source : str, Path or dict
        A YAML file, a bundled name (:func:`bundled_explorations`: ``doorway``, ``maze``,
        ``warehouse``) or the parsed mapping.

    Returns
    -------
    tuple of Scenario and ExplorationSpec
        The scenario with ``map`` set to the true world (and a goal at the start, unused).

    Raises
    ------
    ScenarioError
        Not ``map: unknown``, no ``world.map``, a key exploration does not take, a lidar
        missing, or a field that fails validation; the message names the key.
    """
    if isinstance(source, dict):
        label, data, folder = "<dict>", dict(source), None
    elif isinstance(source, (str, Path)):
        path = Path(source)
        bundled = bundled_explorations()
        if not path.is_file() and str(source) in bundled:
            path = bundled[str(source)]
        if not path.is_file():
            names = ", ".join(bundled)
            raise ScenarioError(f"{path}: no such file (bundled explorations: {names})")
        label, folder = path.name, path.parent
        try:
            data = yaml.safe_load(read_text(path, "scenario", ScenarioError, label))
        except (ValueError, RecursionError, yaml.YAMLError) as error:
            raise ScenarioError(f"{label}: unreadable YAML: {error}") from None
        if not isinstance(data, dict):
            raise ScenarioError(f"{label}: a scenario must be a mapping of keys to values")
        data = dict(data)
    else:
        raise ScenarioError(
            f"an exploration scenario is a file path or a mapping (got {type(source).__name__})"
        )
    if data.get("map") != "unknown":
        raise ScenarioError(
            f"{label}: map: an exploration starts without a map: write map: unknown and the "
            f"true world in world: {{map: NAME}} (got map: {data.get('map')!r})"
        )
    for key, why in _NOT_HERE.items():
        if key in data:
            raise ScenarioError(f"{label}: {key}: {why}")
    world = data.pop("world", None)
    if not isinstance(world, dict) or not isinstance(world.get("map"), str):
        raise ScenarioError(
            f"{label}: world.map: name the true world (a bundled map or a map file), seen only "
            "through the lidar"
        )
    extra = sorted(set(world) - {"map"})
    if extra:
        raise ScenarioError(f"{label}: world.{extra[0]}: exploration takes only world.map")
    truth = world["map"]
    if folder is not None and not Path(truth).is_absolute() and (folder / truth).exists():
        truth = str(folder / truth)
    if data.get("plant", "kinematic") != "kinematic":
        raise ScenarioError(f"{label}: plant: exploration drives a kinematic plant")
    options = data.pop("exploration", None) or {}
    if not isinstance(options, dict):
        raise ScenarioError(f"{label}: exploration: a mapping of options")
    try:
        spec = ExplorationSpec.model_validate(options)
    except ValidationError as error:
        raise ScenarioError(format_validation_error(error, f"{label}: exploration")) from None
    data["map"] = truth
    data["goals"] = [data.get("start")]
    data.setdefault("goal_tolerance", [0.2, 30.0])
    data.setdefault("duration", 600.0)
    try:
        scenario = Scenario.model_validate(data)
    except ValidationError as error:
        raise ScenarioError(format_validation_error(error, label)) from None
    if scenario.sensors.lidar is None:
        raise ScenarioError(f"{label}: sensors.lidar: exploration maps with a lidar: give one")
    return scenario, spec


@dataclass
class _Parts:
    robot: Any
    footprint: Any
    limits: Any
    engine: Any
    lidar: Any
    follows_path: bool
    margin: float
    radius: float


def _parts(scenario: Scenario, truth: Any) -> _Parts:
    """Robot, controller, plant, sensors and the engine, as :func:`wheelbase.runner.prepare`
    builds them, without a plan (each leg gets its own)."""
    from wheelbase import runner
    from wheelbase.scenario_sensors import build_estimator, build_sensors
    from wheelbase.sim import Engine, KinematicPlant, WheelAxle
    from wheelbase.timing import SpeedLimits

    field_ = runner._field
    robot = field_("robot", lambda: runner.build_robot(scenario.robot))
    limits = field_("trajectory", lambda: SpeedLimits(**scenario.trajectory.model_dump()))
    law = scenario.controller.law
    if law not in runner.LAWS or law in runner.TORQUE_LAWS or law in ("mppi", "dwa"):
        raise ScenarioError(
            f"controller.law: exploration tracks its plans with a kinematic law (got {law!r})"
        )
    controller, kind = field_(
        "controller.gains",
        lambda: runner._build_controller(law, robot, dict(scenario.controller.gains), limits,
                                         truth),
    )  # fmt: skip
    footprint = runner._footprint(robot)
    axle = WheelAxle(
        robot.wheel_radius,
        robot.half_track,
        radius_scale=tuple(scenario.odometry.wheel_radius_scale),
        track_scale=scenario.odometry.track_scale,
    )
    sensors = field_("sensors", lambda: build_sensors(scenario, truth))
    estimator = field_("localization", lambda: build_estimator(scenario, robot, truth, sensors))
    engine = Engine(
        plant=KinematicPlant(robot.model, axle),
        controller=controller,
        reference=None,
        dt=scenario.dt,
        duration=scenario.duration,
        estimator=estimator,
        sensors=sensors,
        collides=lambda poses: truth.in_collision(footprint, poses),
        max_steps=scenario.resources.max_steps,
    )
    spec = scenario.planner
    radius = robot.turning_radius if spec.turning_radius is None else spec.turning_radius
    return _Parts(robot, footprint, limits, engine, sensors.lidar, kind == "path", spec.margin,
                  radius)  # fmt: skip


def _planner(grid: Any, parts: _Parts, scenario: Scenario) -> Any:
    from wheelbase.planning import HybridAStar

    m = parts.margin
    options = {"time_limit": 30.0, **scenario.planner.options}
    options.setdefault("max_iterations", scenario.replanning.max_expansions)
    return HybridAStar(
        grid,
        footprint=(parts.robot.footprint[0] + 2 * m, parts.robot.footprint[1] + 2 * m),
        turning_radius=parts.radius,
        reverse=scenario.planner.reverse,
        rear_axle_to_center=parts.robot.center_offset,
        **options,
    )


def _distance_field(grid: Any, parts: _Parts, pose: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Path distance [m] from the robot through the cells whose clearance from every occupied
    or unknown cell exceeds half the planning footprint's width; and the cells where the
    planning footprint fits in any heading (clearance above its circumscribed radius), the
    goals' candidates."""
    from scipy import ndimage

    from wheelbase.planning import OccupancyGrid
    from wheelbase.planning.astar import dijkstra

    clearance = ndimage.distance_transform_edt(~grid.occupied) * grid.resolution
    length, width = (side + 2 * parts.margin for side in parts.robot.footprint)
    offset = abs(parts.robot.center_offset)
    blocked = clearance <= 0.5 * width
    targets = clearance > math.hypot(0.5 * length + offset, 0.5 * width) + grid.resolution
    if not grid.contains(pose[:2]):
        return np.full(grid.shape, np.inf), targets
    cell = grid.world_to_cell(pose[:2])
    blocked[cell[0], cell[1]] = False
    field = dijkstra(OccupancyGrid.from_array(blocked, grid.resolution, grid.origin), cell)
    return field, targets


def _render(slam: Any, log: Any, poses: np.ndarray, limit: int) -> Any:
    return slam.render(log, poses, max_cells=limit).to_grid()


def _scan_log(times, ranges, odometry, truth_poses, lidar):
    from wheelbase.datasets.scans import ScanLog

    return ScanLog(
        np.asarray(times, float), np.asarray(ranges, float), np.asarray(lidar.beam_angles, float),
        float(lidar.max_range), np.asarray(odometry, float), np.asarray(truth_poses, float),
        _mount(lidar), 0, "exploration",
    )  # fmt: skip


def _mount(lidar) -> tuple[float, float, float]:
    return tuple(lidar.mount) if hasattr(lidar, "mount") else (0.0, 0.0, 0.0)


def _without_final_turn(plan: Any) -> Any:
    """The plan without the turn on the spot it ends with (if any): with a 360° lidar the
    heading at a frontier's goal sees nothing more, and a robot that stops off its plan
    (tracking, the SLAM pose) sweeps its corners into the wall beside it while it turns there
    (measured on the maze, seed 1: 0.40 m from a wall, the footprint's corner radius)."""
    from wheelbase.planning.path import PlannedPath

    spin = np.isinf(plan.curvatures)
    k = len(spin)
    while k > 2 and spin[k - 1]:
        k -= 1
    if k == len(spin):
        return plan
    return PlannedPath(plan.poses[:k], plan.directions[:k], plan.curvatures[:k],
                       plan.arc_length[:k], True, plan.stats)  # fmt: skip


def _cut(plan: Any, distance: float, clearance: np.ndarray | None = None, grid: Any = None) -> Any:
    """The plan up to ``distance`` along it [m] (the plan itself when 0, or when what would be
    left after the cut is shorter than half of it: no stop just before the goal).

    With ``clearance`` (each cell's distance to the nearest occupied or unknown cell of
    ``grid`` [m]), the plan stops at the pose of the clearest cell between half of
    ``distance`` and ``distance`` along it (the farthest of equals) instead: the shortest
    plan hugs walls at the planner's margin, and a robot stopped there, a few centimetres off
    its plan or off in its SLAM pose, starts the next leg closer to the wall than the margin
    (measured on the warehouse: legs cut beside a shelf left the robot 1 cm from it, and the
    next leg's first turn swept its corner into the shelf)."""
    from wheelbase.planning.path import PlannedPath

    arc = plan.arc_length
    if distance <= 0 or arc[-1] <= 1.5 * distance:
        return plan
    k = max(1, int(np.searchsorted(arc, distance)))
    if clearance is not None:
        first = max(1, int(np.searchsorted(arc, 0.5 * distance)))
        cells = grid.world_to_cell(plan.poses[first : k + 1, :2])
        rows = np.clip(cells[:, 0], 0, clearance.shape[0] - 1)
        cols = np.clip(cells[:, 1], 0, clearance.shape[1] - 1)
        room = clearance[rows, cols]
        k = first + int(np.flatnonzero(room >= room.max() - 1e-9)[-1])
    return PlannedPath(plan.poses[: k + 1], plan.directions[: k + 1], plan.curvatures[: k + 1],
                       arc[: k + 1], True, plan.stats)  # fmt: skip


def _goal_pose(planner: Any, grid: Any, cell: np.ndarray, frontier: Any, pose: np.ndarray):
    """The approach cell's centre facing the frontier; other headings in quarter turns when the
    footprint collides there; None when none is free."""
    xy = np.asarray(grid.cell_to_world(cell[None].astype(float)), float).reshape(-1)[:2]
    towards = frontier.centroid - xy
    if np.hypot(*towards) < 1e-9:
        towards = xy - pose[:2]
    heading = math.atan2(towards[1], towards[0]) if np.hypot(*towards) > 1e-9 else pose[2]
    for turn in (0.0, 0.5 * math.pi, -0.5 * math.pi, math.pi):
        goal = np.array([xy[0], xy[1], float(wrap_angle(heading + turn))])
        if not grid.in_collision(planner.footprint, goal):
            return goal
    return None


def _free_start(planner: Any, grid: Any, pose: np.ndarray) -> np.ndarray | None:
    """The start to plan from: the nearest pose to ``pose``, with its heading and at most half
    the planning footprint's width away, where the planning footprint (the robot grown by the
    planner's margin) clears every occupied cell by a cell's side; else the nearest where it
    is free at all; None when there is none. ``pose`` itself where it qualifies.

    A leg ends where the controller stops, up to a few centimetres off its plan, so it may end
    closer to a wall than the margin; and when SLAM re-draws the map from corrected poses, a
    wall seen long ago may move by some centimetres relative to the robot's latest pose.
    Hybrid A* refuses a start in collision, and without this every frontier would be given up
    at once (measured on the warehouse: the robot stopped 0.35 m from a shelf, the margin's
    footprint needs 0.36 m, and the exploration ended there, "explored", with 6 % of the free
    area unmapped). A start that is free by less than a cell is no better: none of the
    lattice's moves leaves it (measured there: 1 cm from the shelf, 200,000 expansions
    without a path; 6 cm, a path in 4). The controller closes the few centimetres to the plan;
    a start farther than half the footprint's width would not be a correction but another
    place."""
    footprint = planner.footprint
    polygon = footprint.polygon
    reach = 0.5 * float(np.min(polygon.max(axis=0) - polygon.min(axis=0)))
    step = 0.5 * grid.resolution
    offsets = np.arange(-math.ceil(reach / step), math.ceil(reach / step) + 1) * step
    dx, dy = (a.ravel() for a in np.meshgrid(offsets, offsets))
    near = np.hypot(dx, dy)
    order = np.argsort(near[near <= reach], kind="stable")
    candidates = pose + np.stack([dx, dy, np.zeros_like(dx)], -1)[near <= reach][order]
    for clearance in (grid.resolution, 0.0):
        free = ~grid.in_collision(footprint.inflated(clearance), candidates)
        if free.any():
            return candidates[int(np.argmax(free))]
    return None


def explore(
    source: str | Path | dict[str, Any] | tuple[Scenario, ExplorationSpec],
    *,
    progress: Any = None,
) -> ExplorationResult:
    """Explore a world without a map (module docstring).

    Parameters
    ----------
    source : str, Path, dict or tuple
        An exploration scenario file or mapping, or :func:`load_exploration`'s pair.
    progress : callable, optional
        ``progress(leg, status)`` after each leg.

    Returns
    -------
    ExplorationResult

    Raises
    ------
    ScenarioError
        An invalid exploration scenario.
    MapError
        A true world that cannot be read.
    PlanningError
        The start outside the world or in collision.
    """
    from scipy import ndimage

    from wheelbase import runner
    from wheelbase.mapping import LidarSlam, OccupancyMapper
    from wheelbase.mapping.frontiers import choose_frontier, find_frontiers
    from wheelbase.sensors import scan_rays
    from wheelbase.sim import Arrival

    scenario, spec = source if isinstance(source, tuple) else load_exploration(source)
    wall = time.perf_counter()
    limit = scenario.resources.max_map_cells
    truth = runner._field("world.map", lambda: runner._load_map(scenario.map, [], limit))
    parts = _parts(scenario, truth)
    start = runner._pose(scenario.start)
    runner._check_free(truth, parts.robot, start, "start")
    lidar = parts.lidar
    mapper = OccupancyMapper(resolution=spec.resolution, max_range=float(lidar.max_range))
    slam = LidarSlam(use_odometry=True, mapper=mapper)
    rng = np.random.default_rng([scenario.seed, 23])
    sensor = lidar.sensor_poses(start[None])
    first = scan_rays(truth, sensor[:, :2], sensor[:, 2], lidar.beam_angles, lidar.max_range)
    period = 1.0 / scenario.sensors.lidar.rate_hz
    times = [k * period for k in range(spec.initial_scans)]
    ranges = [lidar.readings(first[0], rng) for _ in times]
    odometry, truths = [start.copy() for _ in times], [start.copy() for _ in times]
    true_pose, odo_pose, clock = start.copy(), start.copy(), 0.0
    belief = start.copy()
    estimated = np.array([start])
    goals, centroids, legs, frames, blacklist = [], [], [], [], []
    tolerance = (scenario.goal_tolerance[0], math.radians(scenario.goal_tolerance[1]))
    all_round = scenario.sensors.lidar.fov_deg >= 360.0
    leg_tolerance = (tolerance[0], math.pi) if all_round else tolerance
    min_cells = max(1, math.ceil(spec.min_frontier_size / spec.resolution))
    status = "max_legs"
    grid = None
    timing = {"slam_s": 0.0, "drive_s": 0.0, "plan_s": 0.0}
    session = slam.session(lidar.beam_angles, float(lidar.max_range), mount=_mount(lidar))
    fed = 0  # scans given to the session so far: each leg adds only its own

    def estimate():
        nonlocal fed
        log = _scan_log(times, ranges, odometry, truths, lidar)
        if not spec.slam:
            return log, log.odometry
        session.add(log.ranges[fed:], log.odometry[fed:], log.t[fed:])
        fed = log.n_scans
        return log, session.result().poses

    visits = 0  # frontier legs: those not cut at replan_distance
    while True:
        tick = time.perf_counter()
        log, estimated = estimate()
        timing["slam_s"] += time.perf_counter() - tick
        grid = _render(slam, log, estimated, limit)
        belief = compose(estimated[-1], relative_pose(odometry[-1], odo_pose))
        frames.append((clock, grid, estimated.copy()))
        if visits == spec.max_legs:
            break
        if clock >= scenario.duration - scenario.dt:
            status = "timeout"
            break
        tick = time.perf_counter()
        planner = _planner(grid, parts, scenario)
        origin = _free_start(planner, grid, belief)
        if origin is None:  # the robot is not free on its own map: no frontier is to blame
            timing["plan_s"] += time.perf_counter() - tick
            status = "stuck"
            break
        # from the plans' start: from a robot hemmed in by the margin nothing is reachable
        distance, targets = _distance_field(grid, parts, origin)
        ranked = choose_frontier(
            find_frontiers(grid, min_cells, spec.wall_fringe), distance, grid.resolution,
            approach=spec.approach, distance_weight=spec.distance_weight,
            gain_weight=spec.gain_weight, blacklist=np.array(blacklist).reshape(-1, 2),
            blacklist_radius=spec.blacklist_radius, origin=grid.origin, targets=targets,
        )  # fmt: skip
        plan = goal = None
        chosen = None
        for _cost, frontier, cell in ranked:
            goal = _goal_pose(planner, grid, cell, frontier, belief)
            if goal is not None:
                try:
                    plan = planner.plan(origin, goal)
                except PlanningError:
                    plan = None
                if plan is not None and plan.success and len(plan.poses) >= 2:
                    chosen = frontier
                    break
            middle = np.asarray(grid.cell_to_world(frontier.middle[None].astype(float)))
            blacklist.append(middle.reshape(-1)[:2])
            plan = None
        timing["plan_s"] += time.perf_counter() - tick
        if chosen is None:
            status = "explored"
            break

        room = ndimage.distance_transform_edt(~grid.occupied) * grid.resolution
        cut = _cut(plan, spec.replan_distance, room, grid)
        partial = cut is not plan
        if all_round:  # the heading at the goal does not matter: no turn on the spot there
            cut = _without_final_turn(cut)
        target = goal if cut is plan else cut.poses[-1]

        # the plan in the leg's odometry frame (map→odom from the SLAM pose)
        def to_odom(poses, _b=belief, _o=true_pose):
            return compose(_o, relative_pose(_b, poses))

        path = replace(cut, poses=to_odom(cut.poses))
        timed = runner._timed_reference(path, parts.limits, scenario.dt,
                                        scenario.resources.max_steps)  # fmt: skip
        end = float(timed.t[-1])
        remaining = scenario.duration - clock
        engine = replace(
            parts.engine,
            reference=path if parts.follows_path else timed,
            duration=max(scenario.dt, min(end + spec.leg_slack, remaining)),
            arrival=Arrival(to_odom(target), leg_tolerance, end_time=end),
        )
        tick = time.perf_counter()
        leg_log = engine.run(true_pose[None], seeds=[scenario.seed + len(legs)])
        timing["drive_s"] += time.perf_counter() - tick
        n = int(leg_log.length[0])
        leg_status = leg_log.statuses[0]
        rows = sorted(row for (r, row) in leg_log.scans if r == 0 and row < n)
        leg_est = leg_log.estimated_pose[0, :n]
        leg_true = leg_log.true_pose[0, :n]
        frame_start = leg_est[0].copy()
        for row in rows:
            times.append(clock + float(leg_log.t[row]))
            ranges.append(np.asarray(leg_log.scans[(0, row)], float))
            odometry.append(compose(odo_pose, relative_pose(frame_start, leg_est[row])))
            truths.append(leg_true[row].copy())
        odo_pose = compose(odo_pose, relative_pose(frame_start, leg_est[-1]))
        true_pose = leg_true[-1].copy()
        clock += float(leg_log.t[n - 1])
        legs.append({"status": leg_status, "duration_s": float(leg_log.t[n - 1]),
                     "planning_time_s": float(plan.stats.planning_time_s),
                     "path_length_m": float(cut.length), "cut": partial,
                     "start_error_m": float(np.hypot(*(belief[:2] - leg_true[0][:2]))),
                     "odometry_drift_m": float(np.hypot(*(leg_est[-1][:2] - leg_true[-1][:2])))
                     })  # fmt: skip
        if progress is not None:
            progress(len(legs), leg_status)
        if leg_status == "collision":
            status = "collision"
            break
        if partial and leg_status == "arrived":
            continue  # on the way: re-map, choose and plan again from here
        visits += 1
        goals.append(goal)
        centroids.append(chosen.centroid)
        # a frontier once driven to is not chosen again: what stays of it after the visit
        # cannot be seen from its approach (explore_lite blacklists failures only)
        blacklist.append(chosen.centroid)
        blacklist.append(np.asarray(grid.cell_to_world(chosen.middle[None].astype(float))
                                    ).reshape(-1)[:2])  # fmt: skip
    if len(estimated) != len(truths):  # a leg ended the loop (a collision): map its scans
        log, estimated = estimate()
        grid = _render(slam, log, estimated, limit)
        frames.append((clock, grid, estimated.copy()))
    result = ExplorationResult(
        scenario, spec, grid, truth, np.array(truths), np.asarray(estimated),
        np.array(goals).reshape(-1, 3), np.array(centroids).reshape(-1, 2), legs, status, frames,
    )  # fmt: skip
    metrics = exploration_metrics(result)
    metrics["wall_time_s"] = time.perf_counter() - wall
    metrics["simulated_time_s"] = clock
    metrics.update({f"{key[:-2]}_time_s": value for key, value in timing.items()})
    return replace(result, metrics=metrics)


def reachable_free(truth: Any, start: np.ndarray) -> np.ndarray:
    """The true free cells 8-connected to the start's cell (the area exploration can map).

    Parameters
    ----------
    truth : OccupancyGrid
        The true world.
    start : numpy.ndarray, shape (3,)
        Start pose [m, m, rad].
    """
    from scipy import ndimage

    free = ~truth.occupied
    labels, _ = ndimage.label(free, structure=np.ones((3, 3), bool))
    cell = truth.world_to_cell(np.asarray(start)[:2])
    return labels == labels[cell[0], cell[1]]


def exploration_metrics(result: ExplorationResult) -> dict[str, Any]:
    """Figures of an exploration against the true world.

    ``explored_fraction``: of the true free cells connected to the start, the fraction the map
    calls free (looked up at their centres); ``map_agreement`` (of the cells both call known,
    the fraction that agree, :func:`~wheelbase.mapping.map_agreement`); ``position_rmse_m``: the
    SLAM poses against the true ones at the scans (unaligned: both start at the start pose);
    ``distance_m``: the true path length through the scans; ``legs_cut``: legs
    cut at ``replan_distance``.

    Parameters
    ----------
    result : ExplorationResult
        The exploration.
    """
    from wheelbase.mapping import map_agreement

    truth, grid = result.truth, result.grid
    x, y, heading = result.scenario.start
    start = np.array([x, y, math.radians(heading)])
    region = reachable_free(truth, start)
    rows, cols = np.nonzero(region)
    centres = truth.cell_to_world(np.stack([rows, cols], -1).astype(float))
    inside = grid.contains(centres)
    cells = grid.world_to_cell(centres)
    ci = np.clip(cells[:, 0], 0, grid.shape[0] - 1)
    cj = np.clip(cells[:, 1], 0, grid.shape[1] - 1)
    free = inside & ~grid.occupied[ci, cj]
    agreement, compared = map_agreement(grid, truth)
    error = result.estimated_path[:, :2] - result.true_path[:, :2]
    steps = np.hypot(*np.diff(result.true_path[:, :2], axis=0).T)
    statuses = [leg["status"] for leg in result.legs]
    return {
        "status": result.status,
        "legs": len(result.legs),
        "legs_arrived": statuses.count("arrived"),
        "legs_cut": sum(bool(leg.get("cut")) for leg in result.legs),
        "collisions": statuses.count("collision"),
        "explored_fraction": float(free.mean()) if len(free) else math.nan,
        "reachable_free_area_m2": float(region.sum() * truth.resolution**2),
        "mapped_free_area_m2": float(free.sum() * truth.resolution**2),
        "map_agreement": agreement,
        "cells_compared": compared,
        "position_rmse_m": float(np.sqrt(np.mean(np.sum(error**2, axis=1)))),
        "distance_m": float(steps.sum()),
        "scans": len(result.true_path),
        "planning_time_s": float(sum(leg["planning_time_s"] for leg in result.legs)),
    }
