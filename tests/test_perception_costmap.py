"""The layered costmap: Nav2's inflation, exact ray clearing, marking, the rolling window and the
believed grid, checked against independent references (SciPy's distance transform with the
formula written out here, single-cell ray casts of wheelbase.sensors)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy import ndimage

from perception_scenes import disc_ranges, room
from wheelbase.errors import ConfigError, InputError
from wheelbase.perception import (
    INSCRIBED,
    LETHAL,
    UNKNOWN,
    Costmap,
    CostmapSpec,
    CostmapState,
    LayeredCostmap,
    inflation_cost,
    update_costmap,
)
from wheelbase.planning import HybridAStar, OccupancyGrid
from wheelbase.sensors import cast_rays

BEAMS = -math.pi + 2.0 * math.pi * np.arange(360) / 360


def nav2_cost(d: np.ndarray, inscribed: float, k: float, radius: float) -> np.ndarray:
    """Nav2's InflationLayer::computeCost, written out independently of the library."""
    out = np.zeros(d.shape, np.uint8)
    band = (d > inscribed) & (d <= radius + 1e-12)
    out[band] = np.floor(252.0 * np.exp(-k * (d[band] - inscribed)))
    out[(d > 0) & (d <= inscribed + 1e-12)] = 253
    out[d == 0] = 254
    return out


def reference_cost(layers: LayeredCostmap, obstacle: np.ndarray) -> np.ndarray:
    """The master cost from scratch: layers combined (Nav2's updateWithMax), SciPy's exact
    Euclidean distance transform, the formula, unknown kept unless inscribed."""
    static = layers.static
    combined = np.where(
        obstacle == UNKNOWN,
        static,
        np.where(static == UNKNOWN, obstacle, np.maximum(static, obstacle)),
    )
    lethal = combined == LETHAL
    if lethal.any():
        d = ndimage.distance_transform_edt(~lethal) * layers.resolution
    else:
        d = np.full(lethal.shape, np.inf)
    spec = layers.spec
    cost = nav2_cost(d, layers.inscribed_radius, spec.cost_scaling_factor, spec.inflation_radius)
    cost = np.where((combined == UNKNOWN) & (cost < INSCRIBED), UNKNOWN, cost)
    return np.where(lethal, LETHAL, cost).astype(np.uint8)


def test_inflation_costs_equal_nav2_formula_at_sampled_distances():
    occupied = np.zeros((41, 41), bool)
    occupied[20, 20] = True
    layers = LayeredCostmap.from_map(
        CostmapSpec(inflation_radius=0.55, cost_scaling_factor=3.0),
        OccupancyGrid(occupied, 0.05),
        0.17,
    )
    cost = layers.initial_cost
    # by hand: d = 0.25 m (3, 4 cells): ⌊252 e^(−3·0.08)⌋ = ⌊198.23⌋; d = 0.55 m (11 cells,
    # on the radius): ⌊252 e^(−3·0.38)⌋ = ⌊80.59⌋; beyond it nothing
    assert cost[20, 20] == LETHAL
    assert cost[23, 24] == 198
    assert cost[20, 31] == 80
    assert cost[20, 32] == 0 and cost[28, 28] == 0  # 0.6 m, 0.566 m
    assert cost[23, 21] == INSCRIBED  # 0.158 m <= 0.17 m
    i, j = np.indices(occupied.shape)
    d = np.hypot(i - 20, j - 20) * 0.05
    assert np.array_equal(cost, nav2_cost(d, 0.17, 3.0, 0.55))
    assert np.array_equal(inflation_cost(d, 0.17, 3.0, 0.55, 0.05), nav2_cost(d, 0.17, 3.0, 0.55))


@pytest.mark.parametrize("track_unknown", [False, True])
def test_inflation_of_a_random_map_equals_the_exact_distance_transform(track_unknown):
    rng = np.random.default_rng(3)
    values = rng.random((70, 90))
    grid = OccupancyGrid.from_array(np.where(values < 0.03, np.nan, values > 0.96), 0.1)
    layers = LayeredCostmap.from_map(
        CostmapSpec(inflation_radius=0.7, track_unknown=track_unknown), grid, 0.25
    )
    expected = reference_cost(layers, np.full(layers.shape, layers._initial_obstacle, np.uint8))
    assert np.array_equal(layers.initial_cost, expected)
    assert (layers.static == UNKNOWN).any() == track_unknown


