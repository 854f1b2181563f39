"""The Numba backend of :class:`wheelbase.control.MPPI` (private): one parallel compiled loop that
draws the noise, rolls each sample out and scores it.

Its noise comes from a counter-based SplitMix64 stream keyed by (seed, call, sample, step)
through an inverse-CDF table, so it does not depend on the threads.
"""

from __future__ import annotations

import math

import numba
import numpy as np
from scipy.special import ndtri

from wheelbase.control.footprint_field import clearance_at
from wheelbase.control.obstacle_critics import (
    HOLD_STEP,
    costmap_cost_at,
    track_cost_at,
    track_terms,
)

__all__ = ["NORMAL_TABLE", "SERIAL_SAMPLE_STEPS", "mppi_kernel", "mppi_work", "run_kernel"]

SERIAL_SAMPLE_STEPS = 65536
"""Below this much work (samples × steps, weighted by the tracks checked: see
:func:`mppi_work`) a parallel kernel runs on the calling thread: waking Numba's thread pool
costs about 15 ms on a busy machine (as for the lidar's rays, :mod:`wheelbase.sensors.raycast`;
measured here at a load of 10 on 2 cores: DWA's 400 × 34 scored at 31 calls/s on two threads,
402 on one)."""

TRACK_CHECKS_PER_STEP = 8.0
"""How many track checks cost as much as the rest of one rollout step (measured on a
``crowd_crossing`` call, 1,000 × 56 samples: 73 ns a step without tracks, 8 ns a track a
step)."""


def mppi_work(samples: int, steps: int, tracks: int) -> float:
    """The work of one MPPI kernel call in rollout steps: samples × steps × (1 + tracks /
    :data:`TRACK_CHECKS_PER_STEP`). A crowd call (1,000 × 56, 10 tracks) then runs on the
    thread pool: 9.5 s → 5.8 s wall for 20 s of ``crowd_crossing`` with 50 walkers on 2 idle
    cores; without tracks the same call stays on the calling thread.

    Parameters
    ----------
    samples : int
        K, the samples.
    steps : int
        T, the horizon's steps.
    tracks : int
        The tracks the call checks.

    Returns
    -------
    float
    """
    return samples * steps * (1.0 + tracks / TRACK_CHECKS_PER_STEP)


def run_kernel(kernel, work: float, *args) -> None:
    """Call a parallel kernel, on the calling thread alone when ``work`` (samples × steps, or
    :func:`mppi_work`) is below :data:`SERIAL_SAMPLE_STEPS`.

    Parameters
    ----------
    kernel : numba dispatcher
        The kernel.
    work : float
        Samples × steps of this call (MPPI: :func:`mppi_work`).
    *args
        The kernel's arguments.
    """
    threads = numba.get_num_threads()
    serial = work < SERIAL_SAMPLE_STEPS and threads > 1
    if serial:
        numba.set_num_threads(1)
    try:
        kernel(*args)
    finally:
        if serial:
            numba.set_num_threads(threads)


# Inverse normal CDF at the midpoints of 2,048 equal-probability bins: the numba backend draws
# a normal as Φ⁻¹(u), linearly interpolated in this table (tails truncated at ±3.5σ, where the
# outermost midpoints lie; the standard deviation of the draws is 0.998).
_TABLE_SIZE = 2048
NORMAL_TABLE = ndtri((np.arange(_TABLE_SIZE) + 0.5) / _TABLE_SIZE)


@numba.njit(cache=True, inline="always")
def _table_normal(bits, table):
    """A normal draw from 32 random bits through the inverse-CDF table."""
    position = float(bits) * (table.shape[0] / 4294967296.0) - 0.5
    if position <= 0.0:
        return table[0]
    k = int(position)
    if k >= table.shape[0] - 1:
        return table[table.shape[0] - 1]
    frac = position - k
    return table[k] + frac * (table[k + 1] - table[k])


@numba.njit(cache=True, inline="always")
def _normal_pair(seed, call, sample, step, table):
    """Two standard normals from a counter-based generator (SplitMix64 + inverse-CDF table).

    The stream depends only on (seed, call, sample, step), so it is the same whatever thread
    runs a sample."""
    z = seed * np.uint64(0x9E3779B97F4A7C15) + call * np.uint64(0xD1B54A32D192ED03)
    z = z + sample * np.uint64(0x8CB92BA72F3D8DD7) + step * np.uint64(0x2545F4914F6CDD1D)
    z = (z ^ (z >> np.uint64(30))) * np.uint64(0xBF58476D1CE4E5B9)
    z = (z ^ (z >> np.uint64(27))) * np.uint64(0x94D049BB133111EB)
    z = z ^ (z >> np.uint64(31))
    low = z & np.uint64(0xFFFFFFFF)
    return _table_normal(low, table), _table_normal(z >> np.uint64(32), table)


