"""Reeds–Shepp shortest paths for a car that drives forward and backward.

Reeds & Shepp (1990), "Optimal paths for a car that goes both forwards and backwards", Pacific
J. Math. 145(2): the shortest path between two poses for a turning radius R is one of 48 words
of at most five segments (arcs C = L or R at radius R, straight S) with at most two cusps. The
words come from the paper's formulas 8.1–8.11 (CSC, C|C|C, CC|C, C|CC, CC|CC, C|CC|C, C|C[π/2]SC,
CSC[π/2]|C, C|C[π/2]SC[π/2]|C), each applied to the goal after the *time-flip* (x, y, φ) →
(−x, y, −φ), the *reflection* (x, y, φ) → (x, −y, −φ), both, and for the asymmetric families the
*backwards* transform (the word read from the goal). Formulas 8.3/8.4 and 8.11 have typos in the
paper; the corrected forms used here are those of OMPL's ``ReedsSheppStateSpace`` (Moll), checked
here by the end-pose test of every candidate.

Everything is computed in coordinates normalised by R (goal expressed in the start frame), in
Numba so that Hybrid A* can call it in its inner loop (heuristic and analytic expansion).
"""

from __future__ import annotations

import math

import numba
import numpy as np
from numpy.typing import ArrayLike

from wheelbase._validate import as_float_array, positive
from wheelbase.planning.path import CurvePath

__all__ = [
    "reeds_shepp_candidates",
    "reeds_shepp_length",
    "reeds_shepp_path",
]

_PI = math.pi
_HALF_PI = 0.5 * math.pi
_ZERO = 10 * np.finfo(np.float64).eps
MAX_CANDIDATES = 48


@numba.njit(cache=True)
def _mod2pi(x):
    """Wrap to [−π, π] (the Reeds–Shepp paper's convention)."""
    if -_PI <= x <= _PI:
        return x  # the common case, without the call to fmod
    v = np.fmod(x, 2.0 * _PI)
    if v < -_PI:
        v += 2.0 * _PI
    elif v > _PI:
        v -= 2.0 * _PI
    return v


@numba.njit(cache=True)
def _tau_omega(u, v, xi, eta, phi):
    delta = _mod2pi(u - v)
    a = math.sin(u) - math.sin(delta)
    b = math.cos(u) - math.cos(delta) - 1.0
    t1 = math.atan2(eta * a - xi * b, xi * a + eta * b)
    t2 = 2.0 * (math.cos(delta) - math.cos(v) - math.cos(u)) + 3.0
    tau = _mod2pi(t1 + _PI) if t2 < 0 else _mod2pi(t1)
    omega = _mod2pi(tau - u + v - phi)
    return tau, omega


# Each base formula returns (ok, t, u, v) for the goal (x, y, φ) in normalised coordinates.
@numba.njit(cache=True)
def _lp_sp_lp(x, y, phi, sp, cp):  # 8.1
    xi = x - sp
    eta = y - 1.0 + cp
    u = math.hypot(xi, eta)
    t = math.atan2(eta, xi)
    if t >= -_ZERO:
        v = _mod2pi(phi - t)
        if v >= -_ZERO:
            return True, t, u, v
    return False, 0.0, 0.0, 0.0


@numba.njit(cache=True)
def _lp_sp_rp(x, y, phi, sp, cp):  # 8.2
    xi = x + sp
    eta = y - 1.0 - cp
    u1 = xi * xi + eta * eta
    if u1 >= 4.0:
        t1 = math.atan2(eta, xi)
        u = math.sqrt(u1 - 4.0)
        t = _mod2pi(t1 + math.atan2(2.0, u))
        v = _mod2pi(t - phi)
        if t >= -_ZERO and v >= -_ZERO:
            return True, t, u, v
    return False, 0.0, 0.0, 0.0


@numba.njit(cache=True)
def _lp_rm_l(x, y, phi, sp, cp):  # 8.3 / 8.4 (corrected)
    xi = x - sp
    eta = y - 1.0 + cp
    u1 = math.hypot(xi, eta)
    if u1 <= 4.0:
        theta = math.atan2(eta, xi)
        u = -2.0 * math.asin(0.25 * u1)
        t = _mod2pi(theta + 0.5 * u + _PI)
        v = _mod2pi(phi - t + u)
        if t >= -_ZERO and u <= _ZERO:
            return True, t, u, v
    return False, 0.0, 0.0, 0.0


