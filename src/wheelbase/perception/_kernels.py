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

_PENDING = 1  # an obstacle-layer cell this scan will mark: clearing skips it (and FREE, 0)
_NO_SITE = np.int64(1) << 40  # "no lethal cell within reach" in the distance passes
_NUDGE = 1e-6  # cells past a return: its cell is the one the beam entered there
_EDGE = 1e-6  # cells: the margin to the map's edge within which every step is checked


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
    lethal cell within ``reach`` cells (a column pass, then on each row the lower envelope of
    parabolas of Felzenszwalb and Huttenlocher, "Distance transforms of sampled functions",
    2012), looked up in ``table``.
    Lethal cells up to ``reach`` outside the window count."""
    rows, cols = static.shape
    s0 = max(0, r0 - reach)
    s1 = min(rows, r1 + reach)
    u0 = max(0, c0 - reach)
    u1 = min(cols, c1 + reach)
    h = s1 - s0
    w = u1 - u0
    big = reach + 1
    # vertical distance [cells] to the nearest lethal cell of the same column, capped at big
    # (two sweeps down and up the rows, all columns at once: row-major, cache friendly)
    vertical = np.empty((h, w), np.int64)
    last = np.full(w, -big, np.int64)
    for a in range(h):
        for k in range(w):
            # the combined layers are lethal where either layer is (an unknown layer value
            # never overrides, and otherwise the larger wins)
            if static[s0 + a, u0 + k] == LETHAL or obstacle[s0 + a, u0 + k] == LETHAL:
                last[k] = a
            vertical[a, k] = min(a - last[k], big)
    last[:] = h - 1 + big
    for a in range(h - 1, -1, -1):
        for k in range(w):
            if vertical[a, k] == 0:
                last[k] = a
            vertical[a, k] = min(vertical[a, k], last[k] - a)
    sites = np.empty(w, np.int64)
    bounds = np.empty(w + 1)
    nearest = np.empty(c1 - c0, np.int64)
    size = table.shape[0]
    for a in range(r0 - s0, r1 - s0):
        _row_by_envelope(vertical[a], c0 - u0, c1 - u0, big, nearest, sites, bounds)
        i = s0 + a
        for q in range(c1 - c0):
            j = c0 + q
            layer = _combined(static[i, j], obstacle[i, j])
            if layer == LETHAL:
                cost[i, j] = LETHAL
                continue
            sq = nearest[q]
            inflated = table[sq] if sq < size else FREE
            if layer == UNKNOWN:
                # Nav2 (inflate_unknown false): unknown stays unknown unless inscribed
                cost[i, j] = inflated if inflated >= INSCRIBED else UNKNOWN
            else:
                cost[i, j] = max(layer, inflated)


@numba.njit(cache=True)
def _row_by_envelope(vertical, q0, q1, big, nearest, sites, bounds):
    """``nearest[q − q0]`` = min over columns k of (q − k)² + vertical[k]², by the lower
    envelope of those parabolas for the columns with a lethal cell within reach (Felzenszwalb
    and Huttenlocher): linear in the row whatever the reach (a plain scan of the columns
    within reach was twice slower at 11 cells)."""
    w = vertical.shape[0]
    n = 0
    cross = 0.0
    for k in range(w):
        g = vertical[k]
        if g >= big:
            continue
        fk = g * g + k * k
        while n > 0:
            p = sites[n - 1]
            gp = vertical[p]
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
    for q in range(q0, q1):
        if n == 0:
            nearest[q - q0] = _NO_SITE
            continue
        while m + 1 < n and bounds[m + 1] < q:
            m += 1
        p = sites[m]
        g = vertical[p]
        nearest[q - q0] = (q - p) * (q - p) + g * g


_TILE = 16  # cells: changes are gathered per tile, and groups of changed tiles re-inflated


@numba.njit(cache=True)
def scan_update(static, obstacle_in, obstacle, cost, pose, angles, ranges, params, table, reach):
    """One scan into one robot's layers (``obstacle`` and ``cost`` are copies of the input,
    written in place; ``obstacle_in`` is the input, read); True if a cell changed.

    ``pose`` is the sensor's world pose, ``ranges`` its readings [m], ``params`` = (max_range,
    obstacle_min_range, obstacle_max_range, raytrace_min_range, raytrace_max_range [m],
    x0, y0 [m] of the grid's origin, 1 / resolution [1/m]).
    """
    rows, cols = static.shape
    n_beams = ranges.shape[0]
    inv = params[7]
    px = (pose[0] - params[5]) * inv
    py = (pose[1] - params[6]) * inv
    max_range, mark_min, mark_max = params[0] * inv, params[1] * inv, params[2] * inv
    clear_min, clear_max = params[3] * inv, params[4] * inv
    marks = np.full(n_beams, -1, np.int64)
    dirty = _no_changes(rows, cols)
    ux = np.empty(n_beams)
    uy = np.empty(n_beams)
    cos_h, sin_h = math.cos(pose[2]), math.sin(pose[2])
    for b in range(n_beams):
        cos_b, sin_b = math.cos(angles[b]), math.sin(angles[b])
        ux[b] = cos_h * cos_b - sin_h * sin_b
        uy[b] = sin_h * cos_b + cos_h * sin_b
    # the returns to mark first, so that clearing (of every beam) spares them
    for b in range(n_beams):
        r = ranges[b] * inv
        if math.isnan(r) or r >= max_range or r < mark_min or r > mark_max:
            continue
        x = px + (r + _NUDGE) * ux[b]
        y = py + (r + _NUDGE) * uy[b]
        if 0.0 <= x < cols and 0.0 <= y < rows:  # checked before the cast to an integer
            i, j = int(y), int(x)
            marks[b] = i * cols + j
            obstacle[i, j] = _PENDING
    if 0.0 <= px < cols and 0.0 <= py < rows:
        _clear(obstacle, dirty, px, py, ux, uy, ranges, inv, max_range, clear_min, clear_max)
    for b in range(n_beams):
        cell = marks[b]
        if cell < 0:
            continue
        i = cell // cols
        j = cell - i * cols
        if obstacle[i, j] == _PENDING:
            obstacle[i, j] = LETHAL
            if obstacle_in[i, j] != LETHAL:
                _changed(dirty, i, j)
    return _reinflate(static, obstacle, cost, dirty, table, reach)


@numba.njit(cache=True)
def _no_changes(rows, cols):
    """Per tile of ``_TILE`` × ``_TILE`` cells, the bounds (lowest row, highest row, lowest
    column, highest column) of its changed cells; none yet (highest row −1)."""
    dirty = np.empty((4, (rows + _TILE - 1) // _TILE, (cols + _TILE - 1) // _TILE), np.int64)
    dirty[0] = rows
    dirty[1] = -1
    dirty[2] = cols
    dirty[3] = -1
    return dirty


@numba.njit(cache=True)
def _changed(dirty, i, j):
    ti, tj = i // _TILE, j // _TILE
    dirty[0, ti, tj] = min(dirty[0, ti, tj], i)
    dirty[1, ti, tj] = max(dirty[1, ti, tj], i)
    dirty[2, ti, tj] = min(dirty[2, ti, tj], j)
    dirty[3, ti, tj] = max(dirty[3, ti, tj], j)


@numba.njit(cache=True)
def _reinflate(static, obstacle, cost, dirty, table, reach):
    """Inflate again around the changed cells: the changed tiles that touch (8 neighbours) form
    groups, and each group's bounding box of changed cells, grown by ``reach`` (every cell
    within reach of a changed one may change), is inflated again. True if any cell changed."""
    rows, cols = static.shape
    tiles_i, tiles_j = dirty.shape[1], dirty.shape[2]
    seen = np.zeros((tiles_i, tiles_j), np.bool_)
    stack = np.empty(tiles_i * tiles_j, np.int64)
    changed = False
    for start in range(tiles_i * tiles_j):
        si, sj = start // tiles_j, start % tiles_j
        if dirty[1, si, sj] < 0 or seen[si, sj]:
            continue
        changed = True
        lo_i, hi_i, lo_j, hi_j = rows, -1, cols, -1
        seen[si, sj] = True
        stack[0] = start
        top = 1
        while top > 0:
            top -= 1
            ti, tj = stack[top] // tiles_j, stack[top] % tiles_j
            lo_i, hi_i = min(lo_i, dirty[0, ti, tj]), max(hi_i, dirty[1, ti, tj])
            lo_j, hi_j = min(lo_j, dirty[2, ti, tj]), max(hi_j, dirty[3, ti, tj])
            for ni in range(max(0, ti - 1), min(tiles_i, ti + 2)):
                for nj in range(max(0, tj - 1), min(tiles_j, tj + 2)):
                    if dirty[1, ni, nj] >= 0 and not seen[ni, nj]:
                        seen[ni, nj] = True
                        stack[top] = ni * tiles_j + nj
                        top += 1
        inflate_window(
            static, obstacle, cost, max(0, lo_i - reach), min(rows, hi_i + 1 + reach),
            max(0, lo_j - reach), min(cols, hi_j + 1 + reach), table, reach,
        )  # fmt: skip
    return changed


@numba.njit(cache=True)
def _clear(obstacle, dirty, px, py, ux, uy, ranges, inv, max_range, clear_min, clear_max):
    """Set free every cell a beam passes (module docstring of ``costmap``); a cell that was not
    free is a change (``_changed``). Cells pending a mark stay."""
    rows, cols = obstacle.shape
    for b in range(ranges.shape[0]):
        r = ranges[b] * inv
        if math.isnan(r):
            continue  # no reading: nothing is known along it
        limit = min(min(r, max_range), clear_max)
        if limit <= 0.0:
            continue
        u, v = ux[b], uy[b]
        # Up to a hair before the beam leaves the map no step can leave it: the loop needs no
        # bounds check there (a third faster); the cells past the hair are checked one by one.
        inside = limit
        if u > 0.0:
            inside = min(inside, (cols - px) / u)
        elif u < 0.0:
            inside = min(inside, -px / u)
        if v > 0.0:
            inside = min(inside, (rows - py) / v)
        elif v < 0.0:
            inside = min(inside, -py / v)
        inside -= _EDGE
        i, j, si, sj, tx, ty, dtx, dty = traversal_start(px, py, u, v)
        while True:
            ni, nj, tx, ty, leave = traversal_step(i, j, si, sj, tx, ty, dtx, dty)
            if obstacle[i, j] > _PENDING and leave > clear_min:
                obstacle[i, j] = FREE  # it was not free: a change
                _changed(dirty, i, j)
            if leave >= inside:
                break
            i, j = ni, nj
        while leave < limit and 0 <= ni < rows and 0 <= nj < cols:
            i, j = ni, nj
            ni, nj, tx, ty, leave = traversal_step(i, j, si, sj, tx, ty, dtx, dty)
            if obstacle[i, j] > _PENDING and leave > clear_min:
                obstacle[i, j] = FREE
                _changed(dirty, i, j)


@numba.njit(cache=True)
def batch_update(static, obstacle_in, obstacle, cost, index, poses, angles, ranges, params,
                 table, reach):  # fmt: skip
    """:func:`scan_update` for scan ``n`` into state row ``index[n]``, for every scan."""
    changed = 0
    for n in range(index.shape[0]):
        k = index[n]
        changed += scan_update(static, obstacle_in[k], obstacle[k], cost[k], poses[n], angles,
                               ranges[n], params, table, reach)  # fmt: skip
    return changed
