"""The step kernel: B worlds of A agents advanced by dt in lockstep.

Per world (:func:`step_worlds`), in this order:

1. Goals: an agent within its radius of its goal, or whose goal budget ran out (the agent is
   stuck behind a wall), takes the next one: the next waypoint of its loop, or a random point
   of its region at least its radius from every wall and obstacle (up to 16 counter-based
   draws; the last is kept if none is clear). The budget of a goal is ``3 d / v⁰ + 5 s``.
2. Velocities: ``wander`` and ``waypoints`` agents head for their goal at v⁰ (slower when
   the goal is nearer than v⁰ dt); ORCA agents solve their linear program, all from the
   state at the start of the step (Jacobi: the order of the agents does not matter).
3. Motion in substeps (at most the social force's ``max_substep`` when a world has
   social-force agents, and no agent moving more than half its radius): social-force agents
   accelerate by their forces from the positions and velocities at the start of the
   substep; every agent moves by its velocity; robots are extrapolated at their velocities.
4. Contact with walls and static obstacles is resolved exactly: an agent whose disc
   overlaps one is pushed out along the nearest point's normal (up to 4 times, for corners),
   and the velocity's component into it is removed (``straight``: reflected, which keeps the
   speed). ``straight`` agents also reflect off their region's edges.

Nothing is drawn from a stateful generator (:mod:`wheelbase.world.counter_rng`), and the
outputs are fresh arrays: the step is a pure function of its inputs.
"""

from __future__ import annotations

import math

import numba
import numpy as np

from wheelbase.world.counter_rng import STREAM_DIRECTION, STREAM_GOAL, STREAM_ORCA, counter_uniform
from wheelbase.world.orca import half_plane, solve_lp
from wheelbase.world.social_force import (
    CUTOFF,
    FACTOR,
    INV_TAU,
    KAPPA,
    SUBSTEP,
    A,
    B,
    K,
    driving_force,
    pair_force,
    wall_force,
)
from wheelbase.world.statics import (
    BOUND,
    CIRCLE,
    RES,
    X0,
    Y0,
    push_direction,
    static_nearest,
    wall_points,
)

__all__ = ["GOAL_TRIES", "draw_goal", "initial_motion", "step_worlds", "uniform_keys"]

STRAIGHT, WANDER, WAYPOINTS, SOCIAL_FORCE, ORCA_CODE = 0, 1, 2, 3, 4
GOAL_TRIES = 16
"""Counter-based draws for a goal clear of walls and obstacles."""
GOAL_TIME_FACTOR = 3.0
GOAL_TIME_SLACK = 5.0  # s
_PUSH_EPS = 1e-9  # m beyond contact after a push-out, so the next query finds the disc clear
# ORCA parameter indices (ORCA.packed)
TAU, TAU_OBS, NEIGHBOUR_DIST, MAX_NEIGHBOURS, ORCA_FACTOR, PERTURBATION, MARGIN = range(7)


@numba.njit(cache=True)
def draw_goal(st, seed, step, agent, x0, y0, x1, y1, r):
    """A random goal in the region shrunk by ``r`` whose disc of radius ``r`` is clear of
    walls and obstacles (module docstring, step 1)."""
    gx = gy = 0.0
    for k in range(GOAL_TRIES):
        gx = x0 + r + counter_uniform(seed, STREAM_GOAL, step, agent, 2 * k) * (x1 - x0 - 2 * r)
        gy = y0 + r + counter_uniform(seed, STREAM_GOAL, step, agent, 2 * k + 1) * (y1 - y0 - 2 * r)
        if static_nearest(st, gx, gy, r)[0] >= r:
            break
    return gx, gy


@numba.njit(cache=True, inline="always")
def goal_budget(px, py, gx, gy, v0):
    return GOAL_TIME_FACTOR * math.hypot(gx - px, gy - py) / v0 + GOAL_TIME_SLACK


