"""Hybrid A*'s search kernel (compiled): A* over the lattice's states with curve shots to the
goal, motions checked by conservative advancement on the distance field and exactly near
obstacles, moves cut at contact where asked (see :class:`~wheelbase.planning.HybridAStar`).
"""

from __future__ import annotations

import math
import time
from typing import NamedTuple

import numba
import numpy as np

from wheelbase.geometry_numba import wrap_angle_scalar
from wheelbase.planning._heap import _heap_pop, _heap_push
from wheelbase.planning.collision import _circles_clearance, _collides_one, _scratch
from wheelbase.planning.dubins import _WORDS as _DUBINS_WORDS
from wheelbase.planning.dubins import _dubins_all
from wheelbase.planning.hybrid_heuristic import (
    _MODE_DUBINS,
    _MODE_POINT,
    _MODE_RS,
    _cheap_heuristic,
    _heuristic,
)
from wheelbase.planning.lattice import _ROTATE
from wheelbase.planning.reeds_shepp import _best, _normalise

__all__: list[str] = []

_NO_LIMIT = 2**62  # an iteration limit above this is none (the kernel counts in int64)
_FINITE = 1.0e300  # below this a cost is finite: the kernels compare with it, never with inf
_DEEPER = 1.0e-6
"""The queue key is ``(1 − _DEEPER)·g + w·h``: of two states whose f = g + w·h differ by less
than 1e-6 of the cost, the deeper (larger g) comes first. The search meets many such near-ties
(equal-cost detours on the lattice); breaking them towards depth cut the PythonRobotics maze's
expansions from 77k to 61k. It is A* with the heuristic weighted by 1/(1 − 1e-6): a path at
most 1e-6 of its cost dearer than the best on the lattice."""
_STATUS = {
    0: "goal reached",
    1: "search space exhausted",
    2: "iteration limit reached",
    3: "time limit reached",
}


class _Search(NamedTuple):
    """What the search kernel returns: its status (a key of ``_STATUS``), the goal's node and
    the node arrays (pose, parent, primitive, samples of it driven), and the curve shot."""

    status: int
    goal_node: int
    xs: np.ndarray
    ys: np.ndarray
    ths: np.ndarray
    parents: np.ndarray
    prim_of: np.ndarray
    used_of: np.ndarray
    expanded: int
    shot_types: np.ndarray
    shot_lengths: np.ndarray


@numba.njit(cache=True)
def _now():
    with numba.objmode(t="float64"):
        t = time.perf_counter()
    return t


@numba.njit(cache=True)
def _advance(x, y, th, kind, s, radius):
    if kind == _ROTATE:
        return x, y, th + s
    if kind == 0:
        return x + s * math.cos(th), y + s * math.sin(th), th
    k = kind / radius
    th1 = th + k * s
    return x + (math.sin(th1) - math.sin(th)) / k, y + (math.cos(th) - math.cos(th1)) / k, th1


@numba.njit(cache=True)
def _shot_word(x, y, th, gx, gy, gth, mode, radius, families, reverse_ok):
    """Segment types and signed lengths (m, or rad for turns in place) of the curve shot."""
    types = np.zeros(5, dtype=np.int64)
    lengths = np.zeros(5)
    if mode == _MODE_RS:
        nx, ny, nphi = _normalise(x, y, th, gx, gy, gth, radius)
        t, ell, total = _best(nx, ny, nphi, families)
        if not np.isfinite(total):
            return False, types, lengths
        for i in range(5):
            types[i] = t[i]
            lengths[i] = ell[i] * radius
        return True, types, lengths
    if mode == _MODE_DUBINS:
        segs = _dubins_all(x, y, th, gx, gy, gth, radius)
        best = -1
        best_len = np.inf
        for w in range(6):
            if not np.isnan(segs[w, 0]):
                total = segs[w, 0] + segs[w, 1] + segs[w, 2]
                if total < best_len:
                    best_len = total
                    best = w
        if best < 0:
            return False, types, lengths
        for i in range(3):
            types[i] = _DUBINS_WORDS[best, i]
            lengths[i] = segs[best, i] * radius
        return True, types, lengths
    # rotate - straight - rotate
    dx = gx - x
    dy = gy - y
    d = math.hypot(dx, dy)
    heading = math.atan2(dy, dx) if d > 1e-12 else th
    sign = 1.0
    a1 = wrap_angle_scalar(heading - th)
    if reverse_ok:
        a1b = wrap_angle_scalar(heading + math.pi - th)
        a2b = wrap_angle_scalar(gth - heading - math.pi)
        a2 = wrap_angle_scalar(gth - heading)
        if abs(a1b) + abs(a2b) < abs(a1) + abs(a2):
            a1 = a1b
            sign = -1.0
    a2 = wrap_angle_scalar(gth - (th + a1))
    types[0] = _ROTATE
    lengths[0] = a1
    types[1] = 0
    lengths[1] = sign * d
    types[2] = _ROTATE
    lengths[2] = a2
    return True, types, lengths


