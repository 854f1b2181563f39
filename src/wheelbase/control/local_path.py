"""The local path window that the sampling controllers (MPPI, DWA) score their rollouts against.

A reference path (a :class:`~wheelbase.planning.PlannedPath` or points) is densified every
``spacing`` metres into :class:`PathTables`; its maximal runs of one direction are *sections*
joined at cusps. :class:`PathWindow` keeps, per robot, the progress along the path (the index
of the densified point nearest the robot, never moving backwards) and the active section, and
at each call cuts the window of the next ``reach`` metres of the active section, relative to
the robot (the critics then see the same small numbers wherever the robot is).

The next section becomes active within ``cusp_tolerance`` of the cusp, or once the robot has
crossed the line through the cusp square to the path while within ``goal_distance`` of it (as
the path followers of :mod:`wheelbase.control.path` switch): a car that cannot close the last
few centimetres sideways must not stall before the cusp.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from wheelbase.control.path import _as_polyline, path_key, same_path
from wheelbase.errors import ConfigError
from wheelbase.geometry import wrap_angle
from wheelbase.limits import MAX_PATH_POINTS

__all__ = ["PathTables", "PathWindow"]


class PathTables:
    """A reference path densified every ``spacing`` metres, with its sections.

    Parameters
    ----------
    points : numpy.ndarray, shape (P, 2)
        Path points [m] in the order of travel.
    directions : numpy.ndarray, shape (P - 1,)
        +1 (forward) or −1 (reverse) per segment.
    spacing : float
        Largest distance [m] between neighbouring densified points, > 0.
    end_heading : float, optional
        The goal's heading [rad] (a planned path knows it).

    Attributes
    ----------
    xy : numpy.ndarray, shape (Q, 2)
        Densified points [m].
    heading : numpy.ndarray, shape (Q,)
        Robot heading [rad] when travelling the path there (the chord's, reversed on a reverse
        section, or ``end_heading`` at the last point).
    direction : numpy.ndarray, shape (Q,)
        ±1 of the segment that reaches each point.
    arc : numpy.ndarray, shape (Q,)
        Arc length [m] from the first point.
    section : numpy.ndarray, shape (Q,)
        Index of the direction run of each point (a cusp belongs to the run that ends there).
    n_sections : int
        Number of direction runs.
    section_end : numpy.ndarray, shape (n_sections,)
        Index of the last point of each run.
    """

    def __init__(
        self,
        points: np.ndarray,
        directions: np.ndarray,
        spacing: float,
        end_heading: float | None = None,
    ) -> None:
        directions = np.asarray(directions)
        seg = np.diff(points, axis=0)
        length = np.hypot(seg[:, 0], seg[:, 1])
        counts = np.maximum(1.0, np.ceil(length / spacing - 1e-9))
        needed = float(np.sum(counts))
        if not needed <= MAX_PATH_POINTS:
            raise ConfigError(
                f"the reference path ({length.sum():.3g} m) at path_spacing = {spacing:g} m "
                f"needs {needed:.3g} points: more than {MAX_PATH_POINTS:.0e} "
                "(wheelbase.limits.MAX_PATH_POINTS); use a larger path_spacing"
            )
        counts = counts.astype(np.int64)
        # every segment cut into `count` equal steps: point k of segment i at k / count of it
        of = np.repeat(np.arange(seg.shape[0]), counts)
        k = np.arange(of.size) - np.repeat(np.cumsum(counts) - counts, counts) + 1
        frac = k / counts[of]
        seg_heading = np.arctan2(seg[:, 1], seg[:, 0])
        robot_heading = np.where(directions > 0, seg_heading, seg_heading + math.pi)
        runs = np.concatenate([[0], np.cumsum(directions[1:] != directions[:-1])])
        start_arc = np.concatenate([[0.0], np.cumsum(length)[:-1]])
        # The first point takes the values of the first segment.
        self.xy = np.concatenate([points[:1], points[of] + frac[:, None] * seg[of]])
        heading = robot_heading[of]
        self.heading = np.asarray(wrap_angle(np.concatenate([heading[:1], heading])),
                                  dtype=np.float64)  # fmt: skip
        direction = np.asarray(directions, dtype=np.float64)[of]
        self.direction = np.concatenate([direction[:1], direction])
        self.arc = np.concatenate([[0.0], start_arc[of] + frac * length[of]])
        section = runs[of].astype(np.int64)
        self.section = np.concatenate([section[:1], section])
        run = int(runs[-1])
        if end_heading is not None:
            # The goal's heading (a planned path knows it): the last chord's direction differs
            # from it by half the turn of the last segment.
            self.heading[-1] = float(wrap_angle(end_heading))
        # A cusp point belongs to the section that ends there.
        self.n_sections = run + 1
        self.section_end = np.array(
            [np.flatnonzero(self.section == k)[-1] for k in range(self.n_sections)]
        )


class PathWindow:
    """Progress along a reference path and the local window ahead (see the module docstring).

    Parameters
    ----------
    spacing : float
        Spacing [m] of the densified path, > 0.
    reach : float
        Length [m] of path the window holds ahead of the robot, > 0.
    goal_distance : float
        Distance [m] to the end of the active section under which the goal critics take over
        (the window's ``goal mode``), and within which a crossed cusp line switches section.
    cusp_tolerance : float
        Distance [m] to a cusp at which the next section becomes active.

    Attributes
    ----------
    window_points : int
        Points in each window (the reach, cut to the path's length).
    section : int
        The active section.
    """

    def __init__(
        self, spacing: float, reach: float, goal_distance: float, cusp_tolerance: float
    ) -> None:
        self.spacing = spacing
        self.goal_distance = goal_distance
        self.cusp_tolerance = cusp_tolerance
        self._reach = reach
        self._reach_points = math.ceil(min(reach / spacing, 1e12)) + 1
        self.window_points = self._reach_points
        self._tables: tuple[object, PathTables, tuple] | None = None
        self._anchor = np.zeros(2)
        self.reset()

    def reset(self) -> None:
        """Forget the progress along the path (the tables of the last path are kept)."""
        self._progress: int | None = None
        self.section = 0

    def tables(self, reference: Any) -> PathTables:
        """The tables of ``reference``, made once per path.

        The path is known by its content, not by the object: a caller that builds a fresh array
        on every call keeps its progress along the path (and its cusp section).

        Parameters
        ----------
        reference : PlannedPath or array_like (M, 2)
            The reference path.

        Returns
        -------
        PathTables
        """
        if self._tables is not None and self._tables[0] is reference:
            return self._tables[1]
        line = _as_polyline(reference)
        key = path_key(line, reference)
        if self._tables is not None and same_path(self._tables[2], key):
            self._tables = (reference, self._tables[1], self._tables[2])
            return self._tables[1]
        points = np.asarray(line.points)
        self._anchor = points[0].copy()  # the tables' origin: their numbers stay small
        tables = PathTables(points - self._anchor, np.asarray(line.directions), self.spacing,
                            key[2])  # fmt: skip
        self._tables = (reference, tables, key)
        # The window holds `reach` metres of path, however finely the path was sampled (a
        # Hybrid A* path every 0.025 m gave half the reach at 0.05 m spacing, and the robot
        # never went faster than half its top speed): as many points as the densest stretch
        # needs, cut at the reach in window(). Never more points than the path (a huge dt
        # reaches 1e6 m ahead).
        arc = tables.arc
        ahead = np.searchsorted(arc, arc + self._reach, side="right") - np.arange(len(arc))
        self.window_points = int(min(max(self._reach_points, int(ahead.max())), len(arc) + 1))
        self.reset()
        return tables

    def last_section(self, tables: PathTables) -> bool:
        """Whether the active section is the path's last.

        Parameters
        ----------
        tables : PathTables
            The path's tables.

        Returns
        -------
        bool
        """
        return self.section == tables.n_sections - 1

    def window(self, pose: np.ndarray, tab: PathTables) -> tuple[np.ndarray, np.ndarray]:
        """Advance the progress to ``pose`` and cut the window ahead.

        Parameters
        ----------
        pose : numpy.ndarray, shape (3,)
            The robot's pose (x [m], y [m], θ [rad]).
        tab : PathTables
            The path's tables (from :meth:`tables`).

        Returns
        -------
        window : numpy.ndarray, shape (M, 4)
            (x [m], y [m], heading [rad], arc length [m] from its first point), positions
            relative to the robot.
        info : numpy.ndarray, shape (7,)
            (goal mode 0/1, section end x, y [m] relative to the robot, its heading [rad], its
            direction ±1, distance left to it [m], 0: a slot for the caller's collision
            relief [m]).
        """
        rel = pose[:2] - self._anchor  # the robot in the tables' frame
        end = int(tab.section_end[self.section])
        start = 0 if self.section == 0 else int(tab.section_end[self.section - 1])
        if self._progress is None:
            lo, hi = start, end + 1
        else:
            lo = max(start, self._progress - 10)
            hi = min(end + 1, self._progress + 4 * min(self._reach_points, len(tab.arc) + 1))
        d2 = np.sum((tab.xy[lo:hi] - rel) ** 2, axis=1)
        index = lo + int(np.argmin(d2))
        if self._progress is None:
            # First call: the earliest point about as near as the nearest one (a closed path
            # starts where it ends: begin at its start, not at its end).
            near = np.sqrt(d2) <= np.sqrt(d2[index - lo]) + 0.1
            index = lo + int(np.argmax(near))
        self._progress = max(index, self._progress or 0) if self._progress is not None else index
        if not self.last_section(tab) and self._reached_cusp(pose, tab, end):
            self.section += 1
            self._progress = end
            return self.window(pose, tab)
        stop = min(self._progress + self.window_points, end + 1)
        # the last point within the reach (past it, the window repeats it, as at a section end)
        last = int(np.searchsorted(tab.arc, tab.arc[self._progress] + self._reach, "right")) - 1
        stop = min(stop, max(last, self._progress) + 1)
        idx = np.arange(self._progress, self._progress + self.window_points)
        idx = np.minimum(idx, stop - 1)
        along = tab.arc[idx] - tab.arc[self._progress]
        window = np.stack(
            [tab.xy[idx, 0] - rel[0], tab.xy[idx, 1] - rel[1], tab.heading[idx], along], -1
        )
        remaining = tab.arc[end] - tab.arc[self._progress]
        goal_mode = 1.0 if remaining <= self.goal_distance else 0.0
        info = np.array(
            [
                goal_mode,
                tab.xy[end, 0] - rel[0],
                tab.xy[end, 1] - rel[1],
                tab.heading[end],
                tab.direction[end],
                # distance left to the section's end: along the path, or straight if farther
                max(remaining, float(np.hypot(*(tab.xy[end] - rel)))),
                0.0,  # collision relief, set by the controller
            ]
        )
        return np.ascontiguousarray(window), info

    def _reached_cusp(self, pose: np.ndarray, tab: PathTables, end: int) -> bool:
        offset = pose[:2] - self._anchor - tab.xy[end]
        distance = float(np.hypot(*offset))
        if distance <= self.cusp_tolerance:
            return True
        if distance > self.goal_distance or end == 0:
            return False
        incoming = tab.xy[end] - tab.xy[end - 1]
        return float(offset @ incoming) >= 0.0
