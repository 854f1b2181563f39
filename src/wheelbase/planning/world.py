"""Vector worlds: obstacles as polygons (convex or not, with holes) and discs, alone or on a grid.

A :class:`PolygonWorld` answers the same queries as an
:class:`~wheelbase.planning.OccupancyGrid` (``in_collision``, ``footprint_clearance``,
``contains``, ``is_occupied``, ``clearance``, ``extent``, a raster for plots), so Hybrid A*, the
scenario runner and the plots take either. Collision and clearance are **exact** on the
polygons: every polygon is split into triangles (constrained Delaunay, holes respected), and a
footprint collides with a triangle iff no edge normal of either separates them (separating axis
theorem on convex pieces); a disc collides iff the footprint polygon comes within its radius.
A uniform grid of buckets over the world (the broad phase) lists the pieces whose bounding box
meets each bucket, so a check looks only at the pieces under the footprint.

A conservative raster (a cell is occupied when its closed square meets an obstacle) supplies
the distance field that decides clear poses fast: only poses near an obstacle reach the exact
test, so a check costs about a microsecond. The rectangle ``bounds`` is the map: leaving it is a
collision, as leaving a grid is.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from functools import cached_property

import numba
import numpy as np
from numpy.typing import ArrayLike

from wheelbase._validate import as_float_array, integer, nonnegative, positive
from wheelbase.errors import MapError
from wheelbase.limits import MAX_MAP_CELLS
from wheelbase.planning.collision import (
    _NVERTS,
    _PIECES,
    _PRAD,
    FootprintChecks,
    _convex_separated,
    _pieces_in_box,
    _point_polygon_distance,
    _world_tuple,
)
from wheelbase.planning.occupancy import OccupancyGrid

__all__ = ["PolygonWorld"]

DEFAULT_RESOLUTION = 0.1
"""Raster cell [m] of a polygon world without a grid (distance field, heuristic, plots)."""
_MAX_BUCKETS = 1 << 16


@dataclass(frozen=True, eq=False)
class PolygonWorld(FootprintChecks):
    """Obstacles as polygons and discs inside a rectangle, optionally on an occupancy grid.

    Parameters
    ----------
    polygons : sequence
        Each polygon is an array of vertices ``(M, 2)`` [m] (the exterior ring; either
        orientation; not closed, or closed by repeating the first vertex), or a pair
        ``(exterior, holes)`` with ``holes`` a sequence of such rings. Convex or not; holes are
        free space inside the polygon.
    discs : array_like
        Discs ``(K, 3)`` = (x [m], y [m], radius [m]).
    bounds : tuple of float or None
        The map rectangle ``(x_min, x_max, y_min, y_max)`` [m]; default the grid's extent, or
        else the obstacles' bounding box. Leaving it is a collision.
    resolution : float or None
        Raster cell [m] (distance field, heuristic, plots); default the grid's, or 0.1 m.
    grid : OccupancyGrid or None
        Occupied cells that are obstacles too (exact to the cell, as on a grid alone); the
        world then takes the grid's extent and resolution.
    max_cells : int
        Most raster cells the bounds may span at the resolution (default
        :data:`wheelbase.limits.MAX_MAP_CELLS` = 1e8; the raster's distance field alone takes
        8 bytes a cell).

    Raises
    ------
    MapError
        A polygon with NaN vertices, fewer than 3 distinct vertices, no area or a
        self-intersection (the message names its index and the place), a disc with a radius
        <= 0, bounds that are empty, or more raster cells than ``max_cells``.

    Examples
    --------
    >>> world = PolygonWorld([[(2, 2), (4, 2), (4, 4), (2, 4)]], bounds=(0, 10, 0, 6))
    >>> from wheelbase.planning import Footprint
    >>> fp = Footprint.rectangle(1.0, 0.5)
    >>> world.in_collision(fp, [[1.4, 3.0, 0.0], [1.6, 3.0, 0.0]]).tolist()
    [False, True]
    """

    polygons: tuple = ()
    discs: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))
    bounds: tuple[float, float, float, float] | None = None
    resolution: float | None = None
    grid: OccupancyGrid | None = None
    max_cells: int = MAX_MAP_CELLS

    def __post_init__(self) -> None:
        rings = tuple(_polygon_rings(i, p) for i, p in enumerate(self.polygons))
        object.__setattr__(self, "polygons", rings)
        discs = np.asarray(self.discs, dtype=float).reshape(-1, 3) if len(self.discs) else None
        discs = np.zeros((0, 3)) if discs is None else discs
        for i, (x, y, r) in enumerate(discs):
            if not (math.isfinite(x) and math.isfinite(y) and math.isfinite(r)) or r <= 0:
                raise MapError(f"disc {i}: centre must be finite and radius > 0 m (got {x, y, r})")
        discs.setflags(write=False)
        object.__setattr__(self, "discs", discs)
        if self.grid is not None:
            if not isinstance(self.grid, OccupancyGrid):
                raise MapError(f"grid must be an OccupancyGrid (got {type(self.grid).__name__})")
            object.__setattr__(self, "bounds", self.grid.extent)
            object.__setattr__(self, "resolution", self.grid.resolution)
            return
        res = DEFAULT_RESOLUTION if self.resolution is None else self.resolution
        object.__setattr__(self, "resolution", positive("resolution", res, "m"))
        if self.bounds is None:
            points = [r for ring in rings for r in (ring[0],)]
            if len(discs):
                points.append(discs[:, :2] - discs[:, 2:])
                points.append(discs[:, :2] + discs[:, 2:])
            if not points:
                raise MapError(
                    "a world without obstacles needs bounds (x_min, x_max, y_min, y_max)"
                )
            allp = np.concatenate(points)
            lo, hi = allp.min(0), allp.max(0)
            bounds = (lo[0], hi[0], lo[1], hi[1])
        else:
            bounds = tuple(as_float_array("bounds", self.bounds, max_ndim=1).tolist())
        if len(bounds) != 4 or not all(map(math.isfinite, bounds)):
            raise MapError(
                f"bounds must be 4 finite numbers (x_min, x_max, y_min, y_max) [m] (got {bounds})"
            )
        if bounds[1] <= bounds[0] or bounds[3] <= bounds[2]:
            raise MapError(f"bounds {bounds} are empty: need x_min < x_max and y_min < y_max [m]")
        object.__setattr__(self, "bounds", tuple(float(b) for b in bounds))
        limit = integer("max_cells", self.max_cells, minimum=1)
        x0, x1, y0, y1 = self.bounds
        res = float(self.resolution)
        cells = math.ceil((x1 - x0) / res - 1e-9) * math.ceil((y1 - y0) / res - 1e-9)
        if cells > limit:
            raise MapError(
                f"bounds {self.bounds} at resolution {res:g} m span {cells:.3g} raster cells: "
                f"more than max_cells = {limit}; use a coarser resolution or smaller bounds, "
                "or raise max_cells (scenarios: resources.max_map_cells)"
            )

    # ------------------------------------------------------------------ pieces and raster
    @cached_property
    def triangles(self) -> np.ndarray:
        """Triangles ``(T, 3, 2)`` [m] whose union is the polygons (holes excluded)."""
        import shapely

        out = [np.zeros((0, 3, 2))]
        for exterior, holes in self.polygons:
            poly = shapely.Polygon(exterior, holes)
            tris = shapely.get_parts(shapely.constrained_delaunay_triangles(poly))
            coords = [np.asarray(t.exterior.coords)[:3] for t in tris]
            if coords:
                out.append(np.array(coords))
        return np.ascontiguousarray(np.concatenate(out))

    @cached_property
    def _pieces(self) -> tuple:
        tris = self.triangles
        n_t, n_d = len(tris), len(self.discs)
        verts = np.zeros((n_t + n_d, 3, 2))
        verts[:n_t] = tris
        verts[n_t:, 0] = self.discs[:, :2]
        nverts = np.concatenate([np.full(n_t, 3), np.ones(n_d)]).astype(np.int64)
        rad = np.concatenate([np.zeros(n_t), self.discs[:, 2]])
        lo = np.concatenate([tris.min(1), self.discs[:, :2] - self.discs[:, 2:]])
        hi = np.concatenate([tris.max(1), self.discs[:, :2] + self.discs[:, 2:]])
        aabb = np.ascontiguousarray(np.column_stack([lo[:, 0], hi[:, 0], lo[:, 1], hi[:, 1]]))
        x0, x1, y0, y1 = self.extent
        size = max(1.0, math.sqrt((x1 - x0) * (y1 - y0) / _MAX_BUCKETS))
        bnx = max(1, math.ceil((x1 - x0) / size))
        bny = max(1, math.ceil((y1 - y0) / size))
        geom = (x0, y0, size, bnx, bny)
        # file every piece in each bucket its bounding box meets (CSR lists)
        jlo = np.clip(np.floor((aabb[:, 0] - x0) / size), 0, bnx - 1).astype(np.int64)
        jhi = np.clip(np.floor((aabb[:, 1] - x0) / size), 0, bnx - 1).astype(np.int64)
        ilo = np.clip(np.floor((aabb[:, 2] - y0) / size), 0, bny - 1).astype(np.int64)
        ihi = np.clip(np.floor((aabb[:, 3] - y0) / size), 0, bny - 1).astype(np.int64)
        buckets, items = [], []
        for k in range(len(aabb)):
            ii, jj = np.meshgrid(np.arange(ilo[k], ihi[k] + 1), np.arange(jlo[k], jhi[k] + 1))
            cells = (ii * bnx + jj).ravel()
            buckets.append(cells)
            items.append(np.full(len(cells), k))
        bucket_of = np.concatenate(buckets) if buckets else np.zeros(0, np.int64)
        item = np.concatenate(items) if items else np.zeros(0, np.int64)
        order = np.argsort(bucket_of, kind="stable")
        start = np.zeros(bnx * bny + 1, np.int64)
        np.cumsum(np.bincount(bucket_of, minlength=bnx * bny), out=start[1:])
        return (verts, nverts, rad, aabb, start, item[order].astype(np.int64), geom)

    @cached_property
    def raster(self) -> OccupancyGrid:
        """The world as a grid: every cell whose closed square meets an obstacle is occupied
        (conservative), on the grid's cells when there is one."""
        if self.grid is not None:
            base = self.grid
        else:
            x0, x1, y0, y1 = self.bounds
            res = float(self.resolution)
            shape = (math.ceil((y1 - y0) / res - 1e-9), math.ceil((x1 - x0) / res - 1e-9))
            base = OccupancyGrid(np.zeros(shape, bool), res, (x0, y0))
        pieces = self._pieces
        touched = _raster_pieces(
            base.shape[0], base.shape[1], base.resolution, *base.origin, *pieces[:4]
        )
        return OccupancyGrid(base.occupied | touched, base.resolution, base.origin, base.unknown)

    @cached_property
    def _kernel_world(self) -> tuple:
        cells = self.grid if self.grid is not None else self.raster
        return _world_tuple(
            cells.occupied, cells.occupancy_prefix, self.raster.distance_field,
            self.raster.resolution, self.raster.origin, self.grid is not None, self._pieces,
        )  # fmt: skip

    def with_origin(self, origin: ArrayLike) -> PolygonWorld:
        """The same world moved so that its raster's lower-left corner is at ``origin``; the
        triangles, broad phase and raster are moved, not recomputed.

        Planners work in the world's own frame (``world.with_origin((0, 0))``), as on a grid
        (:meth:`OccupancyGrid.with_origin`).

        Parameters
        ----------
        origin : array_like
            ``(x0, y0)`` [m] of the new lower-left corner.

        Returns
        -------
        PolygonWorld
        """
        new = as_float_array("origin", origin, max_ndim=1)
        if new.shape != (2,) or not np.all(np.isfinite(new)):
            raise MapError(f"origin must be 2 finite numbers (x0, y0) [m] (got {new.tolist()})")
        shift = new - np.asarray(self.origin)
        dx, dy = float(shift[0]), float(shift[1])
        moved = object.__new__(PolygonWorld)
        fields = {
            "polygons": tuple(
                (ext + shift, tuple(h + shift for h in holes)) for ext, holes in self.polygons
            ),
            "discs": self.discs + np.array([dx, dy, 0.0]),
            "resolution": self.resolution,
            "grid": None if self.grid is None else self.grid.with_origin(new),
            "max_cells": self.max_cells,
        }
        x0, x1, y0, y1 = self.bounds
        fields["bounds"] = (float(new[0]), float(new[0]) + (x1 - x0),
                            float(new[1]), float(new[1]) + (y1 - y0))  # fmt: skip
        for name, value in fields.items():
            if isinstance(value, np.ndarray):
                value.setflags(write=False)
            object.__setattr__(moved, name, value)
        for ext, holes in fields["polygons"]:
            for ring in (ext, *holes):
                ring.setflags(write=False)
        moved.__dict__["triangles"] = self.triangles + shift
        verts, nverts, rad, aabb, start, items, geom = self._pieces
        moved_verts = verts + shift
        moved_verts[len(self.triangles) :, 1:] = 0.0  # a disc keeps only its centre
        moved.__dict__["_pieces"] = (
            moved_verts, nverts, rad, aabb + np.array([dx, dx, dy, dy]), start, items,
            (geom[0] + dx, geom[1] + dy, *geom[2:]),
        )  # fmt: skip
        moved.__dict__["raster"] = self.raster.with_origin(new)
        return moved

    # ------------------------------------------------------------------ grid-like interface
    @property
    def origin(self) -> tuple[float, float]:
        """Lower-left corner ``(x0, y0)`` [m] of the raster."""
        return self.raster.origin

    @property
    def shape(self) -> tuple[int, int]:
        """``(rows, cols)`` of the raster."""
        return self.raster.shape

    @property
    def width_m(self) -> float:
        """Extent along x [m]."""
        return self.raster.width_m

    @property
    def height_m(self) -> float:
        """Extent along y [m]."""
        return self.raster.height_m

    @property
    def extent(self) -> tuple[float, float, float, float]:
        """``(x_min, x_max, y_min, y_max)`` [m] of the map (whole raster cells)."""
        if self.grid is not None:
            return self.grid.extent
        x0, x1, y0, y1 = self.bounds
        res = float(self.resolution)
        return (x0, x0 + math.ceil((x1 - x0) / res - 1e-9) * res, y0,
                y0 + math.ceil((y1 - y0) / res - 1e-9) * res)  # fmt: skip

    @property
    def occupied(self) -> np.ndarray:
        """The conservative raster's occupancy (for plots and grid search)."""
        return self.raster.occupied

    @property
    def unknown(self) -> np.ndarray | None:
        """The grid's unknown cells, if any."""
        return self.raster.unknown

    @property
    def distance_field(self) -> np.ndarray:
        """The raster's distance field [m] (a bound good to √2 cells of the exact one)."""
        return self.raster.distance_field

    def world_to_cell(self, xy: ArrayLike) -> np.ndarray:
        """Raster cells ``(row, col)`` containing world points (see
        :meth:`OccupancyGrid.world_to_cell`).

        Parameters
        ----------
        xy : array_like
            Points ``(..., 2)`` or poses ``(..., 3)`` [m].

        Returns
        -------
        numpy.ndarray
        """
        return self.raster.world_to_cell(xy)

    def cell_to_world(self, cells: ArrayLike) -> np.ndarray:
        """World coordinates [m] of raster cell centres (see
        :meth:`OccupancyGrid.cell_to_world`).

        Parameters
        ----------
        cells : array_like
            Cell indices ``(..., 2)`` as ``(row, col)``.

        Returns
        -------
        numpy.ndarray
        """
        return self.raster.cell_to_world(cells)

    def contains(self, xy: ArrayLike) -> np.ndarray:
        """Whether world points lie inside the map rectangle.

        Parameters
        ----------
        xy : array_like
            Points or poses [m].

        Returns
        -------
        numpy.ndarray
        """
        return self.raster.contains(xy)

    def clearance(self, xy: ArrayLike) -> np.ndarray:
        """Exact distance [m] from world points to the nearest polygon or disc (and, on a grid,
        the grid's cell bound); 0 inside an obstacle or off the map.

        Parameters
        ----------
        xy : array_like
            Points or poses [m].

        Returns
        -------
        numpy.ndarray
            Shape ``xy.shape[:-1]``.
        """
        xy = as_float_array("xy", xy, min_ndim=1)
        flat = np.ascontiguousarray(xy[..., :2].reshape(-1, 2))
        reach = self.raster.clearance(flat) + 2.0 * math.sqrt(2.0) * self.raster.resolution
        d = _point_distances(self._kernel_world, flat, reach)
        if self.grid is not None:
            d = np.minimum(d, self.grid.clearance(flat))
        d = np.where(self.contains(flat), d, 0.0)
        return d.reshape(xy.shape[:-1])

    def is_occupied(self, xy: ArrayLike) -> np.ndarray:
        """Whether world points are inside a polygon, a disc or an occupied cell, or off the map.

        Parameters
        ----------
        xy : array_like
            Points or poses [m].

        Returns
        -------
        numpy.ndarray
            Boolean, shape ``xy.shape[:-1]``.
        """
        xy = as_float_array("xy", xy, min_ndim=1)
        flat = np.ascontiguousarray(xy[..., :2].reshape(-1, 2))
        inside = _point_distances(self._kernel_world, flat, np.zeros(len(flat))) <= 0.0
        if self.grid is not None:
            inside |= self.grid.is_occupied(flat)
        return (inside | ~self.contains(flat)).reshape(xy.shape[:-1])

    def reference_blocked(self, clearance: float) -> np.ndarray:
        """Raster cells where no reference point at least ``clearance`` from every obstacle
        can lie: the exact distance from the cell centre to an obstacle is below
        ``clearance − r/√2`` (the distance changes by at most ``r/√2`` within a cell).

        Parameters
        ----------
        clearance : float
            Distance [m] the reference point keeps from obstacles, >= 0.

        Returns
        -------
        numpy.ndarray
            Boolean, ``shape``.
        """
        clearance = nonnegative("clearance", clearance, "m")
        threshold = clearance - self.raster.resolution / math.sqrt(2.0)
        rows, cols = self.shape
        if threshold <= 0.0:
            blocked = np.zeros(self.shape, bool)
        else:
            centres = self.raster.cell_to_world(
                np.stack(np.meshgrid(np.arange(rows), np.arange(cols), indexing="ij"), -1)
            ).reshape(-1, 2)
            near = _point_distances(self._kernel_world, centres, np.full(len(centres), threshold))
            blocked = (near < threshold).reshape(rows, cols)
        if self.grid is not None:
            blocked |= self.grid.reference_blocked(clearance)
        return blocked


