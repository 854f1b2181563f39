"""Escape from a tight spot by short moves to contact: the last resort of Hybrid A*.

In a parallel slot barely longer than the car (1.10 car lengths: 0.47 m to spare for a
4.69 m car) the way out is dozens of back-and-forth moves of centimetres to decimetres, each
driven at full lock or straight until the car nearly touches something, each turning the car
a little further out (the manoeuvre of Paromtchik and Laugier, "Motion generation and control
for parking an autonomous vehicle", ICRA 1996). Hybrid A*'s lattice cannot represent them:
its bins are coarser than the moves, so every short move lands in its parent's bin and is
pruned (the 1.10 slot exhausts the lattice after 24–76 expansions even at 0.05 m and 288
headings).

:func:`escape` searches those moves directly, on continuous poses: best first, from the tight
end, six moves per pose (forward and reverse, at curvature −1/R, 0 and +1/R), each driven until
contact, poses told apart at 0.01 m and 0.5°; the score is the straight-line distance left to
the other end, plus a tenth of the arc still to turn to its heading, plus 0.01 m per move.
It stops at the first pose from which a move runs a whole probe length (half the
footprint's length) without contact: one end of the car is out. The way out ends with that
free move driven, clear of the obstacles, and the lattice takes over from there
(:meth:`~wheelbase.planning.HybridAStar.plan`; where it fails, from the next way out). With
a whole footprint's length as the probe the car first stood perpendicular in the slot's mouth;
with half, it sweeps out at about 45°. The escape runs only where the lattice failed.

A move is driven by sphere tracing on the footprint's exact clearance (compiled, as the
lattice's checks): the clearance c of the footprint at a pose bounds how far it may still
drive and keep ``margin``, (c − margin)/(1 + ρ·|κ|), since no footprint point moves faster
than (1 + ρ·|κ|) per metre of arc (ρ the farthest footprint point from the reference point).
Where that reach is shorter than ``step`` the move goes on by samples ``step`` apart, each of
which must keep ``margin``, and it ends at the reach of the last one that did. The clearance
is to the obstacles and to the map's edge (leaving the map is a collision). So every sample
keeps ``margin``, and every pose between samples ``margin − step·(1 + ρ|κ|)/2``: with
``margin`` = step·(1 + ρ/R)/2, the collision margin of the lattice at that step, the moves are
collision-free along their whole length. Hybrid A* samples the escape four times finer than
its lattice (a smaller margin: the 1.10 slot leaves 0.235 m at either end of the car). With the
default lattice of the 1.10 slot behind a curb (``benchmarks/parking.py``) the way out takes
about 2,000 expansions and 1.5 s (it took 8.6 s with the moves checked sample by sample in
NumPy, and 153 moves at the lattice's own margin instead of about 30).
"""

from __future__ import annotations

import heapq
import math
import time

import numba
import numpy as np

from wheelbase._validate import as_float_array, integer, nonnegative, positive
from wheelbase.errors import ConfigError
from wheelbase.geometry_numba import wrap_angle_scalar
from wheelbase.limits import MAX_PRIMITIVE_SAMPLES
from wheelbase.planning.collision import _clearance_one, _scratch
from wheelbase.planning.footprint import Footprint
from wheelbase.planning.occupancy import OccupancyGrid
from wheelbase.planning.path import PlannedPath
from wheelbase.planning.world import PolygonWorld

__all__ = ["escape"]

_XY_KEY = 0.01
"""Poses closer than this [m] (and than :data:`_TH_KEY`) count as one."""
_TH_KEY = math.radians(0.5)
_MOVE_COST = 0.01
"""Score added per move [m]: of two poses equally far from the exit, the one reached in fewer
moves first."""
_HEADING_WEIGHT = 0.1
"""Weight of the arc R·|Δθ| still to turn to the other end's heading, in the score: fewer moves
for a longer search (measured with the moves sampled every 2 cm, before sphere tracing). Into
the 1.10 slot: 46 moves, 15.3 m in all, 1.1 s without it; 43, 15.0
m, 1.4 s with 0.1; 41, 14.2 m, 2.0 s with 0.2. (With a whole car length as the probe and no
heading term the car turned past perpendicular before it left: 50 moves, 27 m.)"""
_MIN_MOVE = 1e-3
"""Moves shorter than this [m] are not taken (they gain nothing)."""


def _arc(pose: np.ndarray, kappa: float, s: np.ndarray) -> np.ndarray:
    """Poses after signed distances ``s`` [m] along curvature ``kappa`` (dθ per signed metre):
    :func:`~wheelbase.geometry.se2_exp` for one pose and one curvature, without its checks and
    broadcasting (this runs some 30,000 times per escape)."""
    x, y, th = pose
    out = np.empty((s.size, 3))
    out[:, 2] = th + kappa * s
    if kappa == 0.0:
        out[:, 0] = x + s * math.cos(th)
        out[:, 1] = y + s * math.sin(th)
    else:
        out[:, 0] = x + (np.sin(out[:, 2]) - math.sin(th)) / kappa
        out[:, 1] = y - (np.cos(out[:, 2]) - math.cos(th)) / kappa
    return out


