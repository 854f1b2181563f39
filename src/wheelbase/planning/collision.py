"""Numba kernels for footprint collision and clearance on an occupancy grid.

A convex footprint polygon placed at a pose is tested against occupied cell squares: covering
circles and the distance field decide clear cases, a row-band scan with per-row prefix sums
decides the rest exactly; the clearance is an exact polygon-to-square distance. The public
entry points are :meth:`OccupancyGrid.in_collision` and
:meth:`OccupancyGrid.footprint_clearance`; Hybrid A* calls :func:`_collides_one` inside its
compiled search.
"""

from __future__ import annotations

import math

import numba
import numpy as np

__all__: list[str] = []


@numba.njit(cache=True)
def _world_polygon(poly, x, y, th):
    c, s = math.cos(th), math.sin(th)
    out = np.empty_like(poly)
    for k in range(poly.shape[0]):
        out[k, 0] = x + c * poly[k, 0] - s * poly[k, 1]
        out[k, 1] = y + s * poly[k, 0] + c * poly[k, 1]
    return out


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
    pxmin = wp[:, 0].min()
    pxmax = wp[:, 0].max()
    pymin = wp[:, 1].min()
    pymax = wp[:, 1].max()
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


@numba.njit(cache=True)
def _collides_one(occ, prefix, dist, res, x0, y0, poly, circles, radius, x, y, th):
    rows, cols = occ.shape
    wp = _world_polygon(poly, x, y, th)
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
        if occ[i, j] and _point_in_polygon(wp, cx, cy):
            return True
        if dist[i, j] - slack <= radius:
            all_clear = False
    if all_clear:
        return False
    return _polygon_hits_cells(prefix, res, x0, y0, wp)


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
    ymin = wp[:, 1].min()
    ymax = wp[:, 1].max()
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
def _collides_batch(occ, prefix, dist, res, x0, y0, poly, circles, radius, poses):
    out = np.empty(poses.shape[0], dtype=np.bool_)
    for n in range(poses.shape[0]):
        out[n] = _collides_one(
            occ,
            prefix,
            dist,
            res,
            x0,
            y0,
            poly,
            circles,
            radius,
            poses[n, 0],
            poses[n, 1],
            poses[n, 2],
        )
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
def _clearance_batch(occ, prefix, dist, res, x0, y0, poly, circles, radius, poses):
    rows, cols = occ.shape
    out = np.empty(poses.shape[0])
    slack = math.sqrt(2.0) * res
    for n in range(poses.shape[0]):
        x, y, th = poses[n, 0], poses[n, 1], poses[n, 2]
        if _collides_one(occ, prefix, dist, res, x0, y0, poly, circles, radius, x, y, th):
            out[n] = 0.0
            continue
        wp = _world_polygon(poly, x, y, th)
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
            out[n] = np.inf
            continue
        j0 = max(0, math.floor((wp[:, 0].min() - reach - x0) / res))
        j1 = min(cols - 1, math.floor((wp[:, 0].max() + reach - x0) / res))
        i0 = max(0, math.floor((wp[:, 1].min() - reach - y0) / res))
        i1 = min(rows - 1, math.floor((wp[:, 1].max() + reach - y0) / res))
        best = np.inf
        for a in range(i0, i1 + 1):
            for b in range(j0, j1 + 1):
                if occ[a, b]:
                    d = _poly_square_distance(wp, x0 + b * res, y0 + a * res, res)
                    best = min(best, d)
        out[n] = best
    return out
