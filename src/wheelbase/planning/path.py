"""The planning result :class:`PlannedPath` and the curve paths of Reeds–Shepp and Dubins.

A :class:`PlannedPath` is a sequence of poses of the robot's **reference point** (the rear-axle
centre for car-like robots, the wheel-axle centre for differential drive) with, at each sample, the
driving direction (+1 forward, −1 reverse) and the steering curvature κ [1/m] (positive = turning
left when driving forward; a reverse move along κ turns the heading by −κ·|Δs|). Turning in
place (differential drive) has zero arc length and κ = ±inf.
"""

from __future__ import annotations

import csv
import itertools
import math
from dataclasses import dataclass, field
from pathlib import Path as FilePath

import numpy as np
from numpy.typing import ArrayLike

from wheelbase._validate import as_float_array, positive
from wheelbase.errors import InputError
from wheelbase.geometry import wrap_angle

__all__ = ["CurvePath", "PlannedPath", "PlanningStats"]


@dataclass(frozen=True)
class PlanningStats:
    """Search statistics of a planner call.

    Parameters
    ----------
    expanded_nodes : int
        Nodes taken off the open list.
    planning_time_s : float
        Wall time of the search [s], compile time excluded.
    compile_time_s : float
        Numba compile (or cache-load) time spent in this call [s]; 0 after the first call.
    message : str
        Why the search stopped ("goal reached", "search space exhausted", …).
    """

    expanded_nodes: int = 0
    planning_time_s: float = 0.0
    compile_time_s: float = 0.0
    message: str = ""


