"""The navigation task of ``wheelbase/Navigate-v0`` for N robots at once (private to the
environments; both :class:`~wheelbase.gym.NavigateEnv` and
:class:`~wheelbase.gym.NavigateVectorEnv` are this one batched task, with N = 1 or N).

Each robot drives on the map from a sampled start to a sampled goal. One step, for every
robot: the normalised action becomes the plant's command, :meth:`wheelbase.sim.Engine.step`
moves the robots (its command hook), and the new poses are judged by the engine's own rule
objects: :class:`~wheelbase.sim.Arrival` (the one arrival rule) and the footprint collision
check; then the lidar (:class:`~wheelbase.sensors.Lidar`) scans all N new poses in one call.

With ``world=`` (a scenario's ``world`` section, :func:`wheelbase.world.world_from_spec`) every
robot has a world of its own, seeded by its episode: obstacles off the map and agents that
move as the robot does, that the lidar sees (:meth:`wheelbase.world.World.cast`) and that the
robot collides with. The policy sees them through the lidar only; agents never spawn on the
episode's start or goal.

Observation (float32, flat, length ``beams + 5``)
    ``ranges / max_range`` (``beams`` values in [0, 1]; NaN readings below ``min_range`` read
    0), ``distance to goal / goal_scale`` (in [0, 1]; ``goal_scale`` is the map's diagonal),
    ``cos`` and ``sin`` of the goal's bearing in the body frame, and the true body twist
    ``u / max_speed`` and ``r / max_yaw_rate`` (clipped to [−1, 1]).
Action (float32, in [−1, 1]²)
    A differential drive or unicycle: ``(v, ω) = (a₀·max_speed, a₁·max_yaw_rate)``; a car
    (bicycle, rear-wheel bicycle, Ackermann): ``(v, δ) = (a₀·max_speed, a₁·max_steering)``.
    Reversing is allowed (a₀ < 0).
Reward (:class:`RewardWeights`)
    ``progress × (d_before − d_after)`` [per m of distance gained towards the goal]
    ``− time`` every step, ``+ arrival`` on arrival, ``− collision`` on a collision.
Termination
    ``terminated`` on arrival (within ``goal_tolerance`` of the goal by the arrival rule;
    with ``stop_at_goal`` also at rest) or on a collision of the footprint; ``truncated`` after
    ``max_episode_steps`` (``gymnasium.make`` and ``make_vec`` take it: :data:`EPISODE_STEPS`
    unless ``max_episode_steps=`` says otherwise).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields
from pathlib import Path
from typing import Any

import numpy as np

from wheelbase._validate import integer, nonnegative, positive
from wheelbase.errors import ConfigError, InputError, MapError
from wheelbase.geometry import wrap_angle
from wheelbase.planning import Footprint, OccupancyGrid
from wheelbase.sensors import Lidar
from wheelbase.sim import Arrival, Engine, EngineState, KinematicPlant

__all__ = ["EPISODE_STEPS", "ROOM_SIZE", "NavigateTask", "RewardWeights"]

EPISODE_STEPS = 300
"""Steps of an episode of ``wheelbase/Navigate-v0`` unless ``max_episode_steps`` says otherwise
(the registered spec's limit; 30 s at the default 0.1 s step)."""

ROOM_SIZE = 10.0
"""Side [m] of the walled empty room of ``map="empty"``."""
_ROOM_RESOLUTION = 0.05  # m/cell
_SAMPLE_TRIES = 200


@dataclass(frozen=True)
class RewardWeights:
    """Weights of the reward terms (all >= 0).

    Parameters
    ----------
    progress : float
        Reward per metre the distance to the goal shrank during the step [1/m].
    time : float
        Penalty every step.
    arrival : float
        Bonus on arrival.
    collision : float
        Penalty on a collision.
    """

    progress: float = 1.0
    time: float = 0.01
    arrival: float = 10.0
    collision: float = 10.0

    def __post_init__(self) -> None:
        for item in fields(self):
            object.__setattr__(
                self, item.name, nonnegative(f"reward {item.name}", getattr(self, item.name))
            )


class _ActionHook:
    """The engine's controller slot; never called: the agent's action is the command."""

    def __init__(self, names: tuple[str, ...]) -> None:
        self.command_names = names

    def __call__(self, t: float, measured: np.ndarray, reference: Any) -> np.ndarray:
        raise ConfigError("the navigation task passes the agent's action to Engine.step")


def _room(size: float) -> OccupancyGrid:
    cells = round(size / _ROOM_RESOLUTION)
    walls = np.pad(np.zeros((cells - 2, cells - 2), bool), 1, constant_values=True)
    return OccupancyGrid.from_array(walls, _ROOM_RESOLUTION)


def _grid(value: Any) -> OccupancyGrid:
    if isinstance(value, OccupancyGrid):
        return value
    if isinstance(value, str | Path):
        if str(value) == "empty":
            return _room(ROOM_SIZE)
        from wheelbase.planning.maps import load_map

        return load_map(value)
    raise ConfigError(
        f"map must be 'empty', a bundled map name, a map file or an OccupancyGrid "
        f"(got {type(value).__name__})"
    )


def _robot(spec: Any):
    from pydantic import ValidationError

    from wheelbase.runner import build_robot
    from wheelbase.scenario import RobotSpec

    if not isinstance(spec, RobotSpec):
        try:
            spec = RobotSpec.model_validate({} if spec is None else spec)
        except ValidationError as error:
            first = error.errors()[0]
            where = ".".join(str(part) for part in first["loc"])
            raise ConfigError(f"robot.{where}: {first['msg']}") from None
    return build_robot(spec)


class NavigateTask:
    """N robots on one map, each driving to its own goal (module docstring).

    Parameters
    ----------
    n : int
        Number of robots, >= 1.
    map : str, Path or OccupancyGrid
        ``"empty"`` (a walled 10 m × 10 m room), a bundled map name, a map file, or a grid.
    robot : dict or RobotSpec, optional
        The robot as a scenario's ``robot`` section (default: a differential drive).
    lidar : Lidar, optional
        The sensor (default: 60 beams over 360°, 5 m range, no noise).
    dt : float
        Control step [s].
    max_episode_steps : int or None
        Steps before an episode is truncated; None: never (a wrapper such as Gymnasium's
        ``TimeLimit`` cuts it).
    max_speed : float
        Speed at action a₀ = ±1 [m/s].
    max_yaw_rate : float
        Yaw rate at a₁ = ±1 of a differential drive [rad/s] (a car: its steering stop).
    goal_tolerance : float
        Arrival radius [m].
    stop_at_goal : bool
        Arrival also needs the robot at rest (the engine's rest speeds); default: reaching the
        goal region ends the episode.
    min_goal_distance : float
        Smallest start-to-goal distance of sampled episodes [m].
    clearance : float
        Extra distance [m] between a sampled pose's footprint circle and obstacles.
    rewards : RewardWeights, optional
        Weights of the reward terms.
    world : dict, optional
        A scenario's ``world`` section: obstacles off the map and agents, one world per
        robot (module docstring).
    """

    def __init__(
        self,
        n: int,
        map: Any = "empty",
        robot: Any = None,
        lidar: Lidar | None = None,
        dt: float = 0.1,
        max_episode_steps: int | None = EPISODE_STEPS,
        max_speed: float = 1.0,
        max_yaw_rate: float = 2.0,
        goal_tolerance: float = 0.3,
        stop_at_goal: bool = False,
        min_goal_distance: float = 1.0,
        clearance: float = 0.1,
        rewards: RewardWeights | None = None,
        world: Any = None,
    ) -> None:
        self.n = integer("num_envs", n, minimum=1)
        self.grid = _grid(map)
        self.robot = _robot(robot)
        self.lidar = Lidar(beams=60, max_range=5.0) if lidar is None else lidar
        if not isinstance(self.lidar, Lidar):
            raise ConfigError(f"lidar must be a wheelbase.sensors.Lidar (got {self.lidar!r})")
        self.dt = positive("dt", dt, "s")
        self.max_episode_steps = (
            None
            if max_episode_steps is None
            else integer("max_episode_steps", max_episode_steps, minimum=1)
        )
        self.max_speed = positive("max_speed", max_speed, "m/s")
        self.goal_tolerance = positive("goal_tolerance", goal_tolerance, "m")
        self.min_goal_distance = nonnegative("min_goal_distance", min_goal_distance, "m")
        self.rewards = RewardWeights() if rewards is None else rewards
        if not isinstance(self.rewards, RewardWeights):
            raise ConfigError(f"rewards must be RewardWeights (got {self.rewards!r})")
        robot = self.robot
        if robot.kind == "car":
            self.command_names = ("speed", "steering")
            self.action_scale = np.array([self.max_speed, robot.max_steering])
            self.max_yaw_rate = self.max_speed * math.tan(robot.max_steering) / robot.wheel_base
        else:
            self.command_names = ("v", "omega")
            self.max_yaw_rate = positive("max_yaw_rate", max_yaw_rate, "rad/s")
            self.action_scale = np.array([self.max_speed, self.max_yaw_rate])
        self.footprint = Footprint.rectangle(
            *robot.footprint, rear_axle_to_center=robot.center_offset
        )
        rest = {} if stop_at_goal else {
            "rest_speed": 2.0 * self.max_speed, "rest_yaw_rate": 2.0 * self.max_yaw_rate
        }  # fmt: skip
        self.arrival = Arrival(np.zeros(3), (self.goal_tolerance, math.pi), **rest)
        self.engine = Engine(
            KinematicPlant(robot.model, integrator="exact"),
            _ActionHook(self.command_names),
            None,
            dt=self.dt,
            # episodes end here, per robot; the engine's clock never does (it is stepped one
            # call at a time, never run to its limit)
            duration=1e15,
            max_steps=10**17,
        )
        # Where a reference point may be sampled: cells whose centre clears the footprint's
        # circle by ``clearance`` (the distance field is to occupied cell centres: + ½ cell).
        margin = self.footprint.max_radius + nonnegative("clearance", clearance, "m")
        free = np.argwhere(self.grid.distance_field > margin + 0.5 * self.grid.resolution)
        if free.size == 0:
            raise MapError(
                f"the map has no free cell {margin:.3g} m (footprint radius + clearance) "
                "from every obstacle: no start or goal can be sampled"
            )
        self._free = free
        rows, cols = self.grid.shape
        self.goal_scale = float(math.hypot(rows, cols) * self.grid.resolution)
        self.observation_size = self.lidar.beams + 5
        self.world = None
        if world is not None:
            from wheelbase.world import world_from_spec

            self.world = world_from_spec(world, self.grid)
        self.world_state: Any = None
        self.state: EngineState | None = None
        self.goal = np.zeros((self.n, 3))
        self.elapsed = np.zeros(self.n, dtype=np.int64)
        self.distance = np.zeros(self.n)
        self.ranges = np.zeros((self.n, self.lidar.beams))

    # ------------------------------------------------------------------ sampling
    def sample(self, count: int, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
        """``count`` start poses and goals in free space, at least ``min_goal_distance`` apart.

        Parameters
        ----------
        count : int
            How many episodes.
        rng : numpy.random.Generator
            The environment's generator.
        """
        start = self._points(count, rng)
        goal = self._points(count, rng)
        for _ in range(_SAMPLE_TRIES):
            near = np.hypot(*(goal[:, :2] - start[:, :2]).T) < self.min_goal_distance
            if not near.any():
                return start, goal
            goal[near] = self._points(int(near.sum()), rng)
        raise MapError(
            f"no goal at least min_goal_distance = {self.min_goal_distance:g} m from the start "
            f"after {_SAMPLE_TRIES} tries: the free space is too small"
        )

    def _points(self, count: int, rng: np.random.Generator) -> np.ndarray:
        cells = self._free[rng.integers(len(self._free), size=count)]
        xy = self.grid.cell_to_world(cells)
        heading = rng.uniform(-math.pi, math.pi, count)
        return np.column_stack([xy, heading])

    # ------------------------------------------------------------------ episodes
    def restart(self, which: np.ndarray, start: np.ndarray, goal: np.ndarray) -> None:
        """Begin new episodes for robots ``which`` (indices or a mask) at ``start`` to ``goal``.

        Parameters
        ----------
        which : numpy.ndarray
            Robot indices (int) or a boolean mask of shape (N,).
        start, goal : numpy.ndarray, shape (M, 3)
            Start poses and goals [m, m, rad] of those robots.
        """
        index = np.flatnonzero(which) if np.asarray(which).dtype == bool else np.asarray(which)
        start = np.asarray(start, dtype=np.float64).reshape(-1, 3)
        goal = np.asarray(goal, dtype=np.float64).reshape(-1, 3)
        if start.shape[0] != index.size or goal.shape[0] != index.size:
            raise InputError(f"give {index.size} start poses and goals (got {start.shape[0]})")
        hit = self.grid.in_collision(self.footprint, start) | ~self.grid.contains(start[:, :2])
        if hit.any():
            raise InputError(f"start pose {start[np.argmax(hit)].tolist()} is in collision")
        if self.world is not None:
            self._restart_worlds(index, start, goal)
        fresh = self.engine.reset(start)
        if self.state is None:
            if index.size != self.n:
                raise InputError("the first reset starts every robot")
            self.state = fresh
        else:
            # The engine's state at t = 0 for these robots, spliced in row by row.
            for item in fields(EngineState):
                value = getattr(self.state, item.name)
                if isinstance(value, np.ndarray) and value.shape[:1] == (self.n,):
                    value[index] = getattr(fresh, item.name)
        goal = goal.copy()
        goal[:, 2] = wrap_angle(goal[:, 2])
        self.goal[index] = goal
        self.elapsed[index] = 0
        self.distance[index] = np.hypot(*(goal[:, :2] - start[:, :2]).T)
        self.ranges[index] = self._scan(start)

    def _restart_worlds(self, index: np.ndarray, start, goal) -> None:
        """New worlds for robots ``index``: agents placed clear of their start and goal, the
        world's seed drawn from where the episode starts (reproducible with the episode)."""
        from dataclasses import replace

        keep = np.stack(
            [np.column_stack([start[:, :2], np.full(len(start), self.footprint.max_radius + 0.1)]),
             np.column_stack([goal[:, :2], np.full(len(goal), self.footprint.max_radius + 0.1)])],
            axis=1,
        )  # fmt: skip
        seeds = np.abs(np.round(start[:, :2] * 1e6).astype(np.int64)).sum(axis=1) % (2**62)
        fresh = self.world.start(seeds, keep, ("the start", "the goal"))
        touching = self.world.collisions(
            start, self.footprint, np.arange(len(start)), fresh, None, None
        )
        if touching.any():
            raise InputError(
                f"start pose {start[np.argmax(touching)].tolist()} touches an obstacle of the world"
            )
        if self.world_state is None:
            if index.size != self.n:
                raise InputError("the first reset starts every robot")
            self.world_state = fresh
            return
        arrays = {}
        for item in fields(fresh):
            value = np.array(getattr(self.world_state, item.name))
            value[index] = getattr(fresh, item.name)
            arrays[item.name] = value
        self.world_state = replace(self.world_state, **arrays)

    def _scan(self, poses: np.ndarray, rng: np.random.Generator | None = None) -> np.ndarray:
        if self.world is not None and self.world_state is not None and len(poses) == self.n:
            sensor = self.lidar.sensor_poses(poses)
            true = self.world.cast(sensor, self.lidar.beam_angles, self.lidar.max_range,
                                   np.arange(self.n), self.world_state)  # fmt: skip
            ranges = self.lidar.readings(true, rng, noise=rng is not None)
        else:
            ranges = self.lidar.scan(self.grid, poses, rng, noise=rng is not None)
        return np.nan_to_num(ranges, nan=0.0).reshape(-1, self.lidar.beams)

    def step(
        self, action: np.ndarray, rng: np.random.Generator
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Step every robot by its normalised action ``(N, 2)``.

        Parameters
        ----------
        action : numpy.ndarray, shape (N, 2)
            Actions in [−1, 1] (checked by ``check_actions``).
        rng : numpy.random.Generator
            Randomness of the lidar noise.

        Returns
        -------
        reward : numpy.ndarray, shape (N,)
        arrived, collided, truncated : numpy.ndarray of bool, shape (N,)
        """
        if self.state is None:
            raise InputError("reset the task before stepping it")
        state, _ = self.engine.step(self.state, action * self.action_scale)
        pose = state.pose
        collided = self.grid.in_collision(self.footprint, pose)
        if self.world is not None:
            from wheelbase.world import RobotBodies

            c, s = np.cos(self.state.pose[:, 2]), np.sin(self.state.pose[:, 2])
            velocity = np.column_stack([c * self.state.twist[:, 0], s * self.state.twist[:, 0]])
            bodies = RobotBodies(self.state.pose[:, None], velocity[:, None], self.footprint)
            self.world_state = self.world.step(self.world_state, self.dt, bodies)
            collided |= self.world.collisions(
                pose, self.footprint, np.arange(self.n), self.world_state, None, None
            )
        arrived = self.arrival.within(pose, self.goal) & self.arrival.at_rest(state.twist)
        arrived &= ~collided
        distance = np.hypot(pose[:, 0] - self.goal[:, 0], pose[:, 1] - self.goal[:, 1])
        w = self.rewards
        reward = w.progress * (self.distance - distance) - w.time
        reward += w.arrival * arrived - w.collision * collided
        self.state, self.distance = state, distance
        self.elapsed += 1
        limit = self.max_episode_steps
        truncated = (
            np.zeros(self.n, dtype=bool)
            if limit is None
            else (self.elapsed >= limit) & ~(arrived | collided)
        )
        noisy = self.lidar.range_std > 0.0 or self.lidar.beam_model.z_hit < 1.0
        self.ranges = self._scan(pose, rng if noisy else None)
        return reward, arrived, collided, truncated

    def observation_bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """Lower and upper bounds ``(beams + 5,)`` float32 of one robot's observation."""
        size = self.observation_size
        low = np.full(size, -1.0, dtype=np.float32)
        low[: self.lidar.beams + 1] = 0.0  # ranges and the goal distance are >= 0
        return low, np.ones(size, dtype=np.float32)

    def observations(self) -> np.ndarray:
        """The observation ``(N, beams + 5)`` of every robot (module docstring), float32."""
        state = self.state
        pose, twist = state.pose, state.twist
        dx, dy = self.goal[:, 0] - pose[:, 0], self.goal[:, 1] - pose[:, 1]
        bearing = np.arctan2(dy, dx) - pose[:, 2]
        out = np.empty((self.n, self.observation_size), dtype=np.float32)
        beams = self.lidar.beams
        out[:, :beams] = self.ranges / self.lidar.max_range
        out[:, beams] = np.minimum(self.distance / self.goal_scale, 1.0)
        out[:, beams + 1] = np.cos(bearing)
        out[:, beams + 2] = np.sin(bearing)
        out[:, beams + 3] = np.clip(twist[:, 0] / self.max_speed, -1.0, 1.0)
        out[:, beams + 4] = np.clip(twist[:, 2] / self.max_yaw_rate, -1.0, 1.0)
        return out

    def draw(self, ax: Any, robots: Any = None) -> None:
        """Draw the map, the robots' footprints, their lidar rays and goals on ``ax``.

        Parameters
        ----------
        ax : matplotlib.axes.Axes
            Where to draw.
        robots : iterable of int, optional
            Which robots (default: all).
        """
        from wheelbase.geometry import transform_points

        grid = self.grid
        x0, y0 = grid.origin
        rows, cols = grid.shape
        extent = (x0, x0 + cols * grid.resolution, y0, y0 + rows * grid.resolution)
        ax.imshow(grid.occupied, origin="lower", extent=extent, cmap="Greys", vmin=0, vmax=1.6,
                  interpolation="nearest")  # fmt: skip
        polygon = np.vstack([self.footprint.polygon, self.footprint.polygon[:1]])
        for i in range(self.n) if robots is None else robots:
            pose = self.state.pose[i]
            ends = self.lidar.endpoints(pose, self.ranges[i])
            ax.plot(*np.stack([np.broadcast_to(pose[:2], ends.shape), ends], 1).T,
                    color="tab:green", lw=0.4, alpha=0.5)  # fmt: skip
            ax.plot(*transform_points(pose, polygon).T, color="tab:blue", lw=1.2)
            ax.plot(*self.goal[i, :2], "*", color="tab:red", ms=10)
        ax.set_xlim(extent[0], extent[1])
        ax.set_ylim(extent[2], extent[3])
        ax.set_aspect("equal")
        ax.set_xticks([])
        ax.set_yticks([])


def check_actions(action: Any, n: int) -> np.ndarray:
    """Actions as float64 ``(n, 2)`` in [−1, 1], or an InputError naming the problem.

    Parameters
    ----------
    action : array_like, shape (n, 2) or (2,) for n = 1
        Normalised actions.
    n : int
        Number of robots.
    """
    array = np.asarray(action, dtype=np.float64)
    if array.size != 2 * n or array.shape[-1:] != (2,):
        expected = "(2,)" if n == 1 else f"({n}, 2)"
        raise InputError(f"action must have shape {expected} (got {array.shape})")
    array = array.reshape(n, 2)
    if not np.all(np.isfinite(array)):
        raise InputError(f"action must be finite (got {array[~np.isfinite(array).all(1)][0]})")
    if np.any(np.abs(array) > 1.0 + 1e-6):
        bad = array[np.any(np.abs(array) > 1.0 + 1e-6, axis=1)][0]
        raise InputError(
            f"action must lie in the action space [-1, 1]^2 (got {bad.tolist()}); wrap the "
            "environment in gymnasium.wrappers.ClipAction to clip a policy's raw output"
        )
    return np.clip(array, -1.0, 1.0)