@numba.njit(cache=True)
def _resolve(st, px, py, vx, vy, r, reflect, rob_x, rob_y, rob_r, n_rob):
    """Push a disc out of walls, obstacles and (``n_rob`` > 0) robot discs; remove or reflect
    the velocity's component into them (module docstring, step 4)."""
    for _ in range(4):
        d, nx, ny = static_nearest(st, px, py, r)
        for k in range(n_rob):
            dd = math.hypot(px - rob_x[k], py - rob_y[k]) - rob_r
            if dd < d:
                d = dd
                nx, ny = push_direction(1.0, rob_x[k], rob_y[k], px, py)
        if d >= r:
            break
        px += (r - d + _PUSH_EPS) * nx
        py += (r - d + _PUSH_EPS) * ny
        vn = vx * nx + vy * ny
        if vn < 0.0:
            scale = 2.0 if reflect else 1.0
            vx -= scale * vn * nx
            vy -= scale * vn * ny
    return px, py, vx, vy


@numba.njit(cache=True)
def _orca_velocity(a, seed, step, pos, vel, goal, dt, radius, speed, code, reacts, orca, st, rob_xy,
                   rob_v, rob_r, nx, ny, c, pnx, pny, pc, nb_d, nb_i):  # fmt: skip
    """The ORCA velocity of agent ``a`` of one world (``pos``, ``vel``: that world's)."""
    px, py = pos[a, 0], pos[a, 1]
    vx, vy = vel[a, 0], vel[a, 1]
    r = radius[a]
    v0 = speed[a]
    vmax = orca[ORCA_FACTOR] * v0
    tau_obs = orca[TAU_OBS]
    ex = goal[a, 0] - px
    ey = goal[a, 1] - py
    dist = math.hypot(ex, ey)
    scale = 0.0 if dist == 0.0 else (v0 / dist if dist > v0 * dt else 1.0 / dt)
    ox, oy = ex * scale, ey * scale
    if orca[PERTURBATION] > 0.0:
        # a tiny random change of the preferred velocity breaks perfectly symmetric deadlocks
        turn = 2.0 * math.pi * counter_uniform(seed, STREAM_ORCA, step, a, 0)
        size = orca[PERTURBATION] * counter_uniform(seed, STREAM_ORCA, step, a, 1)
        ox += size * math.cos(turn)
        oy += size * math.sin(turn)
    # walls and obstacles: hard half-planes, first in the program
    m = wall_points(st, px, py, r + vmax * tau_obs, c, nx, ny)
    for k in range(m):
        d = c[k]
        c[k] = (r - d) / tau_obs if d >= r else min((r - d) / dt, vmax)
    hard = m
    # the nearest neighbours: agents, then robots when the agent reacts to them
    kmax = int(orca[MAX_NEIGHBOURS])
    reach2 = orca[NEIGHBOUR_DIST] ** 2
    count = 0
    n_agents = pos.shape[0]
    n_cand = n_agents + (rob_xy.shape[0] if reacts[a] else 0)
    for j in range(n_cand):
        if j == a:
            continue
        if j < n_agents:
            qx, qy = pos[j, 0], pos[j, 1]
        else:
            qx, qy = rob_xy[j - n_agents, 0], rob_xy[j - n_agents, 1]
        d2 = (qx - px) ** 2 + (qy - py) ** 2
        if d2 > reach2 or (count == kmax and d2 >= nb_d[count - 1]):
            continue
        slot = count if count < kmax else kmax - 1
        while slot > 0 and nb_d[slot - 1] > d2:
            nb_d[slot] = nb_d[slot - 1]
            nb_i[slot] = nb_i[slot - 1]
            slot -= 1
        nb_d[slot] = d2
        nb_i[slot] = j
        if count < kmax:
            count += 1
    for s in range(count):
        j = nb_i[s]
        if j < n_agents:
            qx, qy, wx, wy, rb = pos[j, 0], pos[j, 1], vel[j, 0], vel[j, 1], radius[j]
            share = 0.5 if code[j] == ORCA_CODE else 1.0
        else:
            k = j - n_agents
            qx, qy, wx, wy, rb = rob_xy[k, 0], rob_xy[k, 1], rob_v[k, 0], rob_v[k, 1], rob_r
            share = 1.0
        hx, hy, hc = half_plane(px, py, vx, vy, r + orca[MARGIN], qx, qy, wx, wy,
                                rb + orca[MARGIN], orca[TAU], dt, share)  # fmt: skip
        nx[m] = hx
        ny[m] = hy
        c[m] = hc
        m += 1
    return solve_lp(nx, ny, c, m, hard, vmax, ox, oy, pnx, pny, pc)


