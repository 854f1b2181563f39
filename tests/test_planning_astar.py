"""A* and Dijkstra: Moving AI optimal lengths, cross-checks, the turtlebot3 map."""

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from shared_data import DATA as SHARED_DATA
from shared_data import absent
from wheelbase.errors import ConfigError, InputError, PlanningError
from wheelbase.planning import (
    OccupancyGrid,
    astar,
    dijkstra,
    read_movingai_map,
    read_movingai_scenarios,
    read_ros_yaml,
)

SHARED = SHARED_DATA
ARENA = SHARED / "movingai" / "arena.map"
TB3 = SHARED / "maps" / "turtlebot3_world.yaml"


@pytest.mark.skipif(not ARENA.exists(), reason=absent(ARENA))
def test_movingai_arena_all_scenarios_optimal():
    grid = read_movingai_map(ARENA)
    scenarios = read_movingai_scenarios(ARENA.with_name("arena.map.scen"))
    assert len(scenarios) == 130
    for sc in scenarios:
        start, goal = sc.grid_cells()
        result = astar(grid, start, goal)
        assert result.success
        assert result.length == pytest.approx(sc.optimal_length, abs=1e-6), sc


def _check_path_valid(grid, result):
    cells = result.cells
    assert not grid.occupied[cells[:, 0], cells[:, 1]].any()
    steps = np.diff(cells, axis=0)
    assert np.all(np.abs(steps).max(1) == 1)
    diag = np.all(steps != 0, axis=1)
    for (r, c), (dr, dc) in zip(cells[:-1][diag], steps[diag], strict=True):
        assert not grid.occupied[r + dr, c] and not grid.occupied[r, c + dc]  # no corner cut
    length = np.sum(np.where(diag, math.sqrt(2), 1.0)) * grid.resolution
    assert result.length == pytest.approx(length, rel=1e-12)


@settings(max_examples=30, deadline=None)
@given(st.integers(0, 2**31 - 1), st.sampled_from([4, 8]))
def test_astar_matches_dijkstra_on_random_maps(seed, connectivity):
    rng = np.random.default_rng(seed)
    occ = rng.random((25, 30)) < 0.25
    occ[0, 0] = occ[24, 29] = False
    grid = OccupancyGrid.from_array(occ, 0.2)
    cost = dijkstra(grid, (24, 29), connectivity)
    result = astar(grid, (0, 0), (24, 29), connectivity)
    assert result.success == np.isfinite(cost[0, 0])
    if result.success:
        assert result.length == pytest.approx(cost[0, 0], rel=1e-12)
        _check_path_valid(grid, result)
    else:
        assert math.isinf(result.length) and len(result.cells) == 0


def test_no_corner_cutting_and_octile_length():
    occ = np.zeros((3, 3), bool)
    occ[1, 0] = True
    grid = OccupancyGrid.from_array(occ, 1.0)
    # (0,0) -> (1,1) diagonally would cut the corner of (1,0): 2 straight moves instead
    assert astar(grid, (0, 0), (1, 1)).length == pytest.approx(2.0)
    open_grid = OccupancyGrid.from_array(np.zeros((10, 10), bool), 0.5)
    assert astar(open_grid, (0, 0), (3, 9)).length == pytest.approx(0.5 * (6 + 3 * math.sqrt(2)))


def test_astar_errors():
    occ = np.zeros((5, 5), bool)
    occ[2, 2] = True
    grid = OccupancyGrid.from_array(occ, 1.0)
    with pytest.raises(PlanningError, match="start_cell"):
        astar(grid, (2, 2), (0, 0))
    with pytest.raises(PlanningError, match="outside"):
        astar(grid, (0, 0), (9, 0))
    with pytest.raises(ConfigError, match="connectivity"):
        astar(grid, (0, 0), (4, 4), connectivity=6)
    with pytest.raises(InputError, match="integer"):
        astar(grid, (0.5, 0), (4, 4))


@pytest.mark.skipif(not TB3.exists(), reason=absent(TB3))
def test_turtlebot3_world_plan_across():
    with pytest.warns(UserWarning):
        grid = read_ros_yaml(TB3)
    robot = grid.inflate(0.105)  # turtlebot3 burger radius
    start = robot.world_to_cell([-2.0, -0.5])
    goal = robot.world_to_cell([1.8, 0.5])
    result = astar(robot, start, goal)
    assert result.success
    _check_path_valid(robot, result)
    assert result.length == pytest.approx(dijkstra(robot, goal)[tuple(start)], rel=1e-12)
    assert result.length >= math.dist(result.points[0], result.points[-1])
    assert np.all(grid.clearance(result.points) >= 0.105 - math.sqrt(2) * 0.05 - 1e-9)
