"""ORCA: the half-planes of reciprocal collision avoidance and the 2-D linear program.

After J. van den Berg, S. J. Guy, M. Lin and D. Manocha, "Reciprocal n-body collision
avoidance", ISRR 2011 (written here from the paper; :class:`~wheelbase.world.ORCA` documents
the parameters). A half-plane is ``n · v >= c`` with a unit normal n. The program

    minimise |v − v_pref|  subject to  |v| <= v_max  and  n_j · v >= c_j  (every j)

is solved by the incremental algorithm of the paper's section V-B (de Berg et al.'s
randomised LP, in the given order): the optimum so far is kept while it satisfies the next
half-plane; otherwise the new optimum lies on that half-plane's line, a 1-D program over an
interval cut by the earlier ones and the disc. When the program is infeasible (dense crowds),
section V-C's 3-D program is solved the same way: the velocity minimising the largest
penetration ``c_j − n_j · v`` of the agents' half-planes while the first ``hard`` half-planes
(walls and obstacles) still hold.
"""

from __future__ import annotations

import math

import numba
import numpy as np
from numpy.typing import ArrayLike

from wheelbase._validate import as_float_array, integer, positive
from wheelbase.errors import InputError

__all__ = ["orca_half_plane", "solve_velocity_lp"]

_EPS = 1e-12


@numba.njit(cache=True)
def _lp1(nx, ny, c, j, radius, ox, oy, direction_opt):
    """Optimum on the line of half-plane ``j`` subject to half-planes ``0..j−1`` and the
    disc: ``(feasible, vx, vy)``. The line is ``c_j n_j + t d`` with d = (−n_y, n_x)."""
    cj = c[j]
    disc = radius * radius - cj * cj
    if disc < 0.0:
        return False, 0.0, 0.0
    half = math.sqrt(disc)
    dx = -ny[j]
    dy = nx[j]
    px = cj * nx[j]
    py = cj * ny[j]
    tmin = -half
    tmax = half
    for i in range(j):
        den = nx[i] * dx + ny[i] * dy
        num = c[i] - (nx[i] * px + ny[i] * py)
        if abs(den) <= _EPS:
            if num > _EPS:
                return False, 0.0, 0.0  # parallel, and the whole line violates i
            continue
        t = num / den
        if den > 0.0:
            tmin = max(tmin, t)
        else:
            tmax = min(tmax, t)
        if tmin > tmax:
            return False, 0.0, 0.0
    if direction_opt:
        t = tmax if ox * dx + oy * dy > 0.0 else tmin
    else:
        t = min(max(ox * dx + oy * dy, tmin), tmax)
    return True, px + t * dx, py + t * dy


@numba.njit(cache=True)
def _lp2(nx, ny, c, n, radius, ox, oy, direction_opt, vx, vy):
    """The incremental 2-D program from ``(vx, vy)`` (the caller's fallback): returns
    ``(count, vx, vy)`` with count = n when feasible, else the first half-plane that made it
    infeasible (the velocity is then the optimum of the half-planes before it)."""
    if direction_opt:
        vx = ox * radius
        vy = oy * radius
    else:
        norm = math.hypot(ox, oy)
        if norm > radius:
            vx = ox / norm * radius
            vy = oy / norm * radius
        else:
            vx = ox
            vy = oy
    for j in range(n):
        if nx[j] * vx + ny[j] * vy < c[j]:
            ok, ax, ay = _lp1(nx, ny, c, j, radius, ox, oy, direction_opt)
            if not ok:
                return j, vx, vy
            vx = ax
            vy = ay
    return n, vx, vy


