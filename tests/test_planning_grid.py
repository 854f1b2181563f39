"""OccupancyGrid: loaders, writer, transforms, inflation, distance field, footprint checks."""

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from shared_data import DATA as SHARED_DATA
from shared_data import absent
from wheelbase.errors import ConfigError, DataError, InputError, MapError
from wheelbase.planning import (
    Footprint,
    OccupancyGrid,
    read_image,
    read_movingai_map,
    read_ros_yaml,
    write_ros_yaml,
)

SHARED = SHARED_DATA
TB3 = SHARED / "maps" / "turtlebot3_world.yaml"


def test_from_array_orientation_and_transforms():
    occ = np.zeros((4, 6), bool)
    occ[0, 5] = True  # lowest y, highest x
    grid = OccupancyGrid.from_array(occ, 0.5, origin=(1.0, -2.0))
    assert grid.shape == (4, 6)
    assert grid.extent == (1.0, 4.0, -2.0, 0.0)
    assert bool(grid.is_occupied([3.9, -1.9]))
    assert not bool(grid.is_occupied([1.1, -1.9]))
    assert bool(grid.is_occupied([0.0, 0.0]))  # outside: occupied
    cells = np.array([[0, 0], [3, 5], [2, 1]])
    np.testing.assert_array_equal(grid.world_to_cell(grid.cell_to_world(cells)), cells)


def test_numeric_array_thresholds_and_unknown():
    grid = OccupancyGrid.from_array(np.array([[0.0, 0.7], [-1.0, np.nan]]), 1.0)
    np.testing.assert_array_equal(grid.occupied, [[False, True], [True, True]])
    np.testing.assert_array_equal(grid.unknown, [[False, False], [True, True]])


def _write_pgm(path, pixels):
    path.write_bytes(f"P5\n{pixels.shape[1]} {pixels.shape[0]}\n255\n".encode() + pixels.tobytes())


def test_ros_yaml_modes(tmp_path):
    pixels = np.array([[0, 100, 205, 254]], np.uint8)
    _write_pgm(tmp_path / "m.pgm", pixels)
    base = "image: m.pgm\nresolution: 0.1\norigin: [1, 2, 0]\noccupied_thresh: 0.65\n"
    base += "free_thresh: 0.196\n"
    (tmp_path / "a.yaml").write_text(base + "negate: 0\n")
    grid = read_ros_yaml(tmp_path / "a.yaml")
    # p = (255 - v)/255 = 1.0, 0.61, 0.196, 0.004 -> occ, unknown, unknown, free
    np.testing.assert_array_equal(grid.unknown[0], [False, True, True, False])
    np.testing.assert_array_equal(grid.occupied[0], [True, True, True, False])
    free_unknown = read_ros_yaml(tmp_path / "a.yaml", unknown_as_occupied=False)
    np.testing.assert_array_equal(free_unknown.occupied[0], [True, False, False, False])
    (tmp_path / "n.yaml").write_text(base + "negate: 1\n")
    negated = read_ros_yaml(tmp_path / "n.yaml")
    np.testing.assert_array_equal(negated.occupied[0], [False, True, True, True])
    (tmp_path / "s.yaml").write_text(base + "mode: scale\n")
    scaled = read_ros_yaml(tmp_path / "s.yaml")
    np.testing.assert_array_equal(scaled.occupied[0], [True, False, False, False])
    assert grid.origin == (1.0, 2.0) and grid.resolution == 0.1


def test_ros_writer_round_trip(tmp_path):
    rng = np.random.default_rng(1)
    occ = rng.random((17, 23)) < 0.3
    unknown = rng.random((17, 23)) < 0.1
    grid = OccupancyGrid(occ | unknown, 0.05, (-1.5, 2.25), unknown)
    write_ros_yaml(grid, tmp_path / "map.yaml")
    back = read_ros_yaml(tmp_path / "map.yaml")
    np.testing.assert_array_equal(back.occupied, grid.occupied)
    np.testing.assert_array_equal(back.unknown, unknown)
    assert back.origin == grid.origin and back.resolution == grid.resolution


