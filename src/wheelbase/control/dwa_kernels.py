"""Scoring of the dynamic window's trajectories (private helpers of
:class:`~wheelbase.control.DWA`): one compiled kernel, parallel over the sampled velocities, and
its NumPy twin.

Each sample (v, ω) is held for the simulated time (Fox, Burgard & Thrun 1997: the robot drives a
circular arc) and the pose after step j (τ_j = (j + 1)·dt) is the exact arc

    x_j = x_0 + v·τ_j·sinc(ω·τ_j/2)·cos(θ_0 + ω·τ_j/2),
    y_j = y_0 + v·τ_j·sinc(ω·τ_j/2)·sin(θ_0 + ω·τ_j/2),    θ_j = θ_0 + ω·τ_j,

sinc(u) = sin u / u (the chord of the arc, exact for any ω, no branch at ω = 0). With DWB's
standard generator a sample is a target the velocity ramps to at the acceleration limits
(:func:`ramp_profile`), and each step is the exact arc of that step's velocity. The kernel
returns the raw critic values per sample, in the order of :data:`SCORES`, and whether the
trajectory collides; :class:`~wheelbase.control.DWA` weighs them.
"""

from __future__ import annotations

import heapq
import math

import numba
import numpy as np

from wheelbase.control.footprint_field import clearance_at
from wheelbase.control.obstacle_critics import (
    HOLD_STEP,
    PerceptionArrays,
    costmap_cost_at,
    costmap_costs,
    track_cost_at,
    track_costs,
    track_terms,
)
from wheelbase.geometry import wrap_angle
from wheelbase.geometry_numba import wrap_angle_scalar

__all__ = [
    "SCORES",
    "arc_poses",
    "dwa_kernel",
    "dwa_scores_numpy",
    "goal_distance_field",
    "profile_poses",
    "ramp_profile",
]

SCORES = (
    "path_dist",
    "goal_dist",
    "path_align",
    "goal_align",
    "costmap",
    "obstacle",
    "dynamic_obstacle",
    "rotate_to_goal",
)
"""Raw critic values per trajectory: distance [m] from its end to the path window, and to the
local goal; the same from the point ``forward_point_distance`` ahead of its end; the means over
its steps of the costmap cost (0–1), of the map's (r_infl − clearance)² [m²] and of the tracks'
Σ gap² [m²]; |wrap(θ_end − θ_goal)| [rad]."""


@numba.njit(cache=True)
def _wavefront(cost, start_row, start_col, res, out):
    """Distances [m] through the passable cells (cost < 253) from one cell, 8-connected
    (Dijkstra); −1 where unreachable."""
    rows, cols = cost.shape
    out[:] = -1.0
    out[start_row, start_col] = 0.0
    heap = [(0.0, start_row * cols + start_col)]
    diagonal = math.sqrt(2.0) * res
    while len(heap) > 0:
        d, index = heapq.heappop(heap)
        row, col = index // cols, index % cols
        if d > out[row, col]:
            continue
        for dr in range(-1, 2):
            for dc in range(-1, 2):
                if dr == 0 and dc == 0:
                    continue
                r, c = row + dr, col + dc
                if r < 0 or r >= rows or c < 0 or c >= cols or cost[r, c] >= 253:
                    continue
                step = diagonal if dr != 0 and dc != 0 else res
                nd = d + step
                if out[r, c] < 0.0 or nd < out[r, c]:
                    out[r, c] = nd
                    heapq.heappush(heap, (nd, r * cols + c))


