"""A robot footprint as disks on a map's distance field: the static-map obstacle check of the
sampling controllers (MPPI, DWA).

The footprint is checked as disks (x, y, radius) in the body frame: its covering circles, or,
where those reach more than 0.25 m past the outline (a car: 0.56 m past its ends),
:meth:`~wheelbase.planning.Footprint.outline_circles` every :data:`OUTLINE_SPACING` = 0.2 m.
The clearance of a pose is the least over its disks of (distance field at the disk's centre −
disk radius − √2·cell): conservative by a cell diagonal, since the field is sampled at the cell
the centre falls in. A disk whose centre leaves the map is a collision.
"""

from __future__ import annotations

import math
from typing import Any

import numba
import numpy as np

from wheelbase.errors import ConfigError

__all__ = [
    "MAX_FOOTPRINT_DISKS",
    "OUTLINE_SPACING",
    "FootprintField",
    "clearance_at",
    "footprint_disks",
]

OUTLINE_SPACING = 0.2
"""Spacing [m] of the edge disks that stand for a long footprint."""

MAX_FOOTPRINT_DISKS = 100_000
"""Most disks (outline or covering) a footprint may need: each is checked at every step of every
rollout (a 4.5 × 1.8 m car needs 67; 100,000 is a 10 km outline)."""


def _check_disk_count(footprint: Any) -> None:
    """Refuse a footprint whose disks would not fit in memory or time (a 1e9 m car asked for
    2.2 TiB), before any of them is made."""
    poly = np.asarray(footprint.polygon, dtype=np.float64)
    extent = np.ptp(poly, axis=0)
    long_side, short_side = float(np.max(extent)), float(np.min(extent))
    perimeter = float(np.sum(np.hypot(*(np.roll(poly, -1, axis=0) - poly).T)))
    covering = 2.0 * long_side / short_side if short_side > 0 else math.inf
    count = max(covering, perimeter / OUTLINE_SPACING + covering)
    if not count <= MAX_FOOTPRINT_DISKS:
        raise ConfigError(
            f"footprint ({long_side:.3g} × {short_side:.3g} m) needs {count:.3g} outline disks "
            f"of {OUTLINE_SPACING} m or covering circles: more than {MAX_FOOTPRINT_DISKS}, each "
            "checked at every step of every rollout"
        )


def footprint_disks(footprint: Any, outline: bool = True) -> np.ndarray:
    """Disks ``(K, 3)`` = (x [m], y [m], radius [m]) in the body frame that stand for a
    footprint (see the module docstring); a point (one disk of radius 0) for ``None``.

    Parameters
    ----------
    footprint : Footprint or None
        The robot outline.
    outline : bool
        Use the outline disks where the covering circles overshoot by more than 0.25 m;
        ``False``: always the covering circles (fewer disks, more conservative).

    Returns
    -------
    numpy.ndarray
    """
    if footprint is None:
        return np.zeros((1, 3))
    _check_disk_count(footprint)
    if outline and footprint.circle_overshoot > 0.25:
        # A long outline (a car): the covering circles would see a wall 0.5 m early.
        return np.ascontiguousarray(footprint.outline_circles(OUTLINE_SPACING))
    circles = np.asarray(footprint.circles, dtype=np.float64)
    radius = np.full((len(circles), 1), float(footprint.circle_radius))
    return np.ascontiguousarray(np.hstack([circles, radius]))


