"""The world beyond the map in the closed loop: the truth that steps with the robots.

:class:`Surroundings` joins a :class:`wheelbase.world.World` (static obstacles that are not on
the map, moving agents) to the engine's batch of robots. Robots are ordered world by world: with
``robots_per_world`` = R (a fleet of R robots; 1 for a single robot), robot i lives in world
``i // R`` as its robot ``i % R``, and every world's robots see each other. A batch of seeds is
one world per seed (the world of robot i takes the seed of robot ``(i // R)·R``).

Only three phases of the engine read the truth: the collision rule (a footprint touching an
obstacle, an agent or another robot), the lidar's ray cast, and the metrics recorded in the
log (least distances, contacts at fault). The controller and the estimator never do: they see
the sensors' readings (a test runs the same scenario with the world hidden from everything but
the sensors and gets the same log).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from wheelbase.errors import ConfigError, InputError

__all__ = ["AT_FAULT_SPEED", "DISCOMFORT_DISTANCE", "Surroundings", "world_metrics"]

AT_FAULT_SPEED = 0.05
"""A contact is the robot's fault when it moved towards the obstacle faster than this [m/s]
(issue 22's definition; slower, a walker ran into a robot at rest: ``struck_at_rest``)."""


@dataclass(frozen=True)
class Surroundings:
    """The world of a batch of robots (module docstring).

    Parameters
    ----------
    world : World
        Obstacles and agents (:mod:`wheelbase.world`).
    footprint : Footprint
        The robots' outline (all robots of a fleet share the scenario's robot).
    robots_per_world : int
        R, robots of one world (a fleet's size), >= 1.
    keep_clear : array_like, shape (P, 3)
        Discs (x [m], y [m], radius [m]) that no agent may overlap at the start: every robot's
        start and goals.
    keep_clear_labels : sequence of str, optional
        What each disc is, for messages (``"start of robot 1"``).
    """

    world: Any
    footprint: Any
    robots_per_world: int = 1
    keep_clear: Any = None
    keep_clear_labels: tuple[str, ...] | None = None

    def __post_init__(self) -> None:
        if isinstance(self.robots_per_world, bool) or int(self.robots_per_world) < 1:
            raise ConfigError(f"robots_per_world must be >= 1 (got {self.robots_per_world!r})")
        object.__setattr__(self, "robots_per_world", int(self.robots_per_world))
        if self.keep_clear is not None:
            keep = np.asarray(self.keep_clear, dtype=np.float64).reshape(-1, 3)
            object.__setattr__(self, "keep_clear", keep)

    @property
    def has_agents(self) -> bool:
        """Whether the world has moving agents (whose tracking the log scores)."""
        return self.world.agent_count > 0

    # ------------------------------------------------------------------ batch layout
    def _worlds(self, n: int) -> int:
        if n % self.robots_per_world:
            raise InputError(
                f"{n} robots do not make whole worlds of {self.robots_per_world} robots each"
            )
        return n // self.robots_per_world

    def bodies(self, poses: np.ndarray, twists: np.ndarray | None = None) -> Any:
        """Every robot as the world sees it: :class:`~wheelbase.world.RobotBodies` (B, R).

        Parameters
        ----------
        poses : numpy.ndarray, shape (N, 3)
            True poses of all robots [m, m, rad].
        twists : numpy.ndarray, shape (N, 3), optional
            Their body twists (u [m/s], v [m/s], r [rad/s]); default at rest.
        """
        from wheelbase.world import RobotBodies

        n = poses.shape[0]
        b, r = self._worlds(n), self.robots_per_world
        velocity = np.zeros((n, 2))
        if twists is not None:
            c, s = np.cos(poses[:, 2]), np.sin(poses[:, 2])
            velocity = np.column_stack(
                [c * twists[:, 0] - s * twists[:, 1], s * twists[:, 0] + c * twists[:, 1]]
            )
        return RobotBodies(poses.reshape(b, r, 3), velocity.reshape(b, r, 2), self.footprint)

    # ------------------------------------------------------------------ engine phases
    def start(self, seeds: np.ndarray, poses: np.ndarray) -> Any:
        """The worlds at t = 0 (agents placed by each world's seed).

        Parameters
        ----------
        seeds : numpy.ndarray of int64, shape (N,)
            The robots' seeds.
        poses : numpy.ndarray, shape (N, 3)
            Their start poses.
        """
        b = self._worlds(poses.shape[0])
        world_seeds = np.asarray(seeds, dtype=np.int64)[:: self.robots_per_world][:b]
        return self.world.start(world_seeds, self.keep_clear, self.keep_clear_labels)

    def step(self, state: Any, dt: float, poses: np.ndarray, twists: np.ndarray) -> Any:
        """The worlds ``dt`` later, the agents moving among the robots as they are now.

        Parameters
        ----------
        state : WorldState
            The worlds now.
        dt : float
            Step [s].
        poses, twists : numpy.ndarray, shape (N, 3)
            All robots' true poses and body twists now.
        """
        return self.world.step(state, dt, self.bodies(poses, twists))

    def collides(self, state: Any, poses: np.ndarray, index: np.ndarray) -> np.ndarray:
        """Which robots ``index`` touch a static obstacle, an agent or another robot.

        Parameters
        ----------
        state : WorldState
            The worlds now.
        poses : numpy.ndarray, shape (N, 3)
            All robots' true poses.
        index : numpy.ndarray of int, shape (M,)
            The robots to check.
        """
        index = np.asarray(index, dtype=np.int64)
        r = self.robots_per_world
        return np.asarray(
            self.world.collisions(
                poses[index], self.footprint, index // r, state, self.bodies(poses), index % r
            ),
            dtype=bool,
        )

    def caster(self, state: Any, poses: np.ndarray) -> Callable[..., np.ndarray]:
        """The lidar truth of this instant: ``cast(sensor_poses, beam_angles, max_range,
        index) -> ranges (M, K)`` (what :meth:`~wheelbase.sim.SensorSuite.read` takes).

        Parameters
        ----------
        state : WorldState
            The worlds at the instant of the scan.
        poses : numpy.ndarray, shape (N, 3)
            All robots' true poses then (the other robots are obstacles too).
        """
        bodies = self.bodies(poses)
        r = self.robots_per_world

        def cast(sensor_poses, beam_angles, max_range, index):
            index = np.asarray(index, dtype=np.int64)
            return self.world.cast(
                sensor_poses, beam_angles, max_range, index // r, state, bodies, index % r
            )

        return cast

    def signals(self, state: Any, poses: np.ndarray, twists: np.ndarray) -> dict:
        """What the log records of the world at each row, per robot ``(N,)``: the least
        distances [m] to a static obstacle, an agent and another robot, and the speed [m/s]
        at which the robot approaches the nearest of them (positive: closing in).

        Parameters
        ----------
        state : WorldState
            The worlds now.
        poses, twists : numpy.ndarray, shape (N, 3)
            All robots' true poses and body twists now.
        """
        n = poses.shape[0]
        r = self.robots_per_world
        index = np.arange(n, dtype=np.int64)
        bodies = self.bodies(poses, twists)
        found = self.world.distances(poses, self.footprint, index // r, state, bodies, index % r)
        velocity = bodies.velocity.reshape(n, 2)
        closing_agent = np.sum(velocity * found.agent_direction, axis=1)
        closing_obstacle = np.sum(velocity * found.obstacle_direction, axis=1)
        other = np.asarray(found.robot_index, dtype=np.int64)
        closing_robot = np.zeros(n)
        near = other >= 0
        if near.any():  # relative velocity along the line between the reference points
            j = (index[near] // r) * r + other[near]
            line = poses[j, :2] - poses[near, :2]
            line /= np.maximum(np.hypot(line[:, 0], line[:, 1]), 1e-12)[:, None]
            closing_robot[near] = np.sum((velocity[near] - velocity[j]) * line, axis=1)
        return {
            "world_obstacle_distance": np.asarray(found.obstacle, dtype=np.float64),
            "world_agent_distance": np.asarray(found.agent, dtype=np.float64),
            "world_robot_distance": np.asarray(found.robot, dtype=np.float64),
            "world_agent_closing": closing_agent,
            "world_obstacle_closing": closing_obstacle,
            "world_robot_closing": closing_robot,
        }

    def track_scores(self, state: Any, tracks: list, index: np.ndarray) -> np.ndarray:
        """How well robots ``index`` track the agents of their worlds now: per robot the sums
        of squared position [m²] and velocity [m²/s²] errors and the number of matched pairs,
        shape (M, 3) (:func:`wheelbase.perception.track_errors`: confirmed tracks matched to
        the true agents one to one, pairs farther than 1 m apart left out).

        Parameters
        ----------
        state : WorldState
            The worlds now.
        tracks : list of Tracks
            Each robot's tracks.
        index : numpy.ndarray of int, shape (M,)
            Which robots.
        """
        from wheelbase.perception import track_errors

        position, velocity = self.world.agent_truth(state)
        out = np.zeros((len(index), 3))
        for row, (i, found) in enumerate(zip(index, tracks, strict=True)):
            b = int(i) // self.robots_per_world
            errors = track_errors(found, position[b], velocity[b])
            out[row] = (errors.position_square_sum, errors.velocity_square_sum, errors.matches)
        return out

    def agents(self, state: Any) -> np.ndarray:
        """Every agent's (x, y, v_x, v_y) [m, m/s], shape (B, A, 4), for the log."""
        position, velocity = self.world.agent_truth(state)
        return np.concatenate([position, velocity], axis=-1).astype(np.float32)


DISCOMFORT_DISTANCE = 0.2
"""Closer than this [m] to a person is discomfort (CrowdNav, Chen et al. ICRA 2019)."""


def world_metrics(extras: dict, status: str, planar_speed_end: float, dt: np.ndarray) -> dict:
    """The world's figures of one robot's run (``metrics.json``), from its logged signals.

    Parameters
    ----------
    extras : dict of str to numpy.ndarray
        The robot's own rows of the log's extras (``world_*`` signals, shape (T,)).
    status : str
        Its final status.
    planar_speed_end : float
        Its planar speed [m/s] at its last row (a contact with the map: at fault when moving).
    dt : numpy.ndarray, shape (T,)
        Duration [s] of each row (0 for the last).

    Returns
    -------
    dict
        ``min_obstacle_distance_m``, ``min_agent_distance_m``, ``min_robot_distance_m`` (None
        where the world has none), ``discomfort_s`` (time within :data:`DISCOMFORT_DISTANCE`
        of an agent), ``collision_at_fault`` and ``struck_at_rest``.
    """

    def least(name: str) -> float | None:
        values = np.asarray(extras[name], dtype=np.float64)
        value = float(np.min(values)) if values.size else np.inf
        return value if np.isfinite(value) else None

    out = {
        "min_obstacle_distance_m": least("world_obstacle_distance"),
        "min_agent_distance_m": least("world_agent_distance"),
        "min_robot_distance_m": least("world_robot_distance"),
        "discomfort_s": float(
            np.sum(dt[np.asarray(extras["world_agent_distance"]) < DISCOMFORT_DISTANCE])
        ),
        "collision_at_fault": False,
        "struck_at_rest": False,
    }
    if status != "collision":
        return out
    last = {name: float(np.asarray(values)[-1]) for name, values in extras.items()}
    touching = [
        (last[f"world_{kind}_distance"], last[f"world_{kind}_closing"])
        for kind in ("obstacle", "agent", "robot")
        if np.isfinite(last[f"world_{kind}_distance"])
    ]
    closing = min(touching)[1] if touching and min(touching)[0] <= 1e-9 else planar_speed_end
    out["collision_at_fault"] = bool(closing > AT_FAULT_SPEED)
    out["struck_at_rest"] = not out["collision_at_fault"]
    return out
