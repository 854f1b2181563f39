"""Occupancy mapping with known poses: the update rules (log odds, counting), the traversal,
the grid."""

import math

import numpy as np
import pytest

from wheelbase.errors import ConfigError, MapError
from wheelbase.mapping.evaluation import map_agreement
from wheelbase.mapping.occupancy import OccupancyMapper, logit
from wheelbase.planning import OccupancyGrid, load_map, read_ros_yaml, write_ros_yaml
from wheelbase.sensors import Lidar


def _room():
    occ = np.zeros((40, 60), bool)
    occ[0, :] = occ[-1, :] = occ[:, 0] = occ[:, -1] = True
    occ[15:25, 30] = True
    return OccupancyGrid.from_array(occ, 0.1)


def test_one_beam_marks_its_cells_exactly():
    mapper = OccupancyMapper(resolution=0.1, max_range=10.0)
    grid = mapper.empty_map((0.0, 2.0, 0.0, 1.0))
    # from the centre of cell (5, 2) along +x to a return at 1.0 m: cells 2..11 missed, 12 hit
    mapper.integrate(grid, [0.25, 0.55, 0.0], [1.0], [0.0])
    row = grid.log_odds[5]
    np.testing.assert_allclose(row[2:12], logit(0.4), rtol=1e-6)
    assert row[12] == pytest.approx(logit(0.7), rel=1e-6)
    assert np.all(row[13:] == 0) and np.all(grid.stamp[[4, 6]] == -1)
    # a diagonal beam crosses |Δi| + |Δj| + 1 cells (Amanatides-Woo), the last one hit
    diag = mapper.empty_map((0.0, 2.0, 0.0, 2.0))
    mapper.integrate(diag, [0.05, 0.07, 0.0], [math.hypot(1.0, 0.9)], [math.atan2(0.9, 1.0)])
    assert (diag.stamp >= 0).sum() == 10 + 9 + 1
    assert (diag.log_odds > 0).sum() == 1


def test_no_return_clears_without_marking_and_nan_is_counted():
    mapper = OccupancyMapper(resolution=0.1, max_range=1.0)
    grid = mapper.empty_map((-2.0, 2.0, -2.0, 2.0))
    angles = np.linspace(-math.pi, math.pi, 90, endpoint=False)
    ranges = np.full(90, 5.0)
    ranges[:3] = np.nan
    skipped = mapper.integrate(grid, [0.0, 0.0, 0.0], ranges, angles, sensor_max_range=5.0)
    assert skipped == 3
    assert not (grid.log_odds > 0).any() and (grid.log_odds < 0).any()
    cells = np.argwhere(grid.log_odds < 0)
    centres = np.column_stack([grid.origin[0] + (cells[:, 1] + 0.5) * 0.1,
                               grid.origin[1] + (cells[:, 0] + 0.5) * 0.1])  # fmt: skip
    assert np.hypot(*centres.T).max() <= 1.0 + 0.1 * math.sqrt(2)


def test_a_cell_is_updated_once_per_scan_and_clamped():
    mapper = OccupancyMapper(resolution=0.1, max_range=5.0, l_max=2.0)
    grid = mapper.empty_map((-1.0, 1.0, -1.0, 1.0))
    angles = np.linspace(-0.01, 0.01, 50)  # 50 beams through the same cells
    for _ in range(10):
        mapper.integrate(grid, [0.05, 0.05, 0.0], np.full(50, 0.5), angles)
    assert grid.log_odds.max() == pytest.approx(2.0)
    assert grid.log_odds[grid.stamp >= 0].min() == pytest.approx(max(10 * logit(0.4), -2.0))


@pytest.mark.parametrize("name", ["room", "warehouse"])
def test_known_poses_reproduce_the_map(name):
    truth = _room() if name == "room" else load_map("warehouse")
    lidar = Lidar(beams=360, max_range=8.0)
    rng = np.random.default_rng(0)
    free = np.argwhere(~truth.inflate(0.3).occupied)
    poses = np.column_stack([truth.cell_to_world(free[rng.choice(len(free), 60)]),
                             rng.uniform(-math.pi, math.pi, 60)])  # fmt: skip
    scans = lidar.scan(truth, poses, noise=False)
    built = OccupancyMapper(resolution=truth.resolution, max_range=8.0).build(
        poses, scans, lidar.beam_angles, sensor_max_range=8.0
    )
    grid = built.to_grid()
    agreement, cells = map_agreement(grid, truth)
    assert cells > 1000 and agreement >= 0.98
    assert grid.unknown is not None and grid.unknown.any()  # never observed: unknown