# ---------------------------------------------------------------------- validation
def _ring(index: int, ring: object, what: str) -> np.ndarray:
    try:
        arr = np.asarray(ring, dtype=float)
    except (TypeError, ValueError):
        raise MapError(f"polygon {index}: {what} must be a list of [x, y] vertices [m]") from None
    if arr.ndim != 2 or arr.shape[1] != 2:
        raise MapError(f"polygon {index}: {what} must have shape (M, 2) (got {arr.shape})")
    if not np.all(np.isfinite(arr)):
        bad = int(np.argwhere(~np.isfinite(arr))[0, 0])
        raise MapError(f"polygon {index}: {what} vertex {bad} is not finite ({arr[bad].tolist()})")
    if len(arr) > 1 and np.allclose(arr[0], arr[-1]):
        arr = arr[:-1]
    if len(np.unique(arr, axis=0)) < 3:
        raise MapError(f"polygon {index}: {what} needs >= 3 distinct vertices (got {len(arr)})")
    return np.ascontiguousarray(arr)


def _is_ring(value: object) -> bool:
    """Whether ``value`` looks like a ring of vertices (its first item is not a number), so that
    a pair (exterior, holes) is told from a two-vertex exterior; an empty or unindexable value
    is not one (the ring check then names what is wrong)."""
    try:
        return len(value) > 0 and not np.isscalar(value[0])  # type: ignore[arg-type, index]
    except (TypeError, KeyError, IndexError):
        return False


