"""Frontier detection and choice on hand-made grids (exact expected frontiers)."""

import numpy as np
import pytest

from wheelbase.errors import ConfigError
from wheelbase.mapping.frontiers import choose_frontier, find_frontiers, frontier_mask
from wheelbase.planning import OccupancyGrid
from wheelbase.planning.astar import dijkstra


def grid_of(rows: list[str], resolution: float = 0.5) -> OccupancyGrid:
    """'#' occupied, '?' unknown, '.' free; the first string is the top row."""
    chars = np.array([list(row) for row in rows[::-1]])
    unknown = chars == "?"
    return OccupancyGrid((chars == "#") | unknown, resolution, (0.0, 0.0), unknown)


UNKNOWN_CORNER = [
    "######",
    "#...??",
    "#...??",
    "#.....",
    "######",
]  # fmt: skip
"""A room whose upper right corner is unknown."""


def test_frontier_cells_are_free_cells_with_an_unknown_edge_neighbour():
    grid = grid_of(UNKNOWN_CORNER)
    expected = np.zeros(grid.shape, bool)
    # row index 0 is the bottom row: the '?' block sits in rows 2-3, columns 4-5
    expected[3, 3] = expected[2, 3] = True  # left of the block
    expected[1, 4] = expected[1, 5] = True  # below it; (1, 5) also touches the map edge
    assert np.array_equal(frontier_mask(grid), expected)


def test_diagonal_contact_is_not_a_frontier_but_joins_a_frontier():
    grid = grid_of([
        "#####",
        "#..?#",
        "#...#",
        "#####",
    ])  # fmt: skip
    mask = frontier_mask(grid)
    assert sorted(map(tuple, np.argwhere(mask))) == [(1, 3), (2, 2)]
    (one,) = find_frontiers(grid)
    assert len(one.cells) == 2 and one.size == pytest.approx(1.0)  # 8-connected: one frontier


def test_the_map_edge_counts_as_unknown():
    grid = grid_of(["...", "..."])
    assert frontier_mask(grid).sum() == 6 - 0  # every cell touches the edge
    inner = grid_of(["#####", "#...#", "#####"])
    assert not frontier_mask(inner).any()


def test_frontiers_are_split_by_connectivity_filtered_by_size_and_sorted():
    grid = grid_of([
        "#########",
        "?.......?",
        "?.......?",
        "#.......#",
        "#########",
    ])  # fmt: skip
    found = find_frontiers(grid)
    assert [len(f.cells) for f in found] == [2, 2]
    assert [tuple(f.cells[:, 1]) for f in found] == [(1, 1), (7, 7)]
    assert find_frontiers(grid, min_size=3) == []
    left = found[0]
    assert left.centroid == pytest.approx([0.75, 1.5])


def test_choice_ranks_by_distance_and_size_and_honours_the_blacklist():
    grid = grid_of([
        "#########",
        "?.......?",
        "?.......?",
        "#.......#",
        "#########",
    ])  # fmt: skip
    found = find_frontiers(grid)
    distance = dijkstra(grid, (2, 2))  # the robot near the left frontier
    ranked = choose_frontier(found, distance, 0.5)
    assert [tuple(f.cells[0]) for _, f, _ in ranked] == [(2, 1), (2, 7)]
    cost, frontier, cell = ranked[0]
    assert tuple(cell) == (2, 1) or tuple(cell) == (3, 1)
    assert cost == pytest.approx(3.0 * distance[cell[0], cell[1]] - 1.0 * frontier.size)
    banned = choose_frontier(found, distance, 0.5, blacklist=[[0.75, 1.5]])
    assert [tuple(f.cells[0]) for _, f, _ in banned] == [(2, 7)]
    walled = np.where(np.arange(9)[None, :] >= 4, np.inf, distance)  # the right one unreachable
    only = choose_frontier(found, walled, 0.5, approach=0.6)
    assert [tuple(f.cells[0]) for _, f, _ in only] == [(2, 1)]


def test_bad_input_errors():
    grid = grid_of(["...", "..."])
    with pytest.raises(ConfigError, match="min_size"):
        find_frontiers(grid, 0)
    with pytest.raises(ConfigError, match="resolution"):
        choose_frontier([], np.zeros((2, 3)), 0.0)
    with pytest.raises(ConfigError, match="distance"):
        choose_frontier([], np.zeros(3), 0.5)
    with pytest.raises(ConfigError, match="targets"):
        choose_frontier([], np.zeros((2, 3)), 0.5, targets=np.ones((3, 3), bool))


def test_a_walls_fringe_makes_no_frontier_but_open_unknown_space_does():
    # a wall along the top with a one-cell unknown strip under it (its blurred surface), and
    # an opening to unknown space on the right; 0.05 m cells
    grid = grid_of([
        "###########?????",
        "#???????????????",
        "#..........?????",
        "#..........?????",
        "#..........?????",
        "#...............",
        "################",
    ], resolution=0.05)  # fmt: skip
    strip = frontier_mask(grid)[4, 1:11]
    assert strip.all()  # without a fringe: the whole strip under the wall is a frontier
    mask = frontier_mask(grid, fringe=0.1)
    assert not mask[4, 1:9].any()  # its cells' unknown neighbour lies 0.05 m from the wall
    # the opening: free cells beside unknown cells farther than 0.1 m from every wall cell
    assert mask[3:5, 10].all()
    # (2, 10)'s unknown neighbour lies 0.1 m above the bottom wall: the fringe's end
    assert not mask[2, 10] and frontier_mask(grid)[2, 10]
    assert frontier_mask(grid, fringe=0.0).sum() > mask.sum()
    with pytest.raises(ConfigError, match="fringe"):
        frontier_mask(grid, fringe=-0.1)


def test_the_fringe_is_a_distance_so_coarse_cells_keep_their_frontiers():
    # at 0.5 m cells no unknown cell lies within 0.1 m of a wall's centre: nothing changes
    grid = grid_of(UNKNOWN_CORNER)
    assert np.array_equal(frontier_mask(grid, fringe=0.1), frontier_mask(grid))