@pytest.mark.parametrize("track_unknown", [False, True])
def test_incremental_inflation_equals_inflating_everything_again(track_unknown):
    grid = room(8.0, 6.0, 0.05)
    layers = LayeredCostmap.from_map(CostmapSpec(track_unknown=track_unknown), grid, 0.2)
    rng = np.random.default_rng(7)
    state = layers.initial_state(2)
    discs = np.column_stack([rng.uniform(1, 7, 6), rng.uniform(1, 5, 6), rng.uniform(0.1, 0.4, 6)])
    velocity = rng.normal(0.0, 1.0, (6, 2))
    for step in range(25):
        discs[:, :2] += 0.1 * velocity
        poses = np.column_stack([rng.uniform(1, 7, 2), rng.uniform(1, 5, 2), rng.uniform(-3, 3, 2)])
        ranges = disc_ranges(grid, poses, BEAMS, 6.0, discs)
        state = update_costmap(layers, state, poses, BEAMS, ranges, 6.0)
        for robot in range(2):
            expected = reference_cost(layers, state.obstacle[robot])
            assert np.array_equal(state.cost[robot], expected), (step, robot)


def test_a_box_is_marked_where_it_is_and_stays():
    grid = room(10.0, 10.0, 0.05)
    truth = grid.occupied.copy()
    truth[100:112, 120:130] = True  # a 0.5 m × 0.6 m box at x 6.0–6.5, y 5.0–5.6
    world = OccupancyGrid(truth, 0.05)
    layers = LayeredCostmap.from_map(CostmapSpec(), grid, 0.2)
    state = layers.initial_state(1)
    seen = np.zeros(truth.shape, bool)
    for pose in ([4.5, 5.3, 0.0], [6.2, 3.5, 1.0], [7.8, 5.5, 3.0], [6.3, 7.0, -1.5]):
        pose = np.array([pose])
        ranges = disc_ranges(world, pose, BEAMS, 8.0, np.empty((0, 3)))
        state = update_costmap(layers, state, pose, BEAMS, ranges, 8.0)
        marked = state.obstacle[0] == LETHAL
        assert np.all(truth[marked]), "a mark where nothing is"
        assert np.all(marked[seen]), "a mark of the box was cleared"
        seen |= marked & ~grid.occupied
    box = np.zeros(truth.shape, bool)
    box[100:112, 120:130] = True
    perimeter = box & ~ndimage.binary_erosion(box)
    assert seen[perimeter].mean() > 0.9  # its four sides seen
    assert not seen[box & ~perimeter].any()
    master = layers.master(state, 0)
    assert np.all(master.cost_at([[6.25, 5.01], [6.0, 5.0], [6.49, 5.3]]) == LETHAL)
    assert master.cost_at([6.25, 5.3]) == INSCRIBED  # inside, 0.2 m from its sides


