"""What does not move, packed for the kernels: the map's cells and the static obstacles.

The agents' kernels ask one question of it: the nearest point of a wall or an obstacle. The
tuple built by :func:`pack_statics` holds

- the map's occupied cells (an :class:`~wheelbase.planning.OccupancyGrid`'s; cells outside the
  map are occupied, as everywhere in wheelbase) and a lower bound of the distance from any
  point of each cell to the nearest wall or obstacle (the Euclidean distance transform of the
  map with the obstacles rasterised, less √2 cells), which lets the exact searches skip
  everything far from an obstacle;
- the map's feature transform (for each cell, the occupied cell whose centre is nearest to its
  centre, :func:`scipy.ndimage.distance_transform_edt`), which gives the nearest wall point to
  within a cell in O(1): the "distance field" the social forces and ORCA's wall half-planes
  read;
- the static obstacles (:attr:`Obstacles.packed`): polygon edges and bounding circles, discs.

Exact nearest points (:func:`static_nearest`) search the cells within reach one by one and the
obstacles whose bounding circle is within reach; distances are signed (negative inside).
"""

from __future__ import annotations

import math

import numba
import numpy as np
from scipy import ndimage

__all__ = [
    "first_overlap",
    "map_feature_point",
    "map_nearest",
    "nearest_obstacle_points",
    "obstacle_nearest",
    "pack_statics",
    "static_nearest",
    "wall_points",
]

# indices into the tuple of pack_statics
OCC, RES, X0, Y0, BOUND, FEAT, SEGS, START, CIRCLE, KIND = range(10)


def pack_statics(grid, obstacles) -> tuple:
    """The kernels' tuple (module docstring) for a map and its static obstacles.

    Parameters
    ----------
    grid : OccupancyGrid
        The map.
    obstacles : Obstacles
        The static obstacles off the map.

    Returns
    -------
    tuple
        ``(occupied uint8 (rows, cols), resolution, x0, y0, bound (rows, cols) [m],
        feature (rows, cols, 2) int64, segments, start, circle, kind)``.
    """
    from wheelbase.planning import PolygonWorld

    occ = np.ascontiguousarray(grid.occupied.view(np.uint8))
    res = float(grid.resolution)
    if len(obstacles):
        with_obstacles = PolygonWorld(obstacles.polygons, obstacles.discs, grid=grid).raster
        solid = with_obstacles.occupied
    else:
        solid = grid.occupied
    padded = np.pad(solid, 1, constant_values=True)
    centre = ndimage.distance_transform_edt(~padded)[1:-1, 1:-1] * res
    bound = np.ascontiguousarray(np.maximum(centre - math.sqrt(2.0) * res, 0.0))
    _, index = ndimage.distance_transform_edt(
        ~np.pad(grid.occupied, 1, constant_values=True), return_indices=True
    )
    feature = np.ascontiguousarray(np.stack(index, -1)[1:-1, 1:-1].astype(np.int64) - 1)
    segs, start, circle, kind = obstacles.packed
    return (occ, res, float(grid.origin[0]), float(grid.origin[1]), bound, feature,
            segs, start, circle, kind)  # fmt: skip


@numba.njit(cache=True, inline="always")
def bound_at(st, px, py):
    """Lower bound [m] of the distance from ``(px, py)`` to every wall and obstacle (0 off
    the map)."""
    bound = st[BOUND]
    res = st[RES]
    j = math.floor((px - st[X0]) / res)
    i = math.floor((py - st[Y0]) / res)
    if i < 0 or j < 0 or i >= bound.shape[0] or j >= bound.shape[1]:
        return 0.0
    return bound[i, j]


