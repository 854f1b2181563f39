"""Frontiers of an occupancy map and the choice of the next one to visit (Yamauchi 1997).

A **frontier cell** is a known-free cell with at least one of its four edge neighbours unknown;
cells beyond the edge of the map count as unknown (a map whose free space runs into its edge
has not been explored there). Frontier cells that touch, including diagonally (8-connectivity),
form one **frontier**; frontiers shorter than ``min_size`` cells are dropped (Nav2's
explore_lite ``min_frontier_size``, there 0.5 m).

An unknown cell whose centre lies within ``fringe`` [m] of an occupied cell's centre is a
wall's **fringe**, not unexplored space, and makes no frontier: where beams graze a wall, or
where the scans that drew it disagree by a few centimetres (SLAM), the free cells along it
and the wall's cells keep a strip one or two cells thick between them that a miss and a hit
each claim, so it stays unknown however often it is seen; behind it is the wall. Seen from
beside a wall, such a strip is a frontier as long as the wall, which no visit removes
(measured on the bundled warehouse, 0.05 m cells: with ``fringe`` 0 most of the 100 legs
went to strips along walls and shelf faces, 408 m driven, and one aisle was never entered).
A frontier into open unknown space touches the fringe only where it meets a wall, at its
ends. ``fringe`` 0 (the default) keeps every unknown cell.

The choice (:func:`choose_frontier`) follows explore_lite's cost: for each frontier, the
**approach cell** is the cell the robot can reach (finite distance in ``distance``, a
cost-to-go field from the robot over the space its footprint fits in), among ``targets`` when
given, nearest to the
frontier's cells (of those equally near, the one nearest to the frontier's middle cell, the
cell nearest to the cells' centroid), no farther than ``approach`` from it: a long ragged
frontier, where beams graze far walls, is approached where it meets the known free space;
the cost is ``distance_weight · d − gain_weight · size``, with ``d`` the path distance to
the approach cell [m] and ``size`` the frontier's length (cells × resolution) [m]
(explore_lite's ``potential_scale`` 3 and ``gain_scale`` 1 are the defaults). Frontiers
without an approach cell, or whose middle lies within ``blacklist_radius`` of a blacklisted
point (a goal that Hybrid A* could not reach or the robot could not drive to), are skipped.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import ndimage

from wheelbase._validate import finite, integer, nonnegative, positive
from wheelbase.errors import ConfigError

__all__ = ["Frontier", "choose_frontier", "find_frontiers", "frontier_mask"]

_EDGE = np.array([[0, 1, 0], [1, 0, 1], [0, 1, 0]], bool)
_EIGHT = np.ones((3, 3), bool)


def _masks(grid) -> tuple[np.ndarray, np.ndarray]:
    occupied = np.asarray(grid.occupied, bool)
    unknown = (np.zeros_like(occupied) if grid.unknown is None
               else np.asarray(grid.unknown, bool))  # fmt: skip
    return ~occupied & ~unknown, unknown


def frontier_mask(grid, fringe: float = 0.0) -> np.ndarray:
    """The frontier cells of ``grid`` (module docstring): free with an unknown edge neighbour
    that is not a wall's fringe.

    Parameters
    ----------
    grid : OccupancyGrid
        The map; its ``unknown`` mask marks the unknown cells (None: none).
    fringe : float
        Unknown cells whose centre lies within this of an occupied cell's centre make no
        frontier [m], >= 0.

    Returns
    -------
    numpy.ndarray of bool, shape ``grid.shape``
    """
    fringe = nonnegative("fringe", fringe, "m")
    free, unknown = _masks(grid)
    wall = np.asarray(grid.occupied, bool) & ~unknown
    if fringe > 0 and wall.any():
        unknown = unknown & (ndimage.distance_transform_edt(~wall) * grid.resolution > fringe)
    padded = np.pad(unknown, 1, constant_values=True)  # beyond the edge: unknown
    near_unknown = ndimage.binary_dilation(padded, _EDGE)[1:-1, 1:-1]
    return free & near_unknown


@dataclass(frozen=True)
class Frontier:
    """One frontier: connected frontier cells.

    Attributes
    ----------
    cells : numpy.ndarray of int64, shape (K, 2)
        (row, col) of its cells, in row-major order.
    middle : numpy.ndarray of int64, shape (2,)
        The cell nearest to the cells' centroid (the one the robot heads for).
    centroid : numpy.ndarray, shape (2,)
        World (x, y) of the cells' centroid [m].
    size : float
        Length: cells × resolution [m].
    """

    cells: np.ndarray
    middle: np.ndarray
    centroid: np.ndarray
    size: float


def find_frontiers(grid, min_size: int = 1, fringe: float = 0.0) -> list[Frontier]:
    """The frontiers of ``grid`` with at least ``min_size`` cells, largest first.

    Parameters
    ----------
    grid : OccupancyGrid
        The map.
    min_size : int
        Fewest cells of a frontier, >= 1.
    fringe : float
        Width of a wall's fringe, whose unknown cells make no frontier (:func:`frontier_mask`)
        [m], >= 0.

    Returns
    -------
    list of Frontier
        Ties in size in the order of their first cell (row-major).
    """
    min_size = integer("min_size", min_size, 1)
    labels, count = ndimage.label(frontier_mask(grid, fringe), structure=_EIGHT)
    found = []
    for label in range(1, count + 1):
        cells = np.argwhere(labels == label).astype(np.int64)
        if len(cells) < min_size:
            continue
        mean = cells.mean(axis=0)
        middle = cells[int(np.argmin(np.sum((cells - mean) ** 2, axis=1)))]
        centroid = np.asarray(grid.cell_to_world(mean[None]), float).reshape(-1)[:2]
        found.append(Frontier(cells, middle, centroid, float(len(cells) * grid.resolution)))
    found.sort(key=lambda f: -len(f.cells))  # stable: row-major among equals
    return found


def choose_frontier(
    frontiers: list[Frontier],
    distance: np.ndarray,
    resolution: float,
    *,
    approach: float = 1.0,
    distance_weight: float = 3.0,
    gain_weight: float = 1.0,
    blacklist: np.ndarray | None = None,
    blacklist_radius: float = 0.5,
    origin: tuple[float, float] = (0.0, 0.0),
    targets: np.ndarray | None = None,
) -> list[tuple[float, Frontier, np.ndarray]]:
    """The reachable frontiers ranked by cost, cheapest first (module docstring).

    Parameters
    ----------
    frontiers : list of Frontier
        From :func:`find_frontiers`.
    distance : numpy.ndarray, shape (rows, cols)
        Path distance from the robot to each cell [m]; inf where it cannot go.
    resolution : float
        Cell side [m], > 0.
    approach : float
        Farthest an approach cell may lie from the frontier [m], > 0.
    distance_weight, gain_weight : float
        Weights of the path distance and of the frontier's length in the cost (>= 0).
    blacklist : numpy.ndarray, shape (M, 2), optional
        World points (x, y) [m] of goals given up.
    blacklist_radius : float
        Frontiers whose middle lies within this of a blacklisted point are skipped [m].
    origin : tuple of float
        World (x, y) of cell (0, 0)'s lower-left corner [m] (the grid's origin).
    targets : numpy.ndarray of bool, shape (rows, cols), optional
        Cells that may be approach cells (e.g. where the robot fits in any heading); default
        every reachable cell. Only reachable ones are used.

    Returns
    -------
    list of tuple
        ``(cost [m], frontier, approach cell (row, col))``, cheapest first.
    """
    resolution = positive("resolution", resolution, "m")
    approach = positive("approach", approach, "m")
    distance_weight = nonnegative("distance_weight", distance_weight)
    gain_weight = nonnegative("gain_weight", gain_weight)
    blacklist_radius = nonnegative("blacklist_radius", blacklist_radius, "m")
    distance = np.asarray(distance, float)
    if distance.ndim != 2:
        raise ConfigError(f"distance must be a 2-D field (got shape {distance.shape})")
    ox, oy = (finite("origin", v) for v in origin)
    reachable = np.isfinite(distance)
    if targets is not None:
        targets = np.asarray(targets, bool)
        if targets.shape != distance.shape:
            raise ConfigError(f"targets has shape {targets.shape}, distance {distance.shape}")
        reachable &= targets
    if not reachable.any():
        return []
    # nearest reachable cell to every cell, and how far it is [cells]
    gap, (near_r, near_c) = ndimage.distance_transform_edt(~reachable, return_indices=True)
    points = np.zeros((0, 2)) if blacklist is None else np.asarray(blacklist, float).reshape(-1, 2)
    ranked = []
    for frontier in frontiers:
        gaps = gap[frontier.cells[:, 0], frontier.cells[:, 1]]
        # the frontier cell nearest to where the robot can stand; of equals, nearest the middle
        order = np.lexsort((np.sum((frontier.cells - frontier.middle) ** 2, axis=1), gaps))
        r, c = (int(v) for v in frontier.cells[order[0]])
        if gap[r, c] * resolution > approach:
            continue
        middle_xy = np.array([ox + (c + 0.5) * resolution, oy + (r + 0.5) * resolution])
        if len(points) and np.min(np.hypot(*(points - middle_xy).T)) <= blacklist_radius:
            continue
        cell = np.array([near_r[r, c], near_c[r, c]], np.int64)
        cost = distance_weight * float(distance[cell[0], cell[1]]) - gain_weight * frontier.size
        ranked.append((cost, frontier, cell))
    ranked.sort(key=lambda item: item[0])
    return ranked