def escape(
    world: OccupancyGrid | PolygonWorld,
    footprint: Footprint,
    turning_radius: float,
    start: np.ndarray,
    toward: np.ndarray,
    *,
    step: float,
    margin: float,
    spacing: float | None = None,
    max_expansions: int = 20_000,
    time_limit: float = 5.0,
    exits: int = 1,
) -> tuple[list[PlannedPath], int]:
    """Short moves to contact that take a car-like robot out of a tight spot (module docstring).

    Parameters
    ----------
    world : OccupancyGrid or PolygonWorld
        The obstacles.
    footprint : Footprint
        The robot's outline about its reference point.
    turning_radius : float
        Smallest turning radius R [m], > 0.
    start : numpy.ndarray, shape (3,)
        The tight pose (x [m], y [m], θ [rad]).
    toward : numpy.ndarray, shape (3,)
        The other end of the plan: the moves go towards its position.
    step : float
        Spacing [m] of a move's clearance samples where it runs close to an obstacle.
    margin : float
        Clearance [m] every sample of a move keeps (between samples, ``margin`` less half a
        step's sweep: see the module docstring).
    spacing : float or None
        Spacing [m] of the returned samples (default ``step``).
    max_expansions : int
        Poses expanded at most.
    time_limit : float
        Seconds at most.
    exits : int
        Ways out to return, best first (the caller tries the lattice from each in turn).

    Returns
    -------
    paths : list of PlannedPath
        Up to ``exits`` escapes, each from ``start`` through the pose from which a whole probe
        length is free and then along that free move; ``[start]`` alone when ``start`` is
        such a pose; empty when none was found.
    expanded : int
        Poses expanded.
    """
    radius = positive("turning_radius", turning_radius, "m")
    step = positive("step", step, "m")
    spacing = step if spacing is None else positive("spacing", spacing, "m")
    margin = nonnegative("margin", margin, "m")
    time_limit = positive("time_limit", time_limit, "s")
    max_expansions = integer("max_expansions", max_expansions, minimum=1)
    exits = integer("exits", exits, minimum=1)
    start = as_float_array("start", start, 3, max_ndim=1)
    toward = as_float_array("toward", toward, 3, max_ndim=1)
    rho = footprint.max_radius
    probe = 0.5 * float(np.ptp(footprint.polygon[:, 0]))  # half the footprint's length
    for name, value in (("step", step), ("spacing", spacing)):
        if probe / value > MAX_PRIMITIVE_SAMPLES:
            raise ConfigError(
                f"{name} {value:.3g} m asks for more than {MAX_PRIMITIVE_SAMPLES:g} samples per "
                f"move of {probe:.3g} m; use a larger {name}"
            )
    actions = [(d, k / radius) for d in (1, -1) for k in (1, 0, -1)]
    goal_xy, goal_th = toward[:2], float(toward[2])

    def key(p: np.ndarray) -> tuple[int, int, int]:
        return (round(p[0] / _XY_KEY), round(p[1] / _XY_KEY), round(p[2] / _TH_KEY))

    # leaving the map is a collision, but the obstacle clearance does not see the map's edge
    box = np.array(getattr(world, "bounds", None) or world.extent, dtype=float)
    shape = (world._kernel_world, footprint.polygon, footprint.circles, footprint.circle_radius)
    scratch = _scratch(world._kernel_world, footprint.polygon)

    def move(p: np.ndarray, d: int, kappa: float) -> tuple[float, bool]:
        """Certified length [m] of the move from p (d·s along κ), and whether it ran the whole
        probe without contact."""
        return _move(*shape, box, *p, d, kappa, probe, margin, rho, step, *scratch)

    # nodes: (pose, parent, moves from the start, direction, curvature, length)
    nodes: list[tuple[np.ndarray, int, int, int, float, float]] = [(start, -1, 0, 1, 0.0, 0.0)]
    open_list = [(math.hypot(*(start[:2] - goal_xy)), 0)]
    seen = {key(start)}
    found: list[PlannedPath] = []
    expanded = 0
    deadline = time.perf_counter() + time_limit
    while open_list and expanded < max_expansions and time.perf_counter() < deadline:
        _, index = heapq.heappop(open_list)
        pose, depth = nodes[index][0], nodes[index][2]
        expanded += 1
        for d, kappa in actions:
            length, free = move(pose, d, kappa)
            if length < _MIN_MOVE:
                continue
            if free:  # out: from this pose a whole probe length is clear
                if index > 0:  # ... and driven: the way out ends clear of the obstacles
                    end = _arc(pose, kappa, np.array([d * length]))[0]
                    nodes.append((end, index, depth + 1, d, kappa, length))
                found.append(_path(nodes, len(nodes) - 1 if index > 0 else 0, spacing))
                if len(found) >= exits:
                    return found, expanded
                break
            end = _arc(pose, kappa, np.array([d * length]))[0]
            k = key(end)
            if k in seen:
                continue
            seen.add(k)
            nodes.append((end, index, depth + 1, d, kappa, length))
            score = (
                math.hypot(*(end[:2] - goal_xy))
                + _MOVE_COST * (depth + 1)
                + _HEADING_WEIGHT * radius * abs(wrap_angle_scalar(end[2] - goal_th))
            )
            heapq.heappush(open_list, (score, len(nodes) - 1))
    return found, expanded


