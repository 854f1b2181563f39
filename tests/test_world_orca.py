"""ORCA: the half-planes keep reciprocal pairs apart for τ, the linear program is solved
exactly, and crowds of ORCA agents never touch."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.optimize import linprog, minimize

from wheelbase.planning import OccupancyGrid
from wheelbase.world import ORCA, AgentGroup, World, orca_half_plane, solve_velocity_lp


def min_distance_over(p_rel, v_rel, tau):
    """Least distance of p_rel + t v_rel for t in [0, tau]."""
    vv = v_rel @ v_rel
    t = 0.0 if vv == 0 else np.clip(-(p_rel @ v_rel) / vv, 0.0, tau)
    return np.linalg.norm(p_rel + t * v_rel)


@settings(max_examples=200, deadline=None)
@given(st.lists(st.floats(-3, 3), min_size=8, max_size=8), st.floats(0.1, 0.6),
       st.floats(0.1, 0.6), st.floats(0.5, 5.0))  # fmt: skip
def test_velocities_in_both_half_planes_do_not_collide_within_tau(values, ra, rb, tau):
    pa, pb = np.array(values[:2]) * 2, np.array(values[2:4]) * 2
    va, vb = np.array(values[4:6]), np.array(values[6:8])
    if np.linalg.norm(pb - pa) <= ra + rb + 1e-3:
        return  # the guarantee is for agents apart
    na, ca = orca_half_plane([*pa, *va, ra], [*pb, *vb, rb], tau, 0.1)
    nb, cb = orca_half_plane([*pb, *vb, rb], [*pa, *va, ra], tau, 0.1)
    rng = np.random.default_rng(abs(hash(tuple(values))) % 2**32)
    tried = 0
    for _ in range(400):
        a_new, b_new = rng.uniform(-4, 4, 2), rng.uniform(-4, 4, 2)
        if na @ a_new >= ca and nb @ b_new >= cb:
            tried += 1
            gap = min_distance_over(pb - pa, b_new - a_new, tau)
            assert gap >= ra + rb - 1e-9
    # the current velocities, shifted by half of u each, lie on the boundaries
    np.testing.assert_allclose(na, -nb, atol=1e-12)


def test_half_plane_of_a_head_on_pair():
    n, c = orca_half_plane([0, 0, 1, 0, 0.5], [4, 0, -1, 0, 0.5], tau=2.0, dt=0.1)
    assert n @ [1.0, 0.0] < c  # the current velocity leads to contact within τ
    assert n @ [0.0, 0.0] >= c - 1e-12  # stopping is allowed (half of the change)
    n_far, c_far = orca_half_plane([0, 0, 1, 0, 0.5], [40, 0, -1, 0, 0.5], tau=2.0, dt=0.1)
    assert n_far @ [1.0, 0.0] >= c_far  # 40 m apart: no constraint on it yet


def feasible_problem(rng, n):
    point = rng.uniform(-1, 1, 2)
    angles = rng.uniform(-np.pi, np.pi, n)
    normals = np.column_stack([np.cos(angles), np.sin(angles)])
    offsets = normals @ point - rng.uniform(0, 1, n)
    return normals, offsets


@pytest.mark.parametrize("seed", range(30))
def test_lp_optimum_satisfies_every_half_plane_and_is_optimal(seed):
    rng = np.random.default_rng(seed)
    normals, offsets = feasible_problem(rng, 1 + seed % 12)
    preferred = rng.uniform(-3, 3, 2)
    v = solve_velocity_lp(normals, offsets, preferred, 2.0)
    assert np.all(normals @ v >= offsets - 1e-9)
    assert np.linalg.norm(v) <= 2.0 + 1e-9
    best = minimize(lambda x: np.sum((x - preferred) ** 2), np.zeros(2), method="SLSQP",
                    constraints=[{"type": "ineq", "fun": lambda x: normals @ x - offsets},
                                 {"type": "ineq", "fun": lambda x: 4.0 - x @ x}],
                    options={"ftol": 1e-14, "maxiter": 500})  # fmt: skip
    assert np.linalg.norm(v - preferred) <= np.linalg.norm(best.x - preferred) + 1e-6


def test_infeasible_lp_keeps_the_hard_half_planes_and_least_penetration():
    # x >= 0.5 (hard, a wall) and two agent half-planes that contradict each other
    normals = np.array([[1.0, 0.0], [0.0, 1.0], [0.0, -1.0]])
    offsets = np.array([0.5, 1.0, 1.0])  # y >= 1 and y <= -1
    v = solve_velocity_lp(normals, offsets, [0.0, 0.0], 2.0, hard=1)
    assert v[0] >= 0.5 - 1e-12
    penetration = offsets[1:] - normals[1:] @ v
    np.testing.assert_allclose(penetration, [1.0, 1.0], atol=1e-9)  # shared equally: y = 0


def open_world(groups):
    return World(OccupancyGrid(np.zeros((240, 240), bool), 0.1), agents=groups)


def run_without_contact(world, state, steps):
    r = world.agent_radius
    touch = r[:, None] + r[None]
    np.fill_diagonal(touch, -np.inf)
    worst = np.inf
    for _ in range(steps):
        state = world.step(state, 0.1)
        p = state.position[0]
        gap = np.hypot(*(p[:, None] - p[None]).transpose(2, 0, 1)) - touch
        worst = min(worst, gap.min())
    return state, worst


def test_a_circle_of_agents_swapping_sides_never_touches():
    n = 12
    angle = 2 * np.pi * np.arange(n) / n
    start = 12.0 + 8.0 * np.column_stack([np.cos(angle), np.sin(angle)])
    groups = [AgentGroup(count=1, behaviour="orca", speed=1.0, radius=0.4,
                         region=(x - 0.5, y - 0.5, x + 0.5, y + 0.5),
                         waypoints=[[24.0 - x, 24.0 - y], [24.0 - x, 24.0 - y]])
              for x, y in start]  # fmt: skip
    world = open_world(groups)
    state = world.start([0])
    state = type(state)(start[None], np.zeros((1, n, 2)), state.goal, state.waypoint,
                        state.goal_time, state.seed, state.step)  # fmt: skip
    state, worst = run_without_contact(world, state, 500)
    assert worst >= -1e-9
    np.testing.assert_allclose(state.position[0], 24.0 - start, atol=0.45)  # all arrived


def test_crowd_velocities_satisfy_every_half_plane_when_the_program_is_feasible():
    # 20 agents wandering in a 10 m square: every step, each agent's velocity is checked
    # against its half-planes (10 nearest neighbours, radii + margin), recomputed here; when
    # the program has no solution (scipy's linprog finds none in the 64-gon inside the speed
    # disc) it must penetrate no more than linprog's best (the paper's section V-C)
    orca = ORCA(perturbation=0.0)
    groups = [AgentGroup(count=20, behaviour="orca", speed=1.2, radius=0.3,
                         region=(5, 5, 15, 15))]  # fmt: skip
    world = World(OccupancyGrid(np.zeros((200, 200), bool), 0.1), agents=groups, orca=orca)
    state = world.start([3])
    angle = np.linspace(0, 2 * np.pi, 64, endpoint=False)
    disc = np.column_stack([np.cos(angle), np.sin(angle)])  # the 64-gon's edge normals
    inner = 1.2 * np.cos(np.pi / 64)  # its distance to its edges
    r = 0.3 + orca.margin
    infeasible = 0
    for _ in range(40):
        new = world.step(state, 0.1)
        p, v = state.position[0], state.velocity[0]
        for a in range(20):
            d = np.hypot(*(p - p[a]).T)
            near = [j for j in np.argsort(d) if j != a][:10]
            lines = [orca_half_plane([*p[a], *v[a], r], [*p[j], *v[j], r], 5.0, 0.1, 0.5)
                     for j in near]  # fmt: skip
            normals = np.array([n for n, _ in lines])
            offsets = np.array([c for _, c in lines])
            chosen = new.velocity[0, a]
            assert np.linalg.norm(chosen) <= 1.2 + 1e-9
            # maximise the least slack t: normals·x − offsets >= t inside the 64-gon
            best = linprog(
                [0, 0, -1],
                A_ub=np.vstack([np.column_stack([-normals, np.ones(10)]),
                                np.column_stack([disc, np.zeros(64)])]),
                b_ub=np.concatenate([-offsets, np.full(64, inner)]),
                bounds=[(None, None)] * 3,
            )  # fmt: skip
            slack = normals @ chosen - offsets
            if best.x[2] >= 1e-9:
                assert slack.min() >= -1e-9
            else:
                infeasible += 1
                assert slack.min() >= best.x[2] - 1e-6
        state = new
    assert 0 < infeasible < 40 * 20  # both cases were met


def test_two_streams_crossing_at_right_angles_never_touch():
    east = [AgentGroup(count=1, behaviour="orca", speed=1.0, radius=0.3,
                       region=(2.0, 10.0 + k, 3.0, 11.0 + k), waypoints=[[22.0, 10.5 + k]] * 2)
            for k in range(4)]  # fmt: skip
    north = [AgentGroup(count=1, behaviour="orca", speed=1.0, radius=0.3,
                        region=(10.0 + k, 2.0, 11.0 + k, 3.0), waypoints=[[10.5 + k, 22.0]] * 2)
             for k in range(4)]  # fmt: skip
    world = open_world(east + north)
    state, worst = run_without_contact(world, world.start([0]), 400)
    assert worst >= -1e-9
    assert np.all(state.position[0, :4, 0] > 21.0) and np.all(state.position[0, 4:, 1] > 21.0)
