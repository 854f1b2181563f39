"""Hand-made lidar scenes for the perception tests and benchmark: rooms, moving discs, boxes.

The true range of a beam is the nearer of the map's (``wheelbase.sensors.scan_rays``, exact
traversal) and the first crossing of a disc's circle, solved in closed form: a ray ``o + t u``
meets the circle of centre ``c`` and radius ρ at ``t = b − sqrt(b² − (|c − o|² − ρ²))`` with
``b = u · (c − o)`` (0 when ``o`` is inside); a box's, the nearest crossing of its edges.
"""

from __future__ import annotations

import numpy as np

from wheelbase.planning import OccupancyGrid
from wheelbase.sensors import scan_rays

__all__ = ["box_ranges", "crossing_discs", "disc_ranges", "room"]


def room(width: float, height: float, resolution: float = 0.05) -> OccupancyGrid:
    """An empty rectangular room ``width × height`` [m] with one-cell walls, origin (0, 0)."""
    cols, rows = round(width / resolution), round(height / resolution)
    occupied = np.zeros((rows, cols), bool)
    occupied[[0, -1], :] = True
    occupied[:, [0, -1]] = True
    return OccupancyGrid(occupied, resolution)


def disc_ranges(
    grid: OccupancyGrid | None,
    sensor_poses: np.ndarray,
    beam_angles: np.ndarray,
    max_range: float,
    discs: np.ndarray,
) -> np.ndarray:
    """True ranges ``(M, K)`` from sensors ``(M, 3)`` among the map and discs ``(D, 3)`` =
    (x, y, radius) [m] (the same discs for every sensor)."""
    poses = np.atleast_2d(np.asarray(sensor_poses, float))
    angles = poses[:, 2, None] + np.asarray(beam_angles, float)[None, :]
    if grid is None:
        ranges = np.full(angles.shape, float(max_range))
    else:
        ranges = scan_rays(grid, poses[:, :2], poses[:, 2], beam_angles, max_range, "exact")
    ux, uy = np.cos(angles), np.sin(angles)
    for cx, cy, rho in np.atleast_2d(np.asarray(discs, float)).reshape(-1, 3):
        dx, dy = cx - poses[:, 0, None], cy - poses[:, 1, None]
        b = ux * dx + uy * dy
        c = dx * dx + dy * dy - rho * rho
        disc = b * b - c
        with np.errstate(invalid="ignore"):
            t = np.where(c <= 0.0, 0.0, b - np.sqrt(disc))
        hit = (disc >= 0.0) & (t >= 0.0)
        ranges = np.where(hit & (t < ranges), t, ranges)
    return ranges


def box_ranges(
    sensor_pose: np.ndarray, beam_angles: np.ndarray, max_range: float, corners: np.ndarray
) -> np.ndarray:
    """True ranges ``(K,)`` from one sensor (x, y, θ) to a convex polygon ``corners`` (P, 2)
    in open space (``max_range`` where a beam misses it)."""
    angles = sensor_pose[2] + np.asarray(beam_angles, float)
    ux, uy = np.cos(angles), np.sin(angles)
    ranges = np.full(angles.shape, float(max_range))
    for a, b in zip(corners, np.roll(corners, -1, axis=0), strict=True):
        ex, ey = b - a
        wx, wy = a[0] - sensor_pose[0], a[1] - sensor_pose[1]
        det = ex * uy - ey * ux
        with np.errstate(divide="ignore", invalid="ignore"):
            t = (ex * wy - ey * wx) / det  # along the beam
            lam = (ux * wy - uy * wx) / det  # along the edge
        hit = (np.abs(det) > 1e-12) & (t > 0.0) & (lam >= 0.0) & (lam <= 1.0)
        ranges = np.where(hit & (t < ranges), t, ranges)
    return ranges


def crossing_discs(t: float) -> np.ndarray:
    """Two discs of radius 0.3 m crossing in front of a sensor at the origin: A from (3, −2)
    at (0, +1) m/s, B from (5, 2) at (0, −1) m/s; B passes behind A (fully hidden near
    t = 2 s). Rows (x, y, radius, vx, vy)."""
    return np.array([[3.0, -2.0 + t, 0.3, 0.0, 1.0], [5.0, 2.0 - t, 0.3, 0.0, -1.0]])
