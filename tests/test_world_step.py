"""World.step: pure, reproducible, batched; each behaviour moves as documented; walls hold."""

import itertools
import math

import numpy as np
import pytest

from wheelbase.errors import ConfigError, InputError
from wheelbase.planning import Footprint, OccupancyGrid
from wheelbase.world import AgentGroup, Obstacles, RobotBodies, World, box_polygon
from wheelbase.world.statics import static_nearest


def room(size: int = 120, resolution: float = 0.1, wall: tuple | None = None) -> OccupancyGrid:
    """A square room of ``size`` cells with a one-cell wall around it (and one inside)."""
    occupied = np.zeros((size, size), bool)
    occupied[[0, -1], :] = occupied[:, [0, -1]] = True
    if wall is not None:
        occupied[wall] = True
    return OccupancyGrid(occupied, resolution)


def mixed_world() -> World:
    grid = room(wall=(slice(60, 62), slice(20, 70)))  # an interior wall
    obstacles = Obstacles([box_polygon(9.0, 3.0, 1.0, 0.6, 0.5)], [[3.0, 9.0, 0.4]])
    groups = [
        AgentGroup(count=6, behaviour="straight", speed=0.8),
        AgentGroup(count=6, behaviour="wander"),
        AgentGroup(count=3, behaviour="waypoints", waypoints=[[2, 2], [10, 2], [10, 10]]),
        AgentGroup(count=5, behaviour="social_force", reacts_to_robot=True),
        AgentGroup(count=5, behaviour="orca", reacts_to_robot=True),
    ]
    return World(grid, obstacles, groups)


def robots(batch: int) -> RobotBodies:
    pose = np.tile([6.0, 4.0, 0.3], (batch, 1, 1))
    return RobotBodies(pose, np.tile([0.2, 0.1], (batch, 1, 1)), Footprint.rectangle(0.5, 0.4))


def run(world, state, steps, dt=0.1, bodies=None):
    for _ in range(steps):
        state = world.step(state, dt, bodies)
    return state


def test_step_is_pure_and_reproducible():
    world = mixed_world()
    state = world.start([3, 4])
    bodies = robots(2)
    before = {name: getattr(state, name).copy() for name in ("position", "velocity", "goal")}
    a = world.step(state, 0.1, bodies)
    b = world.step(state, 0.1, bodies)
    assert a.equals(b)
    for name, value in before.items():
        np.testing.assert_array_equal(getattr(state, name), value)
    assert not state.position.flags.writeable  # the state cannot be changed in place
    mine = np.zeros((2, 1, 3))
    RobotBodies(mine, np.zeros((2, 1, 2)), Footprint.rectangle(0.5, 0.4))
    assert mine.flags.writeable  # a caller's own arrays are not frozen
    assert not a.equals(state) and a.step.tolist() == [1, 1]
    # reproducible from the seed alone, over a long run
    assert run(world, world.start([3, 4]), 60, bodies=bodies).equals(
        run(world, state, 60, bodies=bodies)
    )


def test_world_of_a_batch_equals_the_world_alone():
    world = mixed_world()
    together = run(world, world.start([11, 12, 13]), 40, bodies=robots(3))
    alone = run(world, world.start([12]), 40, bodies=robots(1))
    np.testing.assert_array_equal(together.position[1], alone.position[0])
    np.testing.assert_array_equal(together.velocity[1], alone.velocity[0])
    assert not np.array_equal(together.position[0], together.position[1])  # seeds differ


def test_agents_never_enter_walls_or_obstacles():
    world = mixed_world()
    state = world.start([0, 1])
    radius = world.agent_radius
    worst = np.inf
    for _ in range(300):
        state = world.step(state, 0.1, robots(2))
        for b in range(2):
            for a, (x, y) in enumerate(state.position[b]):
                worst = min(worst, static_nearest(world.statics, x, y, 1.0)[0] - radius[a])
    assert worst >= -1e-9


