"""Numba kernels for footprint collision and clearance in a world of cells and convex pieces.

A world reaches the kernels as one tuple (see ``_world_tuple``): an occupancy raster with its
distance field, the exact occupied cells (an :class:`~wheelbase.planning.OccupancyGrid`'s own,
or none), and exact convex pieces (the triangles of polygons and the discs of a
:class:`~wheelbase.planning.PolygonWorld`) filed in a uniform grid of buckets (the broad phase).

A convex footprint polygon placed at a pose collides iff it meets an occupied cell's closed
square, a piece, or leaves the raster's rectangle. Covering circles and the distance field decide
clear cases; a row-band scan with per-row prefix sums decides the cells exactly, and separating
axes (triangles) or a point-to-polygon distance (discs) decide the pieces found in the buckets
under the footprint's bounding box. The clearance is the exact polygon-to-square and
polygon-to-piece distance. The public entry points are the worlds' ``in_collision`` and
``footprint_clearance``; Hybrid A* calls ``_collides_one`` inside its compiled search.

The per-pose kernels (``_circles_clearance``, ``_collides_one`` and what it calls) are
compiled without Numba's reference counting (``_nrt=False``): they allocate nothing (the caller
passes scratch buffers) and keep no array, while with it every call took and released a
reference, with an atomic instruction, to each array of the world tuple and each array
argument, about 34 per check. Those atomics were a third of Hybrid A*'s time on the 60 m maze
(measured with ``perf``: the samples in Numba's ``NRT_incref``/``NRT_decref``); without them the
search's CPU time went from 150 to 80 ms.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numba
import numpy as np
from numpy.typing import ArrayLike

from wheelbase._validate import as_float_array, nonnegative, positive

if TYPE_CHECKING:
    from wheelbase.planning.footprint import Footprint

__all__ = ["FootprintChecks"]

# indices into the world tuple built by _world_tuple
_OCC, _PREFIX, _DIST, _RES, _X0, _Y0, _HAS_CELLS = 0, 1, 2, 3, 4, 5, 6
_PIECES, _NVERTS, _PRAD, _PAABB, _BSTART, _BITEMS, _BGEOM = 7, 8, 9, 10, 11, 12, 13


@numba.njit(cache=True, inline="always")
def _place_polygon(poly, x, y, th, out):
    """``poly`` placed at pose ``(x, y, th)``, written into ``out`` (same shape) and returned:
    the search kernels pass one buffer for all their checks (an allocation per check cost a
    fifth of Hybrid A*'s time)."""
    c, s = math.cos(th), math.sin(th)
    for k in range(poly.shape[0]):
        out[k, 0] = x + c * poly[k, 0] - s * poly[k, 1]
        out[k, 1] = y + s * poly[k, 0] + c * poly[k, 1]
    return out


@numba.njit(cache=True, inline="always")
def _bounds(wp):
    """``(xmin, xmax, ymin, ymax)`` [m] of the vertices ``wp`` (loops, not ``wp[:, 0].min()``:
    the exact check runs without reference counting, see ``_collides_one``)."""
    xmin = xmax = wp[0, 0]
    ymin = ymax = wp[0, 1]
    for k in range(1, wp.shape[0]):
        xmin = min(xmin, wp[k, 0])
        xmax = max(xmax, wp[k, 0])
        ymin = min(ymin, wp[k, 1])
        ymax = max(ymax, wp[k, 1])
    return xmin, xmax, ymin, ymax


@numba.njit(cache=True)
def _point_in_polygon(wp, px, py):
    m = wp.shape[0]
    for i in range(m):
        j = (i + 1) % m
        cross = (wp[j, 0] - wp[i, 0]) * (py - wp[i, 1]) - (wp[j, 1] - wp[i, 1]) * (px - wp[i, 0])
        if cross < 0.0:
            return False
    return True


@numba.njit(cache=True)
def _poly_square_separated(wp, sx0, sy0, side, gap):
    """True if convex polygon ``wp`` and square [sx0, sx0+side]² are more than ``gap`` apart
    along some separating axis (SAT; gap = 0 tests intersection of closed sets)."""
    m = wp.shape[0]
    pxmin, pxmax, pymin, pymax = _bounds(wp)
    if pxmax < sx0 - gap or pxmin > sx0 + side + gap:
        return True
    if pymax < sy0 - gap or pymin > sy0 + side + gap:
        return True
    for i in range(m):
        j = (i + 1) % m
        ex = wp[j, 0] - wp[i, 0]
        ey = wp[j, 1] - wp[i, 1]
        norm = math.sqrt(ex * ex + ey * ey)
        nx = ey / norm
        ny = -ex / norm
        # polygon lies on the side n·p <= n·wp[i] (CCW); square's min projection
        pmax = nx * wp[i, 0] + ny * wp[i, 1]
        smin = min(nx * sx0, nx * (sx0 + side)) + min(ny * sy0, ny * (sy0 + side))
        if smin > pmax + gap:
            return True
    return False


def _world_tuple(
    occupied: np.ndarray,
    prefix: np.ndarray,
    distance: np.ndarray,
    resolution: float,
    origin: tuple[float, float],
    has_cells: bool,
    pieces: tuple | None = None,
) -> tuple:
    """Pack a world for the kernels.

    ``occupied``/``prefix`` are the exact occupied cells (all free when ``has_cells`` is false),
    ``distance`` the distance field [m] of a raster that covers every obstacle (cells and
    pieces); ``pieces`` is ``(vertices (K, 3, 2), nverts (K,), radius (K,), aabb (K, 4),
    bucket_start, bucket_items, (bx0, by0, bucket_size, bnx, bny))`` or None.
    """
    if pieces is None:
        pieces = (
            np.zeros((0, 3, 2)),
            np.zeros(0, np.int64),
            np.zeros(0),
            np.zeros((0, 4)),
            np.zeros(2, np.int64),
            np.zeros(0, np.int64),
            (0.0, 0.0, 1.0, 1, 1),
        )
    return (
        occupied.view(np.uint8),
        prefix,
        np.asarray(distance),
        float(resolution),
        float(origin[0]),
        float(origin[1]),
        bool(has_cells),
        *pieces,
    )


@numba.njit(cache=True, _nrt=False)
def _circles_clearance(dist, res, x0, y0, circles, radius, x, y, th):
    """A lower bound [m] on how far every covering circle at pose ``(x, y, th)`` stays from
    the obstacles and the map's edge: positive means the footprint is clear, and clear still
    after any motion that moves no circle centre that far. The distance field ``dist`` (of
    a raster with cells ``res`` from ``(x0, y0)``) at the cell of a centre less √2·res (the
    farthest a point lies from its cell's centre, and the cell centre from the nearest
    obstacle point) bounds the centre's distance to the obstacles; -1 when a centre is off
    the map. (Arrays and scalars, not the world tuple: taking arrays out of a tuple costs
    atomic reference counts, a third of the search's time when done per sample.)"""
    rows, cols = dist.shape
    slack = math.sqrt(2.0) * res
    c, s = math.cos(th), math.sin(th)
    best = np.inf
    for k in range(circles.shape[0]):
        cx = x + c * circles[k, 0] - s * circles[k, 1]
        cy = y + s * circles[k, 0] + c * circles[k, 1]
        i = math.floor((cy - y0) / res)
        j = math.floor((cx - x0) / res)
        if i < 0 or i >= rows or j < 0 or j >= cols:
            return -1.0
        edge = min(cx - x0, x0 + cols * res - cx, cy - y0, y0 + rows * res - cy)
        best = min(best, dist[i, j] - slack - radius, edge - radius)
    return best


@numba.njit(cache=True, _nrt=False)
def _collides_one(world, poly, circles, radius, x, y, th, wp, near):
    """Does footprint ``poly`` (covered by ``circles`` of ``radius``) at ``(x, y, th)`` collide?
    ``wp`` (shaped as ``poly``) and ``near`` (int64, one per piece) are scratch buffers."""
    occ = world[_OCC]
    dist = world[_DIST]
    res = world[_RES]
    x0 = world[_X0]
    y0 = world[_Y0]
    if _circles_clearance(dist, res, x0, y0, circles, radius, x, y, th) > 0.0:
        return False  # the circles cover the footprint and are all clear (fast path)
    has_cells = world[_HAS_CELLS]
    rows, cols = occ.shape
    _place_polygon(poly, x, y, th, wp)
    xmax_map = x0 + cols * res
    ymax_map = y0 + rows * res
    for k in range(wp.shape[0]):
        if wp[k, 0] < x0 or wp[k, 0] >= xmax_map or wp[k, 1] < y0 or wp[k, 1] >= ymax_map:
            return True
    c, s = math.cos(th), math.sin(th)
    slack = math.sqrt(2.0) * res
    all_clear = True
    for k in range(circles.shape[0]):
        cx = x + c * circles[k, 0] - s * circles[k, 1]
        cy = y + s * circles[k, 0] + c * circles[k, 1]
        j = math.floor((cx - x0) / res)
        i = math.floor((cy - y0) / res)
        if i < 0 or i >= rows or j < 0 or j >= cols:
            all_clear = False
            continue
        if has_cells and occ[i, j] and _point_in_polygon(wp, cx, cy):
            return True
        if dist[i, j] - slack <= radius:
            all_clear = False
    if all_clear:
        return False
    if has_cells and _polygon_hits_cells(world[_PREFIX], res, x0, y0, wp):
        return True
    if world[_PIECES].shape[0] > 0:
        return _polygon_hits_pieces(world, wp, near)
    return False


@numba.njit(cache=True)
def _polygon_hits_cells(prefix, res, x0, y0, wp):
    """Exact test: does convex polygon ``wp`` meet any occupied (closed) cell square?

    Row band by row band: the polygon's x-extent inside the band [y_i, y_i + r] is an interval
    (convexity), and a square of that row meets the polygon iff its x-range meets that interval;
    per-row prefix sums of occupancy answer "any occupied cell in columns j0..j1" in O(1).
    """
    rows = prefix.shape[0]
    cols = prefix.shape[1] - 1
    m = wp.shape[0]
    _xmin, _xmax, ymin, ymax = _bounds(wp)
    i0 = max(0, math.ceil((ymin - y0) / res) - 1)
    i1 = min(rows - 1, math.floor((ymax - y0) / res))
    for i in range(i0, i1 + 1):
        yb0 = y0 + i * res
        yb1 = yb0 + res
        lo = np.inf
        hi = -np.inf
        for k in range(m):
            vx = wp[k, 0]
            vy = wp[k, 1]
            if yb0 <= vy <= yb1:
                lo = min(lo, vx)
                hi = max(hi, vx)
            ax, ay = vx, vy
            bx = wp[(k + 1) % m, 0]
            by = wp[(k + 1) % m, 1]
            if ay != by:
                for yl in (yb0, yb1):
                    if (ay - yl) * (by - yl) <= 0.0:
                        xl = ax + (yl - ay) * (bx - ax) / (by - ay)
                        lo = min(lo, xl)
                        hi = max(hi, xl)
        if lo > hi:
            continue
        j0 = max(0, math.ceil((lo - x0) / res) - 1)
        j1 = min(cols - 1, math.floor((hi - x0) / res))
        if j1 >= j0 and prefix[i, j1 + 1] - prefix[i, j0] > 0:
            return True
    return False


@numba.njit(cache=True)
def _bucket_range(world, xlo, xhi, ylo, yhi):
    bx0, by0, bsize, bnx, bny = world[_BGEOM]
    i0 = max(0, math.floor((ylo - by0) / bsize))
    i1 = min(bny - 1, math.floor((yhi - by0) / bsize))
    j0 = max(0, math.floor((xlo - bx0) / bsize))
    j1 = min(bnx - 1, math.floor((xhi - bx0) / bsize))
    return i0, i1, j0, j1


@numba.njit(cache=True)
def _first_shared_bucket(world, k, i0, j0):
    """The first bucket (row-major) that piece ``k`` and a query starting at ``(i0, j0)``
    share, so that a piece filed in several buckets is tested once."""
    bx0, by0, bsize, _bnx, _bny = world[_BGEOM]
    aabb = world[_PAABB]
    pi = max(0, math.floor((aabb[k, 2] - by0) / bsize))
    pj = max(0, math.floor((aabb[k, 0] - bx0) / bsize))
    return max(i0, pi), max(j0, pj)


@numba.njit(cache=True)
def _pieces_in_box(world, xlo, xhi, ylo, yhi, out):
    """The broad phase: write into ``out`` (room for every piece) the pieces whose bounding
    box meets ``[xlo, xhi] × [ylo, yhi]``, each once, from the buckets under the box; returns
    how many."""
    aabb = world[_PAABB]
    bstart = world[_BSTART]
    bitems = world[_BITEMS]
    bnx = world[_BGEOM][3]
    count = 0
    i0, i1, j0, j1 = _bucket_range(world, xlo, xhi, ylo, yhi)
    for i in range(i0, i1 + 1):
        for j in range(j0, j1 + 1):
            b = i * bnx + j
            for q in range(bstart[b], bstart[b + 1]):
                k = bitems[q]
                if aabb[k, 0] > xhi or aabb[k, 1] < xlo or aabb[k, 2] > yhi or aabb[k, 3] < ylo:
                    continue
                fi, fj = _first_shared_bucket(world, k, i0, j0)
                if fi == i and fj == j:
                    out[count] = k
                    count += 1
    return count


@numba.njit(cache=True)
def _convex_separated(a, na, b, nb):
    """True if convex polygons ``a[:na]`` and ``b[:nb]`` (any orientation) are disjoint as
    closed sets: some edge normal of either separates their projections strictly."""
    for pass_ in range(2):
        p = a if pass_ == 0 else b
        n = na if pass_ == 0 else nb
        for i in range(n):
            j = (i + 1) % n
            ax = -(p[j, 1] - p[i, 1])
            ay = p[j, 0] - p[i, 0]
            amin = np.inf
            amax = -np.inf
            for k in range(na):
                v = ax * a[k, 0] + ay * a[k, 1]
                amin = min(amin, v)
                amax = max(amax, v)
            bmin = np.inf
            bmax = -np.inf
            for k in range(nb):
                v = ax * b[k, 0] + ay * b[k, 1]
                bmin = min(bmin, v)
                bmax = max(bmax, v)
            if amax < bmin or bmax < amin:
                return True
    return False


@numba.njit(cache=True)
def _point_polygon_distance(wp, px, py):
    """Distance [m] from a point to a convex counter-clockwise polygon (0 inside)."""
    if _point_in_polygon(wp, px, py):
        return 0.0
    best = np.inf
    m = wp.shape[0]
    for i in range(m):
        j = (i + 1) % m
        ux = wp[j, 0] - wp[i, 0]
        uy = wp[j, 1] - wp[i, 1]
        ll = ux * ux + uy * uy
        t = (
            0.0
            if ll == 0.0
            else max(0.0, min(1.0, ((px - wp[i, 0]) * ux + (py - wp[i, 1]) * uy) / ll))
        )
        ex = wp[i, 0] + t * ux - px
        ey = wp[i, 1] + t * uy - py
        best = min(best, ex * ex + ey * ey)
    return math.sqrt(best)


@numba.njit(cache=True)
def _piece_hit(wp, piece, nv, rad):
    if nv == 1:
        return _point_polygon_distance(wp, piece[0, 0], piece[0, 1]) <= rad
    return not _convex_separated(wp, wp.shape[0], piece, nv)


@numba.njit(cache=True)
def _polygon_hits_pieces(world, wp, near):
    """Exact test: does convex polygon ``wp`` meet any piece filed under its bounding box?
    (``near``: scratch, room for every piece.)"""
    pieces = world[_PIECES]
    nverts = world[_NVERTS]
    prad = world[_PRAD]
    xmin, xmax, ymin, ymax = _bounds(wp)
    n = _pieces_in_box(world, xmin, xmax, ymin, ymax, near)
    for m in range(n):
        k = near[m]
        if _piece_hit(wp, pieces[k], nverts[k], prad[k]):
            return True
    return False


@numba.njit(cache=True)
def _scratch(world, poly):
    """Scratch buffers for ``_collides_one``: a placed polygon and the broad phase's list."""
    return np.empty_like(poly), np.empty(world[_PIECES].shape[0], dtype=np.int64)


@numba.njit(cache=True)
def _collides_batch(world, poly, circles, radius, poses):
    out = np.empty(poses.shape[0], dtype=np.bool_)
    wp, near = _scratch(world, poly)
    for n in range(poses.shape[0]):
        x, y, th = poses[n, 0], poses[n, 1], poses[n, 2]
        out[n] = _collides_one(world, poly, circles, radius, x, y, th, wp, near)
    return out


@numba.njit(cache=True)
def _seg_seg_dist2(ax, ay, bx, by, cx, cy, dx, dy):
    best = np.inf
    for px, py, qx, qy, rx, ry in (
        (ax, ay, cx, cy, dx, dy),
        (bx, by, cx, cy, dx, dy),
        (cx, cy, ax, ay, bx, by),
        (dx, dy, ax, ay, bx, by),
    ):
        ux, uy = rx - qx, ry - qy
        ll = ux * ux + uy * uy
        t = 0.0 if ll == 0 else max(0.0, min(1.0, ((px - qx) * ux + (py - qy) * uy) / ll))
        ex, ey = qx + t * ux - px, qy + t * uy - py
        best = min(best, ex * ex + ey * ey)
    return best


@numba.njit(cache=True)
def _poly_square_distance(wp, sx, sy, side):
    if not _poly_square_separated(wp, sx, sy, side, 0.0):
        return 0.0
    sq = np.array([[sx, sy], [sx + side, sy], [sx + side, sy + side], [sx, sy + side]])
    best = np.inf
    m = wp.shape[0]
    for i in range(m):
        a = wp[i]
        b = wp[(i + 1) % m]
        for k in range(4):
            c = sq[k]
            d = sq[(k + 1) % 4]
            best = min(best, _seg_seg_dist2(a[0], a[1], b[0], b[1], c[0], c[1], d[0], d[1]))
    return math.sqrt(best)


@numba.njit(cache=True)
def _poly_piece_distance(wp, piece, nv, rad):
    if nv == 1:
        return max(0.0, _point_polygon_distance(wp, piece[0, 0], piece[0, 1]) - rad)
    if not _convex_separated(wp, wp.shape[0], piece, nv):
        return 0.0
    best = np.inf
    m = wp.shape[0]
    for i in range(m):
        a = wp[i]
        b = wp[(i + 1) % m]
        for k in range(nv):
            c = piece[k]
            d = piece[(k + 1) % nv]
            best = min(best, _seg_seg_dist2(a[0], a[1], b[0], b[1], c[0], c[1], d[0], d[1]))
    return math.sqrt(best)


@numba.njit(cache=True)
def _clearance_batch(world, poly, circles, radius, poses):
    wp, near = _scratch(world, poly)
    out = np.empty(poses.shape[0])
    for n in range(poses.shape[0]):
        x, y, th = poses[n, 0], poses[n, 1], poses[n, 2]
        out[n] = _clearance_one(world, poly, circles, radius, x, y, th, wp, near)
    return out


@numba.njit(cache=True)
def _clearance_one(world, poly, circles, radius, x, y, th, wp, near):
    """Distance [m] from the footprint ``poly`` at pose ``(x, y, th)`` to the nearest obstacle
    (0 in collision; ``wp``, ``near``: scratch of :func:`_scratch`)."""
    occ = world[_OCC]
    dist = world[_DIST]
    res = world[_RES]
    x0 = world[_X0]
    y0 = world[_Y0]
    has_cells = world[_HAS_CELLS]
    pieces = world[_PIECES]
    nverts = world[_NVERTS]
    prad = world[_PRAD]
    rows, cols = occ.shape
    slack = math.sqrt(2.0) * res
    if _collides_one(world, poly, circles, radius, x, y, th, wp, near):
        return 0.0
    _place_polygon(poly, x, y, th, wp)  # (the check may return before placing it)
    # search radius: an upper bound on the clearance from points of the polygon (its first
    # vertex and the covering-circle centres that lie inside it)
    j = min(cols - 1, max(0, math.floor((wp[0, 0] - x0) / res)))
    i = min(rows - 1, max(0, math.floor((wp[0, 1] - y0) / res)))
    reach = dist[i, j] + slack
    c, s = math.cos(th), math.sin(th)
    for k in range(circles.shape[0]):
        cx = x + c * circles[k, 0] - s * circles[k, 1]
        cy = y + s * circles[k, 0] + c * circles[k, 1]
        if _point_in_polygon(wp, cx, cy):
            j = min(cols - 1, max(0, math.floor((cx - x0) / res)))
            i = min(rows - 1, max(0, math.floor((cy - y0) / res)))
            reach = min(reach, dist[i, j] + slack)
    if not np.isfinite(reach):
        return np.inf
    xmin, xmax, ymin, ymax = _bounds(wp)
    xlo, xhi, ylo, yhi = xmin - reach, xmax + reach, ymin - reach, ymax + reach
    best = np.inf
    if has_cells:
        j0 = max(0, math.floor((xlo - x0) / res))
        j1 = min(cols - 1, math.floor((xhi - x0) / res))
        i0 = max(0, math.floor((ylo - y0) / res))
        i1 = min(rows - 1, math.floor((yhi - y0) / res))
        for a in range(i0, i1 + 1):
            for b in range(j0, j1 + 1):
                if occ[a, b]:
                    d = _poly_square_distance(wp, x0 + b * res, y0 + a * res, res)
                    best = min(best, d)
    for m in range(_pieces_in_box(world, xlo, xhi, ylo, yhi, near)):
        k = near[m]
        best = min(best, _poly_piece_distance(wp, pieces[k], nverts[k], prad[k]))
    return best


class FootprintChecks:
    """Footprint collision and clearance queries shared by every kind of world.

    A world provides ``_kernel_world`` (its arrays packed by ``_world_tuple``) and
    ``is_occupied(xy)`` (exact point test); these methods do the rest.
    """

    _kernel_world: tuple

    def is_occupied(self, xy: ArrayLike) -> np.ndarray:  # pragma: no cover - overridden
        """Whether world points are inside an obstacle or off the map.

        Parameters
        ----------
        xy : array_like
            Points or poses [m].

        Returns
        -------
        numpy.ndarray
        """
        raise NotImplementedError

    def in_collision(
        self, footprint: Footprint, poses: ArrayLike, *, margin: float = 0.0
    ) -> np.ndarray:
        """Footprint collision check at one pose ``(3,)`` or a batch ``(N, 3)``.

        A pose collides iff the footprint polygon (grown by ``margin`` along every edge
        normal) intersects an occupied cell's square or leaves the map. Exact to the cell
        resolution: the distance field and covering circles decide clear cases, an exact
        separating-axis test decides the rest.

        Parameters
        ----------
        footprint : Footprint
            Robot outline in the body frame of the reference point.
        poses : array_like
            Reference-point poses ``(x, y, θ)`` [m, m, rad], shape ``(3,)`` or ``(N, 3)``.
        margin : float
            Extra clearance [m], >= 0.

        Returns
        -------
        numpy.ndarray
            Boolean, shape ``poses.shape[:-1]``.
        """
        poses = as_float_array("poses", poses, 3, min_ndim=1, max_ndim=2)
        margin = nonnegative("margin", margin, "m")
        fp = footprint.inflated(margin) if margin > 0 else footprint
        flat = poses.reshape(-1, 3)
        out = _collides_batch(
            self._kernel_world,
            fp.polygon,
            fp.circles,
            fp.circle_radius,
            flat,
        )
        return out.reshape(poses.shape[:-1])

    def lattice_collisions(
        self, footprint: Footprint, poses: ArrayLike, spacing: float = 0.02
    ) -> np.ndarray:
        """Brute-force reference check: whether each pose's footprint, sampled as a lattice of
        points ``spacing`` apart, has a point on an occupied cell (or off the map).

        Slow and independent of :meth:`in_collision` (no distance field, no covering circles,
        no cell rasterisation): tests and benchmarks use it to verify the fast path and planned
        paths. A gap narrower than ``spacing`` between lattice points can be missed.

        Parameters
        ----------
        footprint : Footprint
            Robot outline.
        poses : array_like, shape (N, 3)
            Poses [m, m, rad].
        spacing : float
            Lattice spacing [m], > 0.

        Returns
        -------
        numpy.ndarray
            Boolean array of shape (N,).
        """
        spacing = positive("spacing", spacing, "m")
        poses = as_float_array("poses", poses, 3, min_ndim=2, max_ndim=2)
        poly = footprint.polygon
        lo, hi = poly.min(0), poly.max(0)
        xs = np.linspace(lo[0], hi[0], math.ceil((hi[0] - lo[0]) / spacing) + 1)
        ys = np.linspace(lo[1], hi[1], math.ceil((hi[1] - lo[1]) / spacing) + 1)
        points = np.stack(np.meshgrid(xs, ys), -1).reshape(-1, 2)
        # keep the lattice points inside the (convex, counter-clockwise) polygon
        edges = np.roll(poly, -1, 0) - poly
        cross = edges[:, 0] * (points[:, None, 1] - poly[:, 1]) - edges[:, 1] * (
            points[:, None, 0] - poly[:, 0]
        )
        points = points[np.all(cross >= -1e-12, axis=1)]
        hits = np.zeros(len(poses), bool)
        for rows in np.array_split(np.arange(len(poses)), max(1, len(poses) // 500)):
            chunk = poses[rows]
            c, s = np.cos(chunk[:, 2]), np.sin(chunk[:, 2])
            wx = chunk[:, None, 0] + c[:, None] * points[:, 0] - s[:, None] * points[:, 1]
            wy = chunk[:, None, 1] + s[:, None] * points[:, 0] + c[:, None] * points[:, 1]
            hits[rows] = np.any(self.is_occupied(np.stack([wx, wy], -1)), axis=1)
        return hits

    def footprint_clearance(self, footprint: Footprint, poses: ArrayLike) -> np.ndarray:
        """Distance [m] from the footprint polygon at each pose to the nearest occupied cell.

        Exact polygon-to-square distance over occupied cells near the footprint (searched
        within the distance-field bound); 0 when in collision.

        Parameters
        ----------
        footprint : Footprint
            Robot outline.
        poses : array_like
            Poses ``(N, 3)`` or ``(3,)``.

        Returns
        -------
        numpy.ndarray
            Clearances [m], shape ``poses.shape[:-1]``.
        """
        poses = as_float_array("poses", poses, 3, min_ndim=1, max_ndim=2)
        flat = poses.reshape(-1, 3)
        out = _clearance_batch(
            self._kernel_world,
            footprint.polygon,
            footprint.circles,
            footprint.circle_radius,
            flat,
        )
        return out.reshape(poses.shape[:-1])
