"""Numba kernels of the costmap: a scan marked and cleared, and the inflation redone where it
changed (private; :mod:`wheelbase.perception.costmap` documents the rules).

Layer values: the static layer and the obstacle layer hold FREE (0), LETHAL (254) or UNKNOWN
(255). Combined as Nav2's ``updateWithMax`` does, a layer's UNKNOWN never overrides the other
layer and otherwise the larger value wins; the master cost is that combination inflated.
"""

from __future__ import annotations

import math

import numba
import numpy as np

from wheelbase.perception.costs import FREE, INSCRIBED, LETHAL, UNKNOWN
from wheelbase.sensors.raycast import traversal_start, traversal_step

__all__: list[str] = []

_PENDING = 1  # an obstacle-layer cell this scan will mark: clearing skips it
_NO_SITE = np.int64(1) << 40  # "no lethal cell within reach" in the distance passes
_NUDGE = 1e-6  # cells past a return: its cell is the one the beam entered there


@numba.njit(cache=True)
def _combined(static, obstacle):
    if obstacle == UNKNOWN:
        return static
    if static == UNKNOWN:
        return obstacle
    return max(static, obstacle)


@numba.njit(cache=True)
def inflate_window(static, obstacle, cost, r0, r1, c0, c1, table, reach):
    """Rewrite ``cost[r0:r1, c0:c1]`` from the layers: exact squared distances to the nearest
    lethal cell within ``reach`` cells (a column pass, then the lower envelope of parabolas of
    Felzenszwalb and Huttenlocher, "Distance transforms of sampled functions", 2012, on each
    row), looked up in ``table``. Lethal cells up to ``reach`` outside the window count."""
    rows, cols = static.shape
    s0 = max(0, r0 - reach)
    s1 = min(rows, r1 + reach)
    u0 = max(0, c0 - reach)
    u1 = min(cols, c1 + reach)
    h = s1 - s0
    w = u1 - u0
    big = reach + 1
    # vertical distance [cells] to the nearest lethal cell of the same column, capped at big
    vertical = np.empty((h, w), np.int64)
    for k in range(w):
        last = -big
        for a in range(h):
            if _combined(static[s0 + a, u0 + k], obstacle[s0 + a, u0 + k]) == LETHAL:
                last = a
            vertical[a, k] = min(a - last, big)
        last = h - 1 + big
        for a in range(h - 1, -1, -1):
            if vertical[a, k] == 0:
                last = a
            vertical[a, k] = min(vertical[a, k], last - a)
    sites = np.empty(w, np.int64)
    bounds = np.empty(w + 1)
    size = table.shape[0]
    for a in range(r0 - s0, r1 - s0):
        # lower envelope of the parabolas (q − k)² + vertical[a, k]² of the columns with a
        # lethal cell within reach
        n = 0
        cross = 0.0
        for k in range(w):
            g = vertical[a, k]
            if g >= big:
                continue
            fk = g * g + k * k
            while n > 0:
                p = sites[n - 1]
                gp = vertical[a, p]
                cross = (fk - (gp * gp + p * p)) / (2.0 * (k - p))
                if cross <= bounds[n - 1]:
                    n -= 1
                else:
                    break
            if n == 0:
                bounds[0] = -math.inf
            else:
                bounds[n] = cross
            sites[n] = k
            n += 1
        m = 0
        i = s0 + a
        for q in range(c0 - u0, c1 - u0):
            if n == 0:
                sq = _NO_SITE
            else:
                while m + 1 < n and bounds[m + 1] < q:
                    m += 1
                p = sites[m]
                g = vertical[a, p]
                sq = (q - p) * (q - p) + g * g
            j = u0 + q
            layer = _combined(static[i, j], obstacle[i, j])
            if layer == LETHAL:
                cost[i, j] = LETHAL
                continue
            inflated = table[sq] if sq < size else FREE
            if layer == UNKNOWN:
                # Nav2 (inflate_unknown false): unknown stays unknown unless inscribed
                cost[i, j] = inflated if inflated >= INSCRIBED else UNKNOWN
            else:
                cost[i, j] = max(layer, inflated)