def test_image_loader(tmp_path):
    from PIL import Image

    pixels = np.full((3, 4), 255, np.uint8)
    pixels[0, 0] = 0  # top-left: highest y, lowest x
    Image.fromarray(pixels).save(tmp_path / "m.png")
    grid = read_image(tmp_path / "m.png", 0.2)
    assert grid.occupied[2, 0] and grid.occupied.sum() == 1


def test_loader_errors(tmp_path):
    with pytest.raises(MapError, match="non-empty"):
        OccupancyGrid.from_array(np.zeros((0, 3), bool), 1.0)
    with pytest.raises(ConfigError, match="resolution"):
        OccupancyGrid.from_array(np.zeros((2, 3), bool), -1.0)
    (tmp_path / "bad.yaml").write_text("image: x.pgm\nresolution: 0.1\n")
    with pytest.raises(MapError, match="origin"):
        read_ros_yaml(tmp_path / "bad.yaml")
    (tmp_path / "bad2.yaml").write_text("image: x.pgm\nresolution: 0.1\norigin: [0, 0, 0]\n")
    with pytest.raises(DataError, match="not found"):
        read_ros_yaml(tmp_path / "bad2.yaml")
    with pytest.raises(DataError, match="cannot read"):
        read_movingai_map(tmp_path / "none.map")
    grid = OccupancyGrid.from_array(np.zeros((2, 3), bool), 1.0)
    with pytest.raises(InputError, match="poses"):
        grid.in_collision(Footprint.rectangle(1, 1), [1.0, 2.0])


ROS_BASE = "image: m.pgm\nresolution: 0.1\norigin: [1, 2, 0]\n"


@pytest.mark.parametrize(
    ("yaml_text", "error", "match"),
    [
        (ROS_BASE + "negate: maybe\n", MapError, r"negate must be 0 or 1 \(got 'maybe'\)"),
        (ROS_BASE + "negate: 2\n", MapError, r"negate must be 0 or 1 \(got 2\)"),
        (ROS_BASE.replace("[1, 2, 0]", "[a, b, 0]"), MapError, r"origin must be \[x, y, yaw\]"),
        (ROS_BASE.replace("[1, 2, 0]", "[.nan, 0, 0]"), MapError, r"origin must be finite"),
        (ROS_BASE + "occupied_thresh: 1.5\n", MapError, r"occupied_thresh must be in \[0, 1\]"),
        (ROS_BASE + "free_thresh: 0.9\n", MapError, r"free_thresh .* <= occupied_thresh"),
        (ROS_BASE.replace("0.1", "abc"), MapError, r"resolution must be a real number"),
        (ROS_BASE + "x: " + "9" * 5000 + "\n", MapError, r"invalid YAML: .*4300 digits"),
        ("image: [" * 3000 + "]" * 3000 + "\n", MapError, r"invalid YAML"),
    ],
    ids=["negate-word", "negate-2", "origin-letters", "origin-nan", "occupied-1.5",
         "free-above-occupied", "resolution-letters", "5000-digits", "nested-3000-deep"],
)  # fmt: skip
def test_bad_ros_yaml_fields_are_map_errors(tmp_path, yaml_text, error, match):
    _write_pgm(tmp_path / "m.pgm", np.array([[0, 254]], np.uint8))
    (tmp_path / "bad.yaml").write_text(yaml_text)
    with pytest.raises(error, match=match):
        read_ros_yaml(tmp_path / "bad.yaml")


def test_yaml_booleans_for_negate_are_read_as_map_server_does(tmp_path):
    _write_pgm(tmp_path / "m.pgm", np.array([[0, 254]], np.uint8))
    (tmp_path / "y.yaml").write_text(ROS_BASE + "negate: true\n")
    np.testing.assert_array_equal(read_ros_yaml(tmp_path / "y.yaml").occupied[0], [False, True])


