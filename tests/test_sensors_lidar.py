"""Lidar ray casting against analytic geometry, fast against exact, and the beam noise model."""

import math
import warnings

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy import integrate, stats

from shared_data import DATA as SHARED_DATA
from shared_data import absent
from wheelbase.errors import ConfigError, InputError
from wheelbase.planning import BUNDLED_MAPS, OccupancyGrid, load_map
from wheelbase.sensors import RAY_METHODS, BeamModel, Lidar, cast_rays, gap_field, scan_rays

MAPS = SHARED_DATA / "maps"
TURTLEBOT = MAPS / "turtlebot3_world.yaml"


def room(rows=40, cols=60, res=0.1, origin=(-1.0, 2.0)):
    occ = np.zeros((rows, cols), bool)
    occ[0, :] = occ[-1, :] = occ[:, 0] = occ[:, -1] = True
    return OccupancyGrid.from_array(occ, res, origin)


def box_range(points, angles, lo, hi):
    """Distance from ``points (..., 2)`` inside the box [lo, hi] along ``angles`` to its edge."""
    d = np.stack([np.cos(angles), np.sin(angles)], -1)
    with np.errstate(divide="ignore", invalid="ignore"):
        t = np.where(d > 0, (hi - points) / d, (lo - points) / d)
    return np.where(d != 0, t, np.inf).min(-1)


def random_free_poses(grid, n, rng):
    free = np.argwhere(~grid.occupied)
    cells = free[rng.integers(len(free), size=n)]
    xy = grid.cell_to_world(cells) + rng.uniform(-0.5, 0.5, (n, 2)) * grid.resolution
    return np.column_stack([xy, rng.uniform(-np.pi, np.pi, n)])


@pytest.mark.parametrize("method", RAY_METHODS)
def test_ranges_in_a_rectangular_room_are_the_distances_to_its_walls(method):
    grid = room()
    x0, y0 = grid.origin
    res = grid.resolution
    lo = np.array([x0 + res, y0 + res])  # inner faces of the one-cell walls
    hi = np.array([x0 + (grid.shape[1] - 1) * res, y0 + (grid.shape[0] - 1) * res])
    rng = np.random.default_rng(1)
    points = rng.uniform(lo + 0.01, hi - 0.01, (50, 2))
    angles = rng.uniform(-np.pi, np.pi, (50, 64))
    ranges = cast_rays(grid, points[:, None, :], angles, max_range=100.0, method=method)
    expected = box_range(points[:, None, :], angles, lo, hi)
    np.testing.assert_allclose(ranges, expected, atol=1e-6 if method == "numpy" else 1e-9)
    # A short max range caps every beam.
    capped = cast_rays(grid, points[:, None, :], angles, max_range=0.5, method=method)
    np.testing.assert_allclose(capped, np.minimum(expected, 0.5), atol=1e-6)


@pytest.mark.parametrize("method", RAY_METHODS)
def test_range_to_a_disc_lies_between_the_discs_that_bound_its_cells(method):
    res, radius, centre = 0.02, 1.0, np.array([3.0, 3.0])
    n = 300
    xc = (np.arange(n) + 0.5) * res
    inside = np.hypot(xc[None, :] - centre[0], xc[:, None] - centre[1]) <= radius
    grid = OccupancyGrid.from_array(inside, res)
    # Every occupied cell's square lies within R + r/√2 of the centre and every cell whose
    # square meets the disc of radius R − r/√2 is occupied.
    outer, inner = radius + res / math.sqrt(2), radius - res / math.sqrt(2)
    rng = np.random.default_rng(2)
    angle = rng.uniform(-np.pi, np.pi, 200)
    dist = rng.uniform(1.5, 2.5, 200)
    origins = centre + dist[:, None] * np.stack([np.cos(angle), np.sin(angle)], -1)
    offset = rng.uniform(-0.5, 0.5, 200)  # aim beside the centre: grazing rays included
    heading = angle + np.pi + offset

    def disc_range(r):
        # distance along the ray to a circle of radius r (inf when it misses)
        along = dist * np.cos(offset)
        miss2 = (dist * np.sin(offset)) ** 2
        with np.errstate(invalid="ignore"):
            return np.where(miss2 <= r * r, along - np.sqrt(r * r - miss2), np.inf)

    ranges = cast_rays(grid, origins, heading, max_range=20.0, method=method)
    near, far = disc_range(outer), disc_range(inner)
    hit = np.isfinite(near) & (ranges < 20.0)
    assert np.all(ranges[hit] >= near[hit] - 1e-9)
    assert np.all(ranges[np.isfinite(far)] <= far[np.isfinite(far)] + 1e-6)
    # Beams aimed at the centre: d − R within one cell.
    straight = cast_rays(grid, origins, angle + np.pi, max_range=20.0, method=method)
    np.testing.assert_allclose(straight, dist - radius, atol=res)