@numba.njit(cache=True)
def _square_nearest(sx, sy, side, px, py):
    """Signed distance from a point to the closed square ``[sx, sx+side] × [sy, sy+side]`` and
    the nearest point of its boundary."""
    qx = min(max(px, sx), sx + side)
    qy = min(max(py, sy), sy + side)
    if qx != px or qy != py:
        return math.hypot(px - qx, py - qy), qx, qy
    # inside: the nearest side
    best = px - sx
    qx, qy = sx, py
    if sx + side - px < best:
        best = sx + side - px
        qx, qy = sx + side, py
    if py - sy < best:
        best = py - sy
        qx, qy = px, sy
    if sy + side - py < best:
        best = sy + side - py
        qx, qy = px, sy + side
    return -best, qx, qy


@numba.njit(cache=True)
def map_nearest(st, px, py, reach):
    """Exact signed distance from a point to the map's occupied cells (outside the map
    included) and the nearest boundary point; ``inf`` when none is within ``reach``."""
    occ = st[OCC]
    res = st[RES]
    x0 = st[X0]
    y0 = st[Y0]
    rows, cols = occ.shape
    best = np.inf
    bx = px
    by = py
    if bound_at(st, px, py) > reach:
        return best, bx, by
    j0 = math.floor((px - reach - x0) / res)
    j1 = math.floor((px + reach - x0) / res)
    i0 = math.floor((py - reach - y0) / res)
    i1 = math.floor((py + reach - y0) / res)
    for i in range(i0, i1 + 1):
        for j in range(j0, j1 + 1):
            if 0 <= i < rows and 0 <= j < cols and occ[i, j] == 0:
                continue
            d, qx, qy = _square_nearest(x0 + j * res, y0 + i * res, res, px, py)
            if d < best:
                best, bx, by = d, qx, qy
    return best, bx, by


@numba.njit(cache=True)
def map_feature_point(st, px, py):
    """Distance [m] from a point to the nearest wall point by the feature transform (good to
    a cell: the occupied cell nearest to the point's cell centre) and that point."""
    feat = st[FEAT]
    res = st[RES]
    x0 = st[X0]
    y0 = st[Y0]
    rows, cols = feat.shape[0], feat.shape[1]
    j = min(max(math.floor((px - x0) / res), 0), cols - 1)
    i = min(max(math.floor((py - y0) / res), 0), rows - 1)
    fi = feat[i, j, 0]
    fj = feat[i, j, 1]
    return _square_nearest(x0 + fj * res, y0 + fi * res, res, px, py)


@numba.njit(cache=True)
def _segment_nearest(ax, ay, bx, by, px, py):
    ux = bx - ax
    uy = by - ay
    ll = ux * ux + uy * uy
    t = 0.0 if ll == 0.0 else max(0.0, min(1.0, ((px - ax) * ux + (py - ay) * uy) / ll))
    qx = ax + t * ux
    qy = ay + t * uy
    return (px - qx) ** 2 + (py - qy) ** 2, qx, qy


@numba.njit(cache=True)
def obstacle_nearest(st, q, px, py):
    """Signed distance from a point to static obstacle ``q`` (negative inside) and the
    nearest point of its boundary."""
    circle = st[CIRCLE]
    if st[KIND][q] == 1:
        cx, cy, r = circle[q, 0], circle[q, 1], circle[q, 2]
        d = math.hypot(px - cx, py - cy)
        if d == 0.0:
            return -r, cx + r, cy
        return d - r, cx + (px - cx) * r / d, cy + (py - cy) * r / d
    segs = st[SEGS]
    start = st[START]
    best = np.inf
    bx = px
    by = py
    crossings = 0
    for s in range(start[q], start[q + 1]):
        ax, ay, cx, cy = segs[s, 0], segs[s, 1], segs[s, 2], segs[s, 3]
        d2, qx, qy = _segment_nearest(ax, ay, cx, cy, px, py)
        if d2 < best:
            best, bx, by = d2, qx, qy
        if (ay > py) != (cy > py) and px < ax + (py - ay) * (cx - ax) / (cy - ay):
            crossings += 1  # even-odd rule
    d = math.sqrt(best)
    return (-d if crossings % 2 == 1 else d), bx, by