@numba.njit(cache=True)
def _lp_rup_lum_rm(x, y, phi, sp, cp):  # 8.7
    xi = x + sp
    eta = y - 1.0 - cp
    rho = 0.25 * (2.0 + math.hypot(xi, eta))
    if rho <= 1.0:
        u = math.acos(rho)
        t, v = _tau_omega(u, -u, xi, eta, phi)
        if t >= -_ZERO and v <= _ZERO:
            return True, t, u, v
    return False, 0.0, 0.0, 0.0


@numba.njit(cache=True)
def _lp_rum_lum_rp(x, y, phi, sp, cp):  # 8.8
    xi = x + sp
    eta = y - 1.0 - cp
    rho = (20.0 - xi * xi - eta * eta) / 16.0
    if 0.0 <= rho <= 1.0:
        u = -math.acos(rho)
        if u >= -_HALF_PI:
            t, v = _tau_omega(u, u, xi, eta, phi)
            if t >= -_ZERO and v >= -_ZERO:
                return True, t, u, v
    return False, 0.0, 0.0, 0.0


@numba.njit(cache=True)
def _lp_rm_sm_lm(x, y, phi, sp, cp):  # 8.9
    xi = x - sp
    eta = y - 1.0 + cp
    rho = math.hypot(xi, eta)
    if rho >= 2.0:
        theta = math.atan2(eta, xi)
        r = math.sqrt(rho * rho - 4.0)
        u = 2.0 - r
        t = _mod2pi(theta + math.atan2(r, -2.0))
        v = _mod2pi(phi - _HALF_PI - t)
        if t >= -_ZERO and u <= _ZERO and v <= _ZERO:
            return True, t, u, v
    return False, 0.0, 0.0, 0.0


@numba.njit(cache=True)
def _lp_rm_sm_rm(x, y, phi, sp, cp):  # 8.10
    xi = x + sp
    eta = y - 1.0 - cp
    rho = math.hypot(-eta, xi)
    if rho >= 2.0:
        t = math.atan2(xi, -eta)
        u = 2.0 - rho
        v = _mod2pi(t + _HALF_PI - phi)
        if t >= -_ZERO and u <= _ZERO and v <= _ZERO:
            return True, t, u, v
    return False, 0.0, 0.0, 0.0


@numba.njit(cache=True)
def _lp_rm_s_lm_rp(x, y, phi, sp, cp):  # 8.11 (corrected)
    xi = x + sp
    eta = y - 1.0 - cp
    rho = math.hypot(xi, eta)
    if rho >= 2.0:
        u = 4.0 - math.sqrt(rho * rho - 4.0)
        if u <= _ZERO:
            t = _mod2pi(math.atan2((4.0 - u) * xi - 2.0 * eta, -2.0 * xi + (u - 4.0) * eta))
            v = _mod2pi(t - phi)
            if t >= -_ZERO and v >= -_ZERO:
                return True, t, u, v
    return False, 0.0, 0.0, 0.0


@numba.njit(cache=True)
def _base(formula, x, y, phi, sp, cp):
    if formula == 0:
        return _lp_sp_lp(x, y, phi, sp, cp)
    if formula == 1:
        return _lp_sp_rp(x, y, phi, sp, cp)
    if formula == 2:
        return _lp_rm_l(x, y, phi, sp, cp)
    if formula == 3:
        return _lp_rup_lum_rm(x, y, phi, sp, cp)
    if formula == 4:
        return _lp_rum_lum_rp(x, y, phi, sp, cp)
    if formula == 5:
        return _lp_rm_sm_lm(x, y, phi, sp, cp)
    if formula == 6:
        return _lp_rm_sm_rm(x, y, phi, sp, cp)
    return _lp_rm_s_lm_rp(x, y, phi, sp, cp)