def _path(nodes: list, last: int, step: float) -> PlannedPath:
    """The moves from the root to ``nodes[last]``, sampled at most ``step`` apart."""
    chain = []
    while last > 0:
        chain.append(last)
        last = nodes[last][1]
    chain.reverse()
    poses = [nodes[0][0][None, :]]
    directions, curvatures, arc = [1], [0.0], [0.0]
    for index in chain:
        _, parent, _, d, kappa, length = nodes[index]
        n = max(1, math.ceil(length / step))
        s = length * np.arange(1, n + 1) / n
        poses.append(_arc(nodes[parent][0], kappa, d * s))
        directions += [d] * n
        curvatures += [kappa] * n
        arc += list(arc[-1] + s)
    directions[0] = directions[1] if len(directions) > 1 else 1
    curvatures[0] = curvatures[1] if len(curvatures) > 1 else 0.0
    return PlannedPath(
        np.concatenate(poses), np.array(directions), np.array(curvatures), np.array(arc)
    )


@numba.njit(cache=True)
def _move(world, poly, circles, cradius, box, x, y, th, d, kappa, probe, margin, rho, step, wp,
          near):  # fmt: skip
    """Length [m] of the move from ``(x, y, th)`` driven ``d`` (+1/−1) along curvature
    ``kappa`` until contact, and whether it ran the whole ``probe`` length without it.

    At a pose of clearance c (to the obstacles and the map's edge ``box`` = (x0, x1, y0, y1))
    the footprint may drive (c − margin)/(1 + ρ|κ|) further and keep ``margin``, since none of
    its points moves faster: where that reach is at least ``step`` the move advances by it
    (sphere tracing), else by ``step`` to a sample that must keep ``margin`` itself. It stops
    at the reach of the last pose that kept it. So every sample keeps ``margin``, and every
    pose between two samples ``margin − step·(1 + ρ|κ|)/2``. ``wp``, ``near``: scratch of the
    exact clearance."""
    grow = 1.0 + rho * abs(kappa)
    s = 0.0
    clear = _edge_clearance(world, poly, circles, cradius, box, x, y, th, wp, near)
    while True:
        reach = (clear - margin) / grow
        ahead = s + (reach if reach >= step else step)
        if reach >= step and ahead >= probe:
            return probe, True
        ahead = min(ahead, probe)
        px, py, pth = _arc_one(x, y, th, kappa, d * ahead)
        there = _edge_clearance(world, poly, circles, cradius, box, px, py, pth, wp, near)
        if there < margin:
            return s + max(reach, 0.0), False
        if ahead >= probe:
            return probe, True
        s, clear = ahead, there


@numba.njit(cache=True)
def _edge_clearance(world, poly, circles, cradius, box, x, y, th, wp, near):
    """Clearance [m] of the footprint at a pose from the obstacles and the map's edge."""
    clear = _clearance_one(world, poly, circles, cradius, x, y, th, wp, near)
    c, s = math.cos(th), math.sin(th)
    for k in range(poly.shape[0]):  # the map's edge: the nearest point is a corner
        cx = x + c * poly[k, 0] - s * poly[k, 1]
        cy = y + s * poly[k, 0] + c * poly[k, 1]
        clear = min(clear, cx - box[0], box[1] - cx, cy - box[2], box[3] - cy)
    return max(clear, 0.0)


@numba.njit(cache=True, inline="always")
def _arc_one(x, y, th, kappa, s):
    """:func:`_arc` for one signed distance ``s``."""
    th1 = th + kappa * s
    if kappa == 0.0:
        return x + s * math.cos(th), y + s * math.sin(th), th1
    return (
        x + (math.sin(th1) - math.sin(th)) / kappa,
        y - (math.cos(th1) - math.cos(th)) / kappa,
        th1,
    )