@numba.njit(cache=True)
def _lp3(nx, ny, c, n, hard, begin, radius, vx, vy, pnx, pny, pc):
    """Least penetration (section V-C): for each half-plane i >= ``begin`` violated by more
    than the largest penetration so far, the velocity that pushes furthest into i subject to
    the hard half-planes and "j penetrated no more than i" for the soft j < i."""
    dist = 0.0
    for i in range(begin, n):
        if c[i] - (nx[i] * vx + ny[i] * vy) <= dist:
            continue
        m = 0
        for k in range(hard):
            pnx[m] = nx[k]
            pny[m] = ny[k]
            pc[m] = c[k]
            m += 1
        for j in range(hard, i):
            # c_j − n_j·v <= c_i − n_i·v  <=>  (n_j − n_i)·v >= c_j − c_i
            ax = nx[j] - nx[i]
            ay = ny[j] - ny[i]
            norm = math.hypot(ax, ay)
            if norm < 1e-9:
                continue  # same normal: one of the two is always the more penetrated
            pnx[m] = ax / norm
            pny[m] = ay / norm
            pc[m] = (c[j] - c[i]) / norm
            m += 1
        count, ax, ay = _lp2(pnx, pny, pc, m, radius, nx[i], ny[i], True, vx, vy)
        if count == m:  # (rounding can make it fail: then keep the velocity we had)
            vx = ax
            vy = ay
        dist = c[i] - (nx[i] * vx + ny[i] * vy)
    return vx, vy


@numba.njit(cache=True)
def solve_lp(nx, ny, c, n, hard, radius, ox, oy, pnx, pny, pc):
    """The velocity of the program (module docstring) for the first ``n`` half-planes, the
    first ``hard`` of them kept when infeasible; ``pnx, pny, pc``: scratch of length n."""
    count, vx, vy = _lp2(nx, ny, c, n, radius, ox, oy, False, 0.0, 0.0)
    if count < n:
        vx, vy = _lp3(nx, ny, c, n, hard, count, radius, vx, vy, pnx, pny, pc)
    return vx, vy


@numba.njit(cache=True)
def half_plane(px, py, vx, vy, ra, qx, qy, wx, wy, rb, tau, dt, responsibility):
    """ORCA^τ_A|B (paper, section IV) for agent A at ``(px, py)`` with velocity ``(vx, vy)``
    and radius ``ra`` against B at ``(qx, qy)``, ``(wx, wy)``, ``rb``: ``(n_x, n_y, c)`` of
    the half-plane ``n · v >= c``. When the discs overlap already, the velocity obstacle of
    the next step (τ = ``dt``) is used, which pushes them apart."""
    rx = qx - px
    ry = qy - py
    ux_rel = vx - wx
    uy_rel = vy - wy
    dist2 = rx * rx + ry * ry
    rr = ra + rb
    if dist2 > rr * rr:
        # w: from the centre of the cut-off disc (p_B − p_A)/τ to the relative velocity
        ex = ux_rel - rx / tau
        ey = uy_rel - ry / tau
        elen2 = ex * ex + ey * ey
        dot = ex * rx + ey * ry
        if dot < 0.0 and dot * dot > rr * rr * elen2:
            # nearest boundary point on the cut-off circle
            elen = math.sqrt(elen2)
            nxx = ex / elen
            nyy = ey / elen
            ux = (rr / tau - elen) * nxx
            uy = (rr / tau - elen) * nyy
        else:
            # nearest boundary point on a leg of the cone
            leg = math.sqrt(dist2 - rr * rr)
            if rx * ey - ry * ex > 0.0:  # the relative velocity is left of p_B − p_A
                dx = (rx * leg - ry * rr) / dist2
                dy = (rx * rr + ry * leg) / dist2
            else:
                dx = -(rx * leg + ry * rr) / dist2
                dy = -(-rx * rr + ry * leg) / dist2
            proj = ux_rel * dx + uy_rel * dy
            ux = proj * dx - ux_rel
            uy = proj * dy - uy_rel
            nxx = -dy  # the free side is left of the leg's direction (either leg)
            nyy = dx
    else:
        ex = ux_rel - rx / dt
        ey = uy_rel - ry / dt
        elen = math.hypot(ex, ey)
        if elen == 0.0:
            dist = math.sqrt(dist2)
            if dist > 0.0:
                ex, ey, elen = -rx / dist, -ry / dist, 1.0
            else:
                ex, ey, elen = 1.0, 0.0, 1.0
        nxx = ex / elen
        nyy = ey / elen
        ux = (rr / dt - elen) * nxx
        uy = (rr / dt - elen) * nyy
    c = nxx * (vx + responsibility * ux) + nyy * (vy + responsibility * uy)
    return nxx, nyy, c