def map_cases():
    cases = [(name, lambda name=name: load_map(name)) for name in BUNDLED_MAPS]
    cases.append(("turtlebot3_world", _turtlebot))
    return cases


def _turtlebot():
    if not TURTLEBOT.is_file():
        pytest.skip(absent(MAPS / "turtlebot3_world.yaml"))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the YAML names map.pgm; the loader finds the .pgm
        return load_map(TURTLEBOT)


@pytest.mark.parametrize(("name", "loader"), map_cases(), ids=[c[0] for c in map_cases()])
def test_fast_and_numpy_agree_with_the_exact_traversal_on_the_maps(name, loader):
    grid = loader()
    rng = np.random.default_rng(3)
    poses = random_free_poses(grid, 300, rng)
    beams = np.linspace(-np.pi, np.pi, 90, endpoint=False)
    exact = scan_rays(grid, poses[:, :2], poses[:, 2], beams, 8.0, "exact")
    for method in ("fast", "numpy"):
        other = scan_rays(grid, poses[:, :2], poses[:, 2], beams, 8.0, method)
        assert np.max(np.abs(other - exact)) <= grid.resolution  # the promise: one cell
        # in fact the same to rounding, except where a ray passes exactly through a corner
        assert np.mean(np.abs(other - exact) < 1e-6) > 0.999
    assert exact.min() > 0.0 and exact.max() <= 8.0
    # Rays from occupied cells and from outside the map have range 0.
    blocked = np.argwhere(grid.occupied)[:5]
    xy = np.concatenate([grid.cell_to_world(blocked), [[grid.extent[0] - 1.0, 0.0]]])
    for method in RAY_METHODS:
        assert np.all(cast_rays(grid, xy, 0.3, 5.0, method=method) == 0.0)


@settings(max_examples=30, deadline=None)
@given(seed=st.integers(0, 2**31 - 1), density=st.floats(0.02, 0.4))
def test_exact_range_ends_where_the_ray_enters_its_first_occupied_cell(seed, density):
    # An independent check of the reference: sample the ray densely.
    rng = np.random.default_rng(seed)
    occ = rng.random((25, 30)) < density
    grid = OccupancyGrid.from_array(occ, 0.2, (0.5, -1.0))
    free = np.argwhere(~occ)
    if free.size == 0:
        return
    cells = free[rng.integers(len(free), size=20)]
    origins = grid.cell_to_world(cells) + rng.uniform(-0.1, 0.1, (20, 2))
    angles = rng.uniform(-np.pi, np.pi, 20)
    ranges = cast_rays(grid, origins, angles, 10.0, method="exact")
    fast = cast_rays(grid, origins, angles, 10.0, method="fast")
    np.testing.assert_allclose(fast, ranges, atol=1e-9)
    direction = np.stack([np.cos(angles), np.sin(angles)], -1)
    for p, d, r in zip(origins, direction, ranges, strict=True):
        before = p + np.linspace(0.0, max(r - 1e-7, 0.0), 400)[:, None] * d
        assert not grid.is_occupied(before).any()
        if r < 10.0:
            assert grid.is_occupied(p + (r + 1e-7) * d)


def test_gap_field_is_the_distance_from_a_cell_to_the_nearest_occupied_square():
    rng = np.random.default_rng(4)
    occ = rng.random((12, 15)) < 0.1
    grid = OccupancyGrid.from_array(occ, 1.0)
    gap = gap_field(grid)
    assert gap.shape == (14, 17) and gap is gap_field(grid)  # cached
    padded = np.pad(occ, 1, constant_values=True)
    blocked = np.argwhere(padded)
    for i, j in np.argwhere(~padded):
        di = np.maximum(np.abs(blocked[:, 0] - i) - 1, 0)
        dj = np.maximum(np.abs(blocked[:, 1] - j) - 1, 0)
        assert gap[i, j] == pytest.approx(np.sqrt(di**2 + dj**2).min(), abs=1e-5)
    assert np.all(gap[padded] == -1.0)


def test_lidar_beams_mount_and_batch_shapes():
    lidar = Lidar(beams=4, fov=2 * math.pi, max_range=30.0, mount=(0.2, 0.0, math.pi / 2))
    np.testing.assert_allclose(lidar.beam_angles, [-math.pi, -math.pi / 2, 0.0, math.pi / 2])
    partial = Lidar(beams=5, fov=math.radians(180))
    np.testing.assert_allclose(partial.beam_angles, np.radians([-90, -45, 0, 45, 90]))
    grid = room(res=0.1, origin=(0.0, 0.0))  # inner faces at x = 0.1, 5.9 and y = 0.1, 3.9
    pose = np.array([2.0, 2.0, 0.0])  # the sensor at (2.2, 2.0) looking along +y
    one = lidar.scan(grid, pose, noise=False)
    # beams along -y, +x, +y, -x: 2.0 - 0.1, 5.9 - 2.2, 3.9 - 2.0, 2.2 - 0.1
    np.testing.assert_allclose(one, [1.9, 3.7, 1.9, 2.1], atol=1e-9)
    batch = lidar.scan(grid, np.stack([pose, pose]), noise=False)
    assert batch.shape == (2, 4)
    np.testing.assert_allclose(batch, np.stack([one, one]))
    ends = lidar.endpoints(pose, one)
    np.testing.assert_allclose(ends[2], [2.2, 3.9], atol=1e-9)  # beam 2 along the sensor axis
    assert np.all(grid.is_occupied(lidar.endpoints(pose, one + 1e-6)))


