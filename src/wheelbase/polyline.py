"""Distance from points to a polyline: exact, compiled, and quick on long paths.

Every point's distance is the minimum over the segments of the polyline, as brute force would
give it, but most segments are skipped: consecutive segments are grouped in blocks of
:data:`BLOCK`, each block bounded by a circle, and a block is only opened when the point could
be closer to it than to the best segment found so far (its circle's distance is a lower bound).
The search starts from the previous point's nearest segment, which along a driven path is
almost always the answer, so a point costs about one bound per block.
"""

from __future__ import annotations

import math

import numba
import numpy as np
from numpy.typing import ArrayLike

from wheelbase._validate import as_float_array
from wheelbase.errors import InputError

__all__ = ["BLOCK", "distance_to_polyline"]

BLOCK = 16
"""Segments per bounding circle."""


def distance_to_polyline(points: ArrayLike, polyline: ArrayLike) -> np.ndarray:
    """Distance [m] from each point to the nearest point of a polyline.

    Parameters
    ----------
    points : array_like, shape (..., 2)
        Query points [m].
    polyline : array_like, shape (M, 2)
        Vertices [m], M >= 1 (one vertex: the distance to that point).

    Returns
    -------
    numpy.ndarray, shape (...)
        Distances [m].

    Examples
    --------
    >>> distance_to_polyline([[0.5, 1.0], [2.0, 3.0]], [[0, 0], [1, 0], [1, 2]]).tolist()
    [0.5, 1.4142135623730951]
    """
    xy = as_float_array("points", points, 2)
    vertices = as_float_array("polyline", polyline, 2, min_ndim=2, max_ndim=2)
    if vertices.shape[0] == 0:
        raise InputError("polyline must have at least one vertex")
    flat = np.ascontiguousarray(xy.reshape(-1, 2))
    if vertices.shape[0] == 1:
        vertices = np.vstack([vertices, vertices])
    out = _distances(flat, np.ascontiguousarray(vertices), BLOCK)
    return out.reshape(xy.shape[:-1])


@numba.njit(cache=True)
def _segment_distance2(px, py, ax, ay, bx, by):
    dx, dy = bx - ax, by - ay
    length2 = dx * dx + dy * dy
    u = 0.0
    if length2 > 0.0:
        u = min(1.0, max(0.0, ((px - ax) * dx + (py - ay) * dy) / length2))
    ex, ey = px - ax - u * dx, py - ay - u * dy
    return ex * ex + ey * ey


@numba.njit(cache=True)
def _distances(points, vertices, block):
    segments = vertices.shape[0] - 1
    blocks = (segments + block - 1) // block
    centre = np.empty((blocks, 2))
    radius = np.empty(blocks)
    for k in range(blocks):
        first, last = k * block, min(segments, (k + 1) * block)
        x0, x1 = vertices[first, 0], vertices[first, 0]
        y0, y1 = vertices[first, 1], vertices[first, 1]
        for j in range(first, last + 1):
            x0, x1 = min(x0, vertices[j, 0]), max(x1, vertices[j, 0])
            y0, y1 = min(y0, vertices[j, 1]), max(y1, vertices[j, 1])
        centre[k, 0], centre[k, 1] = 0.5 * (x0 + x1), 0.5 * (y0 + y1)
        radius[k] = 0.5 * math.hypot(x1 - x0, y1 - y0)
    out = np.empty(points.shape[0])
    guess = 0
    for i in range(points.shape[0]):
        px, py = points[i, 0], points[i, 1]
        best2 = _segment_distance2(
            px, py, vertices[guess, 0], vertices[guess, 1],
            vertices[guess + 1, 0], vertices[guess + 1, 1],
        )  # fmt: skip
        best = math.sqrt(best2)
        for k in range(blocks):
            # |p − c| − r >= best  ⇔  |p − c|² >= (best + r)²: no square root per block
            dx, dy = px - centre[k, 0], py - centre[k, 1]
            reach = best + radius[k]
            if dx * dx + dy * dy >= reach * reach:
                continue
            for j in range(k * block, min(segments, (k + 1) * block)):
                d2 = _segment_distance2(
                    px, py, vertices[j, 0], vertices[j, 1], vertices[j + 1, 0], vertices[j + 1, 1]
                )
                if d2 < best2:
                    best2, guess = d2, j
                    best = math.sqrt(best2)
        out[i] = best
    return out
