"""Robot footprints: a convex outline in the body frame, its covering circles and offsets.

Collision checks against a world (:mod:`wheelbase.planning.occupancy`) take a
:class:`Footprint`; the reference point is the origin of the body frame.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from wheelbase._validate import as_float_array, finite, nonnegative, positive
from wheelbase.errors import ConfigError
from wheelbase.limits import MAX_COORDINATE

__all__ = ["Footprint"]


MAX_COVER_CIRCLES = 10_000
"""Most circles covering a footprint (:attr:`Footprint.circles`: twice the aspect ratio): a
1e9 m × 1e-9 m footprint asked for 4e9 of them, 30 GB."""


@dataclass(frozen=True, eq=False)
class Footprint:
    """A convex robot outline in the body frame of its reference point.

    The reference point is the origin of the body frame: the rear-axle centre for car-like
    robots, the wheel-axle centre for differential drive. Planners report poses of it.

    Parameters
    ----------
    polygon : numpy.ndarray
        Convex polygon vertices ``(M, 2)`` [m] in the body frame (x forward, y left), in
        counter-clockwise or clockwise order.

    Examples
    --------
    >>> fp = Footprint.rectangle(4.5, 1.8, rear_axle_to_center=1.35)
    >>> [round(float(v), 3) for v in (fp.polygon[:, 0].min(), fp.polygon[:, 0].max())]
    [-0.9, 3.6]
    """

    polygon: np.ndarray

    def __post_init__(self) -> None:
        poly = as_float_array("polygon", self.polygon, 2, min_ndim=2, max_ndim=2)
        if len(poly) < 3:
            raise ConfigError(f"polygon needs >= 3 vertices (got {len(poly)})")
        reach = float(np.max(np.abs(poly)))
        if reach > MAX_COORDINATE:
            raise ConfigError(
                f"polygon vertices must be within ±{MAX_COORDINATE:g} m of the reference point "
                f"(got one {reach:.3g} m away)"
            )
        area2 = np.sum(poly[:, 0] * np.roll(poly[:, 1], -1) - np.roll(poly[:, 0], -1) * poly[:, 1])
        if abs(area2) < 1e-12:
            raise ConfigError("polygon must have a non-zero area")
        if area2 < 0:
            poly = poly[::-1]
        edges = np.roll(poly, -1, axis=0) - poly
        nxt = np.roll(edges, -1, axis=0)
        if np.any(edges[:, 0] * nxt[:, 1] - edges[:, 1] * nxt[:, 0] < -1e-12):
            raise ConfigError("polygon must be convex")
        extent = np.ptp(poly, axis=0)
        if 2.0 * extent.max() / extent.min() > MAX_COVER_CIRCLES:  # see circles
            raise ConfigError(
                f"polygon is {extent[0]:.3g} m × {extent[1]:.3g} m: covering it needs more than "
                f"{MAX_COVER_CIRCLES} circles (an aspect ratio above "
                f"{MAX_COVER_CIRCLES // 2}); a robot is not that thin"
            )
        poly = np.ascontiguousarray(poly)
        poly.setflags(write=False)
        object.__setattr__(self, "polygon", poly)

    @classmethod
    def rectangle(cls, length: float, width: float, rear_axle_to_center: float = 0.0) -> Footprint:
        """A ``length × width`` rectangle whose centre is ``rear_axle_to_center`` ahead of the
        reference point.

        Parameters
        ----------
        length : float
            Extent along the body x axis [m], > 0.
        width : float
            Extent along the body y axis [m], > 0.
        rear_axle_to_center : float
            Distance [m] from the reference point (rear-axle centre) forward to the
            rectangle's centre; 0 for a robot whose reference point is its centre.

        Returns
        -------
        Footprint
        """
        length = positive("length", length, "m")
        width = positive("width", width, "m")
        c = finite("rear_axle_to_center", rear_axle_to_center, "m")
        hl, hw = length / 2.0, width / 2.0
        return cls(np.array([[c - hl, -hw], [c + hl, -hw], [c + hl, hw], [c - hl, hw]]))

    @cached_property
    def circles(self) -> np.ndarray:
        """Centres ``(K, 2)`` [m] of circles that together cover the polygon's bounding box."""
        (xmin, ymin), (xmax, ymax) = self.polygon.min(0), self.polygon.max(0)
        length, width = xmax - xmin, ymax - ymin
        along_x = length >= width
        long_side, short_side = (length, width) if along_x else (width, length)
        n = max(1, math.ceil(2.0 * long_side / short_side))
        t = (np.arange(n) + 0.5) / n
        if along_x:
            return np.stack([xmin + t * length, np.full(n, (ymin + ymax) / 2)], -1)
        return np.stack([np.full(n, (xmin + xmax) / 2), ymin + t * width], -1)

    @cached_property
    def circle_radius(self) -> float:
        """Radius [m] of each covering circle."""
        (xmin, ymin), (xmax, ymax) = self.polygon.min(0), self.polygon.max(0)
        length, width = xmax - xmin, ymax - ymin
        n = len(self.circles)
        long_side, short_side = max(length, width), min(length, width)
        return float(math.hypot(long_side / (2 * n), short_side / 2))

    @property
    def circle_overshoot(self) -> float:
        """How far [m] the covering :attr:`circles` reach beyond the polygon at most (at the
        ends of a long outline: 0.56 m for a 4.5 × 1.8 m car)."""
        return float(self.outline_distance(self.circles, np.full(len(self.circles),
                                                                 self.circle_radius)))  # fmt: skip

    def outline_distance(self, centres: np.ndarray, radii: np.ndarray) -> float:
        """Largest distance [m] from the polygon to a point of the disks ``(centres, radii)``.

        The farthest point of a disk from a convex polygon lies on its rim; 64 rim points per
        disk bound it to 0.1 % of the radius.

        Parameters
        ----------
        centres : numpy.ndarray, shape (K, 2)
            Disk centres [m] in the body frame.
        radii : numpy.ndarray, shape (K,)
            Disk radii [m].

        Returns
        -------
        float
            0 when every disk lies inside the polygon.
        """
        angle = np.linspace(0.0, 2.0 * math.pi, 64, endpoint=False)
        rim = np.stack([np.cos(angle), np.sin(angle)], -1)
        points = (centres[:, None, :] + radii[:, None, None] * rim).reshape(-1, 2)
        return float(np.max(_polygon_distance(self.polygon, points), initial=0.0))

    def outline_circles(self, spacing: float) -> np.ndarray:
        """Disks ``(K, 3)`` = (x [m], y [m], radius [m]) that follow the outline closely.

        Disks of radius ``spacing / 2`` centred on the edges every ``spacing`` at most (the
        vertices included) cover a band along the outline and reach at most ``spacing / 2``
        beyond it; disks inscribed in the polygon along its long axis (every half its width)
        fill the middle. Unlike :attr:`circles`, which reach 0.56 m past the ends of a car, this
        lets a critic see a wall close behind a reversing car; a point obstacle can only get
        into the uncovered pockets at the corners by crossing the band, which a step shorter
        than ``spacing`` does not skip.

        Parameters
        ----------
        spacing : float
            Largest gap [m] between neighbouring edge disks, > 0.

        Returns
        -------
        numpy.ndarray
        """
        spacing = positive("spacing", spacing, "m")
        poly = self.polygon
        rows = []
        for start, end in zip(poly, np.roll(poly, -1, axis=0), strict=True):
            count = max(1, math.ceil(float(np.hypot(*(end - start))) / spacing - 1e-9))
            frac = np.arange(count)[:, None] / count
            rows.append(start + frac * (end - start))
        edge = np.concatenate(rows)
        (xmin, ymin), (xmax, ymax) = poly.min(0), poly.max(0)
        along_x = xmax - xmin >= ymax - ymin
        short = min(xmax - xmin, ymax - ymin)
        lo, hi = (xmin, xmax) if along_x else (ymin, ymax)
        first, last = lo + short / 2.0, hi - short / 2.0
        count = max(1, math.ceil((last - first) / (short / 2.0) - 1e-9))
        t = first + (last - first) * np.arange(count + 1) / count
        mid = (ymin + ymax) / 2.0 if along_x else (xmin + xmax) / 2.0
        inner = np.stack([t, np.full_like(t, mid)], -1) if along_x else np.stack(
            [np.full_like(t, mid), t], -1)  # fmt: skip
        inner_radius = np.maximum(-_polygon_distance(poly, inner), 0.0)
        keep = inner_radius > 0.0
        return np.ascontiguousarray(
            np.concatenate(
                [
                    np.column_stack([edge, np.full(len(edge), spacing / 2.0)]),
                    np.column_stack([inner[keep], inner_radius[keep]]),
                ]
            )
        )

    @cached_property
    def max_radius(self) -> float:
        """Largest distance [m] from the reference point to a vertex."""
        return float(np.max(np.hypot(self.polygon[:, 0], self.polygon[:, 1])))

    @cached_property
    def inscribed_radius(self) -> float:
        """Distance [m] from the reference point to the nearest edge (0 if it is outside)."""
        poly = self.polygon
        edges = np.roll(poly, -1, axis=0) - poly
        normals = np.stack([edges[:, 1], -edges[:, 0]], -1)
        normals /= np.linalg.norm(normals, axis=1, keepdims=True)
        d = -np.sum(normals * poly, axis=1)  # signed distance of the origin, <0 inside
        return float(max(0.0, -d.max()))

    def inflated(self, margin: float) -> Footprint:
        """The polygon with every edge moved outward by ``margin`` (contains the Minkowski sum
        with a disk of that radius).

        Parameters
        ----------
        margin : float
            Offset [m], >= 0.

        Returns
        -------
        Footprint
        """
        margin = nonnegative("margin", margin, "m")
        if margin == 0:
            return self
        poly = self.polygon
        m = len(poly)
        edges = np.roll(poly, -1, axis=0) - poly
        normals = np.stack([edges[:, 1], -edges[:, 0]], -1)
        normals /= np.linalg.norm(normals, axis=1, keepdims=True)
        offset = np.sum(normals * poly, axis=1) + margin
        out = np.empty_like(poly)
        for i in range(m):
            j = (i - 1) % m  # edges j and i meet at vertex i
            a = np.array([normals[j], normals[i]])
            out[i] = np.linalg.solve(a, [offset[j], offset[i]])
        return Footprint(out)


def _polygon_distance(poly: np.ndarray, points: np.ndarray) -> np.ndarray:
    """Signed distance [m] from ``points (P, 2)`` to a convex counter-clockwise polygon
    (negative inside)."""
    edges = np.roll(poly, -1, axis=0) - poly
    normals = np.stack([edges[:, 1], -edges[:, 0]], -1)
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    # outside: the distance to the nearest edge segment; inside: minus the nearest edge line
    rel = points[:, None, :] - poly[None]
    t = np.clip(np.sum(rel * edges, -1) / np.sum(edges * edges, -1), 0.0, 1.0)
    gap = np.linalg.norm(rel - t[..., None] * edges, axis=-1).min(1)
    side = np.max(np.sum(rel * normals, -1), axis=1)
    return np.where(side > 0.0, gap, side)
