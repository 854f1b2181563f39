"""Benchmark harness: localisation trials without the closed loop, a wandering robot, its
odometry, and a driver that feeds a lidar and :class:`~wheelbase.localization.AMCL`; the
kidnapped robot (:func:`kidnapped_run`). Used by ``benchmarks/sensors.py`` and the AMCL tests
(``tests/conftest.py`` puts this folder on the path); not part of the library.

:func:`wander` drives a point robot straight ahead at ``step`` metres per tick, turning in place
away from anything its lidar sees within ``clearance`` in front; the heading takes a small random
walk so that routes differ between seeds. Where a full turn finds no free heading (a room
smaller than the clearance), it stops with a :class:`~wheelbase.errors.PlanningError`.
:func:`noisy_odometry` integrates the true motion with multiplicative errors on each tick's
distance and turn and an additive turn error, as wheel odometry drifts. :func:`run_amcl`
replays a route: the filter updates whenever the odometry has moved enough, with a scan taken
at the true pose, and the error of the estimate is recorded.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from wheelbase._validate import as_rng, positive
from wheelbase.errors import MapError, PlanningError
from wheelbase.geometry import compose, wrap_angle
from wheelbase.localization.amcl import AMCL, AMCLState
from wheelbase.planning import OccupancyGrid
from wheelbase.sensors import Lidar

__all__ = ["AMCLRun", "clear_pose", "kidnapped_run", "noisy_odometry", "run_amcl", "wander"]


def wander(
    grid: OccupancyGrid,
    distance: float,
    rng: np.random.Generator | int | None = None,
    *,
    start: np.ndarray | None = None,
    step: float = 0.05,
    clearance: float = 0.8,
    turn_step: float = 0.15,
) -> np.ndarray:
    """True poses of a robot wandering through the free space.

    Parameters
    ----------
    grid : OccupancyGrid
        The map.
    distance : float
        Distance to travel [m], > 0.
    rng : numpy.random.Generator, int or None
        Randomness of the start (when not given) and of the heading's random walk.
    start : numpy.ndarray or None
        Start pose; default a random pose at least 0.6 m from obstacles.
    step : float
        Distance per tick [m].
    clearance : float
        Turn in place when an obstacle is this close ahead [m].
    turn_step : float
        Turn per tick while turning [rad].

    Returns
    -------
    numpy.ndarray, shape (T, 3)
        One pose per tick.

    Raises
    ------
    PlanningError
        Every heading is blocked: a full turn in place found no way ahead.
    """
    rng = as_rng(rng)
    distance = positive("distance", distance, "m")
    turn_step = positive("turn_step", turn_step, "rad")
    pose = clear_pose(grid, rng) if start is None else np.array(start, dtype=np.float64)
    probe = Lidar(beams=9, fov=math.radians(60.0), max_range=3.0)
    poses = [pose.copy()]
    travelled, turn = 0.0, 0.0
    full_turn = math.ceil(2.0 * math.pi / turn_step)  # ticks of turning that see every heading
    turning = 0
    while travelled < distance:
        if probe.scan(grid, pose, noise=False).min() < clearance:
            turning += 1
            if turning > full_turn:
                raise PlanningError(
                    f"wander: every heading from ({pose[0]:.2f}, {pose[1]:.2f}) m is blocked "
                    f"within clearance = {clearance:g} m (a full turn found no way ahead); give "
                    "a smaller clearance or a larger free space"
                )
            turn = turn or float(rng.choice([-1.0, 1.0]))
            pose[2] = wrap_angle(pose[2] + turn * turn_step)
        else:
            turn, turning = 0.0, 0
            pose[0] += step * math.cos(pose[2])
            pose[1] += step * math.sin(pose[2])
            pose[2] = wrap_angle(pose[2] + rng.normal(0.0, 0.02))
            travelled += step
        poses.append(pose.copy())
    return np.array(poses)


def clear_pose(
    grid: OccupancyGrid, rng: np.random.Generator | int | None = None, clearance: float = 0.6
) -> np.ndarray:
    """A random pose, any heading, on a cell more than ``clearance`` [m] from obstacles.

    Parameters
    ----------
    grid : OccupancyGrid
        The map.
    rng : numpy.random.Generator, int or None
        Source of randomness.
    clearance : float
        Least distance [m] from the cell to an obstacle (the distance field's).

    Returns
    -------
    numpy.ndarray, shape (3,)

    Raises
    ------
    MapError
        No cell is that far from the obstacles.
    """
    rng = as_rng(rng)
    cells = np.argwhere(grid.distance_field > clearance)
    if cells.size == 0:
        raise MapError(
            f"no free cell of the map is more than clearance = {clearance:g} m from an obstacle"
        )
    pose = np.array([*grid.cell_to_world(cells[rng.integers(len(cells))]), 0.0])
    pose[2] = rng.uniform(-math.pi, math.pi)
    return pose


def noisy_odometry(
    truth: np.ndarray,
    rng: np.random.Generator | int | None = None,
    *,
    distance_error: float = 0.02,
    turn_error: float = 0.02,
    turn_noise: float = 0.002,
) -> np.ndarray:
    """Odometry poses that drift from a true route, starting at the origin.

    Parameters
    ----------
    truth : numpy.ndarray, shape (T, 3)
        True poses, one per tick.
    rng : numpy.random.Generator, int or None
        Randomness of the errors.
    distance_error : float
        Standard deviation of the relative error of each tick's distance.
    turn_error : float
        Standard deviation of the relative error of each tick's turn.
    turn_noise : float
        Standard deviation of an additive turn error per tick [rad].

    Returns
    -------
    numpy.ndarray, shape (T, 3)
        Odometry poses in the odometry frame (the first is (0, 0, 0)).
    """
    rng = as_rng(rng)
    step = np.diff(truth, axis=0)
    dist = np.hypot(step[:, 0], step[:, 1]) * (1.0 + rng.normal(0.0, distance_error, len(step)))
    turn = wrap_angle(step[:, 2]) * (1.0 + rng.normal(0.0, turn_error, len(step)))
    turn += rng.normal(0.0, turn_noise, len(step))
    heading = np.concatenate([[0.0], np.cumsum(turn)])
    mid = heading[:-1] + 0.5 * turn
    x = np.concatenate([[0.0], np.cumsum(dist * np.cos(mid))])
    y = np.concatenate([[0.0], np.cumsum(dist * np.sin(mid))])
    return np.column_stack([x, y, wrap_angle(heading)])


@dataclass(frozen=True)
class AMCLRun:
    """Errors of :func:`run_amcl` at each filter update.

    Attributes
    ----------
    travelled : numpy.ndarray, shape (U,)
        Distance driven [m] at each update.
    error : numpy.ndarray, shape (U,)
        Position error [m] of the estimate.
    heading_error : numpy.ndarray, shape (U,)
        Heading error [rad].
    clusters : numpy.ndarray, shape (U,)
        Clusters of particles.
    particles : numpy.ndarray, shape (U,)
        Particles after the update.
    injected : numpy.ndarray, shape (U,)
        Random particles injected by recovery.
    tick : numpy.ndarray, shape (U,)
        Tick of the route at each update.
    state : AMCLState
        The final belief.
    """

    travelled: np.ndarray
    error: np.ndarray
    heading_error: np.ndarray
    clusters: np.ndarray
    particles: np.ndarray
    injected: np.ndarray
    tick: np.ndarray
    state: AMCLState

    def converged_after(self, tolerance: float = 0.2) -> float:
        """Distance [m] driven before the error stayed below ``tolerance`` to the end.

        Parameters
        ----------
        tolerance : float
            Position error [m].

        Returns
        -------
        float
            ``inf`` if the last error is above it.
        """
        return self._settled(self.travelled, tolerance)

    def converged_at_tick(self, tolerance: float = 0.2) -> float:
        """Tick of the route from which the error stayed below ``tolerance`` (``inf`` if never).

        Parameters
        ----------
        tolerance : float
            Position error [m].

        Returns
        -------
        float
        """
        return self._settled(self.tick, tolerance)

    def _settled(self, at: np.ndarray, tolerance: float) -> float:
        """``at`` (one entry per update) where the error fell below ``tolerance`` for good."""
        above = np.flatnonzero(self.error >= tolerance)
        if above.size == 0:
            return float(at[0]) if at.size else math.inf
        if above[-1] == self.error.size - 1:
            return math.inf
        return float(at[above[-1] + 1])


def run_amcl(
    amcl: AMCL,
    lidar: Lidar,
    truth: np.ndarray,
    odometry: np.ndarray,
    state: AMCLState,
    rng: np.random.Generator | int | None = None,
    *,
    start: int = 0,
) -> AMCLRun:
    """Replay a route through the filter (module docstring).

    Parameters
    ----------
    amcl : AMCL
        The filter (its grid is the world the scans are taken in).
    lidar : Lidar
        The simulated lidar.
    truth : numpy.ndarray, shape (T, 3)
        True poses.
    odometry : numpy.ndarray, shape (T, 3)
        Odometry poses at the same ticks.
    state : AMCLState
        Initial belief.
    rng : numpy.random.Generator, int or None
        Randomness of the scans and of the filter.
    start : int
        First tick to replay.

    Returns
    -------
    AMCLRun
    """
    rng = as_rng(rng)
    assert amcl.grid is not None
    travelled, records = 0.0, []
    for k in range(start + 1, truth.shape[0]):
        travelled += float(np.hypot(*(truth[k, :2] - truth[k - 1, :2])))
        if not amcl.needs_update(state, odometry[k]):
            continue
        scan = lidar.scan(amcl.grid, truth[k], rng)
        state, info = amcl.update(state, odometry[k], rng, scan=scan)
        estimate = amcl.estimate(state)
        error = float(np.hypot(*(estimate.pose[:2] - truth[k, :2])))
        heading = float(abs(wrap_angle(estimate.pose[2] - truth[k, 2])))
        records.append(
            (travelled, error, heading, len(estimate.clusters), info.particles, info.injected, k)
        )
    table = np.array(records, dtype=np.float64).reshape(-1, 7)
    return AMCLRun(*table.T, state=state)


def kidnapped_run(
    amcl: AMCL,
    lidar: Lidar,
    rng: np.random.Generator | int | None = None,
    *,
    start: ArrayLike = (2.0, 2.0, 0.0),
    teleport: ArrayLike = (15.0, 14.0, math.pi),
    before: float = 4.0,
    after: float = 15.0,
) -> tuple[AMCLRun, AMCLRun]:
    """Track a wandering robot from a known pose, then teleport it; its odometry notices nothing.

    Parameters
    ----------
    amcl : AMCL
        The filter (with recovery enabled to recover).
    lidar : Lidar
        The simulated lidar.
    rng : numpy.random.Generator, int or None
        Randomness of the routes, the odometry, the scans and the filter.
    start : array_like, shape (3,)
        True (and initially believed) pose.
    teleport : array_like, shape (3,)
        Pose the robot is carried to.
    before, after : float
        Distances [m] driven before and after the teleport.

    Returns
    -------
    tracked, kidnapped : AMCLRun
        The runs before and after the teleport.
    """
    rng = as_rng(rng)
    assert amcl.grid is not None
    first = wander(amcl.grid, before, rng, start=np.asarray(start, dtype=np.float64))
    state = amcl.initial_state(first[0], np.diag([0.1, 0.1, 0.05]) ** 2, (0, 0, 0), rng)
    tracked = run_amcl(amcl, lidar, first, noisy_odometry(first, rng), state, rng)
    second = wander(amcl.grid, after, rng, start=np.asarray(teleport, dtype=np.float64))
    odometry = compose(tracked.state.odom, noisy_odometry(second, rng))
    return tracked, run_amcl(amcl, lidar, second, odometry, tracked.state, rng)