@numba.njit(cache=True, inline="always")
def _next_sample(k, clear, per):
    """The first sample after ``k`` that the clearance ``clear`` [m] at sample ``k`` does not
    vouch for, when no covering circle moves more than ``per`` [m] from one sample to the
    next (conservative advancement: the samples in between are clear)."""
    if clear <= 0.0:
        return k + 1
    if per <= 0.0:
        return 1 << 62
    return k + max(1, math.ceil(min(clear / per, 1.0e15)))


@numba.njit(cache=True, _nrt=False)
def _shot_free(
    x,
    y,
    th,
    types,
    lengths,
    radius,
    step,
    rho,
    world,
    poly,
    circles,
    cradius,
    wp,
    near,
):
    for i in range(5):
        ell = lengths[i]
        if ell == 0.0:
            continue
        kind = types[i]
        span = abs(ell) * rho if kind == _ROTATE else abs(ell)
        n = max(1, math.ceil(span / step))
        # the most any covering circle (within rho of the reference point) moves per sample
        per = (
            span / n
            if kind == _ROTATE
            else abs(ell) / n * (1.0 + (rho / radius if kind != 0 else 0.0))
        )
        dist, res, x0, y0 = world[2], world[3], world[4], world[5]
        k = _next_sample(0, _circles_clearance(dist, res, x0, y0, circles, cradius, x, y, th), per)
        while k <= n:
            px, py, pth = _advance(x, y, th, kind, ell * k / n, radius)
            clear = _circles_clearance(dist, res, x0, y0, circles, cradius, px, py, pth)
            if clear <= 0.0 and _collides_one(world, poly, circles, cradius, px, py, pth, wp, near):
                return False
            k = _next_sample(k, clear, per)
        x, y, th = _advance(x, y, th, kind, ell, radius)
    return True


@numba.njit(cache=True, _nrt=False)
def _free_prefix(
    world, dist, res, x0, y0, poly, circles, cradius, x, y, th, offsets, p, ns, sweep, clear0,
    wp, near,
):  # fmt: skip
    """How many leading samples ``offsets[p, :ns]`` of primitive ``p`` from pose ``(x, y, th)``
    are free (``ns``: all). Not inlined and without reference counting, as the collision
    kernels (see :mod:`wheelbase.planning.collision`): inlined, it took and released a
    reference to each of its 15 array arguments at every call. ``sweep`` bounds how far a
    covering circle moves along the whole primitive and ``clear0`` is the clearance of the
    circles at the pose (see ``_circles_clearance``; ``dist``, ``res``, ``x0``, ``y0``
    are the world's distance field and raster geometry; ``wp``, ``near``: scratch)."""
    c = math.cos(th)
    s = math.sin(th)
    per = sweep / ns
    k = _next_sample(-1, clear0, per)
    while k < ns:
        px = x + c * offsets[p, k, 0] - s * offsets[p, k, 1]
        py = y + s * offsets[p, k, 0] + c * offsets[p, k, 1]
        pth = th + offsets[p, k, 2]
        clear = _circles_clearance(dist, res, x0, y0, circles, cradius, px, py, pth)
        if clear <= 0.0 and _collides_one(world, poly, circles, cradius, px, py, pth, wp, near):
            return k
        k = _next_sample(k, clear, per)
    return ns


@numba.njit(cache=True, inline="always")
def _bin(x, y, th, x0, y0, xy_res, nx, ny, nh):
    ix = math.floor((x - x0) / xy_res)
    iy = math.floor((y - y0) / xy_res)
    if ix < 0 or ix >= nx or iy < 0 or iy >= ny:
        return -1
    ih = math.floor(wrap_angle_scalar(th) / (2.0 * math.pi / nh) + 0.5) % nh
    return (iy * nx + ix) * nh + ih


@numba.njit(cache=True)
def _grown(a, n, capacity):
    """A copy of ``a[:n]`` in a new array of ``capacity`` entries."""
    out = np.empty(capacity, dtype=a.dtype)
    out[:n] = a[:n]
    return out