def goal_distance_field(
    cost: np.ndarray, geometry: np.ndarray, goal: np.ndarray, reach: float
) -> tuple[np.ndarray, np.ndarray]:
    """DWB's goal map grid: distance [m] from the local goal through the costmap's passable
    cells (cost < 253; 8-connected Dijkstra), on the part of the costmap within ``reach`` of
    the robot, −1 where unreachable.

    Parameters
    ----------
    cost : numpy.ndarray of uint8, shape (rows, cols)
        The costmap.
    geometry : numpy.ndarray, shape (5,)
        Its geometry relative to the robot
        (:attr:`~wheelbase.control.obstacle_critics.PerceptionArrays.geometry`).
    goal : numpy.ndarray, shape (2,)
        The local goal [m] relative to the robot (a cell of the cropped grid).
    reach : float
        Half side [m] of the square around the robot that is searched.

    Returns
    -------
    field : numpy.ndarray, shape (r, c)
        Distances [m], −1 unreachable.
    field_geometry : numpy.ndarray, shape (4,)
        (x0, y0 [m] relative to the robot, resolution [m], 1).
    """
    x0, y0, res = geometry[0], geometry[1], geometry[2]
    rows, cols = cost.shape
    lo_col = max(0, math.floor((-reach - x0) / res))
    hi_col = min(cols, math.floor((reach - x0) / res) + 1)
    lo_row = max(0, math.floor((-reach - y0) / res))
    hi_row = min(rows, math.floor((reach - y0) / res) + 1)
    crop = np.ascontiguousarray(cost[lo_row:hi_row, lo_col:hi_col])
    fgeo = np.array([x0 + lo_col * res, y0 + lo_row * res, res, 1.0])
    field = np.full(crop.shape if crop.size else (1, 1), -1.0)
    col = math.floor((goal[0] - fgeo[0]) / res)
    row = math.floor((goal[1] - fgeo[1]) / res)
    if crop.size and 0 <= row < crop.shape[0] and 0 <= col < crop.shape[1]:
        _wavefront(crop, row, col, res, field)
    else:
        fgeo[3] = 0.0  # the goal is off the costmap: straight distances
    return field, fgeo


@numba.njit(cache=True, inline="always")
def _goal_distance(x, y, goal, field, fgeo):
    """Distance [m] from (x, y) to the local goal: through the goal field where it covers the
    point (−1: unreachable), else straight."""
    if fgeo[3] > 0.5:
        col = math.floor((x - fgeo[0]) / fgeo[2])
        row = math.floor((y - fgeo[1]) / fgeo[2])
        if 0 <= row < field.shape[0] and 0 <= col < field.shape[1]:
            return field[row, col]
    return math.hypot(x - goal[0], y - goal[1])


@numba.njit(cache=True, inline="always")
def _sinc(u):
    if abs(u) < 1.0e-4:
        return 1.0 - u * u / 6.0
    return math.sin(u) / u


@numba.njit(cache=True, inline="always")
def _nearest_distance(x, y, window):
    best = 1.0e300
    for j in range(window.shape[0]):
        dx, dy = x - window[j, 0], y - window[j, 1]
        best = min(best, dx * dx + dy * dy)
    return math.sqrt(best)