def _polygon_rings(index: int, polygon: object) -> tuple[np.ndarray, tuple[np.ndarray, ...]]:
    if isinstance(polygon, tuple) and len(polygon) == 2 and _is_ring(polygon[0]):
        exterior, holes = polygon
    else:
        exterior, holes = polygon, ()
    ext = _ring(index, exterior, "exterior")
    hole_rings = tuple(_ring(index, h, f"hole {k}") for k, h in enumerate(holes))
    import shapely

    if shapely.MultiPoint(ext).convex_hull.area <= 1e-12:
        raise MapError(f"polygon {index} has no area (degenerate: collinear vertices)")
    shape = shapely.Polygon(ext, hole_rings)
    if not shapely.is_valid(shape):
        raise MapError(f"polygon {index} is invalid: {shapely.is_valid_reason(shape)}")
    for ring in (ext, *hole_rings):
        ring.setflags(write=False)
    return ext, hole_rings


# ---------------------------------------------------------------------- Numba kernels
@numba.njit(cache=True)
def _raster_pieces(rows, cols, res, x0, y0, verts, nverts, rad, aabb):
    """Cells whose closed square meets a piece (triangle or disc)."""
    out = np.zeros((rows, cols), dtype=np.bool_)
    square = np.empty((4, 2))
    for k in range(verts.shape[0]):
        j0 = max(0, math.floor((aabb[k, 0] - x0) / res) - 1)
        j1 = min(cols - 1, math.floor((aabb[k, 1] - x0) / res) + 1)
        i0 = max(0, math.floor((aabb[k, 2] - y0) / res) - 1)
        i1 = min(rows - 1, math.floor((aabb[k, 3] - y0) / res) + 1)
        for i in range(i0, i1 + 1):
            for j in range(j0, j1 + 1):
                if out[i, j]:
                    continue
                sx = x0 + j * res
                sy = y0 + i * res
                square[0, 0], square[0, 1] = sx, sy
                square[1, 0], square[1, 1] = sx + res, sy
                square[2, 0], square[2, 1] = sx + res, sy + res
                square[3, 0], square[3, 1] = sx, sy + res
                if nverts[k] == 1:
                    hit = _point_polygon_distance(square, verts[k, 0, 0], verts[k, 0, 1]) <= rad[k]
                else:
                    hit = not _convex_separated(square, 4, verts[k], nverts[k])
                if hit:
                    out[i, j] = True
    return out


