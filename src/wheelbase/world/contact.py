"""Exact contact and distance of robot footprints with agents and with each other.

A footprint is a convex polygon placed at a pose; an agent a disc. Contact is of closed sets:
touching counts. The polygon–disc distance is the centre's distance to the polygon less the
radius; the polygon–polygon distance is 0 when no edge normal separates them (separating
axes) and otherwise the least distance between their edges. The primitives are those of
:mod:`wheelbase.planning.collision`, shared with the planners' footprint checks. Contact with
the static obstacles is a :class:`~wheelbase.planning.PolygonWorld`'s (see
:meth:`World.collisions`).
"""

from __future__ import annotations

import math

import numba
import numpy as np

from wheelbase.planning.collision import (
    _convex_separated,
    _place_polygon,
    _point_polygon_distance,
    _seg_seg_dist2,
)

__all__ = ["contact_kernel", "polygon_distance"]


@numba.njit(cache=True)
def polygon_distance(a, b):
    """Distance [m] between convex counter-clockwise polygons ``a`` and ``b`` (0 in
    contact)."""
    na = a.shape[0]
    nb = b.shape[0]
    if not _convex_separated(a, na, b, nb):
        return 0.0
    best = np.inf
    for i in range(na):
        j = (i + 1) % na
        for k in range(nb):
            m = (k + 1) % nb
            best = min(best, _seg_seg_dist2(a[i, 0], a[i, 1], a[j, 0], a[j, 1], b[k, 0],
                                            b[k, 1], b[m, 0], b[m, 1]))  # fmt: skip
    return math.sqrt(best)


@numba.njit(cache=True)
def contact_kernel(poses, poly, world_index, self_index, agent_pos, agent_r, rob_pose,
                   rob_poly):  # fmt: skip
    """Per pose ``m``: the least distance [m] from footprint ``poly`` at ``poses[m]`` to an
    agent disc of world ``world_index[m]``, that agent (−1: none), the least distance to
    another robot's footprint ``rob_poly`` (never robot ``self_index[m]``) and that robot."""
    n = poses.shape[0]
    agent_d = np.full(n, np.inf)
    agent_i = np.full(n, -1, np.int64)
    robot_d = np.full(n, np.inf)
    robot_i = np.full(n, -1, np.int64)
    wp = np.empty_like(poly)
    other = np.empty_like(rob_poly)
    for m in range(n):
        b = world_index[m]
        _place_polygon(poly, poses[m, 0], poses[m, 1], poses[m, 2], wp)
        for a in range(agent_pos.shape[1]):
            d = _point_polygon_distance(wp, agent_pos[b, a, 0], agent_pos[b, a, 1])
            d = max(d - agent_r[a], 0.0)
            if d < agent_d[m]:
                agent_d[m] = d
                agent_i[m] = a
        for k in range(rob_pose.shape[1]):
            if k == self_index[m]:
                continue
            _place_polygon(rob_poly, rob_pose[b, k, 0], rob_pose[b, k, 1], rob_pose[b, k, 2],
                           other)  # fmt: skip
            d = polygon_distance(wp, other)
            if d < robot_d[m]:
                robot_d[m] = d
                robot_i[m] = k
    return agent_d, agent_i, robot_d, robot_i