@pytest.mark.parametrize(
    ("name", "content", "match"),
    [
        ("m.yaml", b"image: m.pgm\nresolution: 0.1\norigin: [1, 2, 0] # caf\xe9\n", "not UTF-8"),
        ("m.map", b"type octile\nheight 1\nwidth 1\nmap\n\xff\n", "not UTF-8"),
        ("m.scen", b"version 1\n\xfe\n", "not UTF-8"),
        ("m.map", b"type octile\nheight abc\nwidth 2\nmap\n..\n", r"height must be an integer"),
        ("m.map", b"type octile\nheight -1\nwidth 2\nmap\n..\n", r"height must be an integer"),
        ("m.map", b"type octile\nheight 100000\nwidth 100000\nmap\n", r"1e\+10 cells.*max_cells"),
        ("m.pgm", b"P5\n100000000 100000000\n255\n\x00", r"1e\+16 pixels.*max_cells"),
        ("m.pgm", b"P5\n4 4\n255\n\x00\x00", r"cannot read map image"),
        ("m.png", b"\x89PNG\r\n\x1a\n\x00\x00", r"cannot read map image"),
    ],
    ids=["yaml-latin1", "map-binary", "scen-binary", "height-abc", "height-negative",
         "map-1e10-cells", "pgm-1e16-pixels", "pgm-truncated", "png-truncated"],
)  # fmt: skip
def test_unreadable_map_files_are_wheelbase_errors(tmp_path, name, content, match):
    from wheelbase.errors import WheelbaseError
    from wheelbase.planning import read_movingai_scenarios
    from wheelbase.planning.maps import load_map

    path = tmp_path / name
    path.write_bytes(content)
    with pytest.raises(WheelbaseError, match=match):
        if name.endswith(".scen"):
            read_movingai_scenarios(path)
        elif name.endswith((".pgm", ".png")):
            load_map(path, resolution=0.1)  # a bare image needs its scale
        else:
            load_map(path)


def test_cell_limit_can_be_raised(tmp_path):
    from PIL import Image

    Image.fromarray(np.full((30, 40), 255, np.uint8)).save(tmp_path / "m.png")
    with pytest.raises(MapError, match=r"40 × 30 = 1.2e\+03 pixels.*max_cells = 1000"):
        read_image(tmp_path / "m.png", 0.1, max_cells=1000)
    assert read_image(tmp_path / "m.png", 0.1, max_cells=1200).shape == (30, 40)


@pytest.mark.parametrize("threshold", [math.nan, math.inf, "abc"])
def test_thresholds_must_be_finite(tmp_path, threshold):
    # occupied_thresh=nan made every cell free: a silently wrong map
    from PIL import Image

    with pytest.raises(ConfigError, match="occupied_thresh"):
        OccupancyGrid.from_array(np.array([[0.0, 0.9]]), 1.0, occupied_thresh=threshold)
    Image.fromarray(np.zeros((2, 2), np.uint8)).save(tmp_path / "m.png")
    with pytest.raises(ConfigError, match="threshold"):
        read_image(tmp_path / "m.png", 1.0, threshold=threshold)


@pytest.mark.skipif(not TB3.exists(), reason=absent(TB3))
def test_turtlebot3_pixels_follow_map_server_rules():
    with pytest.warns(UserWarning, match="not found"):  # its YAML names map.pgm
        grid = read_ros_yaml(TB3)
    raw = np.flipud(np.asarray(__import__("PIL.Image").Image.open(TB3.with_suffix(".pgm"))))
    np.testing.assert_array_equal(grid.occupied, raw != 254)
    np.testing.assert_array_equal(grid.unknown, raw == 205)
    assert grid.origin == (-10.0, -10.0) and grid.resolution == 0.05


def test_distance_field_and_inflation_match_brute_force():
    rng = np.random.default_rng(3)
    occ = rng.random((15, 12)) < 0.08
    grid = OccupancyGrid.from_array(occ, 0.25)
    rr, cc = np.nonzero(occ)
    ii, jj = np.mgrid[0:15, 0:12]
    brute = np.min(np.hypot(ii[..., None] - rr, jj[..., None] - cc), axis=-1) * 0.25
    np.testing.assert_allclose(grid.distance_field, brute)
    inflated = grid.inflate(0.6)
    np.testing.assert_array_equal(inflated.occupied, brute <= 0.6)
    assert np.isinf(OccupancyGrid.from_array(np.zeros((3, 3), bool), 1.0).distance_field).all()