@dataclass(frozen=True, eq=False)
class PlannedPath:
    """A planned path: poses with driving direction and curvature at each sample.

    Parameters
    ----------
    poses : numpy.ndarray
        ``(N, 3)`` poses ``(x, y, θ)`` [m, m, rad] of the reference point, world frame.
    directions : numpy.ndarray
        ``(N,)`` int8, +1 forward, −1 reverse: the direction of the motion that reaches each
        sample (sample 0 takes that of the first motion).
    curvatures : numpy.ndarray
        ``(N,)`` steering curvature [1/m] of that motion; ±inf for turning in place.
    arc_length : numpy.ndarray
        ``(N,)`` cumulative distance travelled [m] (unsigned), starting at 0.
    success : bool
        ``False`` for a failed search (then the arrays are empty).
    stats : PlanningStats
        Search statistics.
    """

    poses: np.ndarray
    directions: np.ndarray
    curvatures: np.ndarray
    arc_length: np.ndarray
    success: bool = True
    stats: PlanningStats = field(default_factory=PlanningStats)

    def __post_init__(self) -> None:
        poses = np.asarray(self.poses, dtype=np.float64).reshape(-1, 3)
        n = len(poses)
        for name in ("directions", "curvatures", "arc_length"):
            if np.shape(getattr(self, name)) != (n,):
                raise InputError(f"{name} must have shape ({n},) like poses")
        object.__setattr__(self, "poses", poses)
        object.__setattr__(self, "directions", np.asarray(self.directions, dtype=np.int8))
        object.__setattr__(self, "curvatures", np.asarray(self.curvatures, dtype=np.float64))
        object.__setattr__(self, "arc_length", np.asarray(self.arc_length, dtype=np.float64))

    @classmethod
    def failure(cls, stats: PlanningStats) -> PlannedPath:
        """An empty, unsuccessful path carrying the statistics of the failed search.

        Parameters
        ----------
        stats : PlanningStats
            Search statistics.

        Returns
        -------
        PlannedPath
        """
        empty = np.zeros(0)
        return cls(np.zeros((0, 3)), empty.astype(np.int8), empty, empty, False, stats)

    @classmethod
    def from_points(cls, points: ArrayLike, directions: ArrayLike | None = None) -> PlannedPath:
        """A path through points in the order of travel, e.g. for a path follower or MPPI.

        The heading at each point is the robot's along the segment that reaches it (reversed
        by π on a reverse segment; the first point takes the first segment's), the curvature
        the turn of that heading per metre around the point, the direction that of the segment
        reaching it.

        Parameters
        ----------
        points : array_like, shape (M, 2)
            Path points [m]; repeated consecutive points are dropped. At least two distinct.
        directions : array_like, shape (M − 1,), optional
            +1 (forward) or −1 (reverse) for each segment, in the order of ``points`` (before
            duplicates are dropped); default all +1.

        Raises
        ------
        InputError
            Fewer than two distinct points, a bad shape, non-finite values, or directions that
            are not ±1.

        Examples
        --------
        >>> path = PlannedPath.from_points([[0, 0], [1, 0], [1, 1]])
        >>> path.length, path.directions.tolist(), round(float(path.poses[-1, 2]), 4)
        (2.0, [1, 1, 1], 1.5708)
        """
        xy = as_float_array("path points", points, 2, min_ndim=2, max_ndim=2)
        if directions is None:
            run = np.ones(max(xy.shape[0] - 1, 0))
        else:
            run = as_float_array("directions", directions, min_ndim=1, max_ndim=1)
            if run.shape[0] != xy.shape[0] - 1:
                raise InputError(
                    f"directions must have one entry per segment, {xy.shape[0] - 1} "
                    f"(got {run.shape[0]})"
                )
            if not np.all(np.isin(run, (-1.0, 1.0))):
                raise InputError("directions must be +1 (forward) or -1 (reverse)")
        keep = np.ones(xy.shape[0], bool)
        if xy.shape[0] > 1:
            keep[1:] = np.hypot(*np.diff(xy, axis=0).T) > 1e-12
        xy, run = xy[keep], (run[keep[1:]] if run.size else run)
        if xy.shape[0] < 2:
            raise InputError(
                f"a path needs at least two distinct points (got {xy.shape[0]} distinct)"
            )
        chord = np.diff(xy, axis=0)
        lengths = np.hypot(chord[:, 0], chord[:, 1])
        travel = np.arctan2(chord[:, 1], chord[:, 0])
        heading = np.where(run > 0, travel, travel + np.pi)
        # turn of the travel heading per metre between the chords around each point; a reverse
        # move turns the robot by -kappa*ds, so its steering curvature is the opposite
        kappa = np.zeros(xy.shape[0])
        turn = wrap_angle(np.diff(travel)) / (0.5 * (lengths[:-1] + lengths[1:]))
        same = run[1:] == run[:-1]
        kappa[1:-1] = np.where(same, turn * run[1:], 0.0)
        kappa[-1] = kappa[-2] if xy.shape[0] > 2 else 0.0
        kappa[0] = kappa[1]
        poses = np.column_stack([xy, wrap_angle(np.concatenate([heading[:1], heading]))])
        direction = np.concatenate([run[:1], run]).astype(np.int8)
        return cls(poses, direction, kappa, np.concatenate([[0.0], np.cumsum(lengths)]))

    @property
    def points(self) -> np.ndarray:
        """The positions ``(N, 2)`` [m] of the poses."""
        return self.poses[:, :2]

    def distance(self, xy: ArrayLike) -> np.ndarray:
        """Distance [m] from points ``(..., 2)`` to the nearest point of the path.

        Parameters
        ----------
        xy : array_like, shape (..., 2)
            Points [m].
        """
        from wheelbase.polyline import distance_to_polyline

        return distance_to_polyline(xy, self.points)

    def __len__(self) -> int:
        return len(self.poses)

    @property
    def length(self) -> float:
        """Total distance travelled [m] (``inf`` for a failed search)."""
        if not self.success:
            return math.inf
        return float(self.arc_length[-1]) if len(self.arc_length) else 0.0

    @property
    def cusps(self) -> int:
        """Number of changes of driving direction."""
        moving = self.directions[1:][np.diff(self.arc_length) > 0] if len(self) > 1 else []
        return int(np.count_nonzero(np.diff(moving) != 0)) if len(moving) > 1 else 0

    @property
    def cusp_indices(self) -> np.ndarray:
        """Indices of the samples where the direction changes (the cusp poses)."""
        if len(self) < 2:
            return np.zeros(0, dtype=np.int64)
        change = np.nonzero(self.directions[1:] != self.directions[:-1])[0]
        return change

    def segments(self) -> list[slice]:
        """Slices of the samples between cusps (each slice includes both end samples).

        Returns
        -------
        list of slice
        """
        bounds = [0, *(int(i) for i in self.cusp_indices), len(self) - 1]
        return [slice(a, b + 1) for a, b in itertools.pairwise(bounds) if b > a]

    def to_csv(self, path: str | FilePath) -> FilePath:
        """Write ``s, x, y, theta, direction, curvature`` (SI units, θ in rad) to a CSV file.

        Parameters
        ----------
        path : str or pathlib.Path
            Output file.

        Returns
        -------
        pathlib.Path
        """
        path = FilePath(path)
        with path.open("w", newline="") as handle:
            writer = csv.writer(handle)
            writer.writerow(["s_m", "x_m", "y_m", "theta_rad", "direction", "curvature_1pm"])
            for s, (x, y, th), d, k in zip(
                self.arc_length, self.poses, self.directions, self.curvatures, strict=True
            ):
                writer.writerow(
                    [f"{s:.6f}", f"{x:.6f}", f"{y:.6f}", f"{th:.8f}", int(d), f"{k:.8g}"]
                )
        return path