def test_straight_agents_reflect_and_keep_their_speed():
    obstacles = Obstacles([box_polygon(6.0, 6.0, 2.0, 1.0, 0.7)], [[3.0, 3.0, 0.5]])
    world = World(room(), obstacles, [AgentGroup(count=12, behaviour="straight", speed=1.3,
                                                  region=(0.5, 0.5, 11.0, 11.5))])  # fmt: skip
    state = world.start([5])
    reflected = 0
    for _ in range(400):
        new = world.step(state, 0.1)
        speed = np.hypot(*new.velocity[0].T)
        np.testing.assert_allclose(speed, 1.3, rtol=1e-12)
        reflected += int(np.sum(np.any(np.sign(new.velocity) != np.sign(state.velocity), -1)))
        state = new
        inside = state.position[0]
        assert np.all(inside >= 0.5 + 0.3 - 1e-9) and np.all(inside[:, 0] <= 11.0 - 0.3 + 1e-9)
    assert reflected > 50  # they did bounce


def test_wander_goals_lie_in_the_region_and_agents_head_for_them():
    region = (2.0, 3.0, 8.0, 7.0)
    world = World(room(), agents=[AgentGroup(count=10, behaviour="wander", region=region,
                                             speed=0.7)])  # fmt: skip
    state = world.start([9])
    goals = set()
    for _ in range(300):
        state = world.step(state, 0.1)
        g = state.goal[0]
        assert np.all((g[:, 0] >= 2.3) & (g[:, 0] <= 7.7) & (g[:, 1] >= 3.3) & (g[:, 1] <= 6.7))
        heading = g - state.position[0]
        far = np.hypot(*heading.T) > 0.5
        v = state.velocity[0][far]
        np.testing.assert_allclose(np.hypot(*v.T), 0.7, rtol=1e-9)
        cos = np.sum(v * heading[far], -1) / (0.7 * np.hypot(*heading[far].T))
        assert np.all(cos > 1 - 1e-9)  # straight at the goal (nothing in the way here)
        goals |= {tuple(np.round(x, 6)) for x in g}
    assert len(goals) > 30  # new goals on arrival


def test_waypoint_agents_cycle_their_loop():
    loop = [[2.0, 2.0], [9.0, 2.0], [9.0, 9.0], [2.0, 9.0]]
    world = World(room(), agents=[AgentGroup(count=2, behaviour="waypoints", waypoints=loop,
                                             speed=1.0, radius=0.2)])  # fmt: skip
    state = world.start([2])
    visits = []
    for _ in range(700):
        state = world.step(state, 0.1)
        k = int(state.waypoint[0, 0])
        if not visits or visits[-1] != k:
            visits.append(k)
        np.testing.assert_array_equal(state.goal[0, 0], loop[k])
    assert len(visits) >= 8  # two laps of 28 m at 1 m/s in 70 s
    assert all((b - a) % 4 == 1 for a, b in itertools.pairwise(visits))


def test_reactive_agents_avoid_a_robot_that_others_walk_through():
    # one agent walks at a robot standing in its way: a non-reactive one meets it, a
    # social-force or ORCA one keeps off its circumscribed disc
    for behaviour, reacts in (("waypoints", False), ("social_force", True), ("orca", True)):
        group = AgentGroup(count=1, behaviour="waypoints" if behaviour == "waypoints" else
                           behaviour, radius=0.3, speed=0.6, reacts_to_robot=reacts,
                           waypoints=[[10.0, 6.05], [2.0, 6.0]], region=(1, 5, 3, 7))  # fmt: skip
        world = World(room(), agents=[group])
        state = world.start([0])
        bodies = RobotBodies(np.array([[[6.0, 6.0, 0.0]]]), np.zeros((1, 1, 2)),
                             Footprint.rectangle(0.6, 0.6))  # fmt: skip
        closest = np.inf
        for _ in range(250):
            state = world.step(state, 0.1, bodies)
            closest = min(closest, math.hypot(*(state.position[0, 0] - [6.0, 6.0])))
        if reacts:
            assert closest >= 0.3 + bodies.radius - 0.05, behaviour
        else:
            assert closest < 0.1, behaviour


def test_step_rejects_bad_arguments():
    world = mixed_world()
    state = world.start([0])
    with pytest.raises(ConfigError, match="dt"):
        world.step(state, -0.1)
    with pytest.raises(ConfigError, match="dt"):
        world.step(state, 100.0)
    with pytest.raises(InputError, match="robots"):
        world.step(state, 0.1, robots(2))
    other = World(room(), agents=[AgentGroup(count=2)])
    with pytest.raises(InputError, match="agents"):
        other.step(state, 0.1)