@numba.njit(cache=True)
def _social_acceleration(a, pos, vel, goal, radius, speed, sf, st, rob_x, rob_y, rob_v,
                         rob_r, n_rob, wall_d, wall_nx, wall_ny):  # fmt: skip
    """Force per unit mass on social-force agent ``a`` (:class:`SocialForce`)."""
    px, py = pos[a, 0], pos[a, 1]
    vx, vy = vel[a, 0], vel[a, 1]
    r = radius[a]
    ax, ay = driving_force(px, py, vx, vy, goal[a, 0], goal[a, 1], speed[a], sf[INV_TAU])
    for j in range(pos.shape[0]):
        if j != a:
            fx, fy = pair_force(px, py, vx, vy, r, pos[j, 0], pos[j, 1], vel[j, 0], vel[j, 1],
                                radius[j], sf[A], sf[B], sf[K], sf[KAPPA], sf[CUTOFF])  # fmt: skip
            ax += fx
            ay += fy
    for k in range(n_rob):
        fx, fy = pair_force(px, py, vx, vy, r, rob_x[k], rob_y[k], rob_v[k, 0], rob_v[k, 1],
                            rob_r, sf[A], sf[B], sf[K], sf[KAPPA], sf[CUTOFF])  # fmt: skip
        ax += fx
        ay += fy
    # walls: the map's nearest point and each static obstacle
    for k in range(wall_points(st, px, py, r + sf[CUTOFF], wall_d, wall_nx, wall_ny)):
        fx, fy = wall_force(vx, vy, r, wall_d[k], wall_nx[k], wall_ny[k], sf[A], sf[B], sf[K],
                            sf[KAPPA], sf[CUTOFF])  # fmt: skip
        ax += fx
        ay += fy
    return ax, ay


