"""Grid search: A* and Dijkstra on an :class:`~wheelbase.planning.occupancy.OccupancyGrid`.

Moving AI rules (Sturtevant 2012): 8-connected moves of cost 1 (straight) and √2 (diagonal)
cells, and **no corner cutting** (a diagonal move needs both cells it passes beside to be free).
A* uses the octile distance, which is admissible and consistent for these costs, so the lengths
it returns are optimal. Dijkstra from the goal gives the "holonomic with obstacles" heuristic of
Hybrid A* (document 002, Hybrid A* slides; Dolgov et al. 2010).
"""

from __future__ import annotations

import heapq
import math
from dataclasses import dataclass

import numba
import numpy as np
from numpy.typing import ArrayLike

from wheelbase.errors import ConfigError, InputError, PlanningError
from wheelbase.planning._heap import _heap_pop, _heap_push
from wheelbase.planning.occupancy import OccupancyGrid

__all__ = ["GridPath", "astar", "dijkstra"]

_SQRT2 = math.sqrt(2.0)


@dataclass(frozen=True, eq=False)
class GridPath:
    """Result of a grid search.

    Parameters
    ----------
    success : bool
        Whether the goal was reached.
    cells : numpy.ndarray
        Visited cells ``(N, 2)`` as ``(row, col)``, start to goal (empty on failure).
    points : numpy.ndarray
        Cell centres ``(N, 2)`` [m] in the world frame.
    length : float
        Path length [m] (``inf`` on failure).
    expanded_nodes : int
        Number of cells taken off the open list.
    """

    success: bool
    cells: np.ndarray
    points: np.ndarray
    length: float
    expanded_nodes: int


def _check_cell(grid: OccupancyGrid, name: str, cell: ArrayLike) -> tuple[int, int]:
    arr = np.asarray(cell)
    if arr.shape != (2,) or not np.issubdtype(arr.dtype, np.integer):
        raise InputError(f"{name} must be an integer cell (row, col) (got {cell!r})")
    r, c = int(arr[0]), int(arr[1])
    rows, cols = grid.shape
    if not (0 <= r < rows and 0 <= c < cols):
        raise PlanningError(f"{name} {(r, c)} is outside the map (rows {rows}, cols {cols})")
    if grid.occupied[r, c]:
        raise PlanningError(f"{name} {(r, c)} is an occupied cell")
    return r, c


def _check_connectivity(connectivity: int) -> int:
    if connectivity not in (4, 8):
        raise ConfigError(f"connectivity must be 4 or 8 (got {connectivity!r})")
    return int(connectivity)


