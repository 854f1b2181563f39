"""World.cast: the exact lidar truth equals a brute-force geometric reference."""

import numpy as np
import pytest
import shapely

from wheelbase.errors import InputError
from wheelbase.planning import Footprint, OccupancyGrid
from wheelbase.sensors import scan_rays
from wheelbase.world import AgentGroup, Obstacles, RobotBodies, World, box_polygon

MAX_RANGE = 8.0


def grid() -> OccupancyGrid:
    occupied = np.zeros((80, 100), bool)  # 10 m × 8 m at 0.1 m, walls inside only
    occupied[30:34, 20:50] = True
    occupied[60:62, 70:95] = True
    return OccupancyGrid(occupied, 0.1, (-1.0, 0.5))


OBSTACLES = Obstacles(
    [box_polygon(6.0, 2.5, 1.0, 0.6, 0.4), [[1.0, 6.0], [2.5, 6.2], [1.4, 7.5], [1.6, 6.6]]],
    [[4.0, 6.5, 0.4], [7.5, 5.0, 0.25]],
)
FOOTPRINT = Footprint.rectangle(0.6, 0.4, 0.1)


def scene(batch: int = 2) -> tuple[World, object, RobotBodies]:
    groups = [AgentGroup(count=8, behaviour="wander", radius=0.3),
              AgentGroup(count=4, behaviour="straight", radius=0.2)]  # fmt: skip
    world = World(grid(), OBSTACLES, groups)
    state = world.start(np.arange(batch) + 20, [[0.5, 1.5, 0.5], [8.0, 7.0, 0.5]])
    for _ in range(5):
        state = world.step(state, 0.1)
    pose = np.stack([np.array([[0.5, 1.5, 0.3], [8.0, 7.0, 2.0], [3.0, 4.6, -1.0]])] * batch)
    pose[1:, :, 2] += 0.5
    return world, state, RobotBodies(pose, np.zeros((batch, 3, 2)), FOOTPRINT)


def reference(world, state, robots, pose, angles, b, own):
    """Brute force with shapely: the map's cells and its outside, the obstacles, the agents
    (closed-form circles) and the other robots' polygons, intersected with each beam."""
    g = world.grid
    x0, y0 = g.origin
    rows, cols = np.nonzero(g.occupied)
    r = g.resolution
    shapes = [shapely.box(x0 + c * r, y0 + i * r, x0 + (c + 1) * r, y0 + (i + 1) * r)
              for i, c in zip(rows, cols, strict=True)]  # fmt: skip
    ex = g.extent
    shapes.append(shapely.box(ex[0] - 50, ex[2] - 50, ex[1] + 50, ex[3] + 50).difference(
        shapely.box(ex[0], ex[2], ex[1], ex[3])))  # fmt: skip
    shapes += [shapely.Polygon(p) for p in OBSTACLES.polygons]
    for k in range(robots.pose.shape[1]):
        if k != own:
            x, y, th = robots.pose[b, k]
            c, s = np.cos(th), np.sin(th)
            poly = robots.polygon @ np.array([[c, s], [-s, c]]) + [x, y]
            shapes.append(shapely.Polygon(poly))
    solid = shapely.union_all(shapes)
    circles = np.vstack([OBSTACLES.discs,
                         np.column_stack([state.position[b], world.agent_radius])])  # fmt: skip
    out = []
    o = pose[:2]
    for angle in pose[2] + angles:
        u = np.array([np.cos(angle), np.sin(angle)])
        beam = shapely.LineString([o, o + MAX_RANGE * u])
        hit = beam.intersection(solid)
        best = MAX_RANGE if hit.is_empty else shapely.distance(shapely.Point(o), hit)
        e = o - circles[:, :2]
        bq = e @ u
        disc = bq**2 - (np.sum(e * e, 1) - circles[:, 2] ** 2)
        t = -bq - np.sqrt(np.maximum(disc, 0))
        ok = (disc >= 0) & (t >= 0)
        out.append(min(best, t[ok].min(initial=np.inf)))
    return np.array(out)


@pytest.mark.parametrize("beams", [180, 53])
def test_cast_equals_a_brute_force_reference(beams):
    world, state, robots = scene()
    angles = np.linspace(-np.pi, np.pi, beams, endpoint=False) + 0.0123
    sensors = robots.pose.reshape(-1, 3)
    world_index = np.repeat([0, 1], 3)
    own = np.tile([0, 1, 2], 2)
    ranges = world.cast(sensors, angles, MAX_RANGE, world_index, state, robots, own)
    for m in range(len(sensors)):
        expected = reference(world, state, robots, sensors[m], angles, world_index[m], own[m])
        np.testing.assert_allclose(ranges[m], expected, atol=1e-9)
    grid_only = scan_rays(world.grid, sensors[:, :2], sensors[:, 2], angles, MAX_RANGE)
    assert np.sum(ranges < grid_only - 1e-6) > beams // 4  # the world's objects were seen


def test_uneven_beams_are_cast_alike():
    world, state, robots = scene(1)
    angles = np.sort(np.random.default_rng(0).uniform(-np.pi, np.pi, 200))
    even = np.linspace(-np.pi, np.pi, 720, endpoint=False)
    pose = robots.pose[0]
    uneven = world.cast(pose, angles, MAX_RANGE, 0, state, robots, np.arange(3))
    fine = world.cast(pose, even, MAX_RANGE, 0, state, robots, np.arange(3))
    for m in range(3):
        expected = reference(world, state, robots, pose[m], angles[:40], 0, m)
        np.testing.assert_allclose(uneven[m, :40], expected, atol=1e-9)
    assert fine.shape == (3, 720)


def test_cast_equals_scan_rays_without_agents_or_obstacles():
    g = grid()
    world = World(g)
    state = world.start([0])
    poses = np.array([[0.5, 1.5, 0.3], [8.0, 7.0, 2.0], [3.0, 4.6, -1.0]])
    angles = np.linspace(-np.pi, np.pi, 360, endpoint=False)
    for method in ("fast", "exact"):
        np.testing.assert_array_equal(
            world.cast(poses, angles, MAX_RANGE, np.zeros(3, np.int64), state, method=method),
            scan_rays(g, poses[:, :2], poses[:, 2], angles, MAX_RANGE, method),
        )


def test_sensor_inside_something_reads_zero_and_never_sees_its_own_robot():
    world, state, robots = scene(1)
    angles = np.linspace(-np.pi, np.pi, 36, endpoint=False)
    inside_disc = np.array([[4.0, 6.5, 0.0]])
    assert np.all(world.cast(inside_disc, angles, MAX_RANGE, 0, state) == 0)
    on_robot = robots.pose[0, 1:2]
    seen = world.cast(on_robot, angles, MAX_RANGE, 0, state, robots, [-1])
    own = world.cast(on_robot, angles, MAX_RANGE, 0, state, robots, [1])
    assert np.all(seen == 0) and np.all(own > 0)


def test_cast_rejects_bad_rows():
    world, state, robots = scene(1)
    angles = np.zeros(3)
    with pytest.raises(InputError, match="world_index"):
        world.cast([[1.0, 1.0, 0.0]], angles, MAX_RANGE, [3], state)
    with pytest.raises(InputError, match="self_index"):
        world.cast([[1.0, 1.0, 0.0]], angles, MAX_RANGE, [0], state, robots, [7])
    with pytest.raises(InputError, match="sensor_poses"):
        world.cast([[np.nan, 1.0, 0.0]], angles, MAX_RANGE, [0], state)