@numba.njit(cache=True, parallel=True)
def dwa_kernel(
    theta, samples, dt, steps, window, goal, field, fgeo, forward, end, direction, df, mp, circles,
    map_relief, inflation, cost_map, near, cgeo, polygon, tracks, relief, disks, order, counts,
    dynamic_inflation, ramped, profile, scores, first_contact,
):  # fmt: skip
    """Score every sample (see the module docstring); positions relative to the robot.

    ``goal`` = (x, y, heading) of the local goal, ``field, fgeo`` its distance field
    (:func:`goal_distance_field`; −1 scores an unreachable end), ``forward`` the forward-point
    distance [m] (cut to the distance to the section's end ``end`` = (x, y)),
    ``direction`` ±1 the travel direction of the path section; ``df, mp, circles, map_relief``
    the static map (:class:`~wheelbase.control.footprint_field.FootprintField`); ``cost_map`` …
    ``counts`` the fields of :class:`~wheelbase.control.obstacle_critics.PerceptionArrays`.
    Writes ``scores`` (S, 8) and ``first_contact`` (S,): the first step whose pose collides,
    ``steps`` where none does."""
    x0, y0, res, has_map = mp[0], mp[1], mp[2], mp[3] > 0.5
    margin = math.sqrt(2.0) * res + map_relief
    inv_res = 1.0 / res
    has_costmap, has_tracks = cgeo[3] > 0.5, tracks.shape[1] > 0
    terms = track_terms(tracks, disks, dynamic_inflation)
    hold_weight = HOLD_STEP / dt  # a held check stands for HOLD_STEP / dt steps
    for i in numba.prange(samples.shape[0]):
        v, w = samples[i, 0], samples[i, 1]
        x, y, th = 0.0, 0.0, theta
        soft_cost, soft_map, soft_dyn = 0.0, 0.0, 0.0
        hit = False
        first = steps
        for j in range(steps):
            if ramped:  # this step's velocity of the ramp, an exact arc over the step
                v, w = profile[i, j, 0], profile[i, j, 1]
                half = 0.5 * w * dt
                chord = v * dt * _sinc(half)
                x += chord * math.cos(th + half)
                y += chord * math.sin(th + half)
                th += w * dt
            else:  # the arc of the held velocity, in closed form
                tau = (j + 1) * dt
                half = 0.5 * w * tau
                chord = v * tau * _sinc(half)
                x = chord * math.cos(theta + half)
                y = chord * math.sin(theta + half)
                th = theta + w * tau
            c, s = math.cos(th), math.sin(th)
            if has_map:
                clearance, bad = clearance_at(x, y, c, s, df, x0, y0, inv_res, circles, margin)
                hit = hit or bad
                if 0.0 < clearance < inflation:
                    gap = inflation - clearance
                    soft_map += gap * gap
            if has_costmap:
                soft, bad = costmap_cost_at(x, y, c, s, cost_map, near, cgeo, polygon)
                soft_cost += soft
                hit = hit or bad
            if has_tracks:
                soft, bad = track_cost_at(x, y, c, s, j, tracks, relief, disks, dynamic_inflation,
                                          steps, terms, order, counts)  # fmt: skip
                soft_dyn += soft
                hit = hit or bad
            if hit and first == steps:
                first = j
        if has_tracks:  # the final pose held (obstacle_critics: a braking ICS test)
            for j in range(steps, tracks.shape[0]):
                soft, bad = track_cost_at(x, y, c, s, j, tracks, relief, disks, dynamic_inflation,
                                          steps, terms, order, counts)  # fmt: skip
                soft_dyn += hold_weight * soft
                hit = hit or bad
        # the forward point, never past the section's end (it would pull the end short of it)
        ahead = min(forward, math.hypot(x - end[0], y - end[1]))
        fx = x + direction * ahead * math.cos(th)
        fy = y + direction * ahead * math.sin(th)
        scores[i, 0] = _nearest_distance(x, y, window)
        scores[i, 1] = _goal_distance(x, y, goal, field, fgeo)
        scores[i, 2] = _nearest_distance(fx, fy, window)
        to_goal = _goal_distance(fx, fy, goal, field, fgeo)
        if to_goal < 0.0:  # the forward point in an obstacle: the end's distance + the step
            to_goal = scores[i, 1] + ahead if scores[i, 1] >= 0.0 else -1.0
        scores[i, 3] = to_goal
        scores[i, 4] = soft_cost / steps
        scores[i, 5] = soft_map / steps
        scores[i, 6] = soft_dyn / steps
        turn = wrap_angle_scalar(th - goal[2])
        scores[i, 7] = abs(turn)
        first_contact[i] = first  # the held checks are never lethal


def _sinc_array(u: np.ndarray) -> np.ndarray:
    """sin u / u elementwise, as the kernel's ``_sinc`` (its series below 1e-4)."""
    small = np.abs(u) < 1.0e-4
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(small, 1.0 - u * u / 6.0, np.sin(u) / np.where(small, 1.0, u))