def test_a_walker_crossing_leaves_no_trail():
    grid = room(10.0, 10.0, 0.05)
    layers = LayeredCostmap.from_map(CostmapSpec(), grid, 0.2)
    state = layers.initial_state(1)
    sensor = np.array([[5.0, 5.0, 0.3]])
    radius = 0.3
    ever = np.zeros(grid.shape, bool)
    centres = grid.cell_to_world(np.indices(grid.shape).transpose(1, 2, 0))
    for step in range(61):  # 6 s at 10 Hz, 1 m/s from (3.5, 2) to (3.5, 8)
        walker = np.array([[3.5, 2.0 + 0.1 * step, radius]])
        ranges = disc_ranges(grid, sensor, BEAMS, 8.0, walker)
        state = update_costmap(layers, state, sensor, BEAMS, ranges, 8.0)
        marks = (state.obstacle[0] == LETHAL) & ~grid.occupied
        ever |= marks
        # every mark off the walls is a cell the walker now touches, or one in its shadow
        # (no beam reaches it): within half a cell diagonal of the disc, or of the segment
        # from the sensor to the cell centre being blocked by it
        reach = radius + 0.05 / math.sqrt(2) + 1e-9
        cells = centres[marks]
        touching = np.hypot(*(cells - walker[0, :2]).T) <= reach
        ray = cells - sensor[0, :2]
        along = np.clip(((walker[0, :2] - sensor[0, :2]) @ ray.T) / np.sum(ray**2, 1), 0, 1)
        nearest = sensor[0, :2] + along[:, None] * ray
        shadowed = np.hypot(*(nearest - walker[0, :2]).T) <= reach
        assert np.all(touching | shadowed), step
    assert ever.sum() > 100  # it was seen all along
    assert not ((state.obstacle[0] == LETHAL) & ~grid.occupied).any()  # out of range now
    assert np.array_equal(state.cost[0], layers.initial_cost)


def _cells_entered(grid: OccupancyGrid, origins, angles, lengths) -> list[set]:
    """Cells each ray enters before its length, by the exact cast of wheelbase.sensors: cell c
    is entered iff a grid where only c is occupied stops the ray before the length and before
    the ray leaves the map (which the empty grid's cast gives)."""
    empty = cast_rays(grid, origins, angles, 10.0, "exact")
    limit = np.minimum(lengths, empty)
    cells = [set() for _ in angles]
    for i, j in np.ndindex(grid.shape):
        single = np.zeros(grid.shape, bool)
        single[i, j] = True
        probe = OccupancyGrid(single, grid.resolution, grid.origin)
        for ray in np.flatnonzero(cast_rays(probe, origins, angles, 10.0, "exact") < limit):
            cells[ray].add((i, j))
    return cells


def test_ray_traced_cells_equal_the_exact_traversal():
    grid = OccupancyGrid(np.zeros((13, 15), bool), 0.1, (-1.0, -0.5))
    layers = LayeredCostmap.from_map(CostmapSpec(raytrace_max_range=0.9), grid, 0.05)
    full = np.full((1, *grid.shape), LETHAL, np.uint8)
    state = CostmapState(full, np.full_like(full, LETHAL))
    rng = np.random.default_rng(11)
    angles = np.array([0.0, math.pi / 2, math.pi, math.pi / 4, *rng.uniform(-math.pi, math.pi, 8)])
    origins = grid.cell_to_world([6, 7]) + np.where(
        np.arange(12)[:, None] > 3, rng.uniform(-0.05, 0.05, (12, 2)), 0.0
    )
    # no return: clears to raytrace_max_range; a return at 0.6 m: clears what the beam enters
    # before it and marks the cell it is in
    free = _cells_entered(grid, origins, angles, np.full(12, 0.9))
    short = _cells_entered(grid, origins, angles, np.full(12, 0.6))
    for k, angle in enumerate(angles):
        pose = np.array([[*origins[k], angle]])
        after = update_costmap(layers, state, pose, [0.0], [[np.inf]], 5.0)
        cleared = {tuple(c) for c in np.argwhere(after.obstacle[0] == 0)}
        assert cleared == free[k], angle
        after = update_costmap(layers, state, pose, [0.0], [[0.6]], 5.0)
        cleared = {tuple(c) for c in np.argwhere(after.obstacle[0] == 0)}
        end = origins[k] + 0.6 * np.array([math.cos(angle), math.sin(angle)])
        assert cleared == short[k] - {tuple(grid.world_to_cell(end))}, angle
        assert after.obstacle[0][tuple(grid.world_to_cell(end))] == LETHAL