def test_footprint_rectangle_and_validation():
    fp = Footprint.rectangle(4.0, 2.0, rear_axle_to_center=1.5)
    np.testing.assert_allclose(fp.polygon.min(0), [-0.5, -1.0])
    np.testing.assert_allclose(fp.polygon.max(0), [3.5, 1.0])
    assert fp.inscribed_radius == pytest.approx(0.5)
    assert fp.max_radius == pytest.approx(math.hypot(3.5, 1.0))
    big = fp.inflated(0.1)
    np.testing.assert_allclose(big.polygon.max(0), [3.6, 1.1])
    # the covering circles cover every vertex
    d = np.hypot(*(fp.polygon[:, None, :] - fp.circles[None]).transpose(2, 0, 1))
    assert np.all(d.min(1) <= fp.circle_radius + 1e-12)
    with pytest.raises(ConfigError, match="length"):
        Footprint.rectangle(-1.0, 1.0)
    with pytest.raises(ConfigError, match="convex"):
        Footprint(np.array([[0, 0], [2, 0], [1, 0.2], [2, 2], [0, 2]]))


def _brute_collides(grid, footprint, pose, spacing):
    """Fine point sampling of the polygon (interior and boundary)."""
    poly = footprint.polygon
    lo, hi = poly.min(0), poly.max(0)
    xs = np.arange(lo[0], hi[0] + spacing, spacing).clip(lo[0], hi[0])
    ys = np.arange(lo[1], hi[1] + spacing, spacing).clip(lo[1], hi[1])
    pts = np.stack(np.meshgrid(xs, ys), -1).reshape(-1, 2)
    c, s = math.cos(pose[2]), math.sin(pose[2])
    world = pts @ np.array([[c, s], [-s, c]]) + pose[:2]
    return bool(np.any(grid.is_occupied(world)))


@settings(max_examples=40, deadline=None)
@given(st.integers(0, 2**31 - 1))
def test_footprint_check_agrees_with_fine_sampling(seed):
    rng = np.random.default_rng(seed)
    occ = rng.random((30, 30)) < 0.03
    grid = OccupancyGrid.from_array(occ, 0.1)
    fp = Footprint.rectangle(0.9, 0.5, rear_axle_to_center=0.3)
    poses = np.column_stack([rng.uniform(0, 3, 20), rng.uniform(0, 3, 20), rng.uniform(-4, 4, 20)])
    ours = grid.in_collision(fp, poses)
    shrunk = Footprint(fp.polygon * 0.97 + np.array([0.3 * 0.03, 0]))
    for pose, hit in zip(poses, ours, strict=True):
        if _brute_collides(grid, fp, pose, 0.01):
            assert hit  # a sampled point lies in an occupied cell (or outside the map)
        if not hit:
            assert grid.footprint_clearance(fp, pose) > 0
        else:
            # a collision found by the exact test is real up to the sampling spacing
            assert _brute_collides(grid, fp.inflated(0.01), pose, 0.005)
    assert np.all(~grid.in_collision(shrunk, poses) | ours)


def test_footprint_clearance_known_value():
    occ = np.zeros((40, 40), bool)
    occ[20, 30] = True  # square [3.0, 3.1] x [2.0, 2.1]
    grid = OccupancyGrid.from_array(occ, 0.1)
    fp = Footprint.rectangle(1.0, 0.6)  # centred on the reference point
    d = grid.footprint_clearance(fp, [[2.0, 2.05, 0.0], [2.0, 2.05, math.pi / 2]])
    np.testing.assert_allclose(d, [0.5, 0.7], atol=1e-12)
    assert grid.in_collision(fp, [2.51, 2.05, 0.0])
    assert not grid.in_collision(fp, [2.49, 2.05, 0.0])
    assert grid.in_collision(fp, [2.49, 2.05, 0.0], margin=0.02)