def ramp_profile(
    start: np.ndarray, samples: np.ndarray, rates: np.ndarray, dt: float, steps: int
) -> np.ndarray:
    """Velocities ``(S, steps, 2)`` at steps 1..steps of trajectories that ramp from the
    current velocity towards each sample at the acceleration limits (DWB's
    StandardTrajectoryGenerator, ``computeNewVelocity``): v_k = v_c + clip(v* − v_c,
    −a_down·t_k, a_up·t_k), and ω_k alike with ±α·t_k.

    Parameters
    ----------
    start : numpy.ndarray, shape (2,)
        (v_c [m/s], ω_c [rad/s]), the current velocity.
    samples : numpy.ndarray, shape (S, 2)
        The target velocities (v*, ω*).
    rates : numpy.ndarray, shape (3,)
        (a_up, a_down [m/s²], α [rad/s²]): how fast v may grow and fall, and ω change.
    dt : float
        Step [s].
    steps : int
        Number of steps.

    Returns
    -------
    numpy.ndarray
    """
    tau = dt * np.arange(1, steps + 1)
    change = samples[:, None, :] - start
    v = start[0] + np.clip(change[..., 0], -rates[1] * tau, rates[0] * tau)
    w = start[1] + np.clip(change[..., 1], -rates[2] * tau, rates[2] * tau)
    return np.ascontiguousarray(np.stack([v, w], -1))


def profile_poses(theta: float, profile: np.ndarray, dt: float) -> np.ndarray:
    """Poses ``(S, steps, 3)`` after steps 1..steps from (0, 0, θ) of velocity profiles
    ``(S, steps, 2)`` (:func:`ramp_profile`), each step an exact arc of its velocity (heading
    not wrapped).

    Parameters
    ----------
    theta : float
        Start heading [rad].
    profile : numpy.ndarray, shape (S, steps, 2)
        (v [m/s], ω [rad/s]) over each step.
    dt : float
        Step [s].

    Returns
    -------
    numpy.ndarray
    """
    n, steps = profile.shape[:2]
    poses = np.empty((n, steps, 3))
    x, y, th = np.zeros(n), np.zeros(n), np.full(n, float(theta))
    for k in range(steps):
        v, w = profile[:, k, 0], profile[:, k, 1]
        half = 0.5 * w * dt
        chord = v * dt * _sinc_array(half)
        x = x + chord * np.cos(th + half)
        y = y + chord * np.sin(th + half)
        th = th + w * dt
        poses[:, k, 0], poses[:, k, 1], poses[:, k, 2] = x, y, th
    return poses


def arc_poses(theta: float, samples: np.ndarray, dt: float, steps: int) -> np.ndarray:
    """Poses ``(S, steps, 3)`` after steps 1..steps of the arcs of ``samples`` (v [m/s],
    ω [rad/s]) from (0, 0, θ) (module docstring; heading not wrapped).

    Parameters
    ----------
    theta : float
        Start heading [rad].
    samples : numpy.ndarray, shape (S, 2)
        (v, ω) held over the trajectory.
    dt : float
        Step [s].
    steps : int
        Number of steps.

    Returns
    -------
    numpy.ndarray
    """
    tau = dt * np.arange(1, steps + 1)
    v, w = samples[:, :1], samples[:, 1:]
    half = 0.5 * w * tau
    chord = v * tau * _sinc_array(half)
    return np.stack(
        [chord * np.cos(theta + half), chord * np.sin(theta + half), theta + w * tau], -1
    )