# Families: (formula, backwards, segment types (0 = unused slot marker handled by count),
# length template). Template codes: 1 = t, 2 = u, 3 = v, 4 = −u, 5 = −π/2, 0 = unused.
# types: +1 L, 0 S, −1 R.
_FAMILIES = np.array(
    [
        # formula, backwards, n, types[5], template[5]
        [0, 0, 3, 1, 0, 1, 0, 0, 1, 2, 3, 0, 0],  # L S L
        [1, 0, 3, 1, 0, -1, 0, 0, 1, 2, 3, 0, 0],  # L S R
        [2, 0, 3, 1, -1, 1, 0, 0, 1, 2, 3, 0, 0],  # L R L
        [2, 1, 3, 1, -1, 1, 0, 0, 3, 2, 1, 0, 0],  # L R L backwards
        [3, 0, 4, 1, -1, 1, -1, 0, 1, 2, 4, 3, 0],  # L R L R (u, −u)
        [4, 0, 4, 1, -1, 1, -1, 0, 1, 2, 2, 3, 0],  # L R L R (u, u)
        [5, 0, 4, 1, -1, 0, 1, 0, 1, 5, 2, 3, 0],  # L R S L
        [6, 0, 4, 1, -1, 0, -1, 0, 1, 5, 2, 3, 0],  # L R S R
        [5, 1, 4, 1, 0, -1, 1, 0, 3, 2, 5, 1, 0],  # L S R L
        [6, 1, 4, -1, 0, -1, 1, 0, 3, 2, 5, 1, 0],  # R S R L
        [7, 0, 5, 1, -1, 0, 1, -1, 1, 5, 2, 5, 3],  # L R S L R
    ],
    dtype=np.int64,
)


@numba.njit(cache=True)
def _template_value(code, t, u, v):
    if code == 1:
        return t
    if code == 2:
        return u
    if code == 3:
        return v
    if code == 4:
        return -u
    if code == 5:
        return -_HALF_PI
    return 0.0


@numba.njit(cache=True)
def _enumerate(x, y, phi, families, types, lengths):
    """Fill ``types`` and ``lengths`` (capacity 48 × 5) with every feasible candidate word;
    return their number. Unused slots have length 0."""
    count = 0
    sphi = math.sin(phi)
    cphi = math.cos(phi)
    xb = x * cphi + y * sphi
    yb = x * sphi - y * cphi
    for f in range(families.shape[0]):
        formula = families[f, 0]
        backwards = families[f, 1]
        nseg = families[f, 2]
        bx = xb if backwards else x
        by = yb if backwards else y
        for k in range(4):
            sign = -1.0 if (k == 1 or k == 3) else 1.0
            reflect = k >= 2
            xx = -bx if sign < 0 else bx
            yy = -by if reflect else by
            pp = phi if k == 3 or k == 0 else -phi
            sp = sphi if k == 3 or k == 0 else -sphi
            ok, t, u, v = _base(formula, xx, yy, pp, sp, cphi)
            if not ok:
                continue
            for s in range(5):
                if s < nseg:
                    kind = families[f, 3 + s]
                    types[count, s] = -kind if reflect else kind
                    lengths[count, s] = sign * _template_value(families[f, 8 + s], t, u, v)
                else:
                    types[count, s] = 0
                    lengths[count, s] = 0.0
            count += 1
    return count


@numba.njit(cache=True)
def _min_length(x, y, phi, families):
    """Length of the shortest word for the normalised goal (no allocation; for heuristics)."""
    sphi = math.sin(phi)
    cphi = math.cos(phi)
    xb = x * cphi + y * sphi
    yb = x * sphi - y * cphi
    best = np.inf
    for f in range(families.shape[0]):
        formula = families[f, 0]
        bx = xb if families[f, 1] else x
        by = yb if families[f, 1] else y
        nseg = families[f, 2]
        for k in range(4):
            flip = k == 1 or k == 3
            same = k == 0 or k == 3
            ok, t, u, v = _base(
                formula,
                -bx if flip else bx,
                -by if k >= 2 else by,
                phi if same else -phi,
                sphi if same else -sphi,
                cphi,
            )
            if not ok:
                continue
            total = 0.0
            for s in range(nseg):
                total += abs(_template_value(families[f, 8 + s], t, u, v))
            best = min(best, total)
    return best


@numba.njit(cache=True)
def _best(x, y, phi, families):
    """Shortest word for the normalised goal: (types[5], lengths[5], total length)."""
    types = np.zeros((MAX_CANDIDATES, 5), dtype=np.int64)
    lengths = np.zeros((MAX_CANDIDATES, 5))
    n = _enumerate(x, y, phi, families, types, lengths)
    best = -1
    best_len = np.inf
    for i in range(n):
        total = 0.0
        for s in range(5):
            total += abs(lengths[i, s])
        if total < best_len:
            best_len = total
            best = i
    if best < 0:
        return np.zeros(5, dtype=np.int64), np.zeros(5), np.inf
    return types[best].copy(), lengths[best].copy(), best_len