@numba.njit(cache=True)
def step_worlds(pos, vel, goal, waypoint, budget, seed, step, dt, radius, speed, vmax, code,
                region, reacts, wp_start, wp_count, waypoints, sf, orca, st, rob_pose, rob_v,
                rob_r):  # fmt: skip
    """Advance every world by ``dt`` (module docstring): returns new ``(pos, vel, goal,
    waypoint, budget)``.

    Shapes: ``pos, vel, goal`` (B, A, 2); ``waypoint`` int64 and ``budget`` [s] (B, A);
    ``seed, step`` (B,); per agent ``radius, speed, vmax`` (A,), ``code`` (A,) (index in
    :data:`BEHAVIOURS`), ``region`` (A, 4), ``reacts`` (A,), ``wp_start, wp_count`` (A,)
    into ``waypoints`` (W, 2); ``sf`` and ``orca`` the packed parameters; ``st`` the statics
    tuple; robots ``rob_pose`` (B, R, 3), ``rob_v`` (B, R, 2) and their radius ``rob_r``.
    """
    n_worlds, n_agents = pos.shape[0], pos.shape[1]
    n_rob = rob_pose.shape[1]
    rob_xy = rob_pose[:, :, :2]
    out_pos = np.empty_like(pos)
    out_vel = np.empty_like(vel)
    out_goal = np.empty_like(goal)
    out_waypoint = np.empty_like(waypoint)
    out_budget = np.empty_like(budget)
    has_sf = False
    has_orca = False
    ratio = 0.0
    for a in range(n_agents):
        has_sf |= code[a] == SOCIAL_FORCE
        has_orca |= code[a] == ORCA_CODE
        ratio = max(ratio, vmax[a] / radius[a])
    n_sub = max(1, math.ceil(ratio * dt / 0.5 - 1e-9))
    if has_sf:
        n_sub = max(n_sub, math.ceil(dt / sf[SUBSTEP] - 1e-9))
    h = dt / n_sub
    n_lines = st[CIRCLE].shape[0] + 1 + int(orca[MAX_NEIGHBOURS])
    nx = np.empty(n_lines)
    ny = np.empty(n_lines)
    c = np.empty(n_lines)
    pnx = np.empty(n_lines)
    pny = np.empty(n_lines)
    pc = np.empty(n_lines)
    nb_d = np.empty(int(orca[MAX_NEIGHBOURS]))
    nb_i = np.empty(int(orca[MAX_NEIGHBOURS]), np.int64)
    new_v = np.empty((n_agents, 2))
    acc = np.empty((n_agents, 2))
    rob_x = np.empty(n_rob)
    rob_y = np.empty(n_rob)
    bound = st[BOUND]
    res = st[RES]
    x_origin = st[X0]
    y_origin = st[Y0]
    for b in range(n_worlds):
        p = out_pos[b]
        v = out_vel[b]
        g = out_goal[b]
        p[:] = pos[b]
        v[:] = vel[b]
        g[:] = goal[b]
        out_waypoint[b] = waypoint[b]
        out_budget[b] = budget[b]
        # 1. goals
        for a in range(n_agents):
            if code[a] == STRAIGHT:
                continue
            dist = math.hypot(g[a, 0] - p[a, 0], g[a, 1] - p[a, 1])
            if dist > radius[a] and out_budget[b, a] > 0.0:
                continue
            if wp_count[a] > 0:
                k = (out_waypoint[b, a] + 1) % wp_count[a]
                out_waypoint[b, a] = k
                g[a, 0] = waypoints[wp_start[a] + k, 0]
                g[a, 1] = waypoints[wp_start[a] + k, 1]
            else:
                g[a, 0], g[a, 1] = draw_goal(st, seed[b], step[b], a, region[a, 0],
                                             region[a, 1], region[a, 2], region[a, 3],
                                             radius[a])  # fmt: skip
            out_budget[b, a] = goal_budget(p[a, 0], p[a, 1], g[a, 0], g[a, 1], speed[a])
        # 2. velocities
        for a in range(n_agents):
            if code[a] == WANDER or code[a] == WAYPOINTS:
                ex = g[a, 0] - p[a, 0]
                ey = g[a, 1] - p[a, 1]
                dist = math.hypot(ex, ey)
                scale = 0.0 if dist == 0.0 else (
                    speed[a] / dist if dist > speed[a] * dt else 1.0 / dt)  # fmt: skip
                v[a, 0] = ex * scale
                v[a, 1] = ey * scale
        if has_orca:
            for a in range(n_agents):
                if code[a] == ORCA_CODE:
                    new_v[a, 0], new_v[a, 1] = _orca_velocity(
                        a, seed[b], step[b], p, v, g, dt, radius, speed, code, reacts, orca, st,
                        rob_xy[b],
                        rob_v[b], rob_r, nx, ny, c, pnx, pny, pc, nb_d, nb_i,
                    )  # fmt: skip
            for a in range(n_agents):
                if code[a] == ORCA_CODE:
                    v[a, 0] = new_v[a, 0]
                    v[a, 1] = new_v[a, 1]
        # 3. and 4. motion in substeps, contacts resolved
        for s in range(n_sub):
            for k in range(n_rob):
                rob_x[k] = rob_xy[b, k, 0] + s * h * rob_v[b, k, 0]
                rob_y[k] = rob_xy[b, k, 1] + s * h * rob_v[b, k, 1]
            if has_sf:
                for a in range(n_agents):
                    if code[a] == SOCIAL_FORCE:
                        seen = n_rob if reacts[a] else 0
                        acc[a, 0], acc[a, 1] = _social_acceleration(
                            a, p, v, g, radius, speed, sf, st, rob_x, rob_y, rob_v[b],
                            rob_r, seen, pnx, pny, pc,
                        )  # fmt: skip
                for a in range(n_agents):
                    if code[a] == SOCIAL_FORCE:
                        wx = v[a, 0] + h * acc[a, 0]
                        wy = v[a, 1] + h * acc[a, 1]
                        top = sf[FACTOR] * speed[a]
                        norm = math.hypot(wx, wy)
                        if norm > top:
                            wx *= top / norm
                            wy *= top / norm
                        v[a, 0] = wx
                        v[a, 1] = wy
            for a in range(n_agents):
                px = p[a, 0] + h * v[a, 0]
                py = p[a, 1] + h * v[a, 1]
                vx = v[a, 0]
                vy = v[a, 1]
                r = radius[a]
                if code[a] == STRAIGHT:
                    lo, hi = region[a, 0] + r, region[a, 2] - r
                    if px < lo:
                        px, vx = min(2.0 * lo - px, hi), abs(vx)
                    elif px > hi:
                        px, vx = max(2.0 * hi - px, lo), -abs(vx)
                    lo, hi = region[a, 1] + r, region[a, 3] - r
                    if py < lo:
                        py, vy = min(2.0 * lo - py, hi), abs(vy)
                    elif py > hi:
                        py, vy = max(2.0 * hi - py, lo), -abs(vy)
                obstacle_robots = n_rob if (reacts[a] and code[a] <= WAYPOINTS) else 0
                # the distance bound clears most agents without a call (a call passes the
                # statics tuple, whose arrays' reference counts cost more than the check)
                j = math.floor((px - x_origin) / res)
                i = math.floor((py - y_origin) / res)
                far = 0 <= i < bound.shape[0] and 0 <= j < bound.shape[1] and bound[i, j] > r
                if not far or obstacle_robots:
                    px, py, vx, vy = _resolve(st, px, py, vx, vy, r, code[a] == STRAIGHT,
                                              rob_x, rob_y, rob_r, obstacle_robots)  # fmt: skip
                p[a, 0] = px
                p[a, 1] = py
                v[a, 0] = vx
                v[a, 1] = vy
        for a in range(n_agents):
            out_budget[b, a] -= dt
    return out_pos, out_vel, out_goal, out_waypoint, out_budget