@numba.njit(cache=True, inline="always")
def _wrap_scalar(a):
    """a [rad] wrapped into (−π, π] by whole turns (a difference of two wrapped angles is
    one turn away at most: cheaper than atan2(sin a, cos a), which it equals to rounding)."""
    if not abs(a) < 16.0:  # far out (or not finite): no loop of turns
        w = math.atan2(math.sin(a), math.cos(a))
        return math.pi if w <= -math.pi else w
    while a > math.pi:
        a -= 2.0 * math.pi
    while a <= -math.pi:
        a += 2.0 * math.pi
    return a


@numba.njit(cache=True, inline="always", fastmath=True)
def _nearest(x, y, window):
    """Squared distance [m²] from (x, y) to the nearest window point and its index."""
    dx, dy = x - window[0, 0], y - window[0, 1]
    best, index = dx * dx + dy * dy, 0
    for j in range(1, window.shape[0]):
        dx, dy = x - window[j, 0], y - window[j, 1]
        d2 = dx * dx + dy * dy
        if d2 < best:
            best, index = d2, j
    return best, index


@numba.njit(cache=True, parallel=True, fastmath=True)
def mppi_kernel(
    pose, mean, lo, hi, scale, window, info, last, noise, has_noise, held_from, sigma, seed, call,
    kind,
    wheel_base, dt, w, df, mp, circles, stride, table, cost_map, near, cgeo, polygon, tracks,
    relief, disks, order, counts, costs, controls, first_contact,
):  # fmt: skip
    """Draw, roll out and score every sample in one pass (the numba backend).

    Samples ``held_from`` and after hold their first perturbation over the whole horizon.
    The same costs as :func:`wheelbase.control.mppi_numpy.numpy_costs` (to rounding:
    ``fastmath`` lets the compiler reorder the sums), one sample per iteration of the parallel
    loop. ``cost_map`` … ``counts`` are the fields of
    :class:`~wheelbase.control.obstacle_critics.PerceptionArrays`. ``first_contact`` receives
    each sample's first colliding step (T where it never collides), as
    :func:`~wheelbase.control.mppi_numpy.contact_steps` counts them."""
    n, steps = controls.shape[0], controls.shape[1]
    m = window.shape[0]
    goal_mode = info[0] > 0.5
    x0, y0, res, has_map = mp[0], mp[1], mp[2], mp[3] > 0.5
    inv_res = 1.0 / res
    n_checked = max((steps - stride) // stride + 1, 1) if steps >= stride else 1
    margin = math.sqrt(2.0) * res + info[6]
    w_path, w_align = w[0] / n_checked, w[1] / n_checked
    w_goal, w_obstacle = w[3] / steps, w[5] / steps
    w_forward = w[6] * dt
    a0, a1 = 1.0 / scale[0], 1.0 / scale[1]
    holonomic = controls.shape[2] == 3  # (v_x, v_y, ω); else (v, ω) or (v, δ)
    a2 = 1.0 / scale[2] if holonomic else 0.0
    w_effort, w_rate = w[7] / steps, w[8] / steps
    w_twirl = w[9] / steps * (a2 if holonomic else a1)
    inflation, direction = w[10], info[4]
    has_costmap, has_tracks = cgeo[3] > 0.5, tracks.shape[1] > 0
    w_costmap, w_dynamic, dynamic_inflation = w[12] / steps, w[13] / steps, w[14]
    terms = track_terms(tracks, disks, dynamic_inflation)
    hold_weight = HOLD_STEP / dt  # a held check stands for HOLD_STEP / dt steps
    for i in numba.prange(n):
        x, y, th = pose[0], pose[1], pose[2]
        c, s = math.cos(th), math.sin(th)
        p0, p1 = last[0], last[1]
        p2 = last[2] if holonomic else 0.0
        cost = 0.0
        collided = False
        first = steps
        next_check = stride - 1
        held = i >= held_from  # this sample holds its first perturbation all along
        for t in range(steps):
            e2 = 0.0
            draw = 0 if held else t
            if has_noise:
                e0, e1 = noise[i, draw, 0], noise[i, draw, 1]
                if holonomic:
                    e2 = noise[i, draw, 2]
            else:
                e0, e1 = _normal_pair(seed, call, np.uint64(i), np.uint64(draw), table)
                e0 *= sigma[0]
                e1 *= sigma[1]
                if holonomic:  # a third draw from the counters of a step past the horizon
                    e2, _unused = _normal_pair(
                        seed, call, np.uint64(i), np.uint64(draw + steps), table
                    )
                    e2 *= sigma[2]
            u0 = min(max(mean[t, 0] + e0, lo[0]), hi[0])
            u1 = min(max(mean[t, 1] + e1, lo[1]), hi[1])
            controls[i, t, 0] = u0
            controls[i, t, 1] = u1
            u2 = 0.0
            if holonomic:
                u2 = min(max(mean[t, 2] + e2, lo[2]), hi[2])
                planar = math.hypot(u0, u1)
                if planar > hi[0]:  # (v_x, v_y) in the disk of radius hi[0], as MPPI._clip
                    u0 *= hi[0] / planar
                    u1 *= hi[0] / planar
                controls[i, t, 0] = u0
                controls[i, t, 1] = u1
                controls[i, t, 2] = u2
            lateral = 0.0
            if kind == 0:
                speed, rate = u0, u1
            elif kind == 1:
                speed, rate = u0, u0 * math.tan(u1) / wheel_base
            elif kind == 2:
                speed, rate = u0 * math.cos(u1), u0 * math.sin(u1) / wheel_base
            else:
                speed, lateral, rate = u0, u1, u2
            x = x + dt * (c * speed - s * lateral)
            y = y + dt * (s * speed + c * lateral)
            th = th + dt * rate
            if th > math.pi:  # one step turns by less than 2π: a cheap wrap
                th -= 2.0 * math.pi
            elif th <= -math.pi:
                th += 2.0 * math.pi
            c, s = math.cos(th), math.sin(th)
            if t == next_check:
                next_check += stride
                best, bj = _nearest(x, y, window)
                err = _wrap_scalar(th - window[bj, 2])
                cost += w_path * math.sqrt(best) + w_align * err * err
            if goal_mode:
                cost += w_goal * math.hypot(x - info[1], y - info[2])
            if has_map:  # the footprint's clearance: the least over its disks
                clearance, hit = clearance_at(x, y, c, s, df, x0, y0, inv_res, circles, margin)
                collided = collided or hit
                if 0.0 < clearance < inflation:
                    gap = inflation - clearance
                    cost += w_obstacle * gap * gap
            if has_costmap:
                soft, hit = costmap_cost_at(x, y, c, s, cost_map, near, cgeo, polygon)
                cost += w_costmap * soft
                collided = collided or hit
            if has_tracks:
                soft, hit = track_cost_at(x, y, c, s, t, tracks, relief, disks, dynamic_inflation,
                                          steps, terms, order, counts)  # fmt: skip
                cost += w_dynamic * soft
                collided = collided or hit
            if collided and first == steps:
                first = t
            cost += w_forward * max(-direction * u0, 0.0)
            q0, q1, q2 = u0 * a0, u1 * a1, u2 * a2
            r0, r1, r2 = (u0 - p0) * a0, (u1 - p1) * a1, (u2 - p2) * a2
            cost += w_effort * (q0 * q0 + q1 * q1 + q2 * q2)
            cost += w_rate * (r0 * r0 + r1 * r1 + r2 * r2)
            if kind == 0:
                cost += w_twirl * abs(u1)
            elif kind == 3:
                cost += w_twirl * abs(u2)
            p0, p1, p2 = u0, u1, u2
        if has_tracks:  # the final pose held (obstacle_critics: a braking ICS test)
            for t in range(steps, tracks.shape[0]):
                soft, hit = track_cost_at(x, y, c, s, t, tracks, relief, disks, dynamic_inflation,
                                          steps, terms, order, counts)  # fmt: skip
                cost += w_dynamic * hold_weight * soft
                collided = collided or hit
        if goal_mode:
            cost += w[4] * abs(_wrap_scalar(th - info[3]))
        else:
            best, bj = _nearest(x, y, window)
            cost += w[2] * (window[m - 1, 3] - window[bj, 3])
        if collided:
            cost += w[11]
        costs[i] = cost
        first_contact[i] = first
