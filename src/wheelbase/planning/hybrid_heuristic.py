"""Hybrid A*'s heuristic: an admissible cost-to-go from the obstacles (a Dijkstra bound on
the reference point's way around them) and from the kinematics (the Reeds–Shepp or Dubins
length without obstacles), plus the least cost of turning to the goal's heading.

The search kernel (:mod:`wheelbase.planning.hybrid_search`) queues a child on the cheap part
(``_cheap_heuristic``, a table look-up) and computes the curve length
(``_heuristic``) when the child first reaches the top of the queue.
"""

from __future__ import annotations

import math

import numba
import numpy as np

from wheelbase.geometry_numba import wrap_angle_scalar
from wheelbase.planning.astar import _dijkstra_kernel
from wheelbase.planning.dubins import _dubins_all
from wheelbase.planning.reeds_shepp import _min_length, _normalise

__all__: list[str] = []

_MODE_RS, _MODE_DUBINS, _MODE_POINT = 0, 1, 2
"""Curves of the kinematic bound: Reeds–Shepp (a car that may reverse), Dubins (forward only),
or the straight line of a robot that turns in place."""
_OCTILE_RATIO = math.sqrt(4.0 - 2.0 * math.sqrt(2.0))
"""Largest ratio of the 8-connected (octile) distance to the straight-line one (at 22.5°)."""
_HEURISTIC_NORMS = (
    (1.0 / _OCTILE_RATIO, math.sqrt(2.0) / _OCTILE_RATIO),  # octile / worst ratio
    (1.0, 1.0),  # Chebyshev
    (1.0 / math.sqrt(2.0), math.sqrt(2.0)),  # (|x| + |y|) / √2
)
"""(axis, diagonal) move costs of three grid norms that never exceed the Euclidean length."""


