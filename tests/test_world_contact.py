"""World.collisions and World.distances against shapely's exact geometry."""

import numpy as np
import shapely

from wheelbase.planning import Footprint, OccupancyGrid
from wheelbase.world import AgentGroup, Obstacles, RobotBodies, World, box_polygon

OBSTACLES = Obstacles([box_polygon(5.0, 5.0, 1.2, 0.8, 0.6),
                       [[1.0, 7.0], [3.0, 7.0], [3.0, 9.0], [2.2, 7.6], [1.0, 9.0]]],
                      [[8.0, 2.0, 0.5]])  # fmt: skip
FOOTPRINT = Footprint.rectangle(0.7, 0.5, 0.15)


def placed(pose) -> shapely.Polygon:
    c, s = np.cos(pose[2]), np.sin(pose[2])
    return shapely.Polygon(FOOTPRINT.polygon @ np.array([[c, s], [-s, c]]) + pose[:2])


def test_distances_and_contacts_equal_shapely():
    world = World(OccupancyGrid(np.zeros((100, 100), bool), 0.1), OBSTACLES,
                  [AgentGroup(count=25, behaviour="wander", radius=0.35)])  # fmt: skip
    state = world.step(world.start([5, 6]), 0.1)
    rng = np.random.default_rng(1)
    poses = np.column_stack([rng.uniform(0.5, 9.5, (300, 2)), rng.uniform(-np.pi, np.pi, 300)])
    world_index = rng.integers(0, 2, 300)
    fleet = np.stack([poses[:3], poses[3:6]])  # robots 0..2 of each world are the first rows
    robots = RobotBodies(fleet, rng.normal(0, 0.3, (2, 3, 2)), FOOTPRINT)
    self_index = np.full(300, -1)
    self_index[:3] = [0, 1, 2]
    world_index[:3] = 0
    world_index[3:6] = 1
    self_index[3:6] = [0, 1, 2]
    got = world.distances(poses, FOOTPRINT, world_index, state, robots, self_index)
    hits = world.collisions(poses, FOOTPRINT, world_index, state, robots, self_index)
    statics = shapely.union_all([shapely.Polygon(p) for p in OBSTACLES.polygons]
                                + [shapely.Point(x, y).buffer(r, 2048)
                                   for x, y, r in OBSTACLES.discs])  # fmt: skip
    for m, pose in enumerate(poses):
        body = placed(pose)
        b = world_index[m]
        obstacle = shapely.distance(body, statics)
        # the disc as a 2048-gon is within 0.5 (1 − cos(π/2048)) of the circle: 6e-7 m
        assert abs(got.obstacle[m] - obstacle) < 1e-6
        centres = shapely.points(state.position[b])
        agent = np.maximum(shapely.distance(body, centres) - world.agent_radius, 0.0)
        np.testing.assert_allclose(got.agent[m], agent.min(), atol=1e-12)
        assert agent[got.agent_index[m]] == agent.min()
        np.testing.assert_array_equal(got.agent_velocity[m], state.velocity[b, got.agent_index[m]])
        towards = state.position[b, got.agent_index[m]] - pose[:2]
        np.testing.assert_allclose(got.agent_direction[m], towards / np.linalg.norm(towards))
        others = [k for k in range(3) if k != self_index[m]]
        robot = [shapely.distance(body, placed(robots.pose[b, k])) for k in others]
        np.testing.assert_allclose(got.robot[m], min(robot), atol=1e-12)
        touching = obstacle < 1e-9 or agent.min() == 0 or min(robot) == 0
        assert hits[m] == touching
    assert 10 < hits.sum() < 290  # both outcomes are well represented


def test_no_obstacles_no_agents_no_robots_means_no_contact():
    world = World(OccupancyGrid(np.zeros((20, 20), bool), 0.1))
    state = world.start([0])
    d = world.distances([[1.0, 1.0, 0.0]], FOOTPRINT, [0], state)
    assert d.obstacle[0] == np.inf and d.agent[0] == np.inf and d.agent_index[0] == -1
    assert not world.collisions([[1.0, 1.0, 0.0]], FOOTPRINT, [0], state)[0]
    position, velocity = world.agent_truth(state)
    assert position.shape == velocity.shape == (1, 0, 2)