@numba.njit(cache=True)
def scan_update(static, obstacle_in, obstacle, cost, pose, angles, ranges, limits, table, reach):
    """One scan into one robot's layers (``obstacle`` and ``cost`` are copies of the input,
    written in place; ``obstacle_in`` is the input, read); True if a cell changed.

    ``pose`` is the sensor's (x, y) in cells of the grid and its heading [rad], ``ranges``
    and ``limits`` = (max_range, obstacle_min_range, obstacle_max_range, raytrace_min_range,
    raytrace_max_range) in cells.
    """
    rows, cols = static.shape
    n_beams = ranges.shape[0]
    px, py = pose[0], pose[1]
    max_range, mark_min, mark_max = limits[0], limits[1], limits[2]
    clear_min, clear_max = limits[3], limits[4]
    marks = np.full(n_beams, -1, np.int64)
    lo_i, hi_i, lo_j, hi_j = rows, -1, cols, -1
    ux = np.empty(n_beams)
    uy = np.empty(n_beams)
    cos_h, sin_h = math.cos(pose[2]), math.sin(pose[2])
    for b in range(n_beams):
        cos_b, sin_b = math.cos(angles[b]), math.sin(angles[b])
        ux[b] = cos_h * cos_b - sin_h * sin_b
        uy[b] = sin_h * cos_b + cos_h * sin_b
    # the returns to mark first, so that clearing (of every beam) spares them
    for b in range(n_beams):
        r = ranges[b]
        if math.isnan(r) or r >= max_range or r < mark_min or r > mark_max:
            continue
        j = math.floor(px + (r + _NUDGE) * ux[b])
        i = math.floor(py + (r + _NUDGE) * uy[b])
        if 0 <= i < rows and 0 <= j < cols:
            marks[b] = i * cols + j
            if obstacle[i, j] != _PENDING:
                obstacle[i, j] = _PENDING
    inside = 0.0 <= px < cols and 0.0 <= py < rows
    for b in range(n_beams):
        r = ranges[b]
        if not inside or math.isnan(r):
            continue
        limit = min(min(r, max_range), clear_max)
        if limit <= 0.0:
            continue
        i, j, si, sj, tx, ty, dtx, dty = traversal_start(px, py, ux[b], uy[b])
        while True:
            ni, nj, tx, ty, leave = traversal_step(i, j, si, sj, tx, ty, dtx, dty)
            value = obstacle[i, j]
            if leave > clear_min and value != FREE and value != _PENDING:
                obstacle[i, j] = FREE  # it was not free: a change
                lo_i, hi_i = min(lo_i, i), max(hi_i, i)
                lo_j, hi_j = min(lo_j, j), max(hi_j, j)
            if leave >= limit or not (0 <= ni < rows and 0 <= nj < cols):
                break
            i, j = ni, nj
    for b in range(n_beams):
        cell = marks[b]
        if cell < 0:
            continue
        i = cell // cols
        j = cell - i * cols
        if obstacle[i, j] == _PENDING:
            obstacle[i, j] = LETHAL
            if obstacle_in[i, j] != LETHAL:
                lo_i, hi_i = min(lo_i, i), max(hi_i, i)
                lo_j, hi_j = min(lo_j, j), max(hi_j, j)
    if hi_i >= 0:  # every cell within reach of a changed one may change
        inflate_window(
            static, obstacle, cost, max(0, lo_i - reach), min(rows, hi_i + 1 + reach),
            max(0, lo_j - reach), min(cols, hi_j + 1 + reach), table, reach,
        )  # fmt: skip
    return hi_i >= 0


@numba.njit(cache=True)
def batch_update(static, obstacle_in, obstacle, cost, index, poses, angles, ranges, limits,
                 table, reach):  # fmt: skip
    """:func:`scan_update` for scan ``n`` into state row ``index[n]``, for every scan."""
    changed = 0
    for n in range(index.shape[0]):
        k = index[n]
        changed += scan_update(static, obstacle_in[k], obstacle[k], cost[k], poses[n], angles,
                               ranges[n], limits, table, reach)  # fmt: skip
    return changed
