"""Seeded placement of the agents at the start: non-overlapping, clear of everything.

Each group's agents are placed in its region by random sequential addition: candidate
centres drawn uniformly in the region shrunk by the radius (counter-based draws of the
world's seed, :data:`~wheelbase.world.counter_rng.STREAM_SPAWN`) are taken in order while
the disc keeps clear of walls and static obstacles, of the keep-clear discs (robots' starts
and goals) and of the agents placed before. Random addition jams at about 55 % of the area
covered (Rényi's parking constant in 2-D, ~0.547), far from the densest packing, so when
``64 × count`` candidates leave some agents unplaced, the points of a hexagonal lattice of
spacing one diameter (which holds 90.7 % of the area) are tried in a seeded random order. Only
when those run out too is the group reported as not fitting.
"""

from __future__ import annotations

import math

import numba
import numpy as np

from wheelbase.world.counter_rng import STREAM_SPAWN, counter_uniform
from wheelbase.world.statics import static_nearest

__all__ = ["CANDIDATES_PER_AGENT", "SPAWN_GAP", "hex_lattice", "place_points", "place_random"]

CANDIDATES_PER_AGENT = 64
"""Random candidates drawn per agent before the lattice is tried."""
SPAWN_GAP = 1e-6
"""Least gap [m] between a new agent and anything else at the start."""


@numba.njit(cache=True)
def _clear(st, x, y, r, keep, placed, placed_r, n_placed):
    if static_nearest(st, x, y, r + SPAWN_GAP)[0] < r + SPAWN_GAP:
        return False
    for k in range(keep.shape[0]):
        if math.hypot(x - keep[k, 0], y - keep[k, 1]) < r + keep[k, 2] + SPAWN_GAP:
            return False
    for k in range(n_placed):
        if math.hypot(x - placed[k, 0], y - placed[k, 1]) < r + placed_r[k] + SPAWN_GAP:
            return False
    return True


@numba.njit(cache=True)
def place_random(st, seed, group, x0, y0, x1, y1, r, need, keep, placed, placed_r, n_placed):
    """Random sequential addition (module docstring) of up to ``need`` discs of radius ``r``
    after the ``n_placed`` already in ``placed``/``placed_r`` (written in place): returns how
    many were placed."""
    count = 0
    for i in range(CANDIDATES_PER_AGENT * need):
        if count == need:
            break
        x = x0 + r + counter_uniform(seed, STREAM_SPAWN, group, i, 0) * (x1 - x0 - 2 * r)
        y = y0 + r + counter_uniform(seed, STREAM_SPAWN, group, i, 1) * (y1 - y0 - 2 * r)
        if _clear(st, x, y, r, keep, placed, placed_r, n_placed + count):
            placed[n_placed + count, 0] = x
            placed[n_placed + count, 1] = y
            placed_r[n_placed + count] = r
            count += 1
    return count


@numba.njit(cache=True)
def place_points(st, points, r, need, keep, placed, placed_r, n_placed):
    """As :func:`place_random`, trying ``points (L, 2)`` in order."""
    count = 0
    for i in range(points.shape[0]):
        if count == need:
            break
        x, y = points[i, 0], points[i, 1]
        if _clear(st, x, y, r, keep, placed, placed_r, n_placed + count):
            placed[n_placed + count, 0] = x
            placed[n_placed + count, 1] = y
            placed_r[n_placed + count] = r
            count += 1
    return count


def hex_lattice(x0: float, y0: float, x1: float, y1: float, r: float, limit: int) -> np.ndarray:
    """Centres ``(L, 2)`` [m] of a hexagonal packing of discs of radius ``r`` (spacing
    ``2 r (1 + 1e-6)``) inside the rectangle shrunk by ``r``, at most ``limit`` of them.

    Parameters
    ----------
    x0, y0, x1, y1 : float
        The rectangle [m].
    r : float
        Disc radius [m], > 0.
    limit : int
        Most points returned (the first rows).

    Returns
    -------
    numpy.ndarray
    """
    spacing = 2.0 * r * (1.0 + 1e-6) + SPAWN_GAP
    row_step = spacing * math.sqrt(3.0) / 2.0
    cols = max(0, math.floor((x1 - x0 - 2 * r) / spacing) + 1)
    rows = max(0, math.floor((y1 - y0 - 2 * r) / row_step) + 1)
    rows = min(rows, max(1, limit // max(cols, 1) + 1))
    i, j = np.meshgrid(np.arange(rows), np.arange(cols), indexing="ij")
    x = x0 + r + j * spacing + (i % 2) * spacing / 2.0
    y = y0 + r + i * row_step
    keep = x <= x1 - r
    return np.column_stack([x[keep], y[keep]])[:limit]