def test_the_map_server_files_round_trip(tmp_path):
    truth = _room()
    lidar = Lidar(beams=180, max_range=8.0)
    scans = lidar.scan(truth, [[2.0, 2.0, 0.3], [4.5, 2.0, 2.0]], noise=False)
    grid = (
        OccupancyMapper(resolution=0.1)
        .build([[2.0, 2.0, 0.3], [4.5, 2.0, 2.0]], scans, lidar.beam_angles, sensor_max_range=8.0)
        .to_grid()
    )
    write_ros_yaml(grid, tmp_path / "map.yaml")
    back = read_ros_yaml(tmp_path / "map.yaml")
    np.testing.assert_array_equal(back.occupied, grid.occupied)
    np.testing.assert_array_equal(back.unknown, grid.unknown)
    assert back.origin == pytest.approx(grid.origin) and back.resolution == grid.resolution


def test_counting_model_counts_every_beam():
    mapper = OccupancyMapper(resolution=0.1, max_range=10.0, model="counting")
    grid = mapper.empty_map((0.0, 2.0, 0.0, 1.0))
    # the beam of test_one_beam_marks_its_cells_exactly, three times in one scan
    mapper.integrate(grid, [0.25, 0.55, 0.0], [1.0, 1.0, 1.0], [0.0, 0.0, 0.0])
    hits, misses = grid.counts[:, 5]
    assert np.all(misses[2:12] == 3) and not hits[2:12].any()
    assert hits[12] == 3 and misses[12] == 0 and not hits[13:].any() and not misses[13:].any()
    # the Beta(1, 1) posterior mean: (h + 1) / (h + m + 2)
    np.testing.assert_allclose(grid.probability[5, 2:13], [1 / 5] * 10 + [4 / 5], rtol=1e-6)
    # a diagonal beam crosses the same |Δi| + |Δj| + 1 cells as with log odds
    diag = mapper.empty_map((0.0, 2.0, 0.0, 2.0))
    mapper.integrate(diag, [0.05, 0.07, 0.0], [math.hypot(1.0, 0.9)], [math.atan2(0.9, 1.0)])
    assert (diag.stamp >= 0).sum() == 10 + 9 + 1 and diag.counts[0].sum() == 1


def test_counting_model_leaves_a_cell_as_often_crossed_as_hit_unknown():
    # a wall face on the boundary x = 1.0: returns 5 mm short of it and 5 mm beyond, in turn
    for model, expected in (("log_odds", True), ("counting", False)):
        mapper = OccupancyMapper(resolution=0.1, max_range=10.0, model=model)
        grid = mapper.empty_map((0.0, 2.0, 0.0, 1.0))
        for _ in range(20):
            mapper.integrate(grid, [0.25, 0.55, 0.0], [0.745, 0.755], [0.0, 0.0])
        built = grid.to_grid()
        assert built.occupied[5, 10]  # the wall's cell, hit by half the beams, crossed by none
        assert bool(built.occupied[5, 9] & ~built.unknown[5, 9]) is expected  # before the face
        if model == "counting":
            assert built.unknown[5, 9] and not built.occupied[5, 8] | built.unknown[5, 8]


def test_counting_model_reproduces_a_map_seen_with_range_noise():
    truth = load_map("warehouse")
    lidar = Lidar(beams=360, max_range=8.0, range_std=0.01)
    rng = np.random.default_rng(1)
    free = np.argwhere(~truth.inflate(0.3).occupied)
    poses = np.column_stack([truth.cell_to_world(free[rng.choice(len(free), 60)]),
                             rng.uniform(-math.pi, math.pi, 60)])  # fmt: skip
    scans = lidar.scan(truth, poses, rng=rng)
    got = {}
    for model in ("log_odds", "counting"):
        mapper = OccupancyMapper(resolution=truth.resolution, max_range=8.0, model=model)
        grid = mapper.build(poses, scans, lidar.beam_angles, sensor_max_range=8.0).to_grid()
        got[model] = map_agreement(grid, truth)
    # hits first marks the free cells before the faces that noisy returns fall short into
    assert got["counting"][0] >= 0.999 > got["log_odds"][0]
    assert got["counting"][1] >= 0.9 * got["log_odds"][1]


def test_limits_and_parameters():
    with pytest.raises(ConfigError, match="model"):
        OccupancyMapper(model="beams")
    with pytest.raises(ConfigError, match="counting mapper"):
        OccupancyMapper(model="counting").integrate(OccupancyMapper().empty_map((0, 1, 0, 1)),
                                                    [0.5, 0.5, 0.0], [0.3], [0.0])  # fmt: skip
    with pytest.raises(MapError, match="max_cells"):
        OccupancyMapper(resolution=0.01).empty_map((0, 1e4, 0, 1e4))
    with pytest.raises(ConfigError, match="p_hit"):
        OccupancyMapper(p_hit=0.4)
    with pytest.raises(ConfigError, match="l_min"):
        OccupancyMapper(l_min=1.0)