def dwa_scores_numpy(
    theta: float,
    samples: np.ndarray,
    dt: float,
    steps: int,
    window: np.ndarray,
    goal: np.ndarray,
    goal_field: np.ndarray,
    fgeo: np.ndarray,
    forward: float,
    section_end: np.ndarray,
    direction: float,
    field: object,
    mp: np.ndarray,
    map_relief: float,
    inflation: float,
    seen: PerceptionArrays,
    dynamic_inflation: float,
    profile: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """The NumPy twin of :func:`dwa_kernel`.

    Parameters
    ----------
    theta : float
        Robot heading [rad] (positions relative to the robot).
    samples : numpy.ndarray, shape (S, 2)
        (v [m/s], ω [rad/s]).
    dt : float
        Step [s].
    steps : int
        Steps of the simulated time.
    window : numpy.ndarray, shape (M, 4)
        The path window.
    goal : numpy.ndarray, shape (3,)
        Local goal (x, y [m], heading [rad]).
    goal_field, fgeo : numpy.ndarray
        Its distance field and geometry (:func:`goal_distance_field`).
    forward : float
        Forward-point distance [m].
    section_end : numpy.ndarray, shape (2,)
        The section's end [m] relative to the robot (the forward point stops there).
    direction : float
        ±1, the section's direction of travel.
    field : FootprintField
        The static map and footprint disks.
    mp : numpy.ndarray, shape (4,)
        The map's geometry, origin relative to the robot.
    map_relief : float
        Collision relief [m] of the map check.
    inflation : float
        r_infl [m] of the map's obstacle critic.
    seen : PerceptionArrays
        Costmap and tracks.
    dynamic_inflation : float
        r_dyn [m].
    profile : numpy.ndarray, shape (S, steps, 2), optional
        Ramped velocities (:func:`ramp_profile`) in place of the held samples.

    Returns
    -------
    scores : numpy.ndarray, shape (S, 8)
    first_contact : numpy.ndarray of int, shape (S,)
        The first step whose pose collides, ``steps`` where none does.
    """
    if profile is None:
        poses = arc_poses(theta, samples, dt, steps)
    else:
        poses = profile_poses(theta, profile, dt)
    n = samples.shape[0]
    scores = np.zeros((n, len(SCORES)))
    collided = np.zeros((n, steps), bool)
    if field.enabled:
        clearance, hit = field.clearance(poses, map_relief, mp)
        collided |= hit
        gap = np.where(clearance > 0.0, np.maximum(inflation - clearance, 0.0), 0.0)
        scores[:, 5] = np.mean(gap * gap, axis=1)
    if seen.has_costmap:
        soft, hit = costmap_costs(poses, seen.cost, seen.near, seen.geometry, seen.polygon)
        scores[:, 4] = np.mean(soft, axis=1)
        collided |= hit
    if seen.has_tracks:
        soft, hit = track_costs(poses, seen.table, seen.relief, seen.disks, dynamic_inflation,
                                HOLD_STEP / dt)  # fmt: skip
        scores[:, 6] = np.sum(soft, axis=1) / steps  # the held checks added, as the kernel
        collided |= hit[:, :steps]  # the held checks are never lethal
    end = poses[:, -1]
    step = np.minimum(forward, np.hypot(end[:, 0] - section_end[0], end[:, 1] - section_end[1]))
    heading = np.stack([np.cos(end[:, 2]), np.sin(end[:, 2])], -1)
    ahead = end[:, :2] + direction * step[:, None] * heading

    def nearest(points: np.ndarray) -> np.ndarray:
        d2 = (points[:, 0, None] - window[:, 0]) ** 2 + (points[:, 1, None] - window[:, 1]) ** 2
        return np.sqrt(d2.min(axis=1))

    scores[:, 0] = nearest(end[:, :2])
    scores[:, 1] = _goal_distances(end[:, :2], goal, goal_field, fgeo)
    scores[:, 2] = nearest(ahead)
    to_goal = _goal_distances(ahead, goal, goal_field, fgeo)
    fallback = np.where(scores[:, 1] >= 0.0, scores[:, 1] + step, -1.0)
    scores[:, 3] = np.where(to_goal >= 0.0, to_goal, fallback)
    scores[:, 7] = np.abs(wrap_angle(end[:, 2] - goal[2]))
    first = np.where(collided.any(axis=1), np.argmax(collided, axis=1), steps)
    return scores, first


def _goal_distances(points: np.ndarray, goal: np.ndarray, field: np.ndarray, fgeo: np.ndarray):
    """Vectorised twin of ``_goal_distance``."""
    straight = np.hypot(points[:, 0] - goal[0], points[:, 1] - goal[1])
    if fgeo[3] <= 0.5:
        return straight
    col = np.floor((points[:, 0] - fgeo[0]) / fgeo[2]).astype(np.int64)
    row = np.floor((points[:, 1] - fgeo[1]) / fgeo[2]).astype(np.int64)
    inside = (row >= 0) & (row < field.shape[0]) & (col >= 0) & (col < field.shape[1])
    value = field[np.clip(row, 0, field.shape[0] - 1), np.clip(col, 0, field.shape[1] - 1)]
    return np.where(inside, value, straight)
