"""Dubins shortest paths for a car that only drives forward.

Dubins (1957): the shortest forward path between two poses with turning radius R is one of the
six words LSL, RSR, LSR, RSL, RLR, LRL. Closed forms in the normalised coordinates of Shkel &
Lumelsky (2001): d = D/R, α = θ₀ − ψ, β = θ₁ − ψ with ψ the direction from start to goal.
"""

from __future__ import annotations

import math

import numba
import numpy as np
from numpy.typing import ArrayLike

from wheelbase._validate import as_float_array, positive
from wheelbase.planning.path import CurvePath

__all__ = ["dubins_candidates", "dubins_length", "dubins_path"]

_TWO_PI = 2.0 * math.pi
_TOL = 1e-10  # rounding tolerance: a zero-length segment must not become a full turn
# word index -> segment types (+1 L, 0 S, -1 R)
_WORDS = np.array(
    [[1, 0, 1], [-1, 0, -1], [1, 0, -1], [-1, 0, 1], [-1, 1, -1], [1, -1, 1]], dtype=np.int64
)
_NAMES = ("LSL", "RSR", "LSR", "RSL", "RLR", "LRL")


@numba.njit(cache=True)
def _m(x):
    """Wrap to [0, 2π)."""
    v = x - _TWO_PI * math.floor(x / _TWO_PI)
    return 0.0 if (v >= _TWO_PI - _TOL or v < 0.0) else v


@numba.njit(cache=True)
def _dubins_all(x0, y0, th0, x1, y1, th1, radius):
    """Normalised segment lengths ``(6, 3)`` of every word (NaN where infeasible)."""
    dx = (x1 - x0) / radius
    dy = (y1 - y0) / radius
    d = math.hypot(dx, dy)
    psi = math.atan2(dy, dx) if d > 0 else 0.0
    a = _m(th0 - psi)
    b = _m(th1 - psi)
    sa, sb, ca, cb = math.sin(a), math.sin(b), math.cos(a), math.cos(b)
    cab = math.cos(a - b)
    out = np.full((6, 3), np.nan)
    # LSL
    p2 = 2.0 + d * d - 2.0 * cab + 2.0 * d * (sa - sb)
    if p2 >= -_TOL:
        p2 = max(p2, 0.0)
        tmp = math.atan2(cb - ca, d + sa - sb)
        out[0, 0] = _m(tmp - a)
        out[0, 1] = math.sqrt(p2)
        out[0, 2] = _m(b - tmp)
    # RSR
    p2 = 2.0 + d * d - 2.0 * cab + 2.0 * d * (sb - sa)
    if p2 >= -_TOL:
        p2 = max(p2, 0.0)
        tmp = math.atan2(ca - cb, d - sa + sb)
        out[1, 0] = _m(a - tmp)
        out[1, 1] = math.sqrt(p2)
        out[1, 2] = _m(tmp - b)
    # LSR
    p2 = -2.0 + d * d + 2.0 * cab + 2.0 * d * (sa + sb)
    if p2 >= -_TOL:
        p2 = max(p2, 0.0)
        p = math.sqrt(p2)
        tmp = math.atan2(-ca - cb, d + sa + sb) - math.atan2(-2.0, p)
        out[2, 0] = _m(tmp - a)
        out[2, 1] = p
        out[2, 2] = _m(tmp - b)
    # RSL
    p2 = -2.0 + d * d + 2.0 * cab - 2.0 * d * (sa + sb)
    if p2 >= -_TOL:
        p2 = max(p2, 0.0)
        p = math.sqrt(p2)
        tmp = math.atan2(ca + cb, d - sa - sb) - math.atan2(2.0, p)
        out[3, 0] = _m(a - tmp)
        out[3, 1] = p
        out[3, 2] = _m(b - tmp)
    # RLR
    c = (6.0 - d * d + 2.0 * cab + 2.0 * d * (sa - sb)) / 8.0
    if abs(c) <= 1.0 + _TOL:
        c = min(1.0, max(-1.0, c))
        p = _m(_TWO_PI - math.acos(c))
        t = _m(a - math.atan2(ca - cb, d - sa + sb) + p / 2.0)
        out[4, 0] = t
        out[4, 1] = p
        out[4, 2] = _m(a - b - t + p)
    # LRL
    c = (6.0 - d * d + 2.0 * cab + 2.0 * d * (sb - sa)) / 8.0
    if abs(c) <= 1.0 + _TOL:
        c = min(1.0, max(-1.0, c))
        p = _m(_TWO_PI - math.acos(c))
        t = _m(-a - math.atan2(ca - cb, d + sa - sb) + p / 2.0)
        out[5, 0] = t
        out[5, 1] = p
        out[5, 2] = _m(b - a - t + p)
    return out


@numba.njit(cache=True)
def _dubins_length(x0, y0, th0, x1, y1, th1, radius):
    """Dubins length [m] (Numba, for Hybrid A* without reverse)."""
    segs = _dubins_all(x0, y0, th0, x1, y1, th1, radius)
    best = np.inf
    for w in range(6):
        if not np.isnan(segs[w, 0]):
            best = min(best, segs[w, 0] + segs[w, 1] + segs[w, 2])
    return best * radius


def _poses(start: ArrayLike, goal: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    return (
        as_float_array("start", start, 3, min_ndim=1, max_ndim=1),
        as_float_array("goal", goal, 3, min_ndim=1, max_ndim=1),
    )


def dubins_candidates(start: ArrayLike, goal: ArrayLike, turning_radius: float) -> list[CurvePath]:
    """All feasible Dubins words between two poses.

    Parameters
    ----------
    start : array_like
        Start pose ``(x, y, θ)`` [m, m, rad].
    goal : array_like
        Goal pose.
    turning_radius : float
        Turning radius R [m], > 0.

    Returns
    -------
    list of CurvePath
        Up to six paths (forward only), each ending at ``goal``.
    """
    start, goal = _poses(start, goal)
    radius = positive("turning_radius", turning_radius, "m")
    segs = _dubins_all(*start, *goal, radius)
    return [
        CurvePath(start, radius, _NAMES[w], _WORDS[w].copy(), segs[w] * radius)
        for w in range(6)
        if not np.isnan(segs[w, 0])
    ]


def dubins_path(start: ArrayLike, goal: ArrayLike, turning_radius: float) -> CurvePath:
    """The shortest Dubins (forward-only) path from ``start`` to ``goal``.

    Parameters
    ----------
    start : array_like
        Start pose ``(x, y, θ)`` [m, m, rad].
    goal : array_like
        Goal pose.
    turning_radius : float
        Turning radius R [m], > 0.

    Returns
    -------
    CurvePath

    Examples
    --------
    >>> p = dubins_path((0, 0, 0), (4, 0, 0), 1.0)
    >>> p.word, p.length
    ('LSL', 4.0)
    """
    return min(dubins_candidates(start, goal, turning_radius), key=lambda p: p.length)


def dubins_length(start: ArrayLike, goal: ArrayLike, turning_radius: float) -> float:
    """Length [m] of the shortest Dubins path.

    Parameters
    ----------
    start : array_like
        Start pose ``(x, y, θ)``.
    goal : array_like
        Goal pose.
    turning_radius : float
        Turning radius R [m], > 0.

    Returns
    -------
    float
    """
    start, goal = _poses(start, goal)
    radius = positive("turning_radius", turning_radius, "m")
    return float(_dubins_length(*start, *goal, radius))