def test_min_range_readings_are_nan_and_noise_is_seeded():
    grid = room(res=0.1, origin=(0.0, 0.0))
    lidar = Lidar(beams=90, max_range=10.0, min_range=0.5, range_std=0.05)
    pose = np.array([0.4, 2.0, 0.0])  # 0.3 m from the wall behind
    ranges = lidar.scan(grid, pose, rng=5)
    truth = lidar.scan(grid, pose, noise=False)
    assert np.all(np.isnan(ranges[truth < 0.4]))
    np.testing.assert_array_equal(ranges, lidar.scan(grid, pose, rng=5))
    assert not np.array_equal(ranges, lidar.scan(grid, pose, rng=6), equal_nan=True)


def test_hit_noise_is_gaussian_with_the_range_std():
    grid = room(res=0.1, origin=(0.0, 0.0))
    lidar = Lidar(beams=1, fov=0.1, max_range=10.0, range_std=0.03)
    poses = np.tile([3.0, 2.0, 0.0], (20000, 1))  # wall ahead at x = 5.9: 2.9 m
    ranges = lidar.scan(grid, poses, rng=np.random.default_rng(7))[:, 0]
    assert abs(ranges.mean() - 2.9) < 4 * 0.03 / math.sqrt(ranges.size)
    assert abs(ranges.std() / 0.03 - 1.0) < 0.03
    assert stats.kstest((ranges - 2.9) / 0.03, "norm").pvalue > 1e-3


def test_beam_model_sampling_follows_its_density():
    model = BeamModel(z_hit=0.6, z_short=0.2, z_max=0.1, z_rand=0.1, lambda_short=0.8)
    z_true, sigma, z_max = 4.0, 0.2, 8.0
    rng = np.random.default_rng(8)
    z = model.sample(np.full(200000, z_true), sigma, z_max, rng)
    assert np.all((z >= 0.0) & (z <= z_max))
    at_max = z == z_max
    p = model.z_max
    assert abs(at_max.mean() - p) < 4 * math.sqrt(p * (1 - p) / z.size)
    # The continuous part against the CDF of the density (integrated numerically).
    grid_z = np.linspace(0.0, z_max, 40001)
    density = model.pdf(grid_z, z_true, sigma, z_max)
    cdf = integrate.cumulative_trapezoid(density, grid_z, initial=0.0)
    assert cdf[-1] == pytest.approx(1.0 - p, abs=1e-4)  # the density and the point mass: 1
    continuous = np.sort(z[~at_max])
    assert stats.kstest(continuous, lambda x: np.interp(x, grid_z, cdf / cdf[-1])).pvalue > 1e-3
    # Short readings never exceed the true range; no-return beams read the maximum when hit.
    short_only = BeamModel(z_hit=0.0, z_short=1.0)
    assert np.all(short_only.sample(np.full(1000, 2.0), sigma, z_max, rng) <= 2.0)
    hit_only = BeamModel()
    np.testing.assert_array_equal(hit_only.sample(np.full(10, z_max), sigma, z_max, rng), z_max)


def test_bad_parameters_raise_clear_errors():
    with pytest.raises(ConfigError, match="z_hit"):
        BeamModel(z_hit=0.5)
    with pytest.raises(ConfigError, match="lambda_short"):
        BeamModel(lambda_short=0.0)
    with pytest.raises(ConfigError, match="beams"):
        Lidar(beams=0)
    with pytest.raises(ConfigError, match="fov"):
        Lidar(fov=7.0)
    with pytest.raises(ConfigError, match="min_range"):
        Lidar(max_range=2.0, min_range=3.0)
    with pytest.raises(ConfigError, match="range_std"):
        Lidar(range_std=-0.1)
    with pytest.raises(ConfigError, match="method"):
        Lidar().scan(room(), [0.0, 3.0, 0.0], method="bresenham")
    with pytest.raises(InputError, match="poses"):
        Lidar().scan(room(), [0.0, np.nan, 0.0])
    with pytest.raises(ConfigError, match="rng"):
        Lidar(range_std=0.1).scan(room(), [0.0, 3.0, 0.0], rng="seed")