@dataclass(frozen=True, eq=False)
class CurvePath:
    """A Reeds–Shepp or Dubins path: a start pose and a word of arcs and straight segments.

    Parameters
    ----------
    start : numpy.ndarray
        Start pose ``(x, y, θ)`` [m, m, rad].
    turning_radius : float
        Radius of every arc [m].
    word : str
        Segment letters with driving signs, e.g. ``"L+S+R+"`` or ``"L+R-L+"``.
    segment_types : numpy.ndarray
        ``(K,)`` int: +1 left arc, 0 straight, −1 right arc.
    segment_lengths : numpy.ndarray
        ``(K,)`` signed lengths [m]; negative = driven in reverse.
    """

    start: np.ndarray
    turning_radius: float
    word: str
    segment_types: np.ndarray
    segment_lengths: np.ndarray

    @property
    def length(self) -> float:
        """Total length [m]."""
        return float(np.sum(np.abs(self.segment_lengths)))

    @property
    def cusps(self) -> int:
        """Number of direction changes between non-empty segments."""
        signs = np.sign(self.segment_lengths[self.segment_lengths != 0])
        return int(np.count_nonzero(np.diff(signs) != 0))

    @property
    def end(self) -> np.ndarray:
        """End pose computed in closed form."""
        pose = np.array(self.start, dtype=np.float64)
        for kind, length in zip(self.segment_types, self.segment_lengths, strict=True):
            pose = _advance(pose, int(kind), float(length), self.turning_radius)
        return pose

    def sample(self, step: float = 0.1) -> PlannedPath:
        """Sample the path at arc-length spacing at most ``step``, including every segment end.

        Parameters
        ----------
        step : float
            Largest distance between samples [m], > 0.

        Returns
        -------
        PlannedPath
            Poses, driving directions, curvatures and arc length; the last pose is the end
            pose to rounding.
        """
        step = positive("step", step, "m")
        r = self.turning_radius
        poses = [np.array(self.start, dtype=np.float64)]
        dirs: list[int] = []
        curv: list[float] = []
        arc = [0.0]
        pose = poses[0]
        for kind, length in zip(self.segment_types, self.segment_lengths, strict=True):
            if length == 0.0:
                continue
            n = max(1, math.ceil(abs(length) / step - 1e-9))
            s = length * np.arange(1, n + 1) / n
            seg = _advance_many(pose, int(kind), s, r)
            poses.extend(seg)
            dirs.extend([1 if length > 0 else -1] * n)
            curv.extend([kind / r if kind else 0.0] * n)
            arc.extend(arc[-1] + np.abs(s))
            pose = seg[-1]
        if not dirs:
            dirs, curv = [1], [0.0]
        else:
            dirs.insert(0, dirs[0])
            curv.insert(0, curv[0])
        return PlannedPath(np.array(poses), np.array(dirs), np.array(curv), np.array(arc))


def _advance(pose: np.ndarray, kind: int, s: float, r: float) -> np.ndarray:
    return _advance_many(pose, kind, np.array([s]), r)[0]


def _advance_many(pose: np.ndarray, kind: int, s: np.ndarray, r: float) -> np.ndarray:
    """Poses after driving signed distances ``s`` [m] along one segment from ``pose``."""
    x, y, th = pose
    if kind == 0:
        out = np.stack([x + s * math.cos(th), y + s * math.sin(th), np.full_like(s, th)], -1)
    else:
        th1 = th + kind * s / r
        out = np.stack(
            [
                x + kind * r * (np.sin(th1) - math.sin(th)),
                y + kind * r * (math.cos(th) - np.cos(th1)),
                th1,
            ],
            -1,
        )
    out[:, 2] = wrap_angle(out[:, 2])
    return out