@numba.njit(cache=True)
def uniform_keys(n, seed, stream, step):
    """``n`` counter-based uniforms (agent counter 0..n−1), e.g. keys of a seeded shuffle."""
    out = np.empty(n)
    for i in range(n):
        out[i] = counter_uniform(seed, stream, step, i, 0)
    return out


@numba.njit(cache=True)
def initial_motion(st, seeds, position, radius, speed, code, region, wp_start, wp_count,
                   waypoints):  # fmt: skip
    """First velocities, goals, waypoint indices and goal budgets of placed agents: a
    ``straight`` agent heads in a random direction; a ``waypoints`` (or social-force, ORCA
    with waypoints) agent for a random waypoint of its loop; the others for a random goal
    (drawn as in a step, with step counter −1); all at their preferred speed."""
    n_worlds, n_agents = position.shape[0], position.shape[1]
    vel = np.zeros((n_worlds, n_agents, 2))
    goal = position.copy()
    waypoint = np.full((n_worlds, n_agents), -1, np.int64)
    budget = np.full((n_worlds, n_agents), np.inf)
    for b in range(n_worlds):
        for a in range(n_agents):
            px, py = position[b, a, 0], position[b, a, 1]
            if code[a] == STRAIGHT:
                angle = 2.0 * math.pi * counter_uniform(seeds[b], STREAM_DIRECTION, 0, a, 0)
                vel[b, a, 0] = speed[a] * math.cos(angle)
                vel[b, a, 1] = speed[a] * math.sin(angle)
                continue
            if wp_count[a] > 0:
                k = int(counter_uniform(seeds[b], STREAM_DIRECTION, 0, a, 1) * wp_count[a])
                k = min(k, wp_count[a] - 1)
                waypoint[b, a] = k
                gx, gy = waypoints[wp_start[a] + k, 0], waypoints[wp_start[a] + k, 1]
            else:
                gx, gy = draw_goal(st, seeds[b], -1, a, region[a, 0], region[a, 1],
                                   region[a, 2], region[a, 3], radius[a])  # fmt: skip
            goal[b, a, 0] = gx
            goal[b, a, 1] = gy
            budget[b, a] = goal_budget(px, py, gx, gy, speed[a])
            dist = math.hypot(gx - px, gy - py)
            if dist > 0.0:
                vel[b, a, 0] = speed[a] * (gx - px) / dist
                vel[b, a, 1] = speed[a] * (gy - py) / dist
    return vel, goal, waypoint, budget
