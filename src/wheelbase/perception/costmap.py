"""A layered costmap after Nav2's (``nav2_costmap_2d``): static, obstacle and inflation layers.

:class:`LayeredCostmap` holds what does not change during a run: the :class:`CostmapSpec`, the
static layer made from the map, the robot's inscribed radius and the inflation table.
:class:`CostmapState` holds what does, for N robots at once (arrays with a leading robot
axis): each robot's obstacle layer and its master cost (both layers combined, then inflated).
:func:`update_costmap` is a pure function of them: it returns a new state and never writes
its inputs.

Geometry
    The costmap shares :class:`~wheelbase.planning.OccupancyGrid`'s geometry: row 0 the
    lowest y, column 0 the lowest x, ``origin`` the world (x0, y0) [m] of the lower-left
    corner of cell (0, 0), square cells of ``resolution`` [m]; it covers the map (whole cells
    at its resolution). At another resolution than the map's, a costmap cell is lethal when
    any map cell it overlaps is occupied, or when it reaches beyond the map (outside the map
    is occupied, as everywhere in wheelbase).
Static layer
    Occupied map cells are lethal (254), others free (0). With ``track_unknown`` the cells of
    the map's ``unknown`` mask are unknown (255) instead (Nav2's ``track_unknown_space``).
Obstacle layer
    Starts free (unknown with ``track_unknown``). Each scan first clears, then marks (Nav2's
    order, so a return always survives the clearing of its neighbours):

    * clearing: every cell a beam passes, by the exact grid traversal of
      :mod:`wheelbase.sensors.raycast` (Amanatides and Woo), is set free, from
      ``raytrace_min_range`` (a cell is passed once the beam leaves it beyond that range) to
      the return or ``raytrace_max_range``, whichever is nearer; a reading of ``max_range`` or
      ``+inf`` (no return) clears up to ``min(max_range, raytrace_max_range)``;
    * marking: a return with range in [``obstacle_min_range``, ``obstacle_max_range``] and
      below ``max_range`` marks the cell holding its endpoint lethal (the point 1e-6 cells
      beyond the return, so a return on a cell's boundary marks the cell the beam entered);
    * NaN readings neither clear nor mark: wheelbase's lidar reports NaN for a return inside
      its blind zone (``min_range``), i.e. something is there but not where, and clearing
      along it would erase it;
    * a sensor outside the map clears nothing (Nav2 does the same); its returns inside the
      map still mark.

    A moving obstacle thus leaves no trail: the cells it left are passed by later beams (at a
    range where the beams are closer together than a cell, every cell is passed).
Inflation layer
    Nav2's exponential decay (:mod:`wheelbase.perception.costs`) around every lethal cell of
    the combined layers, with the exact Euclidean distance. After a scan only the cells whose
    layer value changed, grown by the inflation radius, are inflated again (the distances
    there are computed with lethal cells up to another inflation radius around them), so an
    update costs what changed, not the map.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np
from numpy.typing import ArrayLike

from wheelbase._validate import as_float_array, integer, positive
from wheelbase.errors import ConfigError, InputError, MapError
from wheelbase.limits import MAX_MAP_CELLS
from wheelbase.perception.costs import FREE, LETHAL, UNKNOWN, inflation_table
from wheelbase.perception.specs import CostmapSpec, check_scan_geometry
from wheelbase.planning import Footprint, OccupancyGrid

__all__ = ["Costmap", "CostmapState", "LayeredCostmap", "update_costmap"]

_ROUNDING = 1e-9  # cells
_MAX_REACH = 1000  # cells of inflation around a lethal cell (see LayeredCostmap)


def _read_only(array: np.ndarray) -> np.ndarray:
    array.setflags(write=False)
    return array


@dataclass(frozen=True, eq=False)
class Costmap:
    """A uint8 cost grid on :class:`~wheelbase.planning.OccupancyGrid`'s geometry (Nav2's
    costs: 0 free, 253 inscribed, 254 lethal, 255 unknown).

    Parameters
    ----------
    cost : numpy.ndarray
        uint8 array ``(rows, cols)``; row 0 the lowest y, column 0 the lowest x. Kept
        read-only (a writable array is copied).
    resolution : float
        Cell side [m], > 0.
    origin : tuple of float
        World ``(x0, y0)`` [m] of the lower-left corner of cell (0, 0).
    """

    cost: np.ndarray
    resolution: float
    origin: tuple[float, float] = (0.0, 0.0)

    def __post_init__(self) -> None:
        cost = np.asarray(self.cost)
        if cost.dtype != np.uint8 or cost.ndim != 2 or cost.size == 0:
            raise MapError(
                f"cost must be a non-empty 2-D uint8 array (got {cost.dtype}, shape {cost.shape})"
            )
        if cost.flags.writeable:
            cost = _read_only(cost.copy())
        object.__setattr__(self, "cost", cost)
        object.__setattr__(self, "resolution", positive("resolution", self.resolution, "m"))
        origin = as_float_array("origin", self.origin, 2, max_ndim=1)
        object.__setattr__(self, "origin", (float(origin[0]), float(origin[1])))

    @property
    def shape(self) -> tuple[int, int]:
        """``(rows, cols)``."""
        return self.cost.shape  # type: ignore[return-value]

    def window(self, pose: ArrayLike, cells: int) -> Costmap:
        """The square window of ``cells`` cells on a side around a pose, aligned with these
        cells, with the cell holding ``pose`` at index ``cells // 2`` along each axis; outside
        this costmap its cells are lethal (a rolling window for local control).

        Parameters
        ----------
        pose : array_like
            (x [m], y [m]) or a pose (x, y, θ).
        cells : int
            Side of the window in cells, >= 1.

        Returns
        -------
        Costmap
        """
        xy = as_float_array("pose", pose, min_ndim=1, max_ndim=1)
        if xy.shape[0] not in (2, 3):
            raise InputError(f"pose must be (x, y) or (x, y, θ) (got shape {xy.shape})")
        n = integer("cells", cells, 1)
        ci = math.floor((xy[1] - self.origin[1]) / self.resolution)
        cj = math.floor((xy[0] - self.origin[0]) / self.resolution)
        i0, j0 = ci - n // 2, cj - n // 2
        rows, cols = self.shape
        out = np.full((n, n), LETHAL, np.uint8)
        a0, a1 = max(i0, 0), min(i0 + n, rows)
        b0, b1 = max(j0, 0), min(j0 + n, cols)
        if a0 < a1 and b0 < b1:
            out[a0 - i0 : a1 - i0, b0 - j0 : b1 - j0] = self.cost[a0:a1, b0:b1]
        origin = (self.origin[0] + j0 * self.resolution, self.origin[1] + i0 * self.resolution)
        return Costmap(_read_only(out), self.resolution, origin)

    @property
    def extent(self) -> tuple[float, float, float, float]:
        """``(x_min, x_max, y_min, y_max)`` [m], e.g. for ``imshow(..., origin="lower")``."""
        return self.grid.extent

    @cached_property
    def grid(self) -> OccupancyGrid:
        """:meth:`to_occupancy_grid` with its defaults: lethal and unknown cells occupied."""
        return self.to_occupancy_grid()

    def to_occupancy_grid(
        self, threshold: int = LETHAL, *, unknown_as_occupied: bool = True
    ) -> OccupancyGrid:
        """The cells a planner must avoid, as an occupancy grid: what the robot believes.

        On a master costmap the default gives the map plus the obstacles seen (lethal cells
        only: a planner such as :class:`~wheelbase.planning.HybridAStar` checks its footprint
        itself); a lower ``threshold`` (e.g. 253, inscribed) blocks the inflated band too.

        Parameters
        ----------
        threshold : int
            Cells with a cost in [``threshold``, 254] are occupied, in [1, 254].
        unknown_as_occupied : bool
            Whether unknown cells (255) are occupied; they are in the grid's ``unknown`` mask
            either way.

        Returns
        -------
        OccupancyGrid
        """
        threshold = integer("threshold", threshold, 1, LETHAL)
        unknown = self.cost == UNKNOWN
        occupied = (self.cost >= threshold) & ~unknown
        if unknown_as_occupied:
            occupied |= unknown
        return OccupancyGrid(occupied, self.resolution, self.origin, unknown)

    def world_to_cell(self, xy: ArrayLike) -> np.ndarray:
        """Cells ``(row, col)`` (int64, shape ``(..., 2)``) holding world points.

        Parameters
        ----------
        xy : array_like
            Points ``(..., 2)`` or poses ``(..., 3)`` [m].

        Returns
        -------
        numpy.ndarray
            Indices; points outside the costmap give indices outside it.
        """
        return self.grid.world_to_cell(xy)

    def cost_at(self, xy: ArrayLike) -> np.ndarray:
        """Costs at world points; outside the costmap lethal (254).

        Parameters
        ----------
        xy : array_like
            Points ``(..., 2)`` or poses ``(..., 3)`` [m].

        Returns
        -------
        numpy.ndarray
            uint8 costs of shape ``xy.shape[:-1]``.
        """
        cells = self.world_to_cell(xy)
        rows, cols = self.shape
        inside = (
            (cells[..., 0] >= 0) & (cells[..., 0] < rows)
            & (cells[..., 1] >= 0) & (cells[..., 1] < cols)
        )  # fmt: skip
        i = np.clip(cells[..., 0], 0, rows - 1)
        j = np.clip(cells[..., 1], 0, cols - 1)
        return np.where(inside, self.cost[i, j], np.uint8(LETHAL)).astype(np.uint8)


@dataclass(frozen=True, eq=False)
class CostmapState:
    """The evolving layers of N robots' costmaps (read-only arrays, robot axis first).

    Parameters
    ----------
    obstacle : numpy.ndarray
        uint8 ``(N, rows, cols)``: each robot's obstacle layer (0 free, 254 lethal, 255
        unknown).
    cost : numpy.ndarray
        uint8 ``(N, rows, cols)``: each robot's master cost (static and obstacle layers
        combined, then inflated).
    """

    obstacle: np.ndarray
    cost: np.ndarray

    @property
    def robots(self) -> int:
        """N, the number of robots."""
        return self.obstacle.shape[0]


def _resampled(grid: OccupancyGrid, resolution: float, track_unknown: bool) -> np.ndarray:
    """The static layer (module docstring) at ``resolution``, covering the map."""
    occupied = grid.occupied
    unknown = grid.unknown if track_unknown and grid.unknown is not None else None
    known_occupied = occupied if unknown is None else occupied & ~unknown
    if math.isclose(resolution, grid.resolution, rel_tol=1e-12, abs_tol=0.0):
        static = np.where(known_occupied, np.uint8(LETHAL), np.uint8(FREE))
        if unknown is not None:
            static[unknown & ~known_occupied] = UNKNOWN
        return static
    map_rows, map_cols = grid.shape
    ratio = resolution / grid.resolution
    rows = math.ceil(map_rows / ratio - _ROUNDING)
    cols = math.ceil(map_cols / ratio - _ROUNDING)
    if rows * cols > MAX_MAP_CELLS:
        raise ConfigError(
            f"costmap.resolution = {resolution:g} m makes a {rows} × {cols} costmap: more than "
            f"{MAX_MAP_CELLS:.0e} cells (wheelbase.limits.MAX_MAP_CELLS); use a coarser one"
        )

    def spans(count: int, size: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        edges = np.arange(count + 1) * ratio
        first = np.floor(edges[:-1] + _ROUNDING).astype(np.int64)
        stop = np.ceil(edges[1:] - _ROUNDING).astype(np.int64)
        return np.minimum(first, size), np.minimum(stop, size), stop > size

    def any_in(mask: np.ndarray) -> np.ndarray:
        table = np.zeros((map_rows + 1, map_cols + 1), np.int64)
        table[1:, 1:] = np.cumsum(np.cumsum(mask, axis=0), axis=1)
        a, b = r0[:, None], r1[:, None]
        return (table[b, c1] - table[a, c1] - table[b, c0] + table[a, c0]) > 0

    r0, r1, beyond_rows = spans(rows, map_rows)
    c0, c1, beyond_cols = spans(cols, map_cols)
    lethal = any_in(known_occupied) | beyond_rows[:, None] | beyond_cols[None, :]
    static = np.where(lethal, np.uint8(LETHAL), np.uint8(FREE))
    if unknown is not None:
        static[any_in(unknown) & ~lethal] = UNKNOWN
    return static


@dataclass(frozen=True, eq=False)
class LayeredCostmap:
    """The constant part of a robot's costmap: spec, static layer and inflation (module
    docstring). Build it with :meth:`from_map`.

    Parameters
    ----------
    spec : CostmapSpec
        The ``costmap:`` keys.
    static : numpy.ndarray
        uint8 static layer ``(rows, cols)``: 0 free, 254 lethal, 255 unknown.
    resolution : float
        Cell side [m].
    origin : tuple of float
        World ``(x0, y0)`` [m] of the lower-left corner of cell (0, 0).
    inscribed_radius : float
        The robot's inscribed radius [m], >= 0 and <= ``spec.inflation_radius``.
    """

    spec: CostmapSpec
    static: np.ndarray
    resolution: float
    origin: tuple[float, float]
    inscribed_radius: float
    table: np.ndarray = field(init=False, repr=False)

    def __post_init__(self) -> None:
        if not isinstance(self.spec, CostmapSpec):
            raise ConfigError(f"spec must be a CostmapSpec (got {type(self.spec).__name__})")
        static = np.asarray(self.static)
        if static.dtype != np.uint8 or static.ndim != 2 or static.size == 0:
            raise MapError(f"static must be a non-empty 2-D uint8 array (got {static.shape})")
        if not np.all((static == FREE) | (static == LETHAL) | (static == UNKNOWN)):
            raise MapError("static layer cells must be 0 (free), 254 (lethal) or 255 (unknown)")
        object.__setattr__(self, "static", _read_only(np.ascontiguousarray(static).copy()))
        object.__setattr__(self, "resolution", positive("resolution", self.resolution, "m"))
        origin = as_float_array("origin", self.origin, 2, max_ndim=1)
        object.__setattr__(self, "origin", (float(origin[0]), float(origin[1])))
        radius = float(self.inscribed_radius)
        if not (math.isfinite(radius) and radius >= 0.0):
            raise ConfigError(f"inscribed radius must be finite and >= 0 m (got {radius!r})")
        if radius > self.spec.inflation_radius:
            raise ConfigError(
                f"costmap.inflation_radius = {self.spec.inflation_radius:g} m is less than the "
                f"robot's inscribed radius {radius:g} m: cells where the robot touches an "
                "obstacle would not be marked inscribed; set it to at least that"
            )
        object.__setattr__(self, "inscribed_radius", radius)
        rows, cols = static.shape
        diagonal = math.ceil(math.hypot(rows, cols))  # no two cells are farther apart
        reach = min(math.floor(self.spec.inflation_radius / self.resolution + _ROUNDING), diagonal)
        if reach > _MAX_REACH:
            raise ConfigError(
                f"costmap.inflation_radius = {self.spec.inflation_radius:g} m is {reach} cells "
                f"at {self.resolution:g} m: more than {_MAX_REACH} (every change would inflate "
                "that far around it); use a smaller radius or a coarser costmap.resolution"
            )
        window = max(1, math.floor(min(self.spec.window / self.resolution, 1e18) + _ROUNDING))
        if window * window > MAX_MAP_CELLS:
            raise ConfigError(
                f"costmap.window = {self.spec.window:g} m is {window} cells a side at "
                f"{self.resolution:g} m: more than {MAX_MAP_CELLS:.0e} cells "
                "(wheelbase.limits.MAX_MAP_CELLS)"
            )
        table = inflation_table(
            self.resolution, radius, self.spec.cost_scaling_factor, self.spec.inflation_radius,
            diagonal,
        )  # fmt: skip
        object.__setattr__(self, "table", _read_only(table))

    @classmethod
    def from_map(
        cls, spec: CostmapSpec, grid: OccupancyGrid, footprint: Footprint | float
    ) -> LayeredCostmap:
        """The costmap of a robot on a map.

        Parameters
        ----------
        spec : CostmapSpec
            The ``costmap:`` keys (its ``resolution`` None: the map's).
        grid : OccupancyGrid
            The map: the static layer.
        footprint : Footprint or float
            The robot's footprint (its inscribed radius: the distance from the reference
            point to the nearest edge) or the radius [m] of a circular robot.

        Returns
        -------
        LayeredCostmap
        """
        if not isinstance(grid, OccupancyGrid):
            raise MapError(f"grid must be an OccupancyGrid (got {type(grid).__name__})")
        if isinstance(footprint, Footprint):
            radius = footprint.inscribed_radius
        else:
            radius = positive("robot radius", footprint, "m")
        resolution = grid.resolution if spec.resolution is None else spec.resolution
        static = _resampled(grid, resolution, spec.track_unknown)
        return cls(spec, static, resolution, grid.origin, radius)

    # ------------------------------------------------------------------ geometry
    @property
    def shape(self) -> tuple[int, int]:
        """``(rows, cols)`` of every layer."""
        return self.static.shape  # type: ignore[return-value]

    @property
    def reach(self) -> int:
        """The inflation radius in whole cells, ⌊inflation_radius / resolution⌋."""
        return math.isqrt(self.table.shape[0]) - 1

    @property
    def window_cells(self) -> int:
        """Side of the rolling window in cells, ⌊window / resolution⌋ (at least 1)."""
        return max(1, math.floor(min(self.spec.window / self.resolution, 1e18) + _ROUNDING))

    @cached_property
    def initial_cost(self) -> np.ndarray:
        """The master cost before any scan (the static layer inflated), read-only."""
        from wheelbase.perception._kernels import inflate_window

        rows, cols = self.shape
        cost = np.empty(self.shape, np.uint8)
        obstacle = np.full(self.shape, self._initial_obstacle, np.uint8)
        inflate_window(self.static, obstacle, cost, 0, rows, 0, cols, self.table, self.reach)
        return _read_only(cost)

    @property
    def _initial_obstacle(self) -> int:
        return UNKNOWN if self.spec.track_unknown else FREE

    # ------------------------------------------------------------------ state
    def initial_state(self, robots: int = 1) -> CostmapState:
        """The state of ``robots`` costmaps before any scan.

        Parameters
        ----------
        robots : int
            N, >= 1; N × rows × cols <= ``wheelbase.limits.MAX_MAP_CELLS``.

        Returns
        -------
        CostmapState
        """
        rows, cols = self.shape
        robots = integer("robots", robots, 1, max(1, MAX_MAP_CELLS // (rows * cols)))
        obstacle = np.full((robots, rows, cols), self._initial_obstacle, np.uint8)
        cost = np.broadcast_to(self.initial_cost, (robots, rows, cols)).copy()
        return CostmapState(_read_only(obstacle), _read_only(cost))

    def _check_state(self, state: CostmapState) -> None:
        if not isinstance(state, CostmapState):
            raise InputError(f"state must be a CostmapState (got {type(state).__name__})")
        expected = self.shape
        for name in ("obstacle", "cost"):
            array = getattr(state, name)
            if (
                not isinstance(array, np.ndarray)
                or array.dtype != np.uint8
                or (array.ndim != 3 or array.shape[1:] != expected)
            ):
                raise InputError(
                    f"state.{name} must be a uint8 array (N, {expected[0]}, {expected[1]}) "
                    f"(got {getattr(array, 'dtype', None)} {getattr(array, 'shape', None)})"
                )
        if state.obstacle.shape[0] != state.cost.shape[0] or state.obstacle.shape[0] == 0:
            raise InputError("state.obstacle and state.cost must hold the same N >= 1 robots")

    def _robot(self, state: CostmapState, robot: int) -> int:
        self._check_state(state)
        return integer("robot", robot, 0, state.robots - 1)

    def master(self, state: CostmapState, robot: int = 0) -> Costmap:
        """One robot's master costmap (a view of the state, no copy).

        ``master(state, robot).to_occupancy_grid()`` is what the robot believes (the map plus
        the obstacles it has seen): the grid to replan on.

        Parameters
        ----------
        state : CostmapState
            The costmaps.
        robot : int
            Which robot, in [0, N).

        Returns
        -------
        Costmap
        """
        robot = self._robot(state, robot)
        return Costmap(state.cost[robot], self.resolution, self.origin)

    def rolling_window(self, state: CostmapState, robot: int, pose: ArrayLike) -> Costmap:
        """The square window of side ``spec.window`` around a robot, for local control.

        The window is ``window_cells`` cells on a side, aligned with the master costmap's
        cells, with the cell holding ``pose`` at index ``window_cells // 2`` along each axis;
        its cells are the master's (outside the map: lethal).

        Parameters
        ----------
        state : CostmapState
            The costmaps.
        robot : int
            Which robot, in [0, N).
        pose : array_like
            The robot's (x [m], y [m]) or pose (x, y, θ).

        Returns
        -------
        Costmap
        """
        return self.master(state, robot).window(pose, self.window_cells)


def update_costmap(
    costmap: LayeredCostmap,
    state: CostmapState,
    sensor_poses: ArrayLike,
    beam_angles: ArrayLike,
    ranges: ArrayLike,
    max_range: float,
    index: ArrayLike | None = None,
) -> CostmapState:
    """The costmaps after one lidar scan per robot (pure: ``state`` is not changed).

    Each scan clears and marks its robot's obstacle layer and the master cost is inflated
    again where a cell changed (module docstring).

    Parameters
    ----------
    costmap : LayeredCostmap
        The constant part.
    state : CostmapState
        The costmaps of N robots.
    sensor_poses : array_like, shape (M, 3)
        World poses (x [m], y [m], θ [rad]) of the M lidars that scanned.
    beam_angles : array_like, shape (K,)
        Beam directions [rad] in the sensor frame.
    ranges : array_like, shape (M, K)
        Readings [m]: >= 0, ``max_range`` or ``+inf`` for no return, NaN for none.
    max_range : float
        The lidar's largest range [m]: readings at or beyond it are no return, > 0.
    index : array_like of int, shape (M,), optional
        The state row (robot) of each scan, distinct, in [0, N); default ``0..M−1`` with
        M = N.

    Returns
    -------
    CostmapState
        A new state (new read-only arrays).
    """
    from wheelbase.perception._kernels import batch_update

    if not isinstance(costmap, LayeredCostmap):
        raise InputError(f"costmap must be a LayeredCostmap (got {type(costmap).__name__})")
    costmap._check_state(state)
    poses = as_float_array("sensor_poses", sensor_poses, 3, min_ndim=2, max_ndim=2)
    angles = as_float_array("beam_angles", beam_angles, min_ndim=1, max_ndim=1)
    scans = _readings(ranges, (poses.shape[0], angles.shape[0]))
    max_range = check_scan_geometry(poses[:, :2], max_range)
    rows = _rows(index, poses.shape[0], state.robots)
    spec = costmap.spec
    params = np.array([max_range, spec.obstacle_min_range, spec.obstacle_max_range,
                       spec.raytrace_min_range, spec.raytrace_max_range, *costmap.origin,
                       1.0 / costmap.resolution])  # fmt: skip
    obstacle, cost = state.obstacle.copy(), state.cost.copy()
    batch_update(costmap.static, state.obstacle, obstacle, cost, rows,
                 np.ascontiguousarray(poses), np.ascontiguousarray(angles), scans, params,
                 costmap.table, costmap.reach)  # fmt: skip
    return CostmapState(_read_only(obstacle), _read_only(cost))


def _readings(ranges: ArrayLike, shape: tuple[int, int]) -> np.ndarray:
    """Lidar readings as float64 of ``shape``: NaN and +inf allowed, negatives are not."""
    try:
        scans = np.asarray(ranges, dtype=np.float64)
    except (TypeError, ValueError):
        raise InputError(f"ranges must be numeric (got {type(ranges).__name__})") from None
    if scans.shape != shape:
        raise InputError(f"ranges must have shape {shape} (scans, beams) (got {scans.shape})")
    if (scans < 0.0).any():
        raise InputError("ranges must be >= 0 m, +inf (no return) or NaN (no reading)")
    return np.ascontiguousarray(scans)


def _rows(index: ArrayLike | None, scans: int, robots: int) -> np.ndarray:
    """The state rows of the scans (``update_costmap``'s ``index``), checked."""
    if index is None:
        if scans != robots:
            raise InputError(
                f"{scans} scans for {robots} robots: pass index (the robot of each scan)"
            )
        return np.arange(robots, dtype=np.int64)
    rows = np.asarray(index)
    if rows.shape != (scans,) or not (
        np.issubdtype(rows.dtype, np.integer) and not np.issubdtype(rows.dtype, np.bool_)
    ):
        raise InputError(f"index must be {scans} integers, one per scan (got {index!r})"[:200])
    if np.any(rows < 0) or np.any(rows >= robots) or np.unique(rows).size != scans:
        raise InputError(
            f"index must be distinct robots in [0, {robots}) (got {rows.tolist()})"[:200]
        )
    return rows.astype(np.int64)
