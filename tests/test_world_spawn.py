"""World.start: seeded, reproducible, never overlapping; clear errors when agents do not fit."""

import numpy as np
import pytest
import shapely
from hypothesis import given, settings
from hypothesis import strategies as st

from wheelbase.errors import ScenarioError
from wheelbase.planning import OccupancyGrid
from wheelbase.world import AgentGroup, Obstacles, World, box_polygon


def grid() -> OccupancyGrid:
    occupied = np.zeros((100, 100), bool)
    occupied[[0, -1], :] = occupied[:, [0, -1]] = True
    occupied[40:45, 10:60] = True
    return OccupancyGrid(occupied, 0.1)


OBSTACLES = Obstacles([box_polygon(7.0, 7.0, 1.5, 0.8, 0.4), [[1, 6], [3, 6], [2, 8]]],
                      [[8.0, 2.0, 0.5]])  # fmt: skip
KEEP = np.array([[1.0, 1.0, 0.4], [9.0, 9.0, 0.6]])


def solid() -> shapely.Geometry:
    """Everything an agent must not overlap, in shapely: walls (cells), the outside of the
    map, the obstacles and the keep-clear discs."""
    g = grid()
    rows, cols = np.nonzero(g.occupied)
    cells = shapely.box(cols * 0.1, rows * 0.1, (cols + 1) * 0.1, (rows + 1) * 0.1).tolist()
    outside = shapely.box(-5, -5, 15, 15).difference(shapely.box(0, 0, 10, 10))
    shapes = [*cells, outside, *(shapely.Polygon(p) for p in OBSTACLES.polygons)]
    shapes += [shapely.Point(x, y).buffer(r, 256) for x, y, r in OBSTACLES.discs]
    return shapely.union_all(shapes)


SOLID = solid()


@settings(max_examples=25, deadline=None)
@given(
    seed=st.integers(-(2**63), 2**63 - 1),
    counts=st.lists(st.integers(0, 40), min_size=1, max_size=3),
    radius=st.floats(0.1, 0.4),
)
def test_agents_start_apart_and_clear_of_everything(seed, counts, radius):
    groups = [AgentGroup(count=n, radius=radius * (1 + 0.3 * g), behaviour="wander")
              for g, n in enumerate(counts)]  # fmt: skip
    world = World(grid(), OBSTACLES, groups)
    try:
        state = world.start([seed], KEEP)
    except ScenarioError as error:
        # only a crowded room may refuse: the discs would cover > 20 % of its free 90 m²
        cover = sum(g.count * np.pi * g.radius**2 for g in groups) / 90.0
        assert cover > 0.2 and "count" in str(error)
        return
    p = state.position[0]
    r = world.agent_radius
    gaps = np.hypot(*(p[:, None] - p[None]).transpose(2, 0, 1)) - (r[:, None] + r[None])
    np.fill_diagonal(gaps, np.inf)
    assert np.all(gaps > 0)
    clearance = shapely.distance(SOLID, shapely.points(p))
    assert np.all(clearance >= r - 1e-9)
    keep = np.hypot(p[:, None, 0] - KEEP[:, 0], p[:, None, 1] - KEEP[:, 1]) - KEEP[:, 2]
    assert np.all(keep >= r[:, None])
    assert world.start([seed], KEEP).equals(state)  # reproducible


def test_seeds_give_different_crowds_and_regions_hold():
    group = AgentGroup(count=15, behaviour="straight", region=(1.0, 5.0, 9.0, 9.5))
    world = World(grid(), agents=[group])
    state = world.start([1, 2])
    assert not np.allclose(state.position[0], state.position[1])
    p = state.position
    assert np.all((p[..., 0] >= 1.3) & (p[..., 0] <= 8.7) & (p[..., 1] >= 5.3) & (p[..., 1] <= 9.2))


def test_a_dense_crowd_fills_the_lattice_when_random_addition_jams():
    # 14 × 14 m region of 0.3 m agents: random sequential addition jams near 55 % cover,
    # the lattice holds more
    open_room = OccupancyGrid(np.zeros((200, 200), bool), 0.1)
    region = (3.0, 3.0, 17.0, 17.0)
    world = World(open_room, agents=[AgentGroup(count=330, radius=0.3, region=region)])
    state = world.start([0])
    p = state.position[0]
    gaps = np.hypot(*(p[:, None] - p[None]).transpose(2, 0, 1))
    np.fill_diagonal(gaps, np.inf)
    assert gaps.min() >= 0.6
    cover = 330 * np.pi * 0.09 / (14.0 * 14.0)
    assert cover > 0.47  # beyond what random addition alone reaches with 64 tries per agent


def test_too_many_agents_name_the_key():
    groups = [AgentGroup(count=5, behaviour="wander"),
              AgentGroup(count=900, radius=0.2, region=(0, 0, 5, 4))]  # fmt: skip
    world = World(grid(), agents=groups)
    with pytest.raises(ScenarioError, match=r"world\.agents\[1\]\.count: 900 agents .* do not fit"):
        world.start([0])


def test_obstacle_on_a_start_names_the_entry():
    world = World(grid(), OBSTACLES)
    with pytest.raises(ScenarioError, match=r"disc 0 overlaps the goal of robot 0"):
        world.start([0], [[8.2, 2.0, 0.3]], labels=["goal of robot 0"])
    with pytest.raises(ScenarioError, match=r"polygon 0 overlaps the keep-clear disc 1"):
        world.start([0], [[5.0, 5.0, 0.1], [7.0, 7.2, 0.1]])
    world.start([0], [[8.0, 2.9, 0.3]])  # 0.4 m from the disc's rim: clear