@numba.njit(cache=True)
def _point_piece_distance(px, py, piece, nv, rad):
    if nv == 1:
        return max(0.0, math.hypot(px - piece[0, 0], py - piece[0, 1]) - rad)
    # a triangle in either orientation: make it counter-clockwise for the distance
    tri = np.empty((3, 2))
    cross = (piece[1, 0] - piece[0, 0]) * (piece[2, 1] - piece[0, 1]) - (
        piece[1, 1] - piece[0, 1]
    ) * (piece[2, 0] - piece[0, 0])
    for k in range(3):
        src = k if cross >= 0 else 2 - k
        tri[k, 0] = piece[src, 0]
        tri[k, 1] = piece[src, 1]
    return _point_polygon_distance(tri, px, py)


@numba.njit(cache=True)
def _point_distances(world, points, reach):
    """Distance [m] from each point to the nearest piece, searched within ``reach[n]``
    (``inf`` when none is that close; a reach of 0 finds the pieces containing the point)."""
    pieces = world[_PIECES]
    nverts = world[_NVERTS]
    prad = world[_PRAD]
    near = np.empty(pieces.shape[0], dtype=np.int64)
    out = np.full(points.shape[0], np.inf)
    for n in range(points.shape[0]):
        px = points[n, 0]
        py = points[n, 1]
        r = reach[n]
        if not np.isfinite(r):
            r = 1e300
        best = np.inf
        for m in range(_pieces_in_box(world, px - r, px + r, py - r, py + r, near)):
            k = near[m]
            best = min(best, _point_piece_distance(px, py, pieces[k], nverts[k], prad[k]))
        out[n] = best
    return out