@numba.njit(cache=True)
def _normalise(x0, y0, th0, x1, y1, th1, radius):
    dx = x1 - x0
    dy = y1 - y0
    c = math.cos(th0)
    s = math.sin(th0)
    return (c * dx + s * dy) / radius, (-s * dx + c * dy) / radius, th1 - th0


@numba.njit(cache=True)
def _rs_length(x0, y0, th0, x1, y1, th1, radius, families):
    """Reeds–Shepp length [m] between two poses (Numba, for Hybrid A*)."""
    x, y, phi = _normalise(x0, y0, th0, x1, y1, th1, radius)
    return _min_length(x, y, phi, families) * radius


def _poses(start: ArrayLike, goal: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    return (
        as_float_array("start", start, 3, min_ndim=1, max_ndim=1),
        as_float_array("goal", goal, 3, min_ndim=1, max_ndim=1),
    )


def _word(types: np.ndarray, lengths: np.ndarray) -> str:
    letters = {1: "L", 0: "S", -1: "R"}
    return "".join(
        f"{letters[int(k)]}{'+' if length >= 0 else '-'}"
        for k, length in zip(types, lengths, strict=True)
    )


def reeds_shepp_path(start: ArrayLike, goal: ArrayLike, turning_radius: float) -> CurvePath:
    """The shortest Reeds–Shepp path from ``start`` to ``goal``.

    Parameters
    ----------
    start : array_like
        Start pose ``(x, y, θ)`` [m, m, rad].
    goal : array_like
        Goal pose ``(x, y, θ)``.
    turning_radius : float
        Minimum turning radius R [m], > 0.

    Returns
    -------
    CurvePath
        Word, signed segment lengths [m] (negative = reverse), ``.length``, ``.sample(step)``.

    Examples
    --------
    >>> path = reeds_shepp_path((0, 0, 0), (-3, 0, 0), 1.0)
    >>> path.word, round(path.length, 9)
    ('S-', 3.0)
    """
    start, goal = _poses(start, goal)
    radius = positive("turning_radius", turning_radius, "m")
    x, y, phi = _normalise(*start, *goal, radius)
    types, lengths, _ = _best(x, y, phi, _FAMILIES)
    keep = lengths != 0.0
    if not keep.any():
        keep[0] = True
    types, lengths = types[keep], lengths[keep] * radius
    return CurvePath(start, radius, _word(types, lengths), types, lengths)


def reeds_shepp_candidates(
    start: ArrayLike, goal: ArrayLike, turning_radius: float
) -> list[CurvePath]:
    """Every feasible Reeds–Shepp word between two poses (not only the shortest).

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
    list of CurvePath
        One per (family, symmetry) that has a solution; every one ends at ``goal``.
    """
    start, goal = _poses(start, goal)
    radius = positive("turning_radius", turning_radius, "m")
    x, y, phi = _normalise(*start, *goal, radius)
    types = np.zeros((MAX_CANDIDATES, 5), dtype=np.int64)
    lengths = np.zeros((MAX_CANDIDATES, 5))
    n = _enumerate(x, y, phi, _FAMILIES, types, lengths)
    out = []
    for i in range(n):
        nseg = int(_used_segments(types[i], lengths[i]))
        t, ell = types[i, :nseg], lengths[i, :nseg] * radius
        out.append(CurvePath(start, radius, _word(t, ell), t, ell))
    return out


def _used_segments(types: np.ndarray, lengths: np.ndarray) -> int:
    nonzero = np.nonzero(lengths)[0]
    return int(nonzero[-1]) + 1 if len(nonzero) else 1


def reeds_shepp_length(start: ArrayLike, goal: ArrayLike, turning_radius: float) -> float:
    """Length [m] of the shortest Reeds–Shepp path between two poses.

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
    float
        The length; it is symmetric (start ↔ goal) and never exceeds the Dubins length.

    Examples
    --------
    >>> round(reeds_shepp_length((0, 0, 0), (0, 0, np.pi), 1.0), 6)
    3.141593
    """
    start, goal = _poses(start, goal)
    radius = positive("turning_radius", turning_radius, "m")
    return float(_rs_length(*start, *goal, radius, _FAMILIES))
