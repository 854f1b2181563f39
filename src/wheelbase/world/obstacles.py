"""Static obstacles that are not on the map: boxes, discs and polygons.

A scenario's ``world.obstacles`` lists them (boxes become 4-gons); the robot does not know
them, only its sensors see them. :class:`Obstacles` holds them as plain arrays: the polygons'
vertex rings and the discs, and packs them for the kernels of :mod:`wheelbase.world` (the
polygons' edges, each obstacle's bounding circle). The exact footprint checks against them are
those of a :class:`~wheelbase.planning.PolygonWorld` (:attr:`Obstacles.polygon_world`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np
from numpy.typing import ArrayLike

from wheelbase._validate import as_float_array
from wheelbase.errors import ConfigError, MapError
from wheelbase.limits import MAX_COORDINATE

__all__ = ["MAX_OBSTACLES", "MAX_VERTICES", "Obstacles", "box_polygon"]

MAX_OBSTACLES = 100_000
"""Most static obstacles of one world (every beam of a scan looks at each one's bounding
circle: 1e5 obstacles make a 360-beam scan take about 0.1 s)."""
MAX_VERTICES = 1_000_000
"""Most polygon vertices of one world, all polygons together."""

_KIND_POLYGON, _KIND_DISC = 0, 1


def box_polygon(x: float, y: float, length: float, width: float, yaw: float) -> np.ndarray:
    """The counter-clockwise corners ``(4, 2)`` [m] of a ``length × width`` box centred at
    ``(x, y)`` whose length lies along the heading ``yaw`` [rad].

    Parameters
    ----------
    x, y : float
        Centre [m].
    length, width : float
        Sides [m] along and across ``yaw``, > 0.
    yaw : float
        Heading of the long side [rad], counter-clockwise from +x.

    Returns
    -------
    numpy.ndarray

    Examples
    --------
    >>> box_polygon(1.0, 2.0, 2.0, 1.0, 0.0).tolist()
    [[0.0, 1.5], [2.0, 1.5], [2.0, 2.5], [0.0, 2.5]]
    """
    c, s = math.cos(yaw), math.sin(yaw)
    half = np.array([[-1, -1], [1, -1], [1, 1], [-1, 1]]) * (length / 2.0, width / 2.0)
    return np.column_stack(
        [x + c * half[:, 0] - s * half[:, 1], y + s * half[:, 0] + c * half[:, 1]]
    )


@dataclass(frozen=True, eq=False)
class Obstacles:
    """Static obstacles off the map: simple polygons (convex or not) and discs.

    Parameters
    ----------
    polygons : sequence of array_like
        Vertex rings ``(M, 2)`` [m], either orientation, not closed (a repeated first vertex is
        dropped); each a simple polygon with >= 3 distinct vertices and an area.
    discs : array_like
        Discs ``(K, 3)`` = (x [m], y [m], radius [m]), radius > 0.
    names : tuple of str or None
        How messages name each obstacle, the polygons first, then the discs (the scenario
        loader passes the key, ``"world.obstacles[2] (box)"``); default ``"polygon i"`` and
        ``"disc i"``.

    Raises
    ------
    MapError
        A polygon with non-finite vertices, fewer than 3 distinct ones, no area or a
        self-intersection; a disc with a radius <= 0; more than :data:`MAX_OBSTACLES`.

    Examples
    --------
    >>> obs = Obstacles([box_polygon(2.0, 2.0, 1.0, 1.0, 0.0)], [[5.0, 5.0, 0.5]])
    >>> len(obs), obs.segments.shape
    (2, (4, 4))
    """

    polygons: tuple = ()
    discs: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))
    names: tuple[str, ...] | None = None

    def __post_init__(self) -> None:
        import shapely

        rings = []
        total = 0
        for i, poly in enumerate(self.polygons):
            try:
                ring = np.asarray(poly, dtype=float)
            except (TypeError, ValueError):
                raise MapError(f"polygon {i} must be a list of [x, y] vertices [m]") from None
            if ring.ndim != 2 or ring.shape[1] != 2:
                raise MapError(f"polygon {i} must have shape (M, 2) (got {ring.shape})")
            total += len(ring)
            if total > MAX_VERTICES:
                raise MapError(f"polygon {i}: more than {MAX_VERTICES} vertices in all")
            if not np.all(np.isfinite(ring)) or np.max(np.abs(ring), initial=0) > MAX_COORDINATE:
                raise MapError(
                    f"polygon {i} must have finite vertices within ±{MAX_COORDINATE:g} m"
                )
            if len(ring) > 1 and np.array_equal(ring[0], ring[-1]):
                ring = ring[:-1]
            if len(np.unique(ring, axis=0)) < 3:
                raise MapError(f"polygon {i} needs >= 3 distinct vertices (got {len(ring)})")
            shape = shapely.Polygon(ring)
            if shapely.MultiPoint(ring).convex_hull.area <= 1e-12:
                raise MapError(f"polygon {i} has no area (its vertices are collinear)")
            if not shapely.is_valid(shape):
                raise MapError(f"polygon {i} is not simple: {shapely.is_valid_reason(shape)}")
            if shapely.is_ccw(shape.exterior) is False:
                ring = ring[::-1]
            ring = np.ascontiguousarray(ring)
            ring.setflags(write=False)
            rings.append(ring)
        object.__setattr__(self, "polygons", tuple(rings))
        try:
            discs = np.asarray(self.discs, dtype=float)
        except (TypeError, ValueError):
            raise MapError("discs must be numbers (x, y, radius) [m]") from None
        discs = discs.reshape(-1, 3) if discs.size else np.zeros((0, 3))
        for i, (x, y, r) in enumerate(discs):
            if not (math.isfinite(x) and math.isfinite(y) and math.isfinite(r)) or r <= 0:
                raise MapError(f"disc {i} must have a finite centre and radius > 0 m (got "
                               f"{[float(x), float(y), float(r)]})")  # fmt: skip
            if max(abs(x), abs(y), r) > MAX_COORDINATE:
                raise MapError(f"disc {i} must lie within ±{MAX_COORDINATE:g} m")
        discs = np.ascontiguousarray(discs)
        discs.setflags(write=False)
        object.__setattr__(self, "discs", discs)
        if len(rings) + len(discs) > MAX_OBSTACLES:
            raise MapError(
                f"{len(rings) + len(discs)} obstacles: more than {MAX_OBSTACLES} in one world"
            )
        if self.names is None:
            names = tuple(f"polygon {i}" for i in range(len(rings))) + tuple(
                f"disc {i}" for i in range(len(discs)))  # fmt: skip
        else:
            names = tuple(str(name) for name in self.names)
        if len(names) != len(rings) + len(discs):
            raise ConfigError(f"names must name each obstacle ({len(names)} for "
                              f"{len(rings) + len(discs)})")  # fmt: skip
        object.__setattr__(self, "names", names)

    def __len__(self) -> int:
        return len(self.polygons) + len(self.discs)

    # ------------------------------------------------------------------ packed for kernels
    @cached_property
    def segments(self) -> np.ndarray:
        """The polygons' edges ``(S, 4)`` = (x1, y1, x2, y2) [m], polygon by polygon."""
        rows = [np.column_stack([ring, np.roll(ring, -1, axis=0)]) for ring in self.polygons]
        out = np.ascontiguousarray(np.concatenate(rows) if rows else np.zeros((0, 4)))
        out.setflags(write=False)
        return out

    @cached_property
    def packed(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """``(segments (S, 4), start (Q + 1,), circle (Q, 3), kind (Q,))``: obstacle ``q``'s
        edges are ``segments[start[q]:start[q + 1]]`` (none for a disc), ``circle[q]`` its
        bounding circle (a disc: itself), ``kind[q]`` 0 for a polygon, 1 for a disc."""
        counts = [len(ring) for ring in self.polygons] + [0] * len(self.discs)
        start = np.zeros(len(counts) + 1, np.int64)
        np.cumsum(counts, out=start[1:])
        circles = np.zeros((len(counts), 3))
        for q, ring in enumerate(self.polygons):
            lo, hi = ring.min(0), ring.max(0)
            centre = (lo + hi) / 2.0
            circles[q, :2] = centre
            circles[q, 2] = np.max(np.hypot(*(ring - centre).T))
        circles[len(self.polygons) :] = self.discs
        kind = np.array([_KIND_POLYGON] * len(self.polygons) + [_KIND_DISC] * len(self.discs),
                        np.int64)  # fmt: skip
        return self.segments, start, np.ascontiguousarray(circles), kind

    def polygon_world(self, bounds: tuple[float, float, float, float], resolution: float):
        """These obstacles as a :class:`~wheelbase.planning.PolygonWorld` inside ``bounds``
        (exact footprint collision and clearance; leaving ``bounds`` counts as contact there,
        so pass bounds well beyond where robots go).

        Parameters
        ----------
        bounds : tuple of float
            ``(x_min, x_max, y_min, y_max)`` [m].
        resolution : float
            Raster cell [m] of its broad phase.

        Returns
        -------
        PolygonWorld
        """
        from wheelbase.planning import PolygonWorld

        return PolygonWorld(self.polygons, self.discs, bounds=bounds, resolution=resolution)

    def contains(self, xy: ArrayLike) -> np.ndarray:
        """Whether points lie inside (or on) an obstacle.

        Parameters
        ----------
        xy : array_like
            Points ``(..., 2)`` [m].

        Returns
        -------
        numpy.ndarray
            Boolean, shape ``xy.shape[:-1]``.
        """
        import shapely

        xy = as_float_array("xy", xy, 2, min_ndim=1)
        flat = xy.reshape(-1, 2)
        inside = np.zeros(len(flat), bool)
        for ring in self.polygons:
            inside |= shapely.intersects_xy(shapely.Polygon(ring), flat[:, 0], flat[:, 1])
        for x, y, r in self.discs:
            inside |= np.hypot(flat[:, 0] - x, flat[:, 1] - y) <= r
        return inside.reshape(xy.shape[:-1])