class FootprintField:
    """A map's distance field and a footprint's disks, for the critics' clearance.

    Parameters
    ----------
    grid : OccupancyGrid or None
        The map (``None``: no map; nothing collides).
    footprint : Footprint or None
        The robot outline (``None``: a point).

    Attributes
    ----------
    distance_field : numpy.ndarray, shape (rows, cols)
        Distance [m] from each cell to the nearest occupied one, capped at 1 km.
    geometry : numpy.ndarray, shape (4,)
        (x0 [m], y0 [m], resolution [m], enabled 0/1).
    circles : numpy.ndarray, shape (K, 3)
        The footprint's disks (:func:`footprint_disks`).
    """

    def __init__(self, grid: Any, footprint: Any) -> None:
        self.grid = grid
        self.footprint = footprint
        if grid is None:
            self.distance_field = np.zeros((1, 1))
            self.geometry = np.array([0.0, 0.0, 1.0, 0.0])
        else:
            self.distance_field = np.ascontiguousarray(np.minimum(grid.distance_field, 1.0e3))
            self.geometry = np.array([grid.origin[0], grid.origin[1], grid.resolution, 1.0])
        self.circles = footprint_disks(footprint)

    @property
    def enabled(self) -> bool:
        """Whether there is a map."""
        return self.grid is not None

    def clearance(
        self, poses: np.ndarray, relief: float = 0.0, geometry: np.ndarray | None = None
    ) -> tuple[np.ndarray, np.ndarray]:
        """The footprint's clearance [m] of poses and whether each is in collision.

        Parameters
        ----------
        poses : numpy.ndarray, shape (..., 3)
            Poses (x [m], y [m], θ [rad]), in the frame of ``geometry``'s origin.
        relief : float
            Subtracted from the clearance [m] (the controllers' collision relief).
        geometry : numpy.ndarray, shape (4,), optional
            The map's (x0, y0, resolution, enabled), e.g. with its origin relative to the robot
            (default: :attr:`geometry`).

        Returns
        -------
        clearance : numpy.ndarray, shape (...)
            The least over the disks of distance field − disk radius − √2·cell − ``relief``
            (0 where a disk leaves the map).
        collided : numpy.ndarray of bool, shape (...)
            Clearance <= 0 or off the map.
        """
        x0, y0, res = (self.geometry if geometry is None else geometry)[:3]
        cos, sin = np.cos(poses[..., 2]), np.sin(poses[..., 2])
        rows, cols = self.distance_field.shape
        collided = np.zeros(poses.shape[:-1], bool)
        clearance = np.full(poses.shape[:-1], np.inf)
        for cx, cy, radius in self.circles:
            px = poses[..., 0] + cos * cx - sin * cy
            py = poses[..., 1] + sin * cx + cos * cy
            col = np.floor((px - x0) / res).astype(np.int64)
            row = np.floor((py - y0) / res).astype(np.int64)
            inside = (row >= 0) & (row < rows) & (col >= 0) & (col < cols)
            field = self.distance_field[np.clip(row, 0, rows - 1), np.clip(col, 0, cols - 1)]
            clear = field - radius - math.sqrt(2.0) * res - relief
            collided |= ~inside | (clear <= 0.0)
            clearance = np.minimum(clearance, np.where(inside, clear, 0.0))
        return clearance, collided

    def relief(self, pose: np.ndarray, geometry: np.ndarray) -> float:
        """The collision relief [m] of a call from ``pose``: 0, or, where the critics already
        see the footprint in collision (their clearance is conservative by a cell diagonal and
        the disks' overshoot; a planned path may pass closer), its clearance now − 1 cm, so
        that only rollouts that get deeper count as collisions and the robot is not frozen for
        good. A footprint that truly overlaps an obstacle keeps relief 0: every rollout is
        lethal, a safe stop.

        Parameters
        ----------
        pose : numpy.ndarray, shape (3,)
            World pose.
        geometry : numpy.ndarray, shape (4,)
            The map's geometry, origin relative to the robot.

        Returns
        -------
        float
        """
        if not self.enabled:
            return 0.0
        now, _ = self.clearance(np.array([0.0, 0.0, pose[2]]), geometry=geometry)
        if now <= 0.0 and not self.truly_colliding(pose):
            return float(now) - 0.01
        return 0.0

    def truly_colliding(self, pose: np.ndarray) -> bool:
        """Whether the exact footprint (or the point) overlaps an obstacle or leaves the map.

        Parameters
        ----------
        pose : numpy.ndarray, shape (3,)
            World pose.

        Returns
        -------
        bool
        """
        if self.footprint is None:
            inside = bool(self.grid.contains(pose[None, :2])[0])
            return not inside or bool(self.grid.is_occupied(pose[None, :2])[0])
        return bool(np.asarray(self.grid.in_collision(self.footprint, pose[None])).reshape(-1)[0])


@numba.njit(cache=True, inline="always")
def clearance_at(x, y, c, s, df, x0, y0, inv_res, circles, margin):
    """The compiled twin of :meth:`FootprintField.clearance` for one pose: the footprint's
    clearance [m] (the least over its disks of field − radius − ``margin``; 0 where a disk leaves
    the map) and whether it collides. ``(c, s)`` = (cos θ, sin θ), ``inv_res`` = 1/resolution,
    positions in the frame of the map origin (x0, y0)."""
    rows, cols = df.shape[0], df.shape[1]
    clearance = 1.0e300  # finite: the kernels run with fastmath (no inf)
    hit = False
    for k in range(circles.shape[0]):
        px = x + c * circles[k, 0] - s * circles[k, 1]
        py = y + s * circles[k, 0] + c * circles[k, 1]
        col = math.floor((px - x0) * inv_res)
        row = math.floor((py - y0) * inv_res)
        if row < 0 or row >= rows or col < 0 or col >= cols:
            hit = True
            clearance = 0.0
            continue
        clear = df[row, col] - circles[k, 2] - margin
        if clear <= 0.0:
            hit = True
        clearance = min(clearance, clear)
    return clearance, hit
