"""The social force model's forces (Helbing and Molnár 1995; Helbing, Farkas and Vicsek 2000).

The kernels return forces per unit mass [m/s²] with the parameters packed by
:meth:`SocialForce.packed` (A/m, B, k/m, κ/m); :class:`~wheelbase.world.SocialForce`
documents the model, its equations and the source of every value.
"""

from __future__ import annotations

import math

import numba
import numpy as np
from numpy.typing import ArrayLike

from wheelbase._validate import as_float_array
from wheelbase.errors import InputError

__all__ = ["pair_force", "social_force_acceleration", "wall_force"]

# indices into SocialForce.packed()
INV_TAU, A, B, K, KAPPA, FACTOR, CUTOFF, SUBSTEP = range(8)


@numba.njit(cache=True)
def pair_force(px, py, vx, vy, ra, qx, qy, wx, wy, rb, a, b, k, kappa, cutoff):
    """Force per unit mass [m/s²] on agent α at ``(px, py)`` (velocity ``(vx, vy)``, radius
    ``ra``) from β at ``(qx, qy)`` (``(wx, wy)``, ``rb``): HFV 2000, eq. 2; zero beyond a gap
    of ``cutoff`` [m]."""
    dx = px - qx
    dy = py - qy
    d2 = dx * dx + dy * dy
    rr = ra + rb
    if d2 > (rr + cutoff) ** 2:  # (no square root for the many far pairs)
        return 0.0, 0.0
    d = math.sqrt(d2)
    if d > 0.0:
        nx = dx / d
        ny = dy / d
    else:
        nx, ny = 1.0, 0.0
    overlap = rr - d
    contact = max(overlap, 0.0)
    push = a * math.exp(min(overlap / b, 50.0)) + k * contact
    fx = push * nx
    fy = push * ny
    if contact > 0.0:
        tx = -ny
        ty = nx
        slip = (wx - vx) * tx + (wy - vy) * ty
        fx += kappa * contact * slip * tx
        fy += kappa * contact * slip * ty
    return fx, fy


@numba.njit(cache=True)
def wall_force(vx, vy, r, d, nx, ny, a, b, k, kappa, cutoff):
    """Force per unit mass [m/s²] of a wall point at signed distance ``d`` [m] in the
    direction ``−n`` (n: unit, from the wall to the agent) on an agent of radius ``r`` and
    velocity ``(vx, vy)``: HFV 2000, eq. 3; zero beyond a gap of ``cutoff``."""
    if d - r > cutoff:
        return 0.0, 0.0
    overlap = r - d
    contact = max(overlap, 0.0)
    push = a * math.exp(min(overlap / b, 50.0)) + k * contact
    tx = -ny
    ty = nx
    along = vx * tx + vy * ty
    return (push * nx - kappa * contact * along * tx, push * ny - kappa * contact * along * ty)


@numba.njit(cache=True, inline="always")
def driving_force(px, py, vx, vy, gx, gy, v0, inv_tau):
    """(v⁰ e − v)/τ [m/s²] with e the unit vector to the goal (HFV 2000, eq. 1)."""
    ex = gx - px
    ey = gy - py
    dist = math.hypot(ex, ey)
    if dist > 0.0:
        ex /= dist
        ey /= dist
    return (v0 * ex - vx) * inv_tau, (v0 * ey - vy) * inv_tau


@numba.njit(cache=True)
def _free_accelerations(pos, vel, goal, radius, speed, sf):
    out = np.empty_like(pos)
    for i in range(pos.shape[0]):
        ax, ay = driving_force(pos[i, 0], pos[i, 1], vel[i, 0], vel[i, 1], goal[i, 0],
                               goal[i, 1], speed[i], sf[INV_TAU])  # fmt: skip
        for j in range(pos.shape[0]):
            if j != i:
                fx, fy = pair_force(pos[i, 0], pos[i, 1], vel[i, 0], vel[i, 1], radius[i],
                                    pos[j, 0], pos[j, 1], vel[j, 0], vel[j, 1], radius[j],
                                    sf[A], sf[B], sf[K], sf[KAPPA], sf[CUTOFF])  # fmt: skip
                ax += fx
                ay += fy
        out[i, 0] = ax
        out[i, 1] = ay
    return out


def social_force_acceleration(
    params,
    position: ArrayLike,
    velocity: ArrayLike,
    goal: ArrayLike,
    radius: ArrayLike,
    speed: ArrayLike,
) -> np.ndarray:
    """Accelerations [m/s²] of agents in free space (no walls): driving plus pair forces.

    Parameters
    ----------
    params : SocialForce
        The model's parameters.
    position, velocity, goal : array_like
        ``(N, 2)`` [m], [m/s], [m].
    radius, speed : array_like
        ``(N,)`` radii [m] and preferred speeds v⁰ [m/s].

    Returns
    -------
    numpy.ndarray
        ``(N, 2)``.

    Examples
    --------
    >>> from wheelbase.world import SocialForce
    >>> acc = social_force_acceleration(SocialForce(), [[0, 0]], [[0, 0]], [[1, 0]], [0.3],
    ...                                 [0.6])
    >>> acc.round(6).tolist()  # v⁰/τ towards the goal
    [[1.2, 0.0]]
    """
    pos = as_float_array("position", position, 2, min_ndim=2, max_ndim=2)
    n = len(pos)
    arrays = [as_float_array(name, value, 2, min_ndim=2, max_ndim=2)
              for name, value in (("velocity", velocity), ("goal", goal))]  # fmt: skip
    scalars = [as_float_array(name, value, min_ndim=1, max_ndim=1)
               for name, value in (("radius", radius), ("speed", speed))]  # fmt: skip
    if any(len(x) != n for x in arrays + scalars):
        raise InputError("position, velocity, goal, radius and speed need one row per agent")
    return _free_accelerations(pos, *arrays, *scalars, params.packed())
