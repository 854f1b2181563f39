"""Terrain maps: which surface and which slope lie under each point of the floor.

A :class:`TerrainMap` is a raster: an index into its ``surfaces`` per cell and the slope of the
ground per cell, over a rectangle (usually the occupancy grid's); outside it lies the default
surface, flat. It is built from regions (:class:`Region`: a polygon with a surface and a grade,
a plane per region) or from a raster of surface indices directly.

The map measures distance along the ground (the floor unrolled): a region's grade G, rise over
horizontal run as road signs give it, tilts the ground by α = atan(G), so one metre of ground
rises by sin α. The slope of a cell is the vector s = sin α·(cos β, sin β), β the uphill
direction in the map frame: gravity pulls a robot there with m·g·s downhill along the ground
and presses it with m·g·√(1 − |s|²) = m·g·cos α onto it.

Overlapping regions with different surfaces or grades are refused (the error names both and a
point of the overlap): where two regions disagree, nothing would say which one is the ground.
Regions may lie over a raster of surfaces (``base``): there they are the ground.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import numba
import numpy as np
from numpy.typing import ArrayLike

from wheelbase._validate import as_float_array, finite, positive
from wheelbase.errors import ConfigError
from wheelbase.limits import MAX_MAP_CELLS
from wheelbase.terrain.surfaces import Surface

__all__ = ["MAX_GRADE", "Region", "TerrainMap", "grade_slope"]

MAX_GRADE = 1.0
"""Steepest grade accepted: 100 % (45°)."""


def grade_slope(grade: float, uphill: float) -> np.ndarray:
    """Slope vector s = sin(atan G)·(cos β, sin β) of a grade G (rise/run) uphill towards β.

    Parameters
    ----------
    grade : float
        Grade G = tan α (0.1 is 10 %), 0 ≤ G ≤ :data:`MAX_GRADE`.
    uphill : float
        Direction β of steepest ascent in the map frame [rad].
    """
    g = finite("grade", grade)
    if not 0.0 <= g <= MAX_GRADE:
        raise ConfigError(f"grade must be in [0, {100 * MAX_GRADE:g}] % (got {100 * g:g} %)")
    beta = finite("uphill direction", uphill, "rad")
    rise = math.sin(math.atan(g))
    return np.array([rise * math.cos(beta), rise * math.sin(beta)])


@dataclass(frozen=True)
class Region:
    """A polygon of the floor with one surface and one grade.

    Parameters
    ----------
    polygon : array_like, shape (M, 2)
        Vertices (x [m], y [m]) in the map frame, M ≥ 3, finite.
    surface : Surface
        Its ground.
    grade : float
        Grade G (rise/run, 0.1 = 10 %), 0 ≤ G ≤ 1.
    uphill : float
        Direction of steepest ascent [rad] in the map frame.
    """

    polygon: np.ndarray
    surface: Surface
    grade: float = 0.0
    uphill: float = 0.0
    slope: np.ndarray = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        polygon = as_float_array("polygon", self.polygon, 2, min_ndim=2, max_ndim=2)
        if polygon.shape[0] < 3:
            raise ConfigError(f"a region's polygon needs >= 3 vertices (got {polygon.shape[0]})")
        if not isinstance(self.surface, Surface):
            raise ConfigError(f"surface must be a Surface (got {type(self.surface).__name__})")
        object.__setattr__(self, "polygon", polygon)
        object.__setattr__(self, "slope", grade_slope(self.grade, self.uphill))


@numba.njit(cache=True)
def _inside(px, py, polygon):
    """Even–odd rule: is (px, py) inside the closed polygon (M, 2)?"""
    inside = False
    m = polygon.shape[0]
    j = m - 1
    for i in range(m):
        xi, yi = polygon[i, 0], polygon[i, 1]
        xj, yj = polygon[j, 0], polygon[j, 1]
        if (yi > py) != (yj > py):
            cross = xi + (py - yi) * (xj - xi) / (yj - yi)
            if px < cross:
                inside = not inside
        j = i
    return inside


@numba.njit(cache=True)
def _paint(polygon, x0, y0, resolution, rows, cols, mask):
    """Mark the cells of ``mask`` (rows, cols) whose centres lie inside ``polygon``."""
    lo_c = max(0, math.floor((polygon[:, 0].min() - x0) / resolution))
    hi_c = min(cols, math.ceil((polygon[:, 0].max() - x0) / resolution) + 1)
    lo_r = max(0, math.floor((polygon[:, 1].min() - y0) / resolution))
    hi_r = min(rows, math.ceil((polygon[:, 1].max() - y0) / resolution) + 1)
    for r in range(lo_r, hi_r):
        py = y0 + (r + 0.5) * resolution
        for c in range(lo_c, hi_c):
            if _inside(x0 + (c + 0.5) * resolution, py, polygon):
                mask[r, c] = True


@dataclass(frozen=True)
class TerrainMap:
    """Surfaces and slopes over a rectangle of the floor (module docstring).

    Parameters
    ----------
    surfaces : sequence of Surface
        The surfaces; index 0 is the default (outside the raster and where no region lies).
    cells : array_like of int, shape (rows, cols)
        Index into ``surfaces`` of each cell, row 0 at the bottom (y = origin y).
    slope : array_like, shape (rows, cols, 2)
        Slope vector of each cell (sin α along the uphill direction); zeros: flat.
    resolution : float
        Cell size [m], > 0.
    origin : tuple of float
        (x, y) of the lower-left corner [m].
    """

    surfaces: tuple[Surface, ...]
    cells: np.ndarray
    slope: np.ndarray
    resolution: float = 1.0
    origin: tuple[float, float] = (0.0, 0.0)
    _table: np.ndarray = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        surfaces = tuple(self.surfaces)
        if not surfaces or not all(isinstance(s, Surface) for s in surfaces):
            raise ConfigError("surfaces must be a non-empty sequence of Surface")
        cells = np.asarray(self.cells)
        if cells.ndim != 2 or cells.size == 0 or not np.issubdtype(cells.dtype, np.integer):
            raise ConfigError(f"cells must be a 2-D integer array (got shape {cells.shape})")
        if cells.min() < 0 or cells.max() >= len(surfaces):
            raise ConfigError(
                f"cells must index surfaces 0..{len(surfaces) - 1} (got {cells.min()}.."
                f"{cells.max()})"
            )
        slope = as_float_array("slope", self.slope, 2, min_ndim=3, max_ndim=3)
        if slope.shape[:2] != cells.shape:
            raise ConfigError(f"slope must have shape {(*cells.shape, 2)} (got {slope.shape})")
        if np.any(np.hypot(slope[..., 0], slope[..., 1]) > math.sin(math.atan(MAX_GRADE))):
            raise ConfigError(f"slopes must be at most a {100 * MAX_GRADE:g} % grade")
        origin = as_float_array("origin", self.origin, 2, max_ndim=1)
        object.__setattr__(self, "surfaces", surfaces)
        object.__setattr__(self, "cells", np.ascontiguousarray(cells, dtype=np.int32))
        object.__setattr__(self, "slope", np.ascontiguousarray(slope))
        object.__setattr__(self, "resolution", positive("resolution", self.resolution, "m"))
        object.__setattr__(self, "origin", (float(origin[0]), float(origin[1])))
        object.__setattr__(self, "_table", np.stack([s.row() for s in surfaces]))

    # ------------------------------------------------------------------ constructors
    @classmethod
    def uniform(cls, surface: Surface) -> TerrainMap:
        """One surface everywhere, flat.

        Parameters
        ----------
        surface : Surface
            The ground.
        """
        return cls((surface,), np.zeros((1, 1), np.int32), np.zeros((1, 1, 2)))

    @classmethod
    def from_regions(
        cls,
        default: Surface,
        regions: Sequence[Region],
        *,
        bounds: tuple[float, float, float, float] | None = None,
        resolution: float = 0.05,
        max_cells: int = MAX_MAP_CELLS,
        base: TerrainMap | None = None,
    ) -> TerrainMap:
        """Rasterise regions over a rectangle (a cell takes the region its centre lies in).

        Parameters
        ----------
        default : Surface
            The ground outside every region (flat) and outside ``base``.
        regions : sequence of Region
            The regions; where two overlap they must agree (surface and grade), else
            ConfigError.
        bounds : (x_min, y_min, x_max, y_max), optional
            The rectangle [m] (default: the regions' bounding box).
        resolution : float
            Cell size [m].
        max_cells : int
            Most cells allowed.
        base : TerrainMap, optional
            A raster of surfaces under the regions (each cell takes the surface under its
            centre); the regions lie over it.
        """
        regions = list(regions)
        if not all(isinstance(region, Region) for region in regions):
            raise ConfigError("regions must be Region objects")
        resolution = positive("resolution", resolution, "m")
        if bounds is None:
            if not regions:
                return cls.uniform(default) if base is None else base
            points = np.vstack([region.polygon for region in regions])
            bounds = (*points.min(0), *points.max(0))
        x0, y0, x1, y1 = (finite("bounds", value, "m") for value in bounds)
        cols = max(1, math.ceil((x1 - x0) / resolution - 1e-9))
        rows = max(1, math.ceil((y1 - y0) / resolution - 1e-9))
        if rows * cols > max_cells:
            raise ConfigError(
                f"the terrain raster would be {rows} × {cols} cells of {resolution:g} m: more "
                f"than {max_cells}; use a coarser resolution"
            )
        surfaces: list[Surface] = [default]
        cells = np.zeros((rows, cols), np.int32)
        slope = np.zeros((rows, cols, 2))
        if base is not None:  # each cell the base's surface under its centre
            cx = x0 + (np.arange(cols) + 0.5) * resolution
            cy = y0 + (np.arange(rows) + 0.5) * resolution
            centres = np.stack(np.meshgrid(cx, cy), -1)
            inside = base.inside(centres)
            codes = base.index(centres)
            for code, surface in enumerate(base.surfaces):
                if surface not in surfaces:
                    surfaces.append(surface)
                cells[inside & (codes == code)] = surfaces.index(surface)
            slope[inside] = base.slope_at(centres)[inside]
        owner = np.full((rows, cols), -1, np.int64)
        for index, region in enumerate(regions):
            mask = np.zeros((rows, cols), np.bool_)
            _paint(region.polygon, x0, y0, resolution, rows, cols, mask)
            if region.surface in surfaces:
                code = surfaces.index(region.surface)
            else:
                surfaces.append(region.surface)
                code = len(surfaces) - 1
            taken = mask & (owner >= 0)
            clash = taken & ((cells != code) | np.any(slope != region.slope, axis=-1))
            if clash.any():
                r, c = np.argwhere(clash)[0]
                other = int(owner[r, c])
                raise ConfigError(
                    f"terrain regions {other} and {index} overlap with different surfaces or "
                    f"grades (e.g. at ({x0 + (c + 0.5) * resolution:.3g}, "
                    f"{y0 + (r + 0.5) * resolution:.3g}) m): make them disjoint"
                )
            cells[mask] = code
            slope[mask] = region.slope
            owner[mask & (owner < 0)] = index
        return cls(tuple(surfaces), cells, slope, resolution, (x0, y0))

    # ------------------------------------------------------------------ queries
    @property
    def table(self) -> np.ndarray:
        """Rows of :meth:`Surface.row` per surface, for the compiled plant (a copy)."""
        return self._table.copy()

    def index(self, points: ArrayLike) -> np.ndarray:
        """Surface index under points ``(..., 2)`` [m] (0 outside the raster).

        Parameters
        ----------
        points : array_like, shape (..., 2)
            Positions in the map frame [m].
        """
        xy = as_float_array("points", points, 2)
        col = np.floor((xy[..., 0] - self.origin[0]) / self.resolution).astype(np.int64)
        row = np.floor((xy[..., 1] - self.origin[1]) / self.resolution).astype(np.int64)
        rows, cols = self.cells.shape
        inside = (row >= 0) & (row < rows) & (col >= 0) & (col < cols)
        out = np.zeros(xy.shape[:-1], np.int64)
        out[inside] = self.cells[row[inside], col[inside]]
        return out

    def under_wheels(self, poses: ArrayLike, half_track: float) -> np.ndarray:
        """Surface index ``(N, 2)`` under the (left, right) wheels of robots at poses ``(N, 3)``.

        Parameters
        ----------
        poses : array_like, shape (N, 3) or more columns
            Poses (x [m], y [m], θ [rad], ...) of the axle's midpoint in the map frame.
        half_track : float
            Half the distance between the wheels [m] (the left wheel is on the +y side).
        """
        xy = np.asarray(poses, dtype=np.float64)
        c, s = np.cos(xy[:, 2]), np.sin(xy[:, 2])
        wheels = np.stack(
            [np.column_stack([xy[:, 0] - s * half_track, xy[:, 1] + c * half_track]),
             np.column_stack([xy[:, 0] + s * half_track, xy[:, 1] - c * half_track])], axis=1,
        )  # fmt: skip
        return self.index(wheels)

    def inside(self, points: ArrayLike) -> np.ndarray:
        """Whether points ``(..., 2)`` [m] lie on the raster.

        Parameters
        ----------
        points : array_like, shape (..., 2)
            Positions in the map frame [m].
        """
        xy = as_float_array("points", points, 2)
        col = np.floor((xy[..., 0] - self.origin[0]) / self.resolution)
        row = np.floor((xy[..., 1] - self.origin[1]) / self.resolution)
        rows, cols = self.cells.shape
        return (row >= 0) & (row < rows) & (col >= 0) & (col < cols)

    def slope_at(self, points: ArrayLike) -> np.ndarray:
        """Slope vectors ``(..., 2)`` under points (zeros outside the raster).

        Parameters
        ----------
        points : array_like, shape (..., 2)
            Positions in the map frame [m].
        """
        xy = as_float_array("points", points, 2)
        col = np.floor((xy[..., 0] - self.origin[0]) / self.resolution).astype(np.int64)
        row = np.floor((xy[..., 1] - self.origin[1]) / self.resolution).astype(np.int64)
        rows, cols = self.cells.shape
        inside = (row >= 0) & (row < rows) & (col >= 0) & (col < cols)
        out = np.zeros((*xy.shape[:-1], 2))
        out[inside] = self.slope[row[inside], col[inside]]
        return out

    @property
    def names(self) -> tuple[str, ...]:
        """Names of the surfaces, by index."""
        return tuple(surface.name for surface in self.surfaces)