def orca_half_plane(
    a: ArrayLike, b: ArrayLike, tau: float, dt: float, responsibility: float = 0.5
) -> tuple[np.ndarray, float]:
    """The half-plane ORCA^τ_A|B of agent A induced by B (van den Berg et al. 2011, eq. 5).

    Parameters
    ----------
    a, b : array_like
        ``(x [m], y [m], vx [m/s], vy [m/s], radius [m])`` of each agent.
    tau : float
        Time horizon τ [s], > 0.
    dt : float
        Step [s], > 0 (the horizon when they overlap already).
    responsibility : float
        Share of the avoidance A takes: ½ between two ORCA agents, 1 against one that does
        not reciprocate.

    Returns
    -------
    normal : numpy.ndarray
        Unit normal n (2,).
    offset : float
        c of ``n · v >= c`` [m/s].

    Examples
    --------
    >>> n, c = orca_half_plane([0, 0, 1, 0, 0.5], [4, 0, -1, 0, 0.5], tau=2.0, dt=0.1)
    >>> bool(n @ [1.0, 0.0] < c)  # A's current velocity heads into B
    True
    """
    a = as_float_array("a", a, 5, min_ndim=1, max_ndim=1)
    b = as_float_array("b", b, 5, min_ndim=1, max_ndim=1)
    tau = positive("tau", tau, "s")
    dt = positive("dt", dt, "s")
    nx, ny, c = half_plane(a[0], a[1], a[2], a[3], a[4], b[0], b[1], b[2], b[3], b[4], tau, dt,
                           float(responsibility))  # fmt: skip
    return np.array([nx, ny]), float(c)


def solve_velocity_lp(
    normals: ArrayLike,
    offsets: ArrayLike,
    preferred: ArrayLike,
    max_speed: float,
    hard: int = 0,
) -> np.ndarray:
    """The velocity closest to ``preferred`` with ``|v| <= max_speed`` in every half-plane
    ``normals[j] · v >= offsets[j]`` (module docstring); when they have no common point, the
    one that least penetrates the half-planes after the first ``hard``.

    Parameters
    ----------
    normals : array_like
        Unit normals ``(n, 2)``.
    offsets : array_like
        Offsets ``(n,)`` [m/s].
    preferred : array_like
        Preferred velocity (2,) [m/s].
    max_speed : float
        Radius of the velocity disc [m/s], > 0.
    hard : int
        How many leading half-planes are never relaxed.

    Returns
    -------
    numpy.ndarray
        The velocity (2,) [m/s].

    Examples
    --------
    >>> solve_velocity_lp([[1.0, 0.0]], [0.5], [0.0, 1.0], 2.0).round(6).tolist()
    [0.5, 1.0]
    """
    normals = as_float_array("normals", normals, 2, min_ndim=2, max_ndim=2)
    offsets = as_float_array("offsets", offsets, min_ndim=1, max_ndim=1)
    if len(offsets) != len(normals):
        raise InputError(f"offsets must have one entry per normal ({len(offsets)} for "
                         f"{len(normals)})")  # fmt: skip
    norm = np.hypot(normals[:, 0], normals[:, 1])
    if np.any(np.abs(norm - 1.0) > 1e-9):
        raise InputError("normals must be unit vectors")
    preferred = as_float_array("preferred", preferred, 2, min_ndim=1, max_ndim=1)
    radius = positive("max_speed", max_speed, "m/s")
    hard = integer("hard", hard, 0, len(offsets))
    n = len(offsets)
    nx, ny = np.ascontiguousarray(normals[:, 0]), np.ascontiguousarray(normals[:, 1])
    scratch = np.empty((3, n))
    vx, vy = solve_lp(nx, ny, np.ascontiguousarray(offsets), n, hard, radius, preferred[0],
                      preferred[1], scratch[0], scratch[1], scratch[2])  # fmt: skip
    return np.array([vx, vy])