def test_outline_circles_follow_a_car_closely():
    car = Footprint.rectangle(4.5, 1.8, rear_axle_to_center=1.35)
    # the covering circles reach 0.56 m past the car's ends
    assert car.circle_overshoot == pytest.approx(math.hypot(0.45, 0.9) - 0.45, abs=1e-3)
    disks = car.outline_circles(0.2)
    assert car.outline_distance(disks[:, :2], disks[:, 2]) <= 0.1 + 1e-9
    # every point of the outline lies inside a disk
    corners = car.polygon
    t = np.linspace(0.0, 1.0, 200)[:, None]
    edges = zip(corners, np.roll(corners, -1, 0), strict=True)
    outline = np.concatenate([a + t * (b - a) for a, b in edges])
    gaps = np.hypot(*(outline[:, None, :] - disks[None, :, :2]).transpose(2, 0, 1)) - disks[:, 2]
    assert np.all(gaps.min(axis=1) <= 1e-9)
    with pytest.raises(ConfigError, match="spacing"):
        car.outline_circles(0.0)


def test_lattice_collisions_is_a_subset_of_the_exact_check():
    occupied = np.zeros((80, 80), bool)
    occupied[30:50, 30:50] = True
    grid = OccupancyGrid.from_array(occupied, 0.05)
    robot = Footprint.rectangle(0.6, 0.4)
    poses = np.column_stack(
        [np.random.default_rng(3).uniform(0.3, 3.7, (300, 2)),
         np.random.default_rng(4).uniform(-np.pi, np.pi, 300)]
    )  # fmt: skip
    lattice = grid.lattice_collisions(robot, poses, 0.02)
    exact = grid.in_collision(robot, poses)
    # a lattice point on an occupied cell means the footprint overlaps it: never a false alarm
    assert not np.any(lattice & ~exact)
    assert lattice.sum() >= 0.9 * exact.sum() > 0  # and it misses only slivers
    assert grid.lattice_collisions(robot, [[2.0, 2.0, 0.0], [0.5, 0.5, 0.0]]).tolist() == [
        True,
        False,
    ]
    with pytest.raises(ConfigError, match="spacing"):
        grid.lattice_collisions(robot, poses, 0.0)


def test_footprint_beyond_1e10_m_is_refused():
    # 1e300 m overflowed the area check (found by the fuzz suite's explore run: wheelbase plan
    # --footprint 1e300 1e300)
    with pytest.raises(ConfigError, match=r"within ±1e\+10 m of the reference point"):
        Footprint.rectangle(1e300, 1e300)


def test_with_origin_moves_the_cells_and_shares_the_derived_maps():
    occ = np.zeros((20, 30), bool)
    occ[5:8, 10:12] = True
    grid = OccupancyGrid.from_array(occ, 0.1, origin=(4.5e9, -2.0))
    field = grid.distance_field
    moved = grid.with_origin((0.0, 0.0))
    assert moved.distance_field is field and moved.origin == (0.0, 0.0)
    np.testing.assert_array_equal(moved.occupied, grid.occupied)
    local = np.array([[1.05, 0.65], [0.25, 0.25]])
    shifted = local + np.array([4.5e9, -2.0])
    np.testing.assert_array_equal(moved.is_occupied(local), grid.is_occupied(shifted))


def test_with_origin_shares_the_derived_maps_whichever_computes_them_first():
    # HybridAStar moves its grid before either copy has a distance field: the planner's
    # moved copy and the caller's grid computed the same transform twice (a replan's largest
    # cost after the search in crowd_crossing)
    occ = np.zeros((20, 30), bool)
    occ[5:8, 10:12] = True
    grid = OccupancyGrid.from_array(occ, 0.1, origin=(3.0, -2.0))
    moved = grid.with_origin((0.0, 0.0)).with_origin((1.0, 1.0))
    field, prefix = moved.distance_field, moved.occupancy_prefix
    assert grid.distance_field is field and grid.occupancy_prefix is prefix
    fresh = OccupancyGrid.from_array(occ, 0.1)
    np.testing.assert_array_equal(field, fresh.distance_field)
    np.testing.assert_array_equal(prefix, fresh.occupancy_prefix)