def _holonomic_heuristic(
    blocked: np.ndarray, resolution: float, xy_resolution: float, goal: np.ndarray
) -> tuple[np.ndarray, float]:
    """Admissible cost-to-go [m] to ``goal`` (in the grid's frame, origin (0, 0)) around the
    obstacles, on cells of about ``xy_resolution`` [m] made of the ``resolution`` [m] cells of
    ``blocked`` (the raster's ``reference_blocked`` at the footprint's inscribed radius);
    returns the grid of bounds and its cell side [m].

    Why it never overestimates:

    1. The reference point keeps at least the footprint's inscribed radius from every
       obstacle, so it never lies in a cell of ``reference_blocked``; a coarse cell is free
       when any of its fine cells is, so every feasible path stays in free coarse cells.
    2. The shortest curve in that free region is a taut polyline bending at cell corners.
       A straight piece spanning ``a >= b`` cells in x and y crosses cells that an
       8-connected walk of ``a − b`` axis and ``b`` diagonal moves follows (diagonal moves
       may cut corners here, as the piece may). With move costs ``α`` (axis) and ``β``
       (diagonal) the walk costs ``N(a, b) = (a − b)·α + b·β``, a norm of the piece.
    3. Three such norms never exceed the Euclidean length: the octile norm divided by its
       worst ratio ``√(4 − 2√2) ≈ 1.0824`` (exact at 22.5°), the Chebyshev norm (α = β =
       1, exact along the axes) and ``(|x| + |y|)/√2`` (α = 1/√2, β = √2, exact at 45°).
       Their maximum is within 2 % of the straight-line distance in every direction (the
       octile distance alone overestimates it by up to 8.2 %).
    4. A corner-to-corner piece saves one move at its ends, which pays for the step
       between the cells around a bend; the two ends of the path may cost one diagonal
       ``√2·hres`` each, which is subtracted.

    So each Dijkstra distance ``D`` obeys ``D − 2√2·hres <= L`` for every feasible path of
    length ``L``, and every motion costs at least its length: the maximum of the three is
    admissible. The search adds a heading term that stays admissible: a path that turns
    the heading by ``Δθ`` (wrapped) turns at least ``|Δθ|`` in all; a car does so on arcs
    of curvature at most 1/R, at least ``R·|Δθ|`` metres of them, each costing
    ``non_straight_penalty − 1`` more than its length; a differential drive pays
    ``turn_in_place_cost`` per radian. So A* with ``heuristic_weight=1`` returns
    least-cost paths on its lattice; a weight above 1 gives this up on purpose, for speed.
    """
    rows, cols = blocked.shape
    # a coarse cell wider than the map is the map (and keeps the padding finite)
    f = max(1, min(round(xy_resolution / resolution), max(rows, cols)))
    pr, pc = (-rows) % f, (-cols) % f
    free = np.pad(~blocked, ((0, pr), (0, pc)), constant_values=False)
    coarse_free = free.reshape(free.shape[0] // f, f, free.shape[1] // f, f).any(axis=(1, 3))
    hres = resolution * f
    gr = int(goal[1] // hres)
    gc = int(goal[0] // hres)
    coarse_free[gr, gc] = True
    occ = (~coarse_free).astype(np.uint8)
    dist = np.zeros(occ.size)
    for axis, diagonal in _HEURISTIC_NORMS:
        d = _dijkstra_kernel(occ, gr, gc, 8, True, axis, diagonal)
        np.maximum(dist, d, out=dist)
    bound = dist.reshape(occ.shape) * hres - 2.0 * math.sqrt(2.0) * hres
    return np.maximum(bound, 0.0), hres


@numba.njit(cache=True, inline="always")
def _cheap_heuristic(x, y, th, gx, gy, gth, mode, hgrid, hres, x0, y0, turn_cost):
    """A lower bound on :func:`_heuristic` without the curve length (a table look-up): the
    holonomic cost-to-go or the straight-line distance, plus the least cost of turning to the
    goal's heading (for turning in place, this is the whole heuristic)."""
    j = math.floor((x - x0) / hres)
    i = math.floor((y - y0) / hres)
    if i < 0 or i >= hgrid.shape[0] or j < 0 or j >= hgrid.shape[1]:
        return np.inf
    return max(math.hypot(gx - x, gy - y), hgrid[i, j]) + turn_cost * abs(
        wrap_angle_scalar(gth - th)
    )


@numba.njit(cache=True)
def _heuristic(x, y, th, gx, gy, gth, mode, radius, families, hgrid, hres, x0, y0, turn_cost):
    """Admissible cost-to-go: max(curve length without obstacles, holonomic cost-to-go with
    them) + ``turn_cost`` × |heading change| (see ``HybridAStar._holonomic_heuristic``)."""
    j = math.floor((x - x0) / hres)
    i = math.floor((y - y0) / hres)
    if i < 0 or i >= hgrid.shape[0] or j < 0 or j >= hgrid.shape[1]:
        return np.inf
    h2 = hgrid[i, j]
    turn = turn_cost * abs(wrap_angle_scalar(gth - th))
    d = math.hypot(gx - x, gy - y)
    if mode == _MODE_POINT or (mode == _MODE_RS and h2 >= d + math.pi * radius):
        # turning in place: the Euclidean distance is the curve length. Reeds–Shepp: turning
        # to face the goal (or away), a straight line and turning to the goal's heading is a
        # path of at most d + πR (each turn in place costs |angle|·R, e.g. by L+R−L+, and
        # the two turns add up to at most π for one of the two driving directions): the
        # curve length cannot exceed h2, and its microseconds are saved
        return max(d, h2) + turn
    if mode == _MODE_RS:
        nx, ny, nphi = _normalise(x, y, th, gx, gy, gth, radius)
        h1 = _min_length(nx, ny, nphi, families) * radius
    else:
        segs = _dubins_all(x, y, th, gx, gy, gth, radius)
        h1 = np.inf
        for w in range(6):
            if not np.isnan(segs[w, 0]):
                h1 = min(h1, (segs[w, 0] + segs[w, 1] + segs[w, 2]) * radius)
    return max(h1, h2) + turn
