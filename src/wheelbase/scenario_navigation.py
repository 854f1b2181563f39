"""A scenario's world, perception and navigation resolved to objects (for :mod:`wheelbase.runner`).

- :func:`build_world`: the ``world`` section on the map (:func:`wheelbase.world.world_from_spec`),
  with the boxes ``world.path_boxes`` drops on the planned path for this seed.
- :func:`build_perception`: the costmap and tracker the robot's lidar feeds
  (:class:`~wheelbase.sim.PerceptionSuite`), when the scenario has a lidar and something to
  perceive (a world, a fleet, or a ``costmap`` section).
- :func:`navigator_options`: the ``replanning`` and ``recovery`` sections.

Decisions where the scenario is silent: a box of ``path_boxes`` is centred on a point of the
plan drawn uniformly along its length (farther than ``clear`` from the start and the goal),
its sides drawn uniformly in ``size`` and its yaw uniformly; a draw that would leave no way to
the goal on the true map (Hybrid A* with the scenario's planner finds none) is drawn again, up
to 50 times, so that every seed is a detour and not a dead end (``doorway_blocked`` is the
dead end, on purpose).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from wheelbase.errors import ScenarioError
from wheelbase.scenario import Scenario

__all__ = [
    "PATH_BOX_STREAM",
    "build_perception",
    "build_world",
    "navigator_options",
    "path_boxes",
    "perceives",
]

PATH_BOX_STREAM = 7
"""Second word of the seed of a run's path boxes: ``default_rng([seed, PATH_BOX_STREAM])``."""

_PATH_BOX_TRIES = 50


def perceives(scenario: Scenario) -> bool:
    """Whether the robot builds a costmap from its lidar: a lidar and something to see.

    Parameters
    ----------
    scenario : Scenario
        The validated scenario.
    """
    if scenario.sensors.lidar is None:
        return False
    return (
        scenario.world is not None
        or (scenario.fleet is not None and len(scenario.fleet) > 1)
        or scenario.costmap is not None
    )


def path_boxes(scenario: Scenario, plan: Any, passable: Any, seed: int) -> list[np.ndarray]:
    """The boxes ``world.path_boxes`` drops on ``plan`` for ``seed`` (module docstring).

    Parameters
    ----------
    scenario : Scenario
        The validated scenario (with ``world.path_boxes``).
    plan : PlannedPath
        The plan made on the map.
    passable : callable
        ``passable(polygons) -> bool``: whether the goal can still be reached with them.
    seed : int
        The run's seed.

    Returns
    -------
    list of numpy.ndarray
        Box outlines ``(4, 2)`` [m].
    """
    from wheelbase.world import box_polygon

    spec = scenario.world.path_boxes
    poses = np.asarray(plan.poses)
    arc = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(poses[:, :2], axis=0).T))])
    low, high = spec.clear, arc[-1] - spec.clear
    if high <= low:
        raise ScenarioError(
            f"world.path_boxes.clear: {spec.clear:g} m from both ends leaves none of the "
            f"{arc[-1]:.3g} m plan to drop boxes on"
        )
    rng = np.random.default_rng([seed, PATH_BOX_STREAM])
    for _ in range(_PATH_BOX_TRIES):
        count = int(rng.integers(spec.count[0], spec.count[1] + 1))
        boxes = []
        for _box in range(count):
            s = rng.uniform(low, high)
            x = float(np.interp(s, arc, poses[:, 0]))
            y = float(np.interp(s, arc, poses[:, 1]))
            length, width = rng.uniform(spec.size[0], spec.size[1], 2)
            boxes.append(box_polygon(x, y, length, width, rng.uniform(-math.pi, math.pi)))
        if passable(boxes):
            return boxes
    raise ScenarioError(
        f"world.path_boxes: {_PATH_BOX_TRIES} draws of boxes all closed the way to the goal; "
        "use smaller or fewer boxes"
    )


def build_world(scenario: Scenario, grid: Any, boxes: list[np.ndarray] | None = None) -> Any:
    """The scenario's world on its map, with ``boxes`` added to its static obstacles.

    Parameters
    ----------
    scenario : Scenario
        The validated scenario (with a ``world`` section).
    grid : OccupancyGrid or PolygonWorld
        The map.
    boxes : list of numpy.ndarray, optional
        More static obstacles (outlines (M, 2) [m]): the path boxes of this seed.
    """
    from dataclasses import replace

    from wheelbase.world import Obstacles, world_from_spec

    spec = scenario.world.truth() if scenario.world is not None else {}
    world = world_from_spec(spec, grid)
    if boxes:
        old = world.obstacles
        polygons = len(old.polygons)  # the names run polygons first, then discs
        names = (
            *old.names[:polygons],
            *(f"world.path_boxes[{i}]" for i in range(len(boxes))),
            *old.names[polygons:],
        )
        obstacles = Obstacles((*old.polygons, *boxes), old.discs, names)
        world = replace(world, obstacles=obstacles)
    return world


def build_perception(scenario: Scenario, grid: Any, footprint: Any, sensors: Any) -> Any:
    """What the robot makes of its lidar: a :class:`~wheelbase.sim.PerceptionSuite`, or None.

    Parameters
    ----------
    scenario : Scenario
        The validated scenario.
    grid : OccupancyGrid or PolygonWorld
        The map (the costmap's static layer).
    footprint : Footprint
        The robot's outline (its inscribed radius starts the inflation).
    sensors : SensorSuite or None
        The scenario's sensors.
    """
    if not perceives(scenario) or sensors is None or sensors.lidar is None:
        return None
    from wheelbase.perception import CostmapSpec, LayeredCostmap, TrackerSpec
    from wheelbase.scenario_sensors import world_grid
    from wheelbase.sim.perceiving import PerceptionSuite

    spec = CostmapSpec.from_mapping(scenario.costmap)
    costmap = LayeredCostmap.from_map(spec, world_grid(grid), footprint)
    tracker = TrackerSpec.from_mapping(scenario.tracker)
    return PerceptionSuite(costmap, sensors.lidar, tracker, world_grid(grid))


def navigator_options(scenario: Scenario, reach: float = 0.0) -> Any:
    """The ``replanning`` and ``recovery`` sections as navigator options
    (:class:`~wheelbase.navigation.NavigatorOptions`).

    Parameters
    ----------
    scenario : Scenario
        The validated scenario.
    reach : float
        How far ahead the local controller looks [m] (its horizon at full speed): its rolling
        window is at least 1 m wider than twice that, whatever ``costmap.window`` says.
    """
    from wheelbase.navigation import NavigatorOptions
    from wheelbase.perception import CostmapSpec

    replanning, recovery = scenario.replanning, scenario.recovery
    window = max(CostmapSpec.from_mapping(scenario.costmap).window, 2.0 * reach + 1.0)
    return NavigatorOptions(
        replan=replanning.enabled,
        rate_hz=replanning.rate_hz,
        lookahead=replanning.lookahead,
        moving_speed=replanning.moving_speed,
        behaviours=tuple(recovery.behaviours),
        max_retries=recovery.max_retries,
        wait_time=recovery.wait_time,
        back_up_distance=recovery.back_up_distance,
        back_up_speed=recovery.back_up_speed,
        spin_angle=math.radians(recovery.spin_angle_deg),
        spin_rate=math.radians(recovery.spin_rate_deg),
        yield_time=recovery.yield_time,
        local_window=window,
    )