def astar(
    grid: OccupancyGrid,
    start_cell: ArrayLike,
    goal_cell: ArrayLike,
    connectivity: int = 8,
) -> GridPath:
    """Shortest grid path by A* with the octile (8) or Manhattan (4) heuristic.

    Parameters
    ----------
    grid : OccupancyGrid
        The map; occupied cells are blocked.
    start_cell : array_like
        Integer ``(row, col)`` of the start.
    goal_cell : array_like
        Integer ``(row, col)`` of the goal.
    connectivity : int
        4 or 8 neighbours; with 8, diagonal moves never cut a blocked corner.

    Returns
    -------
    GridPath
        ``success=False`` with ``length=inf`` when the goal is unreachable.

    Raises
    ------
    PlanningError
        If the start or goal is outside the map or occupied.

    Examples
    --------
    >>> grid = OccupancyGrid.from_array(np.zeros((5, 5), bool), 1.0)
    >>> round(astar(grid, (0, 0), (4, 4)).length, 6)
    5.656854
    """
    connectivity = _check_connectivity(connectivity)
    start = _check_cell(grid, "start_cell", start_cell)
    goal = _check_cell(grid, "goal_cell", goal_cell)
    parent, g, expanded = _astar_kernel(
        grid.occupied.view(np.uint8), start[0], start[1], goal[0], goal[1], connectivity
    )
    _rows, cols = grid.shape
    goal_idx = goal[0] * cols + goal[1]
    if not np.isfinite(g[goal_idx]):
        empty = np.zeros((0, 2))
        return GridPath(False, empty.astype(np.int64), empty, math.inf, int(expanded))
    chain = [goal_idx]
    while chain[-1] != start[0] * cols + start[1]:
        chain.append(int(parent[chain[-1]]))
    idx = np.array(chain[::-1])
    cells = np.stack([idx // cols, idx % cols], -1)
    length = float(g[goal_idx]) * grid.resolution
    return GridPath(True, cells, grid.cell_to_world(cells), length, int(expanded))


def dijkstra(grid: OccupancyGrid, goal_cell: ArrayLike, connectivity: int = 8) -> np.ndarray:
    """Cost-to-go [m] from every cell to ``goal_cell`` (Dijkstra, Moving AI move rules).

    Parameters
    ----------
    grid : OccupancyGrid
        The map.
    goal_cell : array_like
        Integer ``(row, col)``.
    connectivity : int
        4 or 8.

    Returns
    -------
    numpy.ndarray
        Shape ``grid.shape``; ``inf`` on occupied and unreachable cells.

    Examples
    --------
    >>> grid = OccupancyGrid.from_array(np.zeros((3, 3), bool), 0.5)
    >>> float(dijkstra(grid, (0, 0))[2, 2])
    1.4142135623730951
    """
    connectivity = _check_connectivity(connectivity)
    goal = _check_cell(grid, "goal_cell", goal_cell)
    dist = _dijkstra_kernel(grid.occupied.view(np.uint8), goal[0], goal[1], connectivity)
    return dist.reshape(grid.shape) * grid.resolution


# ---------------------------------------------------------------------- kernels
_DR = np.array([1, -1, 0, 0, 1, 1, -1, -1], dtype=np.int64)
_DC = np.array([0, 0, 1, -1, 1, -1, 1, -1], dtype=np.int64)


@numba.njit(cache=True)
def _heuristic(r, c, gr, gc, connectivity):
    dr = abs(r - gr)
    dc = abs(c - gc)
    if connectivity == 4:
        return float(dr + dc)
    return float(max(dr, dc)) + (_SQRT2 - 1.0) * float(min(dr, dc))


@numba.njit(cache=True, inline="always")
def _can_move(occ, r, c, k, rows, cols, cut_corners=False):
    dr = _DR[k]
    dc = _DC[k]
    nr = r + dr
    nc = c + dc
    if nr < 0 or nr >= rows or nc < 0 or nc >= cols or occ[nr, nc]:
        return False
    return cut_corners or not (k >= 4 and (occ[r + dr, c] or occ[r, c + dc]))


@numba.njit(cache=True)
def _astar_kernel(occ, sr, sc, gr, gc, connectivity):
    rows, cols = occ.shape
    n = rows * cols
    g = np.full(n, np.inf)
    parent = np.full(n, -1, dtype=np.int64)
    closed = np.zeros(n, dtype=np.bool_)
    start = sr * cols + sc
    goal = gr * cols + gc
    g[start] = 0.0
    heap = [(_heuristic(sr, sc, gr, gc, connectivity), 0.0, start)]
    expanded = 0
    while len(heap) > 0:
        _, gs, idx = heapq.heappop(heap)
        if closed[idx]:
            continue
        closed[idx] = True
        expanded += 1
        if idx == goal:
            break
        r = idx // cols
        c = idx % cols
        for k in range(connectivity):
            if not _can_move(occ, r, c, k, rows, cols):
                continue
            nidx = (r + _DR[k]) * cols + (c + _DC[k])
            if closed[nidx]:
                continue
            cand = gs + (_SQRT2 if k >= 4 else 1.0)
            if cand < g[nidx]:
                g[nidx] = cand
                parent[nidx] = idx
                h = _heuristic(r + _DR[k], c + _DC[k], gr, gc, connectivity)
                heapq.heappush(heap, (cand + h, cand, nidx))
    return parent, g, expanded


@numba.njit(cache=True)
def _dijkstra_kernel(occ, gr, gc, connectivity, cut_corners=False, axis=1.0, diagonal=_SQRT2):
    n = occ.shape[0] * occ.shape[1]
    g = np.full(n, np.inf)
    closed = np.zeros(n, dtype=np.bool_)
    # an array heap: a cell is pushed at most once per neighbour that improves it
    keys = np.empty(connectivity * n + 1)
    items = np.empty(connectivity * n + 1, dtype=np.int64)
    _dijkstra_fill(occ, gr, gc, connectivity, cut_corners, axis, diagonal, g, closed, keys, items)
    return g


@numba.njit(cache=True, _nrt=False)
def _dijkstra_fill(occ, gr, gc, connectivity, cut_corners, axis, diagonal, g, closed, keys, items):
    """The search of :func:`_dijkstra_kernel` into its arrays, without Numba's reference
    counting (an atomic increment and decrement per array at every inlined heap operation and
    move check was a third of its time)."""
    rows, cols = occ.shape
    goal = gr * cols + gc
    g[goal] = 0.0
    size = _heap_push(keys, items, 0, 0.0, goal)
    while size > 0:
        gs, idx, size = _heap_pop(keys, items, size)
        if closed[idx]:
            continue
        closed[idx] = True
        r = idx // cols
        c = idx % cols
        for k in range(connectivity):
            if not _can_move(occ, r, c, k, rows, cols, cut_corners):
                continue
            nidx = (r + _DR[k]) * cols + (c + _DC[k])
            cand = gs + (diagonal if k >= 4 else axis)
            if cand < g[nidx]:
                g[nidx] = cand
                size = _heap_push(keys, items, size, cand, nidx)