@numba.njit(cache=True)
def _search(
    world,
    poly,
    circles,
    cradius,
    hgrid,
    hres,
    start,
    goal,
    offsets,
    nsamples,
    pdir,
    pkappa,
    pcost,
    psweep,
    nx,
    ny,
    nh,
    xy_res,
    radius,
    mode,
    families,
    rho,
    switch_penalty,
    change_penalty,
    hweight,
    ratio,
    step,
    xy_tol,
    yaw_tol,
    max_iter,
    time_limit,
    turn_cost,
    cut_moves,
):
    t_start = _now()
    dist = world[2]
    res = world[3]
    x0 = world[4]
    y0 = world[5]
    capacity = 4096
    xs = np.empty(capacity)
    ys = np.empty(capacity)
    ths = np.empty(capacity)
    gs = np.empty(capacity)
    parents = np.empty(capacity, dtype=np.int64)
    prim_of = np.empty(capacity, dtype=np.int64)
    used_of = np.empty(capacity, dtype=np.int64)  # samples of the primitive driven (a cut move)
    last_dir = np.empty(capacity, dtype=np.int64)
    # whether a node's queue key holds the full heuristic or only the cheap bound: the curve
    # length (microseconds) is computed when a node first reaches the top of the queue, so
    # children that are never expanded never pay for it (the key only grows: still A*)
    exact_h = np.empty(capacity, dtype=np.bool_)
    nbins = nx * ny * nh
    best_g = np.full(nbins, np.inf)
    gx, gy, gth = goal[0], goal[1], goal[2]
    reverse_ok = False
    for p in range(pdir.shape[0]):
        if pdir[p] < 0:
            reverse_ok = True

    xs[0], ys[0], ths[0], gs[0] = start[0], start[1], start[2], 0.0
    parents[0] = -1
    prim_of[0] = -1
    used_of[0] = 0
    last_dir[0] = 0
    exact_h[0] = True
    n_nodes = 1
    b0 = _bin(start[0], start[1], start[2], x0, y0, xy_res, nx, ny, nh)
    best_g[b0] = 0.0
    h0 = _heuristic(
        start[0],
        start[1],
        start[2],
        gx,
        gy,
        gth,
        mode,
        radius,
        families,
        hgrid,
        hres,
        x0,
        y0,
        turn_cost,
    )
    # the open list: a binary heap of (key, node) in two arrays (numba's heapq on a list costs
    # atomic reference counts at every push and pop, a quarter of the search's time); the
    # order is that of the tuples, so the search is the same
    hcap = 2 * capacity
    hkeys = np.empty(hcap)
    hids = np.empty(hcap, dtype=np.int64)
    hsize = _heap_push(hkeys, hids, 0, hweight * h0, 0)
    expanded = 0
    since_shot = 1 << 30
    status = 1
    goal_node = -1
    shot_types = np.zeros(5, dtype=np.int64)
    shot_lengths = np.zeros(5)
    n_prims = pdir.shape[0]
    placed, listed = _scratch(world, poly)  # scratch buffers of the exact collision check

    # The node arrays grow in the outer loop only: reassigning them inside the search loop
    # makes Numba reference-count all eight at every accepted child (a third of the time).
    while True:
        grow = False
        if n_nodes + n_prims > capacity:
            capacity *= 2
            xs = _grown(xs, n_nodes, capacity)
            ys = _grown(ys, n_nodes, capacity)
            ths = _grown(ths, n_nodes, capacity)
            gs = _grown(gs, n_nodes, capacity)
            parents = _grown(parents, n_nodes, capacity)
            prim_of = _grown(prim_of, n_nodes, capacity)
            used_of = _grown(used_of, n_nodes, capacity)
            last_dir = _grown(last_dir, n_nodes, capacity)
            exact_h = _grown(exact_h, n_nodes, capacity)
        if hsize + n_prims + 1 > hcap:
            hcap *= 2
            hkeys = _grown(hkeys, hsize, hcap)
            hids = _grown(hids, hsize, hcap)
        while hsize > 0:
            if n_nodes + n_prims > capacity or hsize + n_prims + 1 > hcap:
                grow = True  # room for every child of the next node: grow outside this loop
                break
            f, node, hsize = _heap_pop(hkeys, hids, hsize)
            x, y, th, g = xs[node], ys[node], ths[node], gs[node]
            b = _bin(x, y, th, x0, y0, xy_res, nx, ny, nh)
            if g > best_g[b] + 1e-9:  # closed (-inf) or reached more cheaply since
                continue
            if not exact_h[node]:
                exact_h[node] = True
                hfull = _heuristic(
                    x, y, th, gx, gy, gth, mode, radius, families, hgrid, hres, x0, y0, turn_cost
                )
                if not hfull < _FINITE:
                    continue
                if (1.0 - _DEEPER) * g + hweight * hfull > f:
                    key = (1.0 - _DEEPER) * g + hweight * hfull
                    hsize = _heap_push(hkeys, hids, hsize, key, node)
                    continue
            best_g[b] = -np.inf  # closed
            expanded += 1
            if expanded > max_iter:
                status = 2
                break
            if (expanded & 255) == 0 and _now() - t_start > time_limit:
                status = 3
                break
            # goal tolerance
            if (
                xy_tol > 0.0
                and math.hypot(x - gx, y - gy) <= xy_tol
                and abs(wrap_angle_scalar(th - gth)) <= yaw_tol
            ):
                status = 0
                goal_node = node
                break
            # analytic expansion
            h = (f - (1.0 - _DEEPER) * g) / hweight
            since_shot += 1
            # An infinite heuristic (no free way to the goal even for a point) means no shot can
            # succeed either: none is tried, and int() never sees inf (undefined when compiled).
            shots = h < _FINITE
            interval = int(min(max(h, 0.0) / (ratio * xy_res), 1.0e18)) if shots else 0
            if shots and since_shot >= interval:
                since_shot = 0
                ok, types, lengths = _shot_word(
                    x, y, th, gx, gy, gth, mode, radius, families, reverse_ok
                )
                if ok and _shot_free(
                    x,
                    y,
                    th,
                    types,
                    lengths,
                    radius,
                    step,
                    rho,
                    world,
                    poly,
                    circles,
                    cradius,
                    placed,
                    listed,
                ):
                    status = 0
                    goal_node = node
                    shot_types = types
                    shot_lengths = lengths
                    break
            c = math.cos(th)
            s = math.sin(th)
            parent_prim = prim_of[node]
            # lower bound on how far every covering circle may move and stay clear
            free_sweep = _circles_clearance(dist, res, x0, y0, circles, cradius, x, y, th)
            for p in range(n_prims):
                ns = nsamples[p]
                d = pdir[p]
                ld = last_dir[node]
                extra = switch_penalty if (d != 0 and ld != 0 and d != ld) else 0.0
                pc = pcost[p]
                if (
                    parent_prim >= 0
                    and pdir[p] != 0
                    and pdir[parent_prim] != 0
                    and pkappa[p] != pkappa[parent_prim]
                ):
                    extra += change_penalty * pcost[p]  # the whole primitive's, cut or not
                nxp = x + c * offsets[p, ns - 1, 0] - s * offsets[p, ns - 1, 1]
                nyp = y + s * offsets[p, ns - 1, 0] + c * offsets[p, ns - 1, 1]
                nth = wrap_angle_scalar(th + offsets[p, ns - 1, 2])
                nb = _bin(nxp, nyp, nth, x0, y0, xy_res, nx, ny, nh)
                full_open = nb >= 0 and g + (pc + extra) < best_g[nb]
                near = psweep[p] >= free_sweep
                if not full_open and not (cut_moves and near):
                    continue
                use = ns
                if near:
                    use = _free_prefix(
                        world, dist, res, x0, y0, poly, circles, cradius, x, y, th,
                        offsets, p, ns, psweep[p], free_sweep, placed, listed,
                    )  # fmt: skip
                    if use == 0 or (use < ns and not cut_moves) or (use == ns and not full_open):
                        continue
                    if use < ns:  # the move until contact: up to the last free sample
                        nxp = x + c * offsets[p, use - 1, 0] - s * offsets[p, use - 1, 1]
                        nyp = y + s * offsets[p, use - 1, 0] + c * offsets[p, use - 1, 1]
                        nth = wrap_angle_scalar(th + offsets[p, use - 1, 2])
                        nb = _bin(nxp, nyp, nth, x0, y0, xy_res, nx, ny, nh)
                        if nb < 0 or best_g[nb] == -np.inf:
                            continue
                ng = g + ((pc if use == ns else pc * use / ns) + extra)
                if ng >= best_g[nb]:
                    continue
                hn = _cheap_heuristic(
                    nxp, nyp, nth, gx, gy, gth, mode, hgrid, hres, x0, y0, turn_cost
                )
                if not hn < _FINITE:
                    continue
                best_g[nb] = ng
                xs[n_nodes] = nxp
                ys[n_nodes] = nyp
                ths[n_nodes] = nth
                gs[n_nodes] = ng
                parents[n_nodes] = node
                prim_of[n_nodes] = p
                used_of[n_nodes] = use
                last_dir[n_nodes] = d if d != 0 else ld
                exact_h[n_nodes] = mode == _MODE_POINT  # there the cheap bound is the heuristic
                hsize = _heap_push(hkeys, hids, hsize, (1.0 - _DEEPER) * ng + hweight * hn, n_nodes)
                n_nodes += 1
        if not grow:
            break
    return (
        status,
        goal_node,
        xs[:n_nodes],
        ys[:n_nodes],
        ths[:n_nodes],
        parents[:n_nodes],
        prim_of[:n_nodes],
        used_of[:n_nodes],
        expanded,
        shot_types,
        shot_lengths,
    )
