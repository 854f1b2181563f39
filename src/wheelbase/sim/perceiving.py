"""Perception in the closed loop: each robot's lidar scans become its costmap and its tracks.

:class:`PerceptionSuite` holds the constant part (the layered costmap built from the map, the
lidar, the tracker's parameters); the engine keeps the evolving part, a
:class:`PerceptionState` of every robot, in :attr:`~wheelbase.sim.EngineState.perception`.
After each step in which the lidar was read, every robot's scan updates its costmap (marks and
ray-traced clearing, re-inflation) and its tracker, both placed at the robot's *estimated*
pose: the robot does not know where it truly is. A controller that declares
``uses_perception`` is then called with its robot's :class:`~wheelbase.perception.LocalView`
(the master costmap, the tracks, the time).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

__all__ = ["PerceptionState", "PerceptionSuite"]


@dataclass(frozen=True)
class PerceptionState:
    """What every robot has made of its scans.

    Attributes
    ----------
    costmap : CostmapState
        The N robots' obstacle layers and master costs.
    trackers : tuple
        One tracker state per robot (None without a tracker).
    """

    costmap: Any
    trackers: tuple


@dataclass(frozen=True)
class PerceptionSuite:
    """Costmap and tracker of every robot of a batch (module docstring).

    Parameters
    ----------
    costmap : LayeredCostmap
        The constant part of a robot's costmap (the static layer is the map).
    lidar : Lidar
        The sensor whose scans are read (its mount and beam angles place the beams).
    tracker : TrackerSpec or None
        The tracker of obstacles off the map (None: costmap only).
    grid : OccupancyGrid or None
        The map, whose returns the tracker leaves out (needed with a tracker).
    """

    costmap: Any
    lidar: Any
    tracker: Any = None
    grid: Any = None

    def start(self, poses: np.ndarray) -> PerceptionState:
        """Every robot knows only the map at t = 0.

        Parameters
        ----------
        poses : numpy.ndarray, shape (N, 3)
            Start poses (one robot each).
        """
        from wheelbase.perception import TrackerState

        n = poses.shape[0]
        trackers = (None,) * n
        if self.tracker is not None:
            trackers = (TrackerState.initial(self.tracker),) * n  # frozen arrays: shared
        return PerceptionState(self.costmap.initial_state(n), trackers)

    def update(
        self,
        state: PerceptionState,
        t: float,
        readings: Any,
        estimates: np.ndarray,
        index: np.ndarray,
    ) -> PerceptionState:
        """The robots ``index`` have scanned at time ``t`` from their estimated poses.

        Parameters
        ----------
        state : PerceptionState
            Every robot's perception before the scans.
        t : float
            Time of the scans [s].
        readings : Readings
            The sensors' readings; ``readings.scan`` (M, beams) [m] (NaN in the blind zone).
        estimates : numpy.ndarray, shape (M, 3)
            The robots' estimated poses at the scan.
        index : numpy.ndarray of int, shape (M,)
            Which robots scanned.
        """
        from wheelbase.perception import update_costmap, update_tracker

        lidar = self.lidar
        sensor = lidar.sensor_poses(estimates)
        ranges = readings.scan
        costmap = update_costmap(
            self.costmap, state.costmap, sensor, lidar.beam_angles, ranges, lidar.max_range,
            np.asarray(index, dtype=np.int64),
        )  # fmt: skip
        trackers = state.trackers
        if self.tracker is not None:
            trackers = list(trackers)
            for row, i in enumerate(np.asarray(index)):
                trackers[int(i)] = update_tracker(
                    self.tracker, trackers[int(i)], t, sensor[row], lidar.beam_angles,
                    ranges[row], lidar.max_range, self.grid,
                )  # fmt: skip
            trackers = tuple(trackers)
        return PerceptionState(costmap, trackers)

    def view(self, state: PerceptionState, i: int, t: float) -> Any:
        """What robot ``i``'s controller sees at time ``t``: its master costmap and tracks.

        Parameters
        ----------
        state : PerceptionState
            Every robot's perception.
        i : int
            The robot.
        t : float
            Time [s].
        """
        from wheelbase.perception import LocalView

        return LocalView(self.costmap.master(state.costmap, i), self.tracks(state, i), t)

    def snapshot(self, state: PerceptionState, i: int) -> dict:
        """What robot ``i`` perceives, for drawing: the centres (M, 2) [m] of the cells its
        lidar marked (``marks``) and its confirmed tracks (K, 5) = (x, y, v_x, v_y, radius)
        (``tracks``), float32.

        Parameters
        ----------
        state : PerceptionState
            Every robot's perception.
        i : int
            The robot.
        """
        from wheelbase.perception import LETHAL

        res, (x0, y0) = self.costmap.resolution, self.costmap.origin
        rows, cols = np.nonzero(state.costmap.obstacle[i] == LETHAL)
        marks = np.column_stack([x0 + (cols + 0.5) * res, y0 + (rows + 0.5) * res])
        found = self.tracks(state, i)
        keep = np.asarray(found.confirmed, bool)
        tracks = np.column_stack([found.position[keep], found.velocity[keep], found.radius[keep]])
        return {"marks": marks.astype(np.float32), "tracks": tracks.astype(np.float32)}

    def tracks(self, state: PerceptionState, i: int) -> Any:
        """Robot ``i``'s tracks (:class:`~wheelbase.perception.Tracks`; none without a tracker).

        Parameters
        ----------
        state : PerceptionState
            Every robot's perception.
        i : int
            The robot.
        """
        from wheelbase.perception import Tracks

        tracker = state.trackers[i]
        return Tracks.empty() if tracker is None else tracker.tracks()
