"""The world: the truth beyond the map, that only the sensors may see.

A :class:`World` holds parameters only (the map, the static obstacles off the map, the agent
groups and their behaviours' parameters); its evolving part is a
:class:`~wheelbase.world.WorldState` that :meth:`World.start` creates and :meth:`World.step`
advances, B worlds in lockstep, as a pure function. The queries read a state and the robots'
bodies (:class:`~wheelbase.world.RobotBodies`):

- :meth:`World.cast`: the exact lidar ranges to the map, the obstacles, the agents and the
  other robots, the one lidar truth the sensors read;
- :meth:`World.collisions` and :meth:`World.distances`: exact contact and distances of robot
  footprints with the obstacles, the agents and each other, for the metrics;
- :meth:`World.agent_truth`: the agents' positions and velocities, for scoring a tracker.

Nothing that decides (controllers, planners, estimators, perception) may import this
package: they see the world through the sensors only (``tests/test_layers.py``).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np
from numpy.typing import ArrayLike

from wheelbase._validate import as_float_array, check_choice, positive
from wheelbase.errors import ConfigError, InputError, ScenarioError
from wheelbase.limits import MAX_BEAMS
from wheelbase.world.agents import MAX_AGENTS, ORCA, AgentGroup, SocialForce
from wheelbase.world.obstacles import Obstacles
from wheelbase.world.state import Distances, RobotBodies, WorldState

__all__ = ["MAX_DT", "World"]

MAX_DT = 10.0
"""Longest step [s] :meth:`World.step` takes."""
_LATTICE_LIMIT = 2_000_000


@dataclass(frozen=True, eq=False)
class World:
    """The map, the static obstacles off it and the moving agents (module docstring).

    Parameters
    ----------
    map : OccupancyGrid or PolygonWorld
        What the robot knows (a polygon world is seen through its raster here, as the lidar
        of :mod:`wheelbase.sensors` sees it).
    obstacles : Obstacles
        Static obstacles that are not on the map.
    agents : sequence of AgentGroup
        The moving agents, group by group (agent indices run through the groups in order).
    social_force : SocialForce
        Parameters of the ``social_force`` behaviour.
    orca : ORCA
        Parameters of the ``orca`` behaviour.

    Raises
    ------
    ScenarioError
        An agent region or a waypoint off the map, a waypoint closer than the agents' radius
        to a wall or obstacle, an obstacle off the map, more than :data:`MAX_AGENTS` agents;
        the message names the scenario key (``world.agents[0].region: ...``).

    Examples
    --------
    >>> from wheelbase.planning import OccupancyGrid
    >>> room = OccupancyGrid(np.pad(np.zeros((98, 98), bool), 1, constant_values=True), 0.1)
    >>> world = World(room, agents=[AgentGroup(count=5, behaviour="wander")])
    >>> state = world.start([0, 1])
    >>> world.step(state, 0.1).position.shape
    (2, 5, 2)
    """

    map: object
    obstacles: Obstacles = field(default_factory=Obstacles)
    agents: tuple[AgentGroup, ...] = ()
    social_force: SocialForce = field(default_factory=SocialForce)
    orca: ORCA = field(default_factory=ORCA)

    def __post_init__(self) -> None:
        from wheelbase.planning import OccupancyGrid, PolygonWorld

        if not isinstance(self.map, (OccupancyGrid, PolygonWorld)):
            raise ConfigError(
                f"map must be an OccupancyGrid or a PolygonWorld (got {type(self.map).__name__})"
            )
        for name, cls in (("obstacles", Obstacles), ("social_force", SocialForce),
                          ("orca", ORCA)):  # fmt: skip
            if not isinstance(getattr(self, name), cls):
                raise ConfigError(f"{name} must be a {cls.__name__} "
                                  f"(got {type(getattr(self, name)).__name__})")  # fmt: skip
        groups = tuple(self.agents)
        for g, group in enumerate(groups):
            if not isinstance(group, AgentGroup):
                raise ConfigError(f"world.agents[{g}] must be an AgentGroup "
                                  f"(got {type(group).__name__})")  # fmt: skip
        object.__setattr__(self, "agents", groups)
        total = sum(group.count for group in groups)
        if total > MAX_AGENTS:
            raise ScenarioError(f"world.agents: {total} agents in all: more than {MAX_AGENTS}")
        x0, x1, y0, y1 = self.grid.extent
        for g, group in enumerate(groups):
            if group.region is not None:
                rx0, ry0, rx1, ry1 = group.region
                if rx0 < x0 or ry0 < y0 or rx1 > x1 or ry1 > y1:
                    raise ScenarioError(
                        f"world.agents[{g}].region {list(group.region)} must lie inside the "
                        f"map [{x0:g}, {y0:g}, {x1:g}, {y1:g}] (x0, y0, x1, y1) [m]"
                    )
            elif x1 - x0 < 2 * group.radius or y1 - y0 < 2 * group.radius:
                raise ScenarioError(f"world.agents[{g}].radius {group.radius:g} m: the agents "
                                    "are larger than the map")  # fmt: skip
        for q in range(len(self.obstacles)):
            lo, hi = self._obstacle_box(q)
            if hi[0] < x0 or lo[0] > x1 or hi[1] < y0 or lo[1] > y1:
                raise ScenarioError(
                    f"{self.obstacles.names[q]} lies outside the map "
                    f"[{x0:g}, {y0:g}, {x1:g}, {y1:g}] (x0, y0, x1, y1) [m]"
                )
        self._check_waypoints()

    # ------------------------------------------------------------------ derived data
    @property
    def grid(self):
        """The map's occupancy grid (a polygon world's raster)."""
        from wheelbase.planning import PolygonWorld

        return self.map.raster if isinstance(self.map, PolygonWorld) else self.map

    @cached_property
    def agent_count(self) -> int:
        """Agents per world A."""
        return sum(group.count for group in self.agents)

    @cached_property
    def agent_group(self) -> np.ndarray:
        """``(A,)`` int64: the group of each agent."""
        return np.repeat(np.arange(len(self.agents)), [g.count for g in self.agents]).astype(
            np.int64
        )

    @cached_property
    def agent_radius(self) -> np.ndarray:
        """``(A,)`` agent radii [m]."""
        return self._per_agent[0]

    @cached_property
    def _per_agent(self) -> tuple:
        x0, x1, y0, y1 = self.grid.extent
        group = self.agent_group

        def pick(values: list, dtype: type = np.float64) -> np.ndarray:
            return np.ascontiguousarray(np.asarray(values, dtype)[group])

        radius = pick([g.radius for g in self.agents] or [0.0])
        speed = pick([g.speed for g in self.agents] or [0.0])
        code = pick([g.behaviour_code for g in self.agents] or [0], np.int64)
        factor = {3: self.social_force.max_speed_factor, 4: self.orca.max_speed_factor}
        vmax = pick([g.speed * factor.get(g.behaviour_code, 1.0) for g in self.agents] or [0.0])
        regions = [g.region if g.region is not None else (x0, y0, x1, y1) for g in self.agents]
        region = np.ascontiguousarray(np.asarray(regions or [(0, 0, 1, 1)], float)[group])
        reacts = pick([g.reacts_to_robot for g in self.agents] or [False], np.bool_)
        loops = [g.waypoints if g.waypoints is not None else np.zeros((0, 2)) for g in self.agents]
        counts = np.array([len(w) for w in loops] or [0], np.int64)
        starts = np.zeros(len(counts), np.int64)
        np.cumsum(counts[:-1], out=starts[1:])
        waypoints = np.ascontiguousarray(np.concatenate(loops) if loops else np.zeros((0, 2)))
        wp_start = np.ascontiguousarray(starts[group])
        wp_count = np.ascontiguousarray(counts[group])
        for array in (radius, speed, code, vmax, region, reacts, waypoints, wp_start, wp_count):
            array.setflags(write=False)
        return radius, speed, vmax, code, region, reacts, wp_start, wp_count, waypoints

    @cached_property
    def statics(self) -> tuple:
        """The kernels' tuple of the map and the obstacles
        (:func:`wheelbase.world.statics.pack_statics`)."""
        from wheelbase.world.statics import pack_statics

        return pack_statics(self.grid, self.obstacles)

    @cached_property
    def obstacle_world(self):
        """The static obstacles as a :class:`~wheelbase.planning.PolygonWorld` (exact
        footprint contact and clearance) over the map's extent padded by half its size on
        every side (leaving it counts as contact there), or None without obstacles."""
        if not len(self.obstacles):
            return None
        x0, x1, y0, y1 = self.grid.extent
        pad_x, pad_y = (x1 - x0) / 2.0, (y1 - y0) / 2.0
        bounds = (x0 - pad_x, x1 + pad_x, y0 - pad_y, y1 + pad_y)
        resolution = max(self.grid.resolution, 2.0 * max(x1 - x0, y1 - y0) / 1024)
        return self.obstacles.polygon_world(bounds, resolution)

    def _obstacle_box(self, q: int) -> tuple[np.ndarray, np.ndarray]:
        _, _, circle, _ = self.obstacles.packed
        return circle[q, :2] - circle[q, 2], circle[q, :2] + circle[q, 2]

    def _check_waypoints(self) -> None:
        from wheelbase.world.statics import static_nearest

        x0, x1, y0, y1 = self.grid.extent
        st = None
        for g, group in enumerate(self.agents):
            if group.waypoints is None:
                continue
            for k, (x, y) in enumerate(group.waypoints):
                if not (x0 <= x <= x1 and y0 <= y <= y1):
                    raise ScenarioError(
                        f"world.agents[{g}].waypoints[{k}] {[float(x), float(y)]} lies off the "
                        f"map [{x0:g}, {y0:g}, {x1:g}, {y1:g}] (x0, y0, x1, y1) [m]"
                    )
                st = self.statics if st is None else st
                clearance = static_nearest(st, float(x), float(y), group.radius)[0]
                if clearance < group.radius:
                    raise ScenarioError(
                        f"world.agents[{g}].waypoints[{k}] {[float(x), float(y)]} is "
                        f"{max(clearance, 0.0):.3g} m from a wall or obstacle: an agent of "
                        f"radius {group.radius:g} m cannot stand there"
                    )

    # ------------------------------------------------------------------ start and step
    def start(
        self,
        seeds: ArrayLike,
        keep_clear: ArrayLike | None = None,
        labels: Sequence[str] | None = None,
    ) -> WorldState:
        """B worlds at t = 0: each world's agents placed by its seed (reproducible), none
        overlapping another, a wall, an obstacle or a keep-clear disc
        (:mod:`wheelbase.world.spawn`); first goals and velocities drawn.

        Parameters
        ----------
        seeds : array_like of int
            ``(B,)`` one seed per world.
        keep_clear : array_like or None
            ``(B, P, 3)`` or ``(P, 3)`` (the same for every world) discs (x [m], y [m],
            radius [m]) no agent or obstacle may overlap at the start: the robots' starts and
            goals.
        labels : sequence of str or None
            What each of the P discs is (``"start"``, ``"goal of robot 1"``), for messages.

        Returns
        -------
        WorldState

        Raises
        ------
        ScenarioError
            A static obstacle overlaps a keep-clear disc (``world.obstacles[2] (box) overlaps
            the start ...``), or a group's agents do not fit in its region
            (``world.agents[0].count: ...``).
        """
        from wheelbase.world.spawn import hex_lattice, place_points, place_random
        from wheelbase.world.step import initial_motion

        seeds = _seeds(seeds)
        batch = len(seeds)
        keep = _keep_clear(keep_clear, batch)
        if labels is not None and len(labels) != keep.shape[1]:
            raise InputError(f"labels must name each keep-clear disc ({len(labels)} for "
                             f"{keep.shape[1]})")  # fmt: skip
        self._check_obstacles_clear(keep, labels)
        radius, speed, _vmax, code, region, _reacts, wp_start, wp_count, waypoints = self._per_agent
        n = self.agent_count
        st = self.statics
        position = np.zeros((batch, n, 2))
        placed_r = np.zeros(n)
        for b in range(batch):
            placed = position[b]
            done = 0
            for g, group in enumerate(self.agents):
                rx0, ry0, rx1, ry1 = region[done] if group.count else (0, 0, 1, 1)
                got = place_random(st, seeds[b], g, rx0, ry0, rx1, ry1, group.radius,
                                   group.count, keep[b], placed, placed_r, done)  # fmt: skip
                if got < group.count:
                    lattice = hex_lattice(rx0, ry0, rx1, ry1, group.radius, _LATTICE_LIMIT)
                    order = _shuffled(len(lattice), seeds[b], g)
                    got += place_points(st, np.ascontiguousarray(lattice[order]), group.radius,
                                        group.count - got, keep[b], placed, placed_r,
                                        done + got)  # fmt: skip
                if got < group.count:
                    raise ScenarioError(
                        f"world.agents[{g}].count: {group.count} agents of radius "
                        f"{group.radius:g} m do not fit in region "
                        f"{[float(v) for v in (rx0, ry0, rx1, ry1)]} [m]: only {got} found room "
                        "clear of the walls, the obstacles, the other agents and the robots' "
                        "starts and goals (world seed "
                        f"{int(seeds[b])}); lower count or radius, or enlarge region"
                    )
                done += group.count
        velocity, goal, waypoint, goal_time = initial_motion(
            st, seeds, position, radius, speed, code, region, wp_start, wp_count, waypoints
        )
        return WorldState(position, velocity, goal, waypoint, goal_time, seeds,
                          np.zeros(batch, np.int64))  # fmt: skip

    def _check_obstacles_clear(self, keep: np.ndarray, labels: Sequence[str] | None) -> None:
        from wheelbase.world.statics import first_overlap

        if not len(self.obstacles) or keep.shape[1] == 0:
            return
        b, p, q, d = first_overlap(self.statics, keep)
        if b >= 0:
            what = labels[p] if labels is not None else f"keep-clear disc {p}"
            x, y, r = keep[b, p]
            raise ScenarioError(
                f"{self.obstacles.names[q]} overlaps the {what} at "
                f"({x:g}, {y:g}) [m]: it comes within {max(d, 0.0):.3g} m of it, less than "
                f"its radius {r:g} m; move the obstacle"
            )

    def step(self, state: WorldState, dt: float, robots: RobotBodies | None = None) -> WorldState:
        """Every agent of every world moves by its behaviour for ``dt``
        (:mod:`wheelbase.world.step`); a pure function: ``state`` is not changed and the same
        arguments give the same result.

        Parameters
        ----------
        state : WorldState
            B worlds of this world's agents.
        dt : float
            Step [s], in (0, :data:`MAX_DT`].
        robots : RobotBodies or None
            The robots of each world (B of them) at the start of the step; None: no robots.

        Returns
        -------
        WorldState
        """
        from wheelbase.world.step import step_worlds

        self._check_state(state)
        if not (isinstance(dt, (float, int)) and 0.0 < dt <= MAX_DT):
            dt = positive("dt", dt, "s")
            if dt > MAX_DT:
                raise ConfigError(f"dt must be <= {MAX_DT:g} s (got {dt:g})")
        robots = self._robots(robots, state.batch)
        radius, speed, vmax, code, region, reacts, wp_start, wp_count, waypoints = self._per_agent
        out = step_worlds(
            state.position, state.velocity, state.goal, state.waypoint, state.goal_time,
            state.seed, state.step, float(dt), radius, speed, vmax, code, region, reacts,
            wp_start, wp_count, waypoints, self._sf_packed, self._orca_packed, self.statics,
            robots.pose, robots.velocity, robots.radius,
        )  # fmt: skip
        return WorldState.trusted(*out, state.seed, state.step + 1)

    @cached_property
    def _sf_packed(self) -> np.ndarray:
        return self.social_force.packed()

    @cached_property
    def _orca_packed(self) -> np.ndarray:
        return self.orca.packed()

    def _check_state(self, state: WorldState) -> None:
        if not isinstance(state, WorldState):
            raise InputError(f"state must be a WorldState (got {type(state).__name__})")
        if state.agents != self.agent_count:
            raise InputError(f"state has {state.agents} agents per world; this world has "
                             f"{self.agent_count}")  # fmt: skip

    def _robots(self, robots: RobotBodies | None, batch: int) -> RobotBodies:
        if robots is None:
            return RobotBodies.none(batch)
        if not isinstance(robots, RobotBodies):
            raise InputError(f"robots must be RobotBodies or None (got {type(robots).__name__})")
        if robots.pose.shape[0] != batch:
            raise InputError(f"robots must have one row per world ({robots.pose.shape[0]} for "
                             f"{batch})")  # fmt: skip
        return robots

    def _rows(
        self, name: str, poses: ArrayLike, world_index: ArrayLike, self_index: ArrayLike | None,
        state: WorldState, robots: RobotBodies,
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:  # fmt: skip
        array = np.asarray(poses, dtype=np.float64) if not isinstance(poses, np.ndarray) or (
            poses.dtype != np.float64) else poses  # fmt: skip
        if array.ndim != 2 or array.shape[1] != 3 or not np.isfinite(array).all():
            array = as_float_array(name, poses, 3, min_ndim=2, max_ndim=2)  # (says what is wrong)
        poses = array
        m = len(poses)
        world_index = _indices("world_index", world_index, m, state.batch)
        n_rob = robots.pose.shape[1]
        if self_index is None:
            self_index = np.full(m, -1, np.int64)
        else:
            self_index = _indices("self_index", self_index, m, n_rob, allow_none=True)
        return np.ascontiguousarray(poses), world_index, self_index

    # ------------------------------------------------------------------ queries
    def cast(
        self,
        sensor_poses: ArrayLike,
        beam_angles: ArrayLike,
        max_range: float,
        world_index: ArrayLike,
        state: WorldState,
        robots: RobotBodies | None = None,
        self_index: ArrayLike | None = None,
        method: str = "fast",
    ) -> np.ndarray:
        """Exact lidar ranges (:mod:`wheelbase.world.cast`): the map's grid
        (:func:`wheelbase.sensors.scan_rays`), the static obstacles' edges, the agents' discs
        and the other robots' footprints.

        Parameters
        ----------
        sensor_poses : array_like
            ``(M, 3)`` sensor poses (x [m], y [m], θ [rad]), world frame.
        beam_angles : array_like
            ``(K,)`` beam directions [rad] relative to the sensor heading.
        max_range : float
            Range [m] of a beam that hits nothing, > 0.
        world_index : array_like of int
            ``(M,)`` the world of each sensor.
        state : WorldState
            The agents.
        robots : RobotBodies or None
            The robots (None: none).
        self_index : array_like of int or None
            ``(M,)`` the robot carrying each sensor (its own footprint is not seen), −1 for
            none; default −1.
        method : {"fast", "exact"}
            The grid's ray casting (:data:`wheelbase.sensors.RAY_METHODS`; equal to rounding).

        Returns
        -------
        numpy.ndarray
            ``(M, K)`` ranges [m] in ``[0, max_range]``.
        """
        from wheelbase.sensors import scan_rays
        from wheelbase.world.cast import cast_kernel, evenly_spaced

        self._check_state(state)
        robots = self._robots(robots, state.batch)
        poses, world_index, self_index = self._rows("sensor_poses", sensor_poses, world_index,
                                                    self_index, state, robots)  # fmt: skip
        beam_angles = as_float_array("beam_angles", beam_angles, min_ndim=1, max_ndim=1)
        if len(beam_angles) > MAX_BEAMS:
            raise InputError(f"beam_angles: {len(beam_angles)} beams, more than {MAX_BEAMS}")
        if method not in ("fast", "exact"):
            check_choice("method", method, ("fast", "exact"))
        ranges = scan_rays(self.grid, poses[:, :2], poses[:, 2], beam_angles, max_range, method)
        cast_kernel(poses, beam_angles, evenly_spaced(beam_angles), float(max_range), ranges,
                    world_index,
                    self_index, self.statics, state.position, self.agent_radius, robots.pose,
                    robots.polygon, robots.radius)  # fmt: skip
        return ranges

    def collisions(
        self,
        poses: ArrayLike,
        footprint,
        world_index: ArrayLike,
        state: WorldState,
        robots: RobotBodies | None = None,
        self_index: ArrayLike | None = None,
    ) -> np.ndarray:
        """Exact contact of a footprint at each pose with a static obstacle, an agent's disc
        or another robot's footprint (the map's own collision is the map's:
        :meth:`OccupancyGrid.in_collision`). Touching counts.

        Parameters
        ----------
        poses : array_like
            ``(M, 3)`` robot poses (x [m], y [m], θ [rad]).
        footprint : Footprint
            The outline at those poses.
        world_index : array_like of int
            ``(M,)`` the world of each pose.
        state : WorldState
            The agents.
        robots : RobotBodies or None
            The robots (None: none).
        self_index : array_like of int or None
            ``(M,)`` which robot each pose is (never in contact with itself), −1 for none.

        Returns
        -------
        numpy.ndarray
            ``(M,)`` bool.
        """
        d = self.distances(poses, footprint, world_index, state, robots, self_index)
        return (d.obstacle <= 0.0) | (d.agent <= 0.0) | (d.robot <= 0.0)

    def distances(
        self,
        poses: ArrayLike,
        footprint,
        world_index: ArrayLike,
        state: WorldState,
        robots: RobotBodies | None = None,
        self_index: ArrayLike | None = None,
    ) -> Distances:
        """Least distances of a footprint at each pose to the static obstacles, the agents
        and the other robots, with the nearest agent and its velocity (for the metrics
        ``min_obstacle_distance_m``, ``min_agent_distance_m`` and ``collision_at_fault``).

        Parameters
        ----------
        poses : array_like
            ``(M, 3)`` robot poses.
        footprint : Footprint
            The outline at those poses.
        world_index : array_like of int
            ``(M,)`` the world of each pose.
        state : WorldState
            The agents.
        robots : RobotBodies or None
            The robots (None: none).
        self_index : array_like of int or None
            ``(M,)`` which robot each pose is, −1 for none.

        Returns
        -------
        Distances
        """
        from wheelbase.planning import Footprint
        from wheelbase.world.contact import contact_kernel
        from wheelbase.world.statics import nearest_obstacle_points

        if not isinstance(footprint, Footprint):
            raise InputError(f"footprint must be a Footprint (got {type(footprint).__name__})")
        self._check_state(state)
        robots = self._robots(robots, state.batch)
        poses, world_index, self_index = self._rows("poses", poses, world_index, self_index,
                                                    state, robots)  # fmt: skip
        agent_d, agent_i, robot_d, robot_i = contact_kernel(
            poses, footprint.polygon, world_index, self_index, state.position,
            self.agent_radius, robots.pose, robots.polygon,
        )  # fmt: skip
        m = len(poses)
        if self.obstacle_world is None:
            obstacle = np.full(m, np.inf)
            direction = np.zeros((m, 2))
        else:
            obstacle = self.obstacle_world.footprint_clearance(footprint, poses)
            _, wx, wy = nearest_obstacle_points(self.statics, poses[:, :2].copy())
            direction = _unit(np.column_stack([wx, wy]) - poses[:, :2])
        has = agent_i >= 0
        rows = np.where(has, agent_i, 0)
        velocity = np.where(has[:, None], state.velocity[world_index, rows], 0.0) if (
            state.agents) else np.zeros((m, 2))  # fmt: skip
        centre = state.position[world_index, rows] if state.agents else poses[:, :2]
        agent_direction = np.where(has[:, None], _unit(centre - poses[:, :2]), 0.0)
        return Distances(obstacle, direction, agent_d, agent_i, velocity, agent_direction,
                         robot_d, robot_i)  # fmt: skip

    def agent_truth(self, state: WorldState) -> tuple[np.ndarray, np.ndarray]:
        """The agents' true positions and velocities, for scoring a tracker.

        Parameters
        ----------
        state : WorldState

        Returns
        -------
        position : numpy.ndarray
            ``(B, A, 2)`` [m] (a copy).
        velocity : numpy.ndarray
            ``(B, A, 2)`` [m/s] (a copy).
        """
        self._check_state(state)
        return state.position.copy(), state.velocity.copy()


def _unit(vectors: np.ndarray) -> np.ndarray:
    norm = np.hypot(vectors[:, 0], vectors[:, 1])[:, None]
    return np.divide(vectors, norm, out=np.zeros_like(vectors), where=norm > 0)


def _seeds(seeds: ArrayLike) -> np.ndarray:
    array = np.asarray(seeds)
    if array.ndim == 0:
        array = array[None]
    if array.ndim != 1 or array.size == 0 or not np.issubdtype(array.dtype, np.integer):
        raise InputError(f"seeds must be a non-empty 1-D array of integers (got {seeds!r})"[:200])
    return np.ascontiguousarray(array.astype(np.int64))


def _keep_clear(keep: ArrayLike | None, batch: int) -> np.ndarray:
    if keep is None:
        return np.zeros((batch, 0, 3))
    array = as_float_array("keep_clear", keep, 3, min_ndim=2, max_ndim=3)
    if array.ndim == 2:
        array = np.broadcast_to(array, (batch, *array.shape))
    if array.shape[0] != batch:
        raise InputError(f"keep_clear must have one row per world ({array.shape[0]} for {batch})")
    if np.any(array[..., 2] < 0):
        raise InputError("keep_clear radii must be >= 0 m")
    return np.ascontiguousarray(array)


def _indices(name: str, value: ArrayLike, m: int, limit: int, allow_none: bool = False):
    from wheelbase.world.cast import within

    low = -1 if allow_none else 0
    if isinstance(value, np.ndarray) and value.dtype == np.int64 and value.shape == (m,) and (
        value.flags.c_contiguous and within(value, low, limit)):  # fmt: skip
        return value  # (the common case, checked in one compiled call)
    array = np.asarray(value)
    if array.ndim == 0:
        array = np.full(m, array)
    if array.shape != (m,) or not np.issubdtype(array.dtype, np.integer):
        raise InputError(f"{name} must be {m} integers (got {value!r})"[:200])
    if m and (array.min() < low or array.max() >= limit):
        raise InputError(f"{name} must lie in [{low}, {limit}) (got {array.min()}..{array.max()})")
    return np.ascontiguousarray(array.astype(np.int64))


def _shuffled(n: int, seed: int, group: int) -> np.ndarray:
    """A seeded random order of ``n`` items (counter-based: argsort of uniform keys)."""
    from wheelbase.world.counter_rng import STREAM_SPAWN
    from wheelbase.world.step import uniform_keys

    return np.argsort(uniform_keys(n, seed, STREAM_SPAWN, -(group + 1)), kind="stable")