@numba.njit(cache=True)
def static_nearest(st, px, py, reach):
    """Exact signed distance from a point to the nearest wall or static obstacle within
    ``reach`` and the push direction (unit vector from that point towards free space):
    ``(distance, nx, ny)``; ``(inf, 0, 0)`` when nothing is within reach."""
    if bound_at(st, px, py) > reach:  # the bound covers the obstacles too
        return np.inf, 0.0, 0.0
    best, wx, wy = map_nearest(st, px, py, reach)
    circle = st[CIRCLE]
    for q in range(circle.shape[0]):
        if math.hypot(px - circle[q, 0], py - circle[q, 1]) - circle[q, 2] > reach:
            continue
        d, qx, qy = obstacle_nearest(st, q, px, py)
        if d < best:
            best, wx, wy = d, qx, qy
    if best == np.inf:
        return best, 0.0, 0.0
    nx, ny = push_direction(best, wx, wy, px, py)
    return best, nx, ny


@numba.njit(cache=True, inline="always")
def push_direction(d, wx, wy, px, py):
    """Unit vector from an obstacle's nearest point ``w`` towards free space for a point at
    signed distance ``d`` (outside: from w to the point; inside: from the point to w)."""
    ex = px - wx
    ey = py - wy
    norm = math.hypot(ex, ey)
    if norm == 0.0:
        return 1.0, 0.0
    if d < 0.0:
        return -ex / norm, -ey / norm
    return ex / norm, ey / norm


@numba.njit(cache=True)
def nearest_obstacle_points(st, points):
    """For each point ``(M, 2)``: the signed distance [m] to the nearest static obstacle (not
    the map) and that obstacle's nearest point, ``(d, wx, wy)``; ``inf`` without obstacles."""
    n = points.shape[0]
    dist = np.full(n, np.inf)
    wx = points[:, 0].copy()
    wy = points[:, 1].copy()
    for m in range(n):
        for q in range(st[CIRCLE].shape[0]):
            d, qx, qy = obstacle_nearest(st, q, points[m, 0], points[m, 1])
            if d < dist[m]:
                dist[m], wx[m], wy[m] = d, qx, qy
    return dist, wx, wy


@numba.njit(cache=True)
def first_overlap(st, discs):
    """The first ``(world, disc, obstacle, distance)`` where a disc of ``discs (B, P, 3)`` =
    (x, y, radius) overlaps a static obstacle (its centre closer than its radius; touching is
    allowed), or ``(-1, -1, -1, inf)``."""
    for b in range(discs.shape[0]):
        for p in range(discs.shape[1]):
            x, y, r = discs[b, p, 0], discs[b, p, 1], discs[b, p, 2]
            for q in range(st[CIRCLE].shape[0]):
                d = obstacle_nearest(st, q, x, y)[0]
                if d < r:
                    return b, p, q, d
    return -1, -1, -1, np.inf


@numba.njit(cache=True)
def wall_points(st, px, py, reach, dist, nx, ny):
    """The walls a behaviour reacts to: the map's nearest point (the feature transform) and
    the nearest point of each static obstacle within ``reach`` [m] of ``(px, py)``; writes
    their signed distances and push directions into ``dist, nx, ny`` (room for one more than
    the obstacles) and returns how many."""
    count = 0
    d, wx, wy = map_feature_point(st, px, py)
    circle = st[CIRCLE]
    for q in range(-1, circle.shape[0]):
        if q >= 0:
            if math.hypot(px - circle[q, 0], py - circle[q, 1]) - circle[q, 2] > reach:
                continue
            d, wx, wy = obstacle_nearest(st, q, px, py)
        if d > reach:
            continue
        dist[count] = d
        nx[count], ny[count] = push_direction(d, wx, wy, px, py)
        count += 1
    return count
