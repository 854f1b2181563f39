"""The occupancy grid: world <-> cell geometry, distance field, inflation and footprint checks.

The planning problem of document 000 ("path planning of a wheeled mobile robot in a static
environment", §1.1) and of document 002 (Hybrid A*) is posed on a 2-D occupancy grid. Here a
grid is a boolean array ``occupied[row, col]`` with **row 0 at the lowest y and column 0 at the
lowest x** (so ``occupied[i, j]`` covers the square ``[x0 + j·r, x0 + (j+1)·r) × [y0 + i·r,
y0 + (i+1)·r)`` for resolution ``r`` and origin ``(x0, y0)``). Image formats (ROS ``map_server``
PGM/PNG, Moving AI ``.map``) store the top row first and are flipped on load.

Cells outside the map are occupied. Unknown cells are occupied unless a loader is told
otherwise (``unknown_as_occupied=False``).

Collision semantics ("exact to the cell resolution"): a robot footprint (a convex polygon in the
body frame) at a pose collides iff the polygon intersects the closed square of an occupied cell,
or leaves the map. The fast path uses the Euclidean distance field and circles covering the
footprint; poses that are neither clearly free nor clearly in collision fall back to an exact
separating-axis test against every occupied cell under the footprint's bounding box (the
kernels are in :mod:`wheelbase.planning.collision`). The file formats are read and written by
:mod:`wheelbase.planning.map_io` and :mod:`wheelbase.planning.movingai`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np
from numpy.typing import ArrayLike
from scipy import ndimage

from wheelbase._validate import as_float_array, finite, nonnegative, positive
from wheelbase.errors import InputError, MapError
from wheelbase.planning.collision import FootprintChecks, _world_tuple

__all__ = ["OccupancyGrid"]


@dataclass(frozen=True, eq=False)
class OccupancyGrid(FootprintChecks):
    """A 2-D occupancy grid in world coordinates.

    Parameters
    ----------
    occupied : numpy.ndarray
        Boolean array of shape ``(rows, cols)``; ``True`` = blocked. Row 0 is the lowest y,
        column 0 the lowest x.
    resolution : float
        Cell side [m/cell], > 0.
    origin : tuple of float
        World position ``(x0, y0)`` [m] of the lower-left corner of cell ``(0, 0)``.
    unknown : numpy.ndarray or None
        Optional boolean mask of cells whose state was unknown in the source map (already
        merged into ``occupied`` or not, as the loader was told).

    Examples
    --------
    >>> grid = OccupancyGrid.from_array(np.zeros((30, 40), bool), 0.5)
    >>> grid.width_m, grid.height_m
    (20.0, 15.0)
    """

    occupied: np.ndarray
    resolution: float
    origin: tuple[float, float] = (0.0, 0.0)
    unknown: np.ndarray | None = field(default=None, repr=False)

    def __post_init__(self) -> None:
        occ = np.asarray(self.occupied)
        if occ.ndim != 2 or occ.size == 0:
            raise MapError(f"occupied must be a non-empty 2-D array (got shape {occ.shape})")
        occ = np.ascontiguousarray(occ.astype(bool))
        occ.setflags(write=False)
        object.__setattr__(self, "occupied", occ)
        object.__setattr__(self, "resolution", positive("resolution", self.resolution, "m/cell"))
        origin = as_float_array("origin", self.origin, max_ndim=1)
        if origin.shape not in ((2,), (3,)):
            raise InputError(f"origin must be (x0, y0) [m] (got shape {origin.shape})")
        object.__setattr__(self, "origin", (float(origin[0]), float(origin[1])))
        if self.unknown is not None:
            unknown = np.asarray(self.unknown, dtype=bool)
            if unknown.shape != occ.shape:
                raise MapError(f"unknown mask shape {unknown.shape} != map shape {occ.shape}")
            object.__setattr__(self, "unknown", unknown)

    # ------------------------------------------------------------------ constructors
    @classmethod
    def from_array(
        cls,
        occupied: ArrayLike,
        resolution: float,
        origin: ArrayLike = (0.0, 0.0),
        *,
        occupied_thresh: float = 0.5,
    ) -> OccupancyGrid:
        """Build a grid from an array (row 0 = lowest y, column 0 = lowest x).

        Parameters
        ----------
        occupied : array_like
            Boolean array (``True`` = occupied) or numeric occupancy probabilities in [0, 1];
            a numeric cell is occupied when its value is >= ``occupied_thresh``, and NaN or
            negative values (ROS's −1) are unknown, hence occupied.
        resolution : float
            Cell side [m/cell].
        origin : array_like
            ``(x0, y0)`` [m] of the lower-left corner of cell (0, 0).
        occupied_thresh : float
            Threshold for numeric arrays, finite (NaN would make every cell free).

        Returns
        -------
        OccupancyGrid
        """
        occupied_thresh = finite("occupied_thresh", occupied_thresh)
        array = np.asarray(occupied)
        if array.dtype == bool:
            return cls(array, resolution, tuple(np.ravel(origin)[:2]))
        if not np.issubdtype(array.dtype, np.number):
            raise MapError(f"occupied must be a bool or numeric array (got dtype {array.dtype})")
        values = array.astype(np.float64)
        unknown = ~np.isfinite(values) | (values < 0)
        with np.errstate(invalid="ignore"):
            occ = (values >= occupied_thresh) | unknown
        return cls(occ, resolution, tuple(np.ravel(origin)[:2]), unknown)

    # ------------------------------------------------------------------ geometry
    @property
    def shape(self) -> tuple[int, int]:
        """``(rows, cols)`` of the grid."""
        return self.occupied.shape  # type: ignore[return-value]

    @property
    def width_m(self) -> float:
        """Extent along x [m]."""
        return self.shape[1] * self.resolution

    @property
    def height_m(self) -> float:
        """Extent along y [m]."""
        return self.shape[0] * self.resolution

    @property
    def extent(self) -> tuple[float, float, float, float]:
        """``(x_min, x_max, y_min, y_max)`` [m], e.g. for ``imshow(..., origin="lower")``."""
        x0, y0 = self.origin
        return (x0, x0 + self.width_m, y0, y0 + self.height_m)

    def world_to_cell(self, xy: ArrayLike) -> np.ndarray:
        """Cells ``(row, col)`` (int64, shape ``(..., 2)``) containing world points ``(x, y)``.

        Parameters
        ----------
        xy : array_like
            Points ``(..., 2)`` or poses ``(..., 3)`` [m]; only x and y are used.

        Returns
        -------
        numpy.ndarray
            Indices; points outside the map give indices outside ``[0, rows) × [0, cols)``.
        """
        xy = as_float_array("xy", xy, min_ndim=1)
        if xy.shape[-1] not in (2, 3):
            raise InputError(f"xy must have shape (..., 2) or (..., 3) (got {xy.shape})")
        col = np.floor((xy[..., 0] - self.origin[0]) / self.resolution).astype(np.int64)
        row = np.floor((xy[..., 1] - self.origin[1]) / self.resolution).astype(np.int64)
        return np.stack([row, col], -1)

    def cell_to_world(self, cells: ArrayLike) -> np.ndarray:
        """World coordinates ``(x, y)`` [m] of the centres of cells ``(row, col)``.

        Parameters
        ----------
        cells : array_like
            Integer or fractional cell indices ``(..., 2)`` as ``(row, col)``.

        Returns
        -------
        numpy.ndarray
            Shape ``(..., 2)``.
        """
        cells = as_float_array("cells", cells, 2)
        x = self.origin[0] + (cells[..., 1] + 0.5) * self.resolution
        y = self.origin[1] + (cells[..., 0] + 0.5) * self.resolution
        return np.stack([x, y], -1)

    def contains(self, xy: ArrayLike) -> np.ndarray:
        """Whether world points ``(..., 2)`` lie inside the map rectangle.

        Parameters
        ----------
        xy : array_like
            Points or poses [m].

        Returns
        -------
        numpy.ndarray
            Boolean array of shape ``xy.shape[:-1]``.
        """
        cells = self.world_to_cell(xy)
        rows, cols = self.shape
        return (
            (cells[..., 0] >= 0)
            & (cells[..., 0] < rows)
            & (cells[..., 1] >= 0)
            & (cells[..., 1] < cols)
        )

    def is_occupied(self, xy: ArrayLike) -> np.ndarray:
        """Whether the cells under world points are occupied (outside the map: ``True``).

        Parameters
        ----------
        xy : array_like
            Points or poses [m].

        Returns
        -------
        numpy.ndarray
            Boolean array of shape ``xy.shape[:-1]``.
        """
        cells = self.world_to_cell(xy)
        inside = self.contains(xy)
        rows = np.clip(cells[..., 0], 0, self.shape[0] - 1)
        cols = np.clip(cells[..., 1], 0, self.shape[1] - 1)
        return ~inside | self.occupied[rows, cols]

    # ------------------------------------------------------------------ derived maps
    @cached_property
    def distance_field(self) -> np.ndarray:
        """Euclidean distance [m] from each cell centre to the nearest occupied cell centre.

        Computed once with ``scipy.ndimage.distance_transform_edt``; 0 on occupied cells and
        ``inf`` everywhere when the map has no occupied cell. The map border is not an
        obstacle here (leaving the map is checked separately).
        """
        source = self.__dict__.get("_same_cells")
        if source is not None:  # a moved copy (with_origin): the source's field serves
            return source.distance_field
        if not self.occupied.any():
            out = np.full(self.shape, np.inf)
        else:
            out = ndimage.distance_transform_edt(~self.occupied) * self.resolution
        out.setflags(write=False)
        return out

    @cached_property
    def occupancy_prefix(self) -> np.ndarray:
        """Per-row prefix counts of occupied cells, shape ``(rows, cols + 1)`` (int32): the
        number of occupied cells in row ``i`` and columns ``j0..j1`` is
        ``prefix[i, j1 + 1] − prefix[i, j0]``."""
        source = self.__dict__.get("_same_cells")
        if source is not None:
            return source.occupancy_prefix
        out = np.zeros((self.shape[0], self.shape[1] + 1), np.int32)
        np.cumsum(self.occupied, axis=1, out=out[:, 1:])
        out.setflags(write=False)
        return out

    def clearance(self, xy: ArrayLike) -> np.ndarray:
        """Distance [m] from world points to the nearest occupied cell (its square).

        A lower bound good to one cell: the distance field at the point's cell minus the
        largest offset between a point and a cell centre in the two cells involved (√2·r).
        Outside the map: 0.

        Parameters
        ----------
        xy : array_like
            Points or poses [m].

        Returns
        -------
        numpy.ndarray
            Shape ``xy.shape[:-1]`` [m], >= 0.
        """
        cells = self.world_to_cell(xy)
        inside = self.contains(xy)
        rows = np.clip(cells[..., 0], 0, self.shape[0] - 1)
        cols = np.clip(cells[..., 1], 0, self.shape[1] - 1)
        d = self.distance_field[rows, cols] - math.sqrt(2.0) * self.resolution
        return np.where(inside, np.maximum(d, 0.0), 0.0)

    def with_origin(self, origin: ArrayLike) -> OccupancyGrid:
        """The same cells placed at another origin; the derived maps (distance field, prefix
        counts) are shared, not recomputed, whichever of the two computes them first.

        Planners work in the grid's own frame (``grid.with_origin((0, 0))``): far from the
        world origin (UTM-like coordinates, 4.5e9 m) absolute float64 keeps only micrometres.

        Parameters
        ----------
        origin : array_like
            ``(x0, y0)`` [m] of the lower-left corner of cell (0, 0).

        Returns
        -------
        OccupancyGrid
        """
        moved = OccupancyGrid(self.occupied, self.resolution, origin, self.unknown)
        moved.__dict__["_same_cells"] = self.__dict__.get("_same_cells", self)
        return moved

    def inflate(self, radius: float) -> OccupancyGrid:
        """A new grid where every cell whose centre is within ``radius`` of an occupied cell
        centre is occupied (a disk-shaped robot of that radius reduced to a point).

        Parameters
        ----------
        radius : float
            Inflation radius [m], >= 0.

        Returns
        -------
        OccupancyGrid
        """
        radius = nonnegative("radius", radius, "m")
        occ = self.occupied | (self.distance_field <= radius)
        return OccupancyGrid(occ, self.resolution, self.origin, self.unknown)

    # ------------------------------------------------------------------ collision kernels
    @cached_property
    def _kernel_world(self) -> tuple:
        """The grid packed for the collision kernels (its cells are exact obstacles)."""
        return _world_tuple(
            self.occupied, self.occupancy_prefix, self.distance_field, self.resolution,
            self.origin, True,
        )  # fmt: skip

    def reference_blocked(self, clearance: float) -> np.ndarray:
        """Cells where no reference point at least ``clearance`` from every obstacle can lie
        (boolean, ``shape``): a cell whose centre is within ``clearance − r`` [m] of an
        occupied cell's centre (``r`` the resolution), as :meth:`inflate` does.

        Parameters
        ----------
        clearance : float
            Distance [m] the reference point keeps from obstacles (e.g. the footprint's
            inscribed radius), >= 0.

        Returns
        -------
        numpy.ndarray
        """
        return self.inflate(
            max(0.0, nonnegative("clearance", clearance, "m") - self.resolution)
        ).occupied