def test_nan_readings_neither_clear_nor_mark_and_max_range_ones_only_clear():
    grid = room(6.0, 6.0, 0.05)
    spec = CostmapSpec(obstacle_max_range=5.0, raytrace_max_range=6.0)
    layers = LayeredCostmap.from_map(spec, grid, 0.2)
    state = layers.initial_state(1)
    pose = np.array([[3.0, 3.0, 0.0]])
    box = np.array([[4.0, 3.0, 0.2]])
    state = update_costmap(layers, state, pose, BEAMS, disc_ranges(grid, pose, BEAMS, 8.0, box),
                           8.0)  # fmt: skip
    marked = state.obstacle[0] == LETHAL
    assert marked[55:65, 74:80].any()
    blind = update_costmap(layers, state, pose, BEAMS, np.full((1, 360), np.nan), 8.0)
    assert np.array_equal(blind.obstacle, state.obstacle)
    empty = update_costmap(layers, state, pose, BEAMS, np.full((1, 360), 8.0), 8.0)
    assert not (empty.obstacle[0] == LETHAL).any()  # the walls were cleared too: off the layer
    assert np.array_equal(empty.cost[0], layers.initial_cost)
    short = update_costmap(layers, state, pose, BEAMS, np.full((1, 360), 2.0), 2.0)
    # readings of 2.0 = max_range are no returns: nothing new marked, the box (1 m) cleared,
    # the walls (3 m) beyond the clearing
    now = short.obstacle[0] == LETHAL
    assert not now[55:65, 74:80].any() and np.all(marked[now]) and now.any()


