"""The world's evolving state, the robots it meets, and what its distance queries return.

Plain frozen dataclasses of NumPy arrays, batch axis first: B worlds in lockstep, A agents
per world (every world has the same agents, placed by its own seed), R robots per world.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np

from wheelbase._validate import as_float_array
from wheelbase.errors import InputError

__all__ = ["Distances", "RobotBodies", "WorldState"]


def _frozen(array: np.ndarray) -> np.ndarray:
    """A read-only view (the caller's own array stays writeable)."""
    view = np.ascontiguousarray(array).view()
    view.setflags(write=False)
    return view


@dataclass(frozen=True, eq=False)
class WorldState:
    """The agents of B worlds at one instant (read-only arrays).

    Parameters
    ----------
    position : numpy.ndarray
        ``(B, A, 2)`` agent centres [m].
    velocity : numpy.ndarray
        ``(B, A, 2)`` velocities [m/s] (world frame).
    goal : numpy.ndarray
        ``(B, A, 2)`` current goals [m] (a ``straight`` agent's is its start).
    waypoint : numpy.ndarray
        ``(B, A)`` int64: index of the current waypoint in its group's loop (−1: none).
    goal_time : numpy.ndarray
        ``(B, A)`` seconds left before a new goal is drawn for a stuck agent.
    seed : numpy.ndarray
        ``(B,)`` int64: each world's seed (its random numbers are a hash of it, the step
        and the agent: :mod:`wheelbase.world.counter_rng`).
    step : numpy.ndarray
        ``(B,)`` int64: steps taken since :meth:`World.start`.
    """

    position: np.ndarray
    velocity: np.ndarray
    goal: np.ndarray
    waypoint: np.ndarray
    goal_time: np.ndarray
    seed: np.ndarray
    step: np.ndarray

    def __post_init__(self) -> None:
        # copies: a state never changes, even when the caller changes the arrays it gave
        for name in ("position", "velocity", "goal", "goal_time"):
            object.__setattr__(self, name, _frozen(np.array(getattr(self, name), np.float64)))
        for name in ("waypoint", "seed", "step"):
            object.__setattr__(self, name, _frozen(np.array(getattr(self, name), np.int64)))
        shape = self.position.shape
        if len(shape) != 3 or shape[2] != 2:
            raise InputError(f"position must have shape (B, A, 2) (got {shape})")
        for name in ("velocity", "goal"):
            if getattr(self, name).shape != shape:
                raise InputError(f"{name} must have the shape of position {shape}")
        for name in ("waypoint", "goal_time"):
            if getattr(self, name).shape != shape[:2]:
                raise InputError(f"{name} must have shape {shape[:2]}")
        for name in ("seed", "step"):
            if getattr(self, name).shape != shape[:1]:
                raise InputError(f"{name} must have shape {shape[:1]}")

    @classmethod
    def trusted(cls, position, velocity, goal, waypoint, goal_time, seed, step) -> WorldState:
        """A state from arrays a kernel just made (contiguous, of the right dtypes and
        shapes): made read-only, not checked again (``World.step`` is called per step).

        Parameters
        ----------
        position, velocity, goal, waypoint, goal_time, seed, step : numpy.ndarray
            As the class's fields.
        """
        state = object.__new__(cls)
        for name, value in (("position", position), ("velocity", velocity), ("goal", goal),
                            ("waypoint", waypoint), ("goal_time", goal_time), ("seed", seed),
                            ("step", step)):  # fmt: skip
            value.setflags(write=False)
            object.__setattr__(state, name, value)
        return state

    @property
    def batch(self) -> int:
        """Number of worlds B."""
        return self.position.shape[0]

    @property
    def agents(self) -> int:
        """Agents per world A."""
        return self.position.shape[1]

    def equals(self, other: WorldState) -> bool:
        """Whether every array of ``other`` equals this state's exactly.

        Parameters
        ----------
        other : WorldState
        """
        return all(
            np.array_equal(getattr(self, name), getattr(other, name))
            for name in ("position", "velocity", "goal", "waypoint", "goal_time", "seed", "step")
        )


@functools.cache
def _placeholder_footprint():
    """The outline of :meth:`RobotBodies.none` (no robot has it; built once)."""
    from wheelbase.planning import Footprint

    return Footprint.rectangle(0.2, 0.2)


@dataclass(frozen=True, eq=False)
class RobotBodies:
    """The controlled robots of each world, as the agents and the sensors see them.

    Parameters
    ----------
    pose : array_like
        ``(B, R, 3)`` poses (x [m], y [m], θ [rad]).
    velocity : array_like
        ``(B, R, 2)`` velocities of the reference points [m/s], world frame.
    footprint : Footprint or array_like
        The robots' outline: a :class:`~wheelbase.planning.Footprint` or its convex polygon
        ``(P, 2)`` [m] in the body frame.
    radius : float or None
        Circumscribed radius [m] (the disc that reactive agents avoid); default the largest
        distance of a vertex from the reference point.

    Examples
    --------
    >>> from wheelbase.planning import Footprint
    >>> bodies = RobotBodies(np.zeros((1, 1, 3)), np.zeros((1, 1, 2)),
    ...                      Footprint.rectangle(0.4, 0.4))
    >>> round(bodies.radius, 4)
    0.2828
    """

    pose: np.ndarray
    velocity: np.ndarray
    footprint: object
    radius: float | None = None

    def __post_init__(self) -> None:
        from wheelbase.planning import Footprint

        pose, velocity = self.pose, self.velocity
        plain = all(isinstance(x, np.ndarray) and x.dtype == np.float64 and x.ndim == 3
                    for x in (pose, velocity))  # fmt: skip
        if not (plain and pose.shape[2] == 3 and velocity.shape[2] == 2
                and np.isfinite(pose).all() and np.isfinite(velocity).all()):  # fmt: skip
            # (the engine passes clean arrays every step; anything else gets the full checks)
            pose = as_float_array("robots.pose", pose, 3, min_ndim=3, max_ndim=3)
            velocity = as_float_array("robots.velocity", velocity, 2, min_ndim=3, max_ndim=3)
        if velocity.shape[:2] != pose.shape[:2]:
            raise InputError(f"robots.velocity must have shape {(*pose.shape[:2], 2)} (got "
                             f"{velocity.shape})")  # fmt: skip
        fp = self.footprint if isinstance(self.footprint, Footprint) else Footprint(
            np.asarray(self.footprint, dtype=float))  # fmt: skip
        object.__setattr__(self, "pose", _frozen(pose))
        object.__setattr__(self, "velocity", _frozen(velocity))
        object.__setattr__(self, "footprint", fp)
        radius = fp.max_radius if self.radius is None else self.radius
        if not (isinstance(radius, (int, float)) and math.isfinite(radius) and radius > 0):
            raise InputError(f"robots.radius must be > 0 m (got {radius!r})")
        object.__setattr__(self, "radius", float(radius))

    @classmethod
    def none(cls, batch: int) -> RobotBodies:
        """No robots in any of ``batch`` worlds.

        Parameters
        ----------
        batch : int
            Number of worlds B.
        """
        return cls(np.zeros((batch, 0, 3)), np.zeros((batch, 0, 2)), _placeholder_footprint())

    @property
    def polygon(self) -> np.ndarray:
        """The footprint polygon ``(P, 2)`` [m], counter-clockwise, body frame."""
        return self.footprint.polygon


@dataclass(frozen=True, eq=False)
class Distances:
    """What :meth:`World.distances` measures for each robot pose (M rows).

    Attributes
    ----------
    obstacle : numpy.ndarray
        ``(M,)`` least distance [m] from the footprint to a static obstacle of the world (not
        the map); 0 in contact, ``inf`` when there is none.
    obstacle_direction : numpy.ndarray
        ``(M, 2)`` unit vector from the robot's reference point to the nearest point of the
        nearest static obstacle (zeros when there is none).
    agent : numpy.ndarray
        ``(M,)`` least distance [m] from the footprint to an agent's disc; 0 in contact.
    agent_index : numpy.ndarray
        ``(M,)`` int64: that agent (−1 when the world has none).
    agent_velocity : numpy.ndarray
        ``(M, 2)`` its velocity [m/s].
    agent_direction : numpy.ndarray
        ``(M, 2)`` unit vector from the robot's reference point to that agent's centre.
    robot : numpy.ndarray
        ``(M,)`` least distance [m] to another robot's footprint; ``inf`` when alone.
    robot_index : numpy.ndarray
        ``(M,)`` int64: that robot (−1 when alone).
    """

    obstacle: np.ndarray
    obstacle_direction: np.ndarray
    agent: np.ndarray
    agent_index: np.ndarray
    agent_velocity: np.ndarray
    agent_direction: np.ndarray
    robot: np.ndarray
    robot_index: np.ndarray
