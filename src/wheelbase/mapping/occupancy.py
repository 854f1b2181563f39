"""Occupancy grid mapping with known poses: log-odds updates along each beam.

The map holds, per cell, the log odds l = ln(p / (1 − p)) of being occupied (Thrun, Burgard and
Fox, *Probabilistic Robotics*, 2005, §9.2, Table 9.1, with l₀ = 0 for the prior p = 0.5). A
beam from the sensor at (x_s, y_s) along its direction to a return at range z walks the grid
cell by cell with the exact traversal of Amanatides and Woo (Eurographics 1987; the same walk as
:mod:`wheelbase.sensors.raycast`'s ``exact`` method): every cell it crosses before the return
gets the miss update l ← l + ln(p_miss / (1 − p_miss)) (p_miss = 0.4: l −0.405), the cell that
holds the return gets the hit update ln(p_hit / (1 − p_hit)) (p_hit = 0.7: l +0.847). A reading
at or beyond the sensor's maximum range (no return) or beyond ``max_range`` of the mapper
clears the cells up to ``max_range`` and marks none; NaN readings are skipped (and counted). Log
odds are clamped to [l_min, l_max] (−2, 3.5: p 0.12 … 0.97) so that a cell can change its mind
when the world does, as Cartographer's and GMapping's grids do.

Within one scan a cell is updated at most once, hits first: the returns of a scan are marked,
then the misses skip the cells marked (by this scan's stamp): grazing beams beside a wall's
return would otherwise erode it (Hess et al., ICRA 2016, §IV, do the same).

**The counting model** (``model="counting"``; the reflection maps of W. Burgard, D. Fox, H. Jans,
C. Matenar and S. Thrun, "Sonar-based mapping of large-scale mobile robot environments using
EM", ICML 1999, which GMapping's grid keeps): per cell the beams that ended in it (hits h) and
those that crossed it (misses m), every beam counted on its own, and the probability of a
reflection is the mean of its Beta(1, 1) posterior, p = (h + 1) / (h + m + 2); ``log_odds``
holds its logit ln((h + 1) / (m + 1)). One hit makes a cell occupied (p 0.67) and four misses
free (0.17), as in the log-odds model, but a cell that as many beams cross as end in stays
between the thresholds: unknown. That is the free cell before a wall's face when the face lies
on a cell boundary and the range noise puts half the returns short of it. Hits-first log odds
call that cell occupied as soon as one return of a scan falls in it (with a 360-beam, 1 cm-noise
lidar on the bundled maze, from the true poses: 502 of the 17,465 cells both maps know, 2.9 %,
all of them free cells beside a wall's face; counting: none), so the walls come out a cell
thicker on the side they were seen from. Grazing beams do erode a wall whose estimate is off by
centimetres more than they do with hits first; the counts hold the rest of the wall's cells.

The grid has the geometry of :class:`wheelbase.planning.OccupancyGrid` (row 0 at the lowest y,
column 0 at the lowest x, ``origin`` the world position of cell (0, 0)'s lower-left corner):
:meth:`LogOddsMap.to_grid` gives one, occupied where p > ``occupied_thresh`` (0.65, as
map_server), free where p < ``free_thresh`` (0.196) and unknown elsewhere, including cells never
observed.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numba
import numpy as np
from numpy.typing import ArrayLike

from wheelbase._validate import as_float_array, check_choice, finite, integer, positive
from wheelbase.errors import ConfigError, MapError
from wheelbase.geometry import compose
from wheelbase.limits import MAX_MAP_CELLS
from wheelbase.planning import OccupancyGrid

__all__ = ["MAP_MODELS", "LogOddsMap", "OccupancyMapper", "logit"]

MAP_MODELS: tuple[str, ...] = ("log_odds", "counting")
"""Names of the occupancy models of :class:`OccupancyMapper` (module docstring)."""


def logit(p: float) -> float:
    """ln(p / (1 − p)), the log odds of a probability in (0, 1)."""
    return math.log(p / (1.0 - p))


@dataclass(frozen=True)
class OccupancyMapper:
    """Parameters of log-odds mapping (module docstring).

    Parameters
    ----------
    resolution : float
        Cell side [m], > 0.
    p_hit : float
        Inverse sensor model at a return, in (0.5, 1).
    p_miss : float
        Inverse sensor model along the beam before the return, in (0, 0.5).
    l_min, l_max : float
        Clamping bounds of the log odds (l_min < 0 < l_max).
    max_range : float
        Readings beyond this [m] are used to clear up to it and mark nothing, > 0.
    occupied_thresh, free_thresh : float
        Probabilities above / below which :meth:`LogOddsMap.to_grid` calls a cell occupied
        / free (map_server's defaults).
    model : {"log_odds", "counting"}
        The log-odds updates with hits first (``p_hit``, ``p_miss``, ``l_min``, ``l_max``), or
        the counting model (module docstring), which ignores those four.
    """

    resolution: float = 0.05
    p_hit: float = 0.7
    p_miss: float = 0.4
    l_min: float = -2.0
    l_max: float = 3.5
    max_range: float = 30.0
    occupied_thresh: float = 0.65
    free_thresh: float = 0.196
    model: str = "log_odds"

    def __post_init__(self) -> None:
        check_choice("model", self.model, MAP_MODELS)
        positive("resolution", self.resolution, "m")
        positive("max_range", self.max_range, "m")
        for name, low, high in (
            ("p_hit", 0.5, 1.0),
            ("p_miss", 0.0, 0.5),
            ("occupied_thresh", 0.0, 1.0),
            ("free_thresh", 0.0, 1.0),
        ):
            value = finite(name, getattr(self, name))
            if not low < value < high:
                raise ConfigError(f"{name} must be in ({low:g}, {high:g}) (got {value:g})")
        if not finite("l_min", self.l_min) < 0.0 < finite("l_max", self.l_max):
            raise ConfigError(f"need l_min < 0 < l_max (got {self.l_min:g}, {self.l_max:g})")
        if self.free_thresh > self.occupied_thresh:
            raise ConfigError("free_thresh must be <= occupied_thresh")

    def empty_map(self, bounds: ArrayLike, *, max_cells: int = MAX_MAP_CELLS) -> LogOddsMap:
        """A map covering ``bounds`` = (x_min, x_max, y_min, y_max) [m], all unobserved.

        Parameters
        ----------
        bounds : array_like
            World rectangle to cover [m].
        max_cells : int
            Most cells allowed (default :data:`wheelbase.limits.MAX_MAP_CELLS`).

        Returns
        -------
        LogOddsMap

        Raises
        ------
        MapError
            If the rectangle needs more than ``max_cells`` cells.
        """
        x0, x1, y0, y1 = as_float_array("bounds", bounds, 4, max_ndim=1)
        r = self.resolution
        # cells on a lattice aligned to the resolution, so that maps of one log line up
        c0, r0 = math.floor(x0 / r), math.floor(y0 / r)
        cols = max(math.floor(x1 / r) - c0 + 1, 1)
        rows = max(math.floor(y1 / r) - r0 + 1, 1)
        max_cells = integer("max_cells", max_cells, 1)
        if rows * cols > max_cells:
            raise MapError(
                f"the map would need {rows} × {cols} = {rows * cols:.3g} cells at "
                f"{r:g} m: more than max_cells = {max_cells} (limits.MAX_MAP_CELLS); use a "
                "coarser resolution or a smaller max_range"
            )
        counts = np.zeros((2, rows, cols), np.float32) if self.model == "counting" else None
        return LogOddsMap(np.zeros((rows, cols), np.float32), np.full((rows, cols), -1, np.int32),
                          r, (c0 * r, r0 * r), 0, counts=counts)  # fmt: skip

    def integrate(
        self,
        grid: LogOddsMap,
        sensor_pose: ArrayLike,
        ranges: ArrayLike,
        angles: ArrayLike,
        sensor_max_range: float = math.inf,
    ) -> int:
        """Add one scan to the map in place (module docstring).

        Parameters
        ----------
        grid : LogOddsMap
            The map, updated in place (its arrays).
        sensor_pose : array_like, shape (3,)
            The sensor's world pose (x [m], y [m], θ [rad]).
        ranges : array_like, shape (B,)
            Readings [m]; NaN is skipped.
        angles : array_like, shape (B,)
            Beam directions in the sensor frame [rad].
        sensor_max_range : float
            The sensor's no-return reading [m]: readings at or beyond it mark nothing.

        Returns
        -------
        int
            Beams skipped (NaN readings).
        """
        pose = as_float_array("sensor_pose", sensor_pose, 3, max_ndim=1)
        ranges = np.ascontiguousarray(ranges, dtype=np.float64)
        angles = np.ascontiguousarray(angles, dtype=np.float64)
        if ranges.shape != angles.shape or ranges.ndim != 1:
            raise ConfigError(f"ranges {ranges.shape} and angles {angles.shape} must match")
        grid.scans += 1
        if self.model == "counting":
            if grid.counts is None:
                raise ConfigError("a counting mapper needs a map made by a counting mapper")
            return int(_count_scan(
                grid.log_odds, grid.counts, grid.stamp, grid.scans, grid.resolution,
                grid.origin[0], grid.origin[1], pose[0], pose[1], pose[2], ranges, angles,
                min(self.max_range, float(sensor_max_range)),
            ))  # fmt: skip
        return int(_integrate_scan(
            grid.log_odds, grid.stamp, grid.scans, grid.resolution, grid.origin[0],
            grid.origin[1], pose[0], pose[1], pose[2], ranges, angles,
            min(self.max_range, float(sensor_max_range)), logit(self.p_hit), logit(self.p_miss),
            self.l_min, self.l_max,
        ))  # fmt: skip

    def build(
        self,
        poses: ArrayLike,
        ranges: ArrayLike,
        angles: ArrayLike,
        *,
        mount: ArrayLike = (0.0, 0.0, 0.0),
        sensor_max_range: float = math.inf,
        margin: float = 1.0,
        max_cells: int = MAX_MAP_CELLS,
    ) -> LogOddsMap:
        """A map from scans taken at known robot poses.

        Parameters
        ----------
        poses : array_like, shape (N, 3)
            Robot poses.
        ranges : array_like, shape (N, B)
            Readings [m].
        angles : array_like, shape (B,)
            Beam directions in the sensor frame [rad].
        mount : array_like, shape (3,)
            Sensor pose in the robot frame.
        sensor_max_range : float
            The sensor's no-return reading [m].
        margin : float
            Free space around the beams' reach [m].
        max_cells : int
            Most cells allowed.

        Returns
        -------
        LogOddsMap
        """
        poses = as_float_array("poses", poses, 3, min_ndim=2, max_ndim=2)
        ranges = np.asarray(ranges, dtype=np.float64)
        if ranges.ndim != 2 or ranges.shape[0] != poses.shape[0]:
            raise ConfigError(f"ranges must have shape ({poses.shape[0]}, beams)")
        sensors = compose(poses, as_float_array("mount", mount, 3, max_ndim=1))
        reach = np.where(np.isfinite(ranges), np.minimum(ranges, self.max_range), 0.0)
        angle = sensors[:, 2, None] + np.asarray(angles)
        ex = sensors[:, 0, None] + reach * np.cos(angle)
        ey = sensors[:, 1, None] + reach * np.sin(angle)
        xs = np.concatenate([ex.ravel(), sensors[:, 0]])
        ys = np.concatenate([ey.ravel(), sensors[:, 1]])
        bounds = (xs.min() - margin, xs.max() + margin, ys.min() - margin, ys.max() + margin)
        grid = self.empty_map(bounds, max_cells=max_cells)
        skipped = 0
        for pose, scan in zip(sensors, ranges, strict=True):
            skipped += self.integrate(grid, pose, scan, angles, sensor_max_range)
        grid.skipped_beams += skipped
        return grid


@dataclass(eq=False)
class LogOddsMap:
    """A log-odds occupancy map (module docstring); its arrays change as scans are added.

    Attributes
    ----------
    log_odds : numpy.ndarray, shape (rows, cols)
        float32 log odds per cell (0: unobserved or even).
    stamp : numpy.ndarray, shape (rows, cols)
        int32 index of the last scan that updated the cell (−1: never observed).
    resolution : float
        Cell side [m].
    origin : tuple of float
        World (x, y) [m] of cell (0, 0)'s lower-left corner.
    scans : int
        Scans added.
    skipped_beams : int
        NaN readings skipped by :meth:`OccupancyMapper.build`.
    counts : numpy.ndarray or None, shape (2, rows, cols)
        The counting model's float32 hits and misses per cell (None for log odds).
    """

    log_odds: np.ndarray
    stamp: np.ndarray
    resolution: float
    origin: tuple[float, float]
    scans: int = 0
    skipped_beams: int = 0
    counts: np.ndarray | None = None

    @property
    def observed(self) -> np.ndarray:
        """Cells some beam has updated."""
        return self.stamp >= 0

    @property
    def probability(self) -> np.ndarray:
        """p = 1 − 1/(1 + exp(l)) per cell."""
        return 1.0 / (1.0 + np.exp(-self.log_odds.astype(np.float64)))

    def to_grid(self, occupied_thresh: float = 0.65, free_thresh: float = 0.196) -> OccupancyGrid:
        """The map as an :class:`~wheelbase.planning.OccupancyGrid`: occupied above
        ``occupied_thresh``, unknown between the thresholds or where never observed (and
        then, as map_server reads it, occupied for planning).

        Parameters
        ----------
        occupied_thresh, free_thresh : float
            Probability thresholds.

        Returns
        -------
        OccupancyGrid
        """
        p = self.probability
        occupied = (p > occupied_thresh) & self.observed
        unknown = ~occupied & ((p >= free_thresh) | ~self.observed)
        return OccupancyGrid(occupied | unknown, self.resolution, self.origin, unknown)


_BEHIND = 1e-2
"""Cells [cell sides] beyond the return where its cell is looked up: a return lies on the
surface of what it hit, and a beam that enters an occupied cell through its far side (going
towards −x or −y) would otherwise put the return on the free cell before it, as would a
range rounded short by 1e-5 m (a float32 ray cast at 8 m)."""


@numba.njit(cache=True, inline="always")
def _axis_walk(p, u):
    """Amanatides-Woo along one grid axis from the coordinate ``p`` [cells] in the direction
    ``u``: the start cell, its step (±1, or 0 along the other axis), the ray parameter of the
    first cell boundary and the one between boundaries [cells of travel]."""
    k = math.floor(p)
    if u > 0.0:
        return k, 1, (k + 1 - p) / u, 1.0 / u
    if u < 0.0:
        return k, -1, (k - p) / u, -1.0 / u
    return k, 0, math.inf, math.inf


@numba.njit(cache=True)
def _integrate_scan(lo, stamp, scan_id, res, x0, y0, sx, sy, st, ranges, angles, max_range,
                    l_hit, l_miss, l_min, l_max):  # fmt: skip
    """The log-odds update of one scan: hits first, then the misses of the cells not hit by
    this scan (Amanatides-Woo from the sensor's cell to the return's); returns NaN beams."""
    rows, cols = lo.shape
    inv = 1.0 / res
    px = (sx - x0) * inv
    py = (sy - y0) * inv
    skipped = 0
    n = ranges.shape[0]
    # hits
    for b in range(n):
        z = ranges[b]
        if z != z or z >= max_range:
            continue
        a = st + angles[b]
        zc = z * inv + _BEHIND
        j = math.floor(px + zc * math.cos(a))
        i = math.floor(py + zc * math.sin(a))
        if 0 <= i < rows and 0 <= j < cols and stamp[i, j] != scan_id:
            stamp[i, j] = scan_id
            v = lo[i, j] + l_hit
            lo[i, j] = l_max if v > l_max else v
    # misses: cross the cells up to the one holding the return (or up to max_range)
    inside = 0.0 <= px < cols and 0.0 <= py < rows
    for b in range(n):
        z = ranges[b]
        if z != z:
            skipped += 1
            continue
        hit = z < max_range
        reach = z * inv + _BEHIND if hit else max_range * inv
        a = st + angles[b]
        ux = math.cos(a)
        uy = math.sin(a)
        j, sj, tx, dtx = _axis_walk(px, ux)
        i, si, ty, dty = _axis_walk(py, uy)
        exit_x = (cols - px) / ux if ux > 0.0 else (-px / ux if ux < 0.0 else math.inf)
        exit_y = (rows - py) / uy if uy > 0.0 else (-py / uy if uy < 0.0 else math.inf)
        last = True  # the cell holding the end point of a no-return beam is crossed too
        if inside:
            # the walk leaves the map at min(exit_x, exit_y): stop before, no bounds checks
            leave = min(exit_x, exit_y)
            if leave <= reach:
                reach = leave
                last = False
            # branch-free steps (selects, not jumps): whether x or y comes next is a coin
            # toss along most beams, and a mispredicted jump per cell tripled the time
            while True:
                cx = tx < ty
                if (tx if cx else ty) >= reach:
                    break
                old = lo[i, j]
                v = old + l_miss
                v = l_min if v < l_min else v
                lo[i, j] = v if stamp[i, j] != scan_id else old
                stamp[i, j] = scan_id
                j += sj if cx else 0
                i += 0 if cx else si
                tx += dtx if cx else 0.0
                ty += 0.0 if cx else dty
            if not hit and last and 0 <= i < rows and 0 <= j < cols and stamp[i, j] != scan_id:
                stamp[i, j] = scan_id
                v = lo[i, j] + l_miss
                lo[i, j] = l_min if v < l_min else v
        else:  # the sensor is off the map: check every cell
            while True:
                t_next = tx if tx < ty else ty
                end = t_next >= reach
                if end and hit:
                    break
                if 0 <= i < rows and 0 <= j < cols and stamp[i, j] != scan_id:
                    stamp[i, j] = scan_id
                    v = lo[i, j] + l_miss
                    lo[i, j] = l_min if v < l_min else v
                if end:
                    break
                if tx < ty:
                    j += sj
                    tx += dtx
                else:
                    i += si
                    ty += dty
    return skipped


@numba.njit(cache=True)
def _count_scan(lo, counts, stamp, scan_id, res, x0, y0, sx, sy, st, ranges, angles,
                max_range):  # fmt: skip
    """The counting model's update of one scan (module docstring): each beam adds a hit to
    the cell holding its return and a miss to every cell it crosses before (Amanatides-Woo;
    a no-return beam crosses up to ``max_range``, its end cell included); returns NaN beams."""
    rows, cols = lo.shape
    inv = 1.0 / res
    px = (sx - x0) * inv
    py = (sy - y0) * inv
    skipped = 0
    for b in range(ranges.shape[0]):
        z = ranges[b]
        if z != z:
            skipped += 1
            continue
        hit = z < max_range
        reach = z * inv + _BEHIND if hit else max_range * inv
        a = st + angles[b]
        ux = math.cos(a)
        uy = math.sin(a)
        j, sj, tx, dtx = _axis_walk(px, ux)
        i, si, ty, dty = _axis_walk(py, uy)
        while True:
            end = (tx if tx < ty else ty) >= reach
            if end and hit:
                break
            if 0 <= i < rows and 0 <= j < cols:
                counts[1, i, j] += 1.0
                lo[i, j] = math.log((counts[0, i, j] + 1.0) / (counts[1, i, j] + 1.0))
                stamp[i, j] = scan_id
            if end:
                break
            if tx < ty:
                j += sj
                tx += dtx
            else:
                i += si
                ty += dty
        if hit and 0 <= i < rows and 0 <= j < cols:
            counts[0, i, j] += 1.0
            lo[i, j] = math.log((counts[0, i, j] + 1.0) / (counts[1, i, j] + 1.0))
            stamp[i, j] = scan_id
    return skipped