def test_rolling_window_is_the_master_sub_array():
    grid = room(6.0, 4.0, 0.05)
    layers = LayeredCostmap.from_map(CostmapSpec(window=1.5), grid, 0.2)
    state = layers.initial_state(2)
    pose = np.array([[1.0, 1.0, 0.0], [4.0, 3.0, 2.0]])
    ranges = disc_ranges(grid, pose, BEAMS, 8.0, np.array([[2.0, 1.5, 0.3]]))
    state = update_costmap(layers, state, pose, BEAMS, ranges, 8.0)
    master = layers.master(state, 1)
    rng = np.random.default_rng(5)
    for xy in [(3.0, 2.0), (0.2, 0.1), (5.9, 3.95), (-0.5, 2.0), *rng.uniform(0, 6, (5, 2))]:
        window = layers.rolling_window(state, 1, xy)
        n = layers.window_cells
        assert window.shape == (n, n) == (30, 30)
        i0, j0 = master.world_to_cell(np.asarray(window.origin) + 0.025)
        assert tuple(window.world_to_cell(xy)) == (n // 2, n // 2)
        for a, b in np.ndindex(n, n):
            i, j = i0 + a, j0 + b
            inside = 0 <= i < master.shape[0] and 0 <= j < master.shape[1]
            assert window.cost[a, b] == (master.cost[i, j] if inside else LETHAL)
        points = np.asarray(window.origin) + rng.uniform(0, 1.5, (50, 2))
        assert np.array_equal(window.cost_at(points), master.cost_at(points))


def test_the_believed_grid_blocks_a_corridor_once_a_box_is_seen():
    grid = room(8.0, 3.0, 0.05)
    occupied = grid.occupied.copy()
    occupied[:, 79:81] = True
    occupied[26:34, 79:81] = False  # a 0.4 m doorway in a wall across the room at x = 4 m
    grid = OccupancyGrid(occupied, 0.05)
    truth = occupied.copy()
    truth[25:35, 81:84] = True  # a box just behind the doorway
    layers = LayeredCostmap.from_map(CostmapSpec(), grid, 0.1)
    state = layers.initial_state(1)
    start, goal = (2.0, 1.5, 0.0), (6.0, 1.5, 0.0)

    def plan(believed: OccupancyGrid):
        return HybridAStar(believed, (0.2, 0.2), 0.3, headings=36, time_limit=5.0).plan(start, goal)

    assert plan(layers.master(state, 0).to_occupancy_grid()).success
    pose = np.array([start])
    ranges = disc_ranges(OccupancyGrid(truth, 0.05), pose, BEAMS, 8.0, np.empty((0, 3)))
    state = update_costmap(layers, state, pose, BEAMS, ranges, 8.0)
    believed = layers.master(state, 0).to_occupancy_grid()
    assert believed.occupied[28, 81] and not grid.occupied[28, 81]
    assert not plan(believed).success


def test_batched_update_with_an_index_equals_one_robot_at_a_time():
    grid = room(6.0, 6.0, 0.05)
    layers = LayeredCostmap.from_map(CostmapSpec(), grid, 0.2)
    discs = np.array([[2.0, 2.0, 0.3], [4.0, 4.5, 0.2]])
    poses = np.array([[3.0, 3.0, 0.1], [1.5, 4.0, -2.0]])
    ranges = disc_ranges(grid, poses, BEAMS, 8.0, discs)
    state = layers.initial_state(3)
    both = update_costmap(layers, state, poses, BEAMS, ranges, 8.0, index=[2, 0])
    for row, scan in ((2, 0), (0, 1)):
        one = update_costmap(layers, layers.initial_state(1), poses[scan : scan + 1], BEAMS,
                             ranges[scan : scan + 1], 8.0)  # fmt: skip
        assert np.array_equal(both.obstacle[row], one.obstacle[0])
        assert np.array_equal(both.cost[row], one.cost[0])
        assert (one.obstacle[0] == LETHAL).any()
    assert np.array_equal(both.cost[1], layers.initial_cost)


_GRID = room(4.0, 4.0, 0.1)
_LAYERS = LayeredCostmap.from_map(CostmapSpec(), _GRID, 0.15)
_READING = st.one_of(st.floats(0.0, 6.0), st.just(np.nan), st.just(np.inf))


@settings(max_examples=25, deadline=None)
@given(
    st.lists(st.floats(0.2, 3.8), min_size=2, max_size=2),
    st.floats(-4.0, 4.0),
    st.lists(_READING, min_size=12, max_size=12),
)
def test_update_is_pure(xy, heading, readings):
    angles = np.linspace(-math.pi, math.pi, 12, endpoint=False)
    pose = np.array([[*xy, heading]])
    scans = np.array([readings])
    seen = disc_ranges(_GRID, pose, angles, 5.0, [[2.0, 2.0, 0.3]])
    state = update_costmap(_LAYERS, _LAYERS.initial_state(1), pose, angles, seen, 5.0)
    before = (state.obstacle.copy(), state.cost.copy(), pose.copy(), scans.copy())
    first = update_costmap(_LAYERS, state, pose, angles, scans, 5.0)
    second = update_costmap(_LAYERS, state, pose, angles, scans, 5.0)
    assert np.array_equal(first.obstacle, second.obstacle)
    assert np.array_equal(first.cost, second.cost)
    for now, then in zip((state.obstacle, state.cost, pose, scans), before, strict=True):
        assert np.array_equal(now, then, equal_nan=True)
    assert not first.cost.flags.writeable and not state.cost.flags.writeable
    assert np.array_equal(first.cost[0], reference_cost(_LAYERS, first.obstacle[0]))


def test_a_coarser_costmap_keeps_every_map_obstacle():
    rng = np.random.default_rng(2)
    grid = OccupancyGrid(rng.random((61, 83)) > 0.97, 0.05, (1.0, -2.0))
    layers = LayeredCostmap.from_map(CostmapSpec(resolution=0.12), grid, 0.2)
    assert layers.shape == (math.ceil(61 * 0.05 / 0.12), math.ceil(83 * 0.05 / 0.12))
    coarse = layers.master(layers.initial_state(1), 0)
    centres = grid.cell_to_world(np.argwhere(grid.occupied))
    assert np.all(coarse.cost_at(centres) == LETHAL)
    corners = centres + 0.024 * np.array([[1, 1], [-1, -1], [1, -1], [-1, 1]])[:, None]
    assert np.all(coarse.cost_at(corners.reshape(-1, 2)) == LETHAL)
    # and nothing else: each lethal cell overlaps an occupied map cell or leaves the map
    for i, j in np.argwhere(layers.static == LETHAL):
        x0, y0 = np.asarray(layers.origin) + 0.12 * np.array([j, i])
        inside = (centres[:, 0] > x0 - 0.025) & (centres[:, 0] < x0 + 0.145)
        inside &= (centres[:, 1] > y0 - 0.025) & (centres[:, 1] < y0 + 0.145)
        assert inside.any() or x0 + 0.12 > 1.0 + 83 * 0.05 or y0 + 0.12 > -2.0 + 61 * 0.05


@pytest.mark.parametrize(
    ("values", "match"),
    [
        ({"inflation_radius": -1.0}, "costmap.inflation_radius must be > 0 m"),
        ({"cost_scaling_factor": "x"}, "costmap.cost_scaling_factor must be a real number"),
        ({"obstacle_max_range": math.nan}, "costmap.obstacle_max_range must be finite"),
        ({"raytrace_min_range": 4.0}, "costmap.raytrace_min_range must be < costmap.raytrace_m"),
        ({"window": 0}, "costmap.window must be > 0 m"),
        ({"resolution": -0.1}, "costmap.resolution must be > 0 m"),
        ({"track_unknown": "yes"}, "costmap.track_unknown must be true or false"),
        ({"raytrace_range": 3.0}, "unknown key costmap.raytrace_range; allowed: inflation_rad"),
    ],
)
def test_bad_costmap_keys_name_the_key(values, match):
    with pytest.raises(ConfigError, match=match):
        CostmapSpec.from_mapping(values)


def test_bad_costmap_inputs_are_clear_errors():
    grid = room(2.0, 2.0, 0.1)
    with pytest.raises(ConfigError, match=r"costmap\.inflation_radius = 0\.55 m is less than"):
        LayeredCostmap.from_map(CostmapSpec(), grid, 0.6)
    with pytest.raises(ConfigError, match=r"costmap\.resolution = 1e-06 m makes"):
        LayeredCostmap.from_map(CostmapSpec(resolution=1e-6), grid, 0.1)
    wide = OccupancyGrid(np.zeros((2000, 10), bool), 0.01)
    with pytest.raises(ConfigError, match=r"costmap\.inflation_radius = 15 m is 1500 cells"):
        LayeredCostmap.from_map(CostmapSpec(inflation_radius=15.0), wide, 0.1)
    # beyond the map's diagonal no distance occurs: the radius is capped there, exactly
    capped = LayeredCostmap.from_map(CostmapSpec(inflation_radius=1e6), grid, 0.1)
    assert capped.reach == math.ceil(math.hypot(20, 20))
    with pytest.raises(ConfigError, match=r"costmap\.window = 1e\+06 m is 10000000 cells"):
        LayeredCostmap.from_map(CostmapSpec(window=1e6), grid, 0.1)
    with pytest.raises(ConfigError, match=r"costmap\.window must be <= 1e\+10 m"):
        CostmapSpec(window=1e11)
    layers = LayeredCostmap.from_map(CostmapSpec(), grid, 0.1)
    state = layers.initial_state(2)
    pose = np.array([[1.0, 1.0, 0.0]] * 2)
    for kwargs, match in (
        ({"ranges": -np.ones((2, 4))}, "ranges must be >= 0 m"),
        ({"ranges": np.ones((2, 3))}, r"ranges must have shape \(2, 4\)"),
        ({"index": [1, 1]}, "index must be distinct robots"),
        ({"index": [0, 2]}, "index must be distinct robots in"),
        ({"sensor_poses": pose[:1]}, "1 scans for 2 robots"),
        ({"max_range": 0.0}, "max_range must be > 0 m"),
    ):
        args = {"sensor_poses": pose, "beam_angles": np.zeros(4), "ranges": np.ones((2, 4)),
                "max_range": 3.0, **kwargs}  # fmt: skip
        if "sensor_poses" in kwargs:
            args["ranges"] = np.ones((1, 4))
        with pytest.raises((InputError, ConfigError), match=match):
            update_costmap(layers, state, **args)
    with pytest.raises(ConfigError, match="robot must be an integer in"):
        layers.master(state, 2)
    assert isinstance(layers.master(state, 1), Costmap)
